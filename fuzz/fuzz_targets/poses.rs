//! KITTI and TUM trajectory files, as read by `evaluate` and by the KITTI loader.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use swarmpose_eval::{Format, Trajectory};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = Path::new("poses.txt");
    for format in [Format::Kitti, Format::Tum] {
        if let Ok(t) = Trajectory::parse(text, path, format) {
            assert_eq!(t.poses.len(), t.stamps.len());
        }
    }
    let _ = swarmpose_datasets::kitti::parse_poses(text, path);
});
