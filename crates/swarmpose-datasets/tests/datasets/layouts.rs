//! `open` detects each of the three real layouts and reads their calibration.

use swarmpose_datasets::karlsruhe::KarlsruheSequence;
use swarmpose_datasets::open;

#[test]
fn the_three_layouts_open() {
    // (data set, layout, frames, width, height, fx, baseline m, has ground truth)
    let cases = [
        (
            "kitti_vo_seq2",
            "kitti",
            51,
            1241,
            376,
            718.856,
            0.53717,
            true,
        ),
        (
            "karlsruhe_2010_03_09_drive_0023",
            "karlsruhe",
            112,
            1344,
            372,
            645.2401,
            0.57074,
            false,
        ),
        (
            "euroc_v1_01_easy_micro",
            "euroc",
            30,
            752,
            480,
            456.134,
            0.11008,
            true,
        ),
    ];
    for (name, layout, len, w, h, fx, baseline, gt) in cases {
        let Some(dir) = crate::common::dataset(name) else {
            continue;
        };
        let seq = open(&dir).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(seq.layout(), layout);
        assert_eq!(seq.len(), len, "{name}");
        assert_eq!(seq.image_size(), (w, h), "{name}");
        let c = seq.calibration();
        assert!((c.fx - fx).abs() < 1e-3, "{name}: fx {}", c.fx);
        assert!(
            (c.baseline_m - baseline).abs() < 2e-4,
            "{name}: {}",
            c.baseline_m
        );
        assert_eq!(seq.ground_truth().is_some(), gt, "{name}");
        let last = seq.frame(len - 1).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!((last.left.width, last.left.height), (w, h), "{name}");
        if let Some(gt) = seq.ground_truth() {
            assert_eq!(gt.len(), len);
            assert!(
                gt[0].translation.vector.norm() < 1e-6,
                "{name}: frame 0 is the origin"
            );
        }
    }
}

#[test]
fn karlsruhe_ins_positions() {
    let Some(dir) = crate::common::dataset("karlsruhe_2010_03_09_drive_0023") else {
        return;
    };
    let seq = KarlsruheSequence::open(&dir).expect("open");
    let p = seq.ins_positions().expect("read").expect("present");
    assert_eq!(p.len(), 112);
    let path: f64 = p
        .windows(2)
        .map(|w| {
            let d = [w[1][0] - w[0][0], w[1][1] - w[0][1], w[1][2] - w[0][2]];
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
        })
        .sum();
    // PROVENANCE: 93.7 m over the sequence.
    assert!((path - 93.7).abs() < 1.0, "{path}");
}
