//! The CLI's integration tests, each file a module: one test binary instead of one per file
//! (one link instead of seventeen: issue 32). Run one file's tests with
//! `cargo test -p swarmpose-cli --test cli odometry::`.

mod catalogue;
mod common;

mod batch;
mod bench;
mod catalogue_calibration;
mod catalogue_ground_truth;
mod catalogue_output_folder;
mod catalogue_outputs;
mod catalogue_register;
mod catalogue_sequences;
mod catalogue_small;
mod catalogue_special_outputs;
mod evaluate;
mod kitti_register;
mod odometry;
mod odometry_split;
mod register;
mod rgbd_bags;
mod ros_bags;
mod simulate;
