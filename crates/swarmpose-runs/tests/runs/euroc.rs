//! The default run on the EuRoC clip where the MAV sits still (ground-truth motion at
//! most 2.6 mm): every estimated position stays within 3 mm of the start, and each frame
//! carries the time the sequence records for it (20 Hz), not an assumed frame period.

#[test]
fn euroc_still_clip_stays_at_its_start() {
    let Some(r) = crate::common::default_run("euroc_v1_01_easy_micro") else {
        return;
    };
    let far = r
        .poses()
        .iter()
        .map(|p| p.translation.vector.norm())
        .fold(0.0f64, f64::max);
    let angle = r
        .poses()
        .iter()
        .map(|p| p.rotation.angle().to_degrees())
        .fold(0.0f64, f64::max);
    eprintln!(
        "euroc still clip: {} frames, farthest from the start {:.2} mm, largest rotation \
         {angle:.3} deg, {} untracked frames, correction {} ({})",
        r.results.len(),
        far * 1e3,
        r.untracked(),
        r.calibration.correction,
        r.calibration.model
    );
    assert_eq!(r.results.len(), 30);
    assert_eq!(r.untracked(), 0);
    for (k, f) in r.results.iter().enumerate() {
        let expected = k as f64 * 0.05;
        assert!(
            (f.timestamp_s - expected).abs() < 2e-3,
            "frame {k} at {} s, not {expected} s",
            f.timestamp_s
        );
    }
    assert!(far <= 0.003, "{:.2} mm from the start", far * 1e3);
}
