//! The JSON report of `register`, as read back by `correspondences --inliers`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| swarmpose_fuzz_checks::register_report(data));
