//! The default run on the Karlsruhe sequence (112 frames, 94 m, a right turn): after
//! the SE(3) Umeyama alignment of our camera positions onto the rough INS positions (no
//! camera-to-INS extrinsic is given), the ATE RMSE is at most 1.3 % of the path length
//! (issue 12's bar) and the final position error is below the OpenCV PnP peer's 2.22 %
//! (`tools/peers`, measured in RESULTS.md; the peer needs OpenCV, so its figure is
//! recorded here rather than run).

/// The OpenCV PnP peer's final position error on this sequence after the same alignment,
/// percent of the INS path (`python3 tools/peers/compare.py`, RESULTS.md).
const PEER_FINAL_PERCENT: f64 = 2.22;

#[test]
fn karlsruhe_ate_after_alignment() {
    let name = "karlsruhe_2010_03_09_drive_0023";
    let Some(dir) = crate::common::dataset(name) else {
        return;
    };
    let r = crate::common::default_run(name).expect("present");
    let (ate, last) = crate::common::karlsruhe_errors_percent(&dir, &r);
    eprintln!(
        "karlsruhe: correction {} ({}), ATE after alignment {ate:.3} % of the path, final \
         error {last:.3} %, {} untracked frames",
        r.calibration.correction,
        r.calibration.model,
        r.untracked()
    );
    // No bound on the frames held at constant velocity: no peer or model gives one (frames
    // 37-38 hold 9-11 points consistent with one motion, below the 12 required, and are
    // held at constant velocity, visibly); what they cost is in the ATE and the final
    // error, bounded below by issue 12's bar and the peer.
    assert!(ate <= 1.3, "ATE {ate:.3} % > 1.3 %");
    assert!(
        last < PEER_FINAL_PERCENT,
        "final error {last:.3} % >= the peer's {PEER_FINAL_PERCENT} %"
    );
}
