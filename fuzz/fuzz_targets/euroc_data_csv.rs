//! EuRoC `data.csv`: a camera's image list and the ground-truth states.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = Path::new("mav0/cam0/data.csv");
    let _ = swarmpose_datasets::euroc::parse_image_list(text, path, Path::new("mav0/cam0"));
    if let Ok(states) = swarmpose_datasets::euroc::parse_groundtruth(text, path) {
        // Every state is a rigid motion (a quaternion of norm 0 gave NaN poses).
        for (_, pose) in states {
            let q = pose.rotation.coords;
            assert!(q.iter().all(|v| v.is_finite()) && (q.norm() - 1.0).abs() < 1e-9);
        }
    }
});
