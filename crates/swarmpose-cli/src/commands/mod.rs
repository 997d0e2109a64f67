//! One module per subcommand: its clap arguments and a `run` returning a [`CliError`].
//!
//! [`CliError`]: crate::error::CliError

pub mod bench;
pub mod correspondences;
pub mod demo;
pub mod evaluate;
pub mod odometry;
pub mod register;
pub mod segments;
pub mod simulate;
pub mod simulate_shard;
pub mod stereo_options;
