//! EuRoC `data.csv`: a camera's image list and the ground-truth states.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| swarmpose_fuzz_checks::euroc_data_csv(data));
