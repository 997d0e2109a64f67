//! End to end on `kitti_vo_seq2`: every consecutive pair yields at least 300 3D-3D
//! correspondences with the fast detector, and the core's `pso` on them, with the stereo
//! covariances attached (Mahalanobis inlier test and fit), recovers the ground-truth
//! relative motion within 0.2 degrees and 5 cm for at least 90 % of the pairs.
//!
//! With the calibration as given, the translations from stereo are about 6 % too long
//! (more for far points): the disparities of this copy of the sequence are short of its
//! `calib.txt` (see docs/kitti-disparity-offset.md). The correction is the one the
//! odometry engine self-calibrates online from the image data alone (no ground truth);
//! the pairs are then registered with it applied. Both counts are printed.

use swarmpose_core::{Estimator, PsoEstimator, PsoEstimatorConfig};
use swarmpose_datasets::open;
use swarmpose_vision::frontend::{FrameMatches, Frontend};

#[test]
fn kitti_pairs_recover_the_ground_truth_motion() {
    let Some(dir) = crate::common::dataset("kitti_vo_seq2") else {
        return;
    };
    let seq = open(&dir).expect("open kitti_vo_seq2");
    assert_eq!(seq.layout(), "kitti");
    assert_eq!(seq.len(), 51);
    let frontend = Frontend::orb(seq.calibration());
    let estimator = PsoEstimator::new(PsoEstimatorConfig::default());

    // The front end on every consecutive pair (frame i+1 = src, frame i = dst).
    let mut prev = None;
    let mut pairs: Vec<FrameMatches> = Vec::new();
    for i in 0..seq.len() {
        let pair = seq.frame(i).expect("frame");
        let frame = frontend.stereo_frame(pair.left.view(), pair.right.view());
        if let Some(p) = prev.take() {
            pairs.push(frontend.match_frames(&p, &frame).expect("matches"));
        }
        prev = Some(frame);
    }
    let mut counts: Vec<usize> = pairs.iter().map(|m| m.correspondences.len()).collect();
    counts.sort_unstable();
    assert_eq!(counts.len(), 50);
    assert!(counts[0] >= 300, "fewest correspondences {}", counts[0]);

    // The engine's self-calibrated correction (image data only).
    let correction = crate::common::default_run("kitti_vo_seq2")
        .expect("present")
        .calibration
        .correction;
    let baseline = seq.calibration().baseline_m;

    let (mut good, mut good_uncalibrated) = (0, 0);
    for (k, m0) in pairs.iter().enumerate() {
        let truth = seq.relative_ground_truth(k, k + 1).expect("ground truth");
        let judge = |m: &FrameMatches| {
            let data = m.correspondences_with_covariance().expect("covariances");
            let est = estimator
                .estimate_seeded(&data, k as u64)
                .expect("estimate");
            let (pose, inliers) = (est.transform, est.inliers);
            let d = truth.inverse() * pose;
            let deg = d.rotation.angle().to_degrees();
            let cm = d.translation.vector.norm() * 100.0;
            (deg, cm, inliers.len())
        };
        let (deg0, cm0, _) = judge(m0);
        good_uncalibrated += usize::from(deg0 < 0.2 && cm0 < 5.0);
        let m = m0
            .with_disparity_correction(correction, baseline)
            .expect("correction");
        let (deg, cm, inliers) = judge(&m);
        let ok = deg < 0.2 && cm < 5.0;
        good += usize::from(ok);
        eprintln!(
            "pair {k:2}-{:2}: {:4} correspondences, {inliers:4} inliers, error {deg:.3} deg \
             {cm:5.2} cm{} (as calibrated: {deg0:.3} deg {cm0:5.2} cm)",
            k + 1,
            m.correspondences.len(),
            if ok { "" } else { "  <-- off" },
        );
    }
    eprintln!(
        "correspondences min {} median {}; disparity correction {correction}; within 0.2 deg \
         and 5 cm: {good}/50 (as calibrated: {good_uncalibrated}/50)",
        counts[0], counts[25]
    );
    assert!(good >= 45, "{good} of 50 pairs within 0.2 deg and 5 cm");
}
