//! The CDR decoder of the ROS 2 message types (`swarmpose_fuzz_checks::ros_cdr`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| swarmpose_fuzz_checks::ros_cdr(data));
