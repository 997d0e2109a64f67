//! # swarmpose-data
//!
//! The file formats of swarmpose, kept out of the I/O-free core:
//!
//! - [`correspondence_csv`]: matched 3D points, one correspondence per row,
//!   `src_x,src_y,src_z,dst_x,dst_y,dst_z` in metres, with `dst = R src + t`;
//! - [`register_report`]: the JSON report of `swarmpose register`, read back to draw
//!   its inliers;
//! - [`truth`]: the ground-truth JSON written beside each scenario CSV by the scenario
//!   generator (`gen_scenarios.py`);
//! - [`output`]: how every output file is written (whole, and never over a device, a
//!   FIFO or a folder).
//!
//! Every error names its input (a file path, or `<stdin>`) and, where one applies, the
//! 1-based line number, so a command-line tool can print it as one line.
#![deny(missing_docs)]
#![forbid(unsafe_code)]
#![warn(clippy::unwrap_used)]

pub mod correspondence_csv;
pub mod output;
pub mod register_report;
pub mod truth;

pub use correspondence_csv::{CsvError, CsvErrorKind, HEADER, HEADER_WITH_COVARIANCE, STDIN_NAME};
pub use truth::{InvalidTruth, ScenarioTruth, TruthError, TruthErrorKind};
