//! The run loops' integration tests, each file a module: one test binary instead of one per
//! file (issue 32). `allocations.rs` stays a binary of its own: its counting global allocator
//! must see only its own test. Run one file's tests with `cargo test -p swarmpose-runs --test runs kitti::`.

mod common;

mod bad_input;
mod calibration;
mod covariance;
mod euroc;
mod karlsruhe;
mod kitti;
mod kitti_pairs;
mod kitti_variants;
mod moving_object;
mod online_steps;
mod rectification;
mod rgbd;
mod settings;
mod streaming;
mod synthetic;
mod two_threads;
mod wall;
mod window;
