//! The dataset readers' integration tests, each file a module: one test binary instead of one per file
//! (issue 32). Run one file's tests with `cargo test -p swarmpose-datasets --test datasets errors::`.

mod common;

mod errors;
mod euroc_rectification;
mod fuzz_regressions;
mod layouts;
