//! KITTI and Karlsruhe `calib.txt`: any text gives a calibration or a typed error.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| swarmpose_fuzz_checks::calib_txt(data));
