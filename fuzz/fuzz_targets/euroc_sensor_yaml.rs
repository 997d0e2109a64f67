//! EuRoC camera `sensor.yaml`.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let _ = swarmpose_datasets::euroc::parse_sensor_yaml(text, Path::new("sensor.yaml"));
});
