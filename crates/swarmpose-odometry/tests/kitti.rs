//! The default run on kitti_vo_seq2 (51 frames, 52 m): final drift at most 2 % of the
//! path length, RMS of eq. (20) at most 0.01.

mod common;

#[test]
fn kitti_vo_seq2_drift_and_rotation_error() {
    let Some(r) = common::default_run("kitti_vo_seq2") else {
        return;
    };
    let e = common::evaluate_run("kitti_vo_seq2", &r);
    for f in &r.frames {
        eprintln!(
            "frame {:2}: {:4} matches {:4} inliers {} {:.1} ms",
            f.frame,
            f.n_matches,
            f.n_inliers,
            f.status.text(),
            f.times.total_ms()
        );
    }
    let drift = e.final_drift_percent.expect("a 52 m path");
    eprintln!(
        "kitti_vo_seq2: offset {:.3} px, path {:.2} m, final drift {:.3} m = {drift:.3} %, \
         RMS eq. (20) {:.5}, ATE aligned {:.3} m, RPE {:.4} m / {:.4} deg, fallbacks {}",
        r.disparity_offset_px,
        e.path_length_m,
        e.final_drift_m,
        e.eq20_rms,
        e.ate_aligned.rmse,
        e.rpe_translation.rmse,
        e.rpe_rotation_deg.rmse,
        r.n_fallbacks()
    );
    assert_eq!(r.poses.len(), 51);
    assert!(drift <= 2.0, "final drift {drift:.3} % > 2 %");
    assert!(e.eq20_rms <= 0.01, "RMS eq. (20) {:.5} > 0.01", e.eq20_rms);
}
