//! EuRoC camera `sensor.yaml`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| swarmpose_fuzz_checks::euroc_sensor_yaml(data));
