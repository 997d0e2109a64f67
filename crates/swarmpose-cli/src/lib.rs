//! The commands of the `swarmpose` command line as a library: the binary (`main.rs`)
//! parses the arguments and calls them, and the Python package runs the items of a batch
//! ([`batch`]) with the same code.

#![forbid(unsafe_code)]
#![warn(clippy::unwrap_used)]

pub mod batch;
pub mod commands;
pub mod error;
pub mod input;
pub mod methods;
pub mod output_file;
pub mod signals;
pub mod streams;
