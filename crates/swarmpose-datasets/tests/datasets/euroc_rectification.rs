//! EuRoC frames are undistorted and rectified on load: features matched across the
//! rectified pair lie on the same row, unlike in the raw pair.

use swarmpose_datasets::euroc::EurocSequence;
use swarmpose_datasets::{StereoPair, StereoSequence};
use swarmpose_vision::features::{Descriptor, FeatureExtractor};
use swarmpose_vision::frontend::Frontend;
use swarmpose_vision::orb::{OrbConfig, OrbExtractor};
use swarmpose_vision::stereo::subpixel::{PairWindow, row_offset};
use swarmpose_vision::temporal::{TemporalConfig, mutual_matches};

/// Row differences (right - left, pixels) of mutual nearest-neighbour ORB matches
/// between the two images, searched without any row constraint.
fn row_differences(pair: &StereoPair) -> Vec<f32> {
    let orb = OrbExtractor::new(OrbConfig {
        fast_threshold: 15,
        oriented: false,
        ..OrbConfig::default()
    });
    let l = orb.extract(pair.left.view());
    let r = orb.extract(pair.right.view());
    let config = TemporalConfig {
        max_distance: 40.0,
        ratio: 0.8,
        max_displacement_px: Some(120.0),
        ..TemporalConfig::default()
    };
    let m = mutual_matches(
        &l.keypoints,
        &l.descriptors,
        &r.keypoints,
        &r.descriptors,
        &config,
    );
    m.iter()
        .filter(|&&(a, b)| l.descriptors[a].distance(&r.descriptors[b]) < 40.0)
        .map(|&(a, b)| r.keypoints[b].y - l.keypoints[a].y)
        .collect()
}

fn median_abs(v: &[f32]) -> f32 {
    let mut a: Vec<f32> = v.iter().map(|d| d.abs()).collect();
    a.sort_by(f32::total_cmp);
    a[a.len() / 2]
}

#[test]
fn euroc_rectified_pairs_share_rows() {
    let Some(dir) = crate::common::dataset("euroc_v1_01_easy_micro") else {
        return;
    };
    let seq = EurocSequence::open(&dir).expect("open EuRoC");
    assert_eq!(seq.len(), 30);
    let rig = seq.calibration();
    assert!(
        (rig.baseline_m - 0.11008).abs() < 2e-4,
        "{}",
        rig.baseline_m
    );
    let (mut rect, mut raw) = (Vec::new(), Vec::new());
    for i in [0, 15, 29] {
        rect.extend(row_differences(&seq.frame(i).expect("frame")));
        raw.extend(row_differences(&seq.raw_frame(i).expect("raw frame")));
    }
    let (mr, mw) = (median_abs(&rect), median_abs(&raw));
    eprintln!(
        "median |row difference|: rectified {mr:.2} px over {} matches, raw {mw:.2} px over {}",
        rect.len(),
        raw.len()
    );
    assert!(rect.len() >= 100, "{} matches", rect.len());
    assert!(mr < 0.5, "rectified median row difference {mr} px");

    // Sub-pixel: the vertical offset of each stereo match, by Gauss-Newton.
    let mut frontend = Frontend::orb(rig);
    frontend.stereo.row_tolerance_px = 2.0;
    let mut dys = Vec::new();
    for i in [0, 15, 29] {
        let p = seq.frame(i).expect("frame");
        let f = frontend.stereo_frame(p.left.view(), p.right.view());
        for (k, d) in f.left_keypoints.iter().zip(&f.disparities_px) {
            let window = PairWindow {
                left: p.left.view(),
                right: p.right.view(),
                xl: k.x.round() as usize,
                y: k.y.round() as usize,
                r: 4,
            };
            if let Some(dy) = row_offset(window, *d) {
                dys.push(dy);
            }
        }
    }
    let sub = median_abs(&dys);
    let mut signed = dys.clone();
    signed.sort_by(f32::total_cmp);
    eprintln!(
        "sub-pixel row offsets of {} stereo matches: median |dy| {sub:.3} px, median dy {:.3} px",
        dys.len(),
        signed[signed.len() / 2]
    );
    assert!(dys.len() >= 100, "{}", dys.len());
    assert!(sub < 0.5, "median sub-pixel row difference {sub} px");
    // The ground truth says the MAV sits still: the motion is tiny.
    let gt = seq.relative_ground_truth(0, 29).expect("ground truth");
    assert!(gt.translation.vector.norm() < 0.01);
}
