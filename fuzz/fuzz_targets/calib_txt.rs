//! KITTI and Karlsruhe `calib.txt`: any text gives a calibration or a typed error.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = Path::new("calib.txt");
    if let Ok((rig, _)) = swarmpose_datasets::kitti::parse_calibration(text, path) {
        assert!(rig.baseline_m.is_finite() && rig.baseline_m > 0.0);
    }
    if let Ok((rig, _)) = swarmpose_datasets::karlsruhe::parse_calibration(text, path) {
        assert!(rig.baseline_m.is_finite() && rig.baseline_m > 0.0);
    }
});
