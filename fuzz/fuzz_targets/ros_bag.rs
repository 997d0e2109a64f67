//! The ROS 2 bag front door (`swarmpose_fuzz_checks::ros_bag`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| swarmpose_fuzz_checks::ros_bag(data));
