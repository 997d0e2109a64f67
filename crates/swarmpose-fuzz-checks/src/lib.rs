//! # swarmpose-fuzz-checks
//!
//! The properties the fuzz targets check, one function per parser: any bytes give a
//! value that satisfies them or a typed error, never a panic. The cargo-fuzz targets in
//! `fuzz/` call these functions with the fuzzer's inputs; this crate's test replays
//! every committed corpus input (`fuzz/corpus/TARGET`) through the same functions in the
//! ordinary `cargo test`, so a regression fails without the fuzzer's toolchain.
//! [`TARGETS`] is the one list of target names.
#![forbid(unsafe_code)]
#![allow(clippy::missing_panics_doc)]

mod ros;

use std::path::Path;

use swarmpose_eval::{Format, Trajectory};
use swarmpose_vision::image::GrayImage;

pub use ros::{ros_bag, ros_cdr};

/// A fuzz target's property: panics when `data` breaks it.
pub type Check = fn(&[u8]);

/// Every fuzz target: its name (the cargo-fuzz binary and its corpus folder) and the
/// property it checks.
pub const TARGETS: &[(&str, Check)] = &[
    ("calib_txt", calib_txt),
    ("correspondence_csv", correspondence_csv),
    ("euroc_data_csv", euroc_data_csv),
    ("euroc_sensor_yaml", euroc_sensor_yaml),
    ("png_decode", png_decode),
    ("poses", poses),
    ("register_report", register_report),
    ("ros_bag", ros::ros_bag),
    ("ros_cdr", ros::ros_cdr),
];

/// The checksum the seeds of the `register_report` corpus carry.
const CHECKSUM: &str = "00112233445566ff";

/// KITTI and Karlsruhe `calib.txt`: any text gives a calibration or a typed error.
pub fn calib_txt(data: &[u8]) {
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
}

/// The correspondence CSV read by `register` (bytes, as from standard input).
pub fn correspondence_csv(data: &[u8]) {
    if let Ok(c) = swarmpose_data::correspondence_csv::read_from(data, "fuzz.csv") {
        assert!(!c.is_empty());
        // What is read writes back and reads back the same.
        let mut out = Vec::new();
        swarmpose_data::correspondence_csv::write_to(&mut out, &c, "out.csv").expect("write");
        let back = swarmpose_data::correspondence_csv::read_from(out.as_slice(), "out.csv")
            .expect("read back");
        assert_eq!(back.src(), c.src());
        assert_eq!(back.dst(), c.dst());
    }
}

/// EuRoC `data.csv`: a camera's image list and the ground-truth states.
pub fn euroc_data_csv(data: &[u8]) {
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
}

/// EuRoC camera `sensor.yaml`.
pub fn euroc_sensor_yaml(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let _ = swarmpose_datasets::euroc::parse_sensor_yaml(text, Path::new("sensor.yaml"));
}

/// The image decoding path of every sequence loader: PNG bytes to 8-bit gray.
pub fn png_decode(data: &[u8]) {
    if let Ok(img) = GrayImage::decode_png(data, Path::new("frame.png")) {
        assert_eq!(img.data.len(), img.width * img.height);
    }
}

/// KITTI and TUM trajectory files, as read by `evaluate` and by the KITTI loader.
pub fn poses(data: &[u8]) {
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
}

/// The JSON report of `register`, as read back by `correspondences --inliers`.
pub fn register_report(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    for rows in [0, 3, 16] {
        if let Ok(flags) =
            swarmpose_data::register_report::parse_inliers(text, "report.json", rows, CHECKSUM)
        {
            assert_eq!(flags.len(), rows);
        }
    }
}
