//! KITTI and TUM trajectory files, as read by `evaluate` and by the KITTI loader.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| swarmpose_fuzz_checks::poses(data));
