//! The simulator's integration tests, each file a module: one test binary instead of one per file
//! (issue 32). Run one file's tests with `cargo test -p swarmpose-sim --test sim generator::`.

mod generator;
mod runner;
mod simulate;
mod stereo_registration;
