//! Calibrations read in full (issue 29, cause 2): projection rows that both carry an
//! offset, as KITTI's colour cameras' `P2`/`P3` do, give the same rig and the same
//! trajectory as the equivalent grey rows; a skew, a rotated camera and a baseline off
//! the rows' axis are refused naming the entry.

use std::path::Path;

use crate::catalogue::{expect, kitti, s, succeeded};
use crate::common::{TempDir, swarmpose};

/// KITTI 00-02's camera matrix.
const FX: f64 = 718.856;
const CX: f64 = 607.1928;
const CY: f64 = 185.2157;

/// The `calib.txt` row of the camera `K [I | t]` (`t` metres, in the rectified frame).
fn row(name: &str, t: [f64; 3]) -> String {
    let [tx, ty, tz] = t;
    format!(
        "{name}: {FX:e} 0 {CX:e} {:.12e} 0 {FX:e} {CY:e} {:.12e} 0 0 1 {:.12e}",
        FX * tx + CX * tz,
        FX * ty + CY * tz,
        tz
    )
}

/// Runs `odometry` on `seq` into `out`; returns the KITTI trajectory's numbers.
fn trajectory(seq: &Path, out: &Path) -> Vec<f64> {
    let run = swarmpose(&["odometry", s(seq), "--out", s(out), "--quiet"], None);
    succeeded(&run);
    std::fs::read_to_string(out.join("trajectory.kitti.txt"))
        .expect("trajectory")
        .split_whitespace()
        .map(|v| v.parse().expect("number"))
        .collect()
}

/// Checks that `correspondences` on `seq` is refused (status 2) with the one line
/// `FILE: message` (`file` and its line, if any, joined by the caller).
fn refused(tmp: &TempDir, seq: &Path, file: &str, message: &str) {
    let out = crate::catalogue::corr(tmp, seq, &[]);
    expect(&out, 2, &format!("swarmpose: error: {file}: {message}"));
}

#[test]
fn colour_camera_rows_give_the_grey_rows_trajectory() {
    let tmp = TempDir::new("calib-colour");
    let Some(seq) = kitti(&tmp.0, "k", 6) else {
        return;
    };
    let calib = seq.join("calib.txt");
    let grey = std::fs::read_to_string(&calib).expect("calib");
    let p1_tx: f64 = grey
        .lines()
        .find_map(|l| l.strip_prefix("P1:"))
        .and_then(|r| r.split_whitespace().nth(3)?.parse().ok())
        .expect("P1[0][3]");
    let baseline = -p1_tx / FX;
    let grey_run = trajectory(&seq, &tmp.0.join("grey"));
    // The same rig as KITTI writes its colour cameras: the left camera 6 cm from the
    // reference and both rows with second- and third-row terms (t of KITTI's P2).
    let left = [0.059_939, -0.001_131, 0.003_780];
    let right = [left[0] - baseline, left[1], left[2]];
    std::fs::write(
        &calib,
        format!("{}\n{}\n", row("P0", left), row("P1", right)),
    )
    .expect("write");
    let colour_run = trajectory(&seq, &tmp.0.join("colour"));
    assert_eq!(grey_run.len(), 6 * 12);
    let worst = grey_run
        .iter()
        .zip(&colour_run)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    // Before, the left row's offset was ignored: a baseline of 0.477 m for 0.537 m, the
    // path 11 % short.
    assert!(worst < 1e-6, "largest difference {worst}");
}

#[test]
fn rows_the_rectified_model_cannot_represent_are_refused() {
    let tmp = TempDir::new("calib-refused");
    let Some(seq) = kitti(&tmp.0, "k", 2) else {
        return;
    };
    let calib = seq.join("calib.txt");
    let p0 = row("P0", [0.0; 3]);
    let cases = [
        // A skew in the right row.
        (
            row("P1", [-0.54, 0.0, 0.0]).replacen(" 0 ", " 2.5 ", 1),
            "P1[0][1] = 2.5 is a skew",
        ),
        // A right camera 3 cm higher than the left one (5.6 % of the baseline).
        (
            row("P1", [-0.54, 0.03, 0.0]),
            "the P1 camera is 0.0300 m above the P0 camera besides its baseline of 0.5400 m (5.56 % of it)",
        ),
    ];
    for (p1, message) in cases {
        std::fs::write(&calib, format!("{p0}\n{p1}\n")).expect("write");
        refused(&tmp, &seq, &format!("{}:2", s(&calib)), message);
    }
}

/// Issue 29, cause 3: numbers that are no camera for the images are refused by every
/// loader, naming the file (before, each ran with exit 0 on points in the wrong place).
#[test]
fn implausible_intrinsics_are_refused_by_every_loader() {
    let tmp = TempDir::new("calib-plausible");
    if let Some(seq) = kitti(&tmp.0, "k", 2) {
        // A principal point with its decimal point one place off.
        let calib = seq.join("calib.txt");
        let p1 = row("P1", [-0.537, 0.0, 0.0]).replace(&format!("{CX:e}"), "6.071928e3");
        let p0 = row("P0", [0.0; 3]).replace(&format!("{CX:e}"), "6.071928e3");
        std::fs::write(&calib, format!("{p0}\n{p1}\n")).expect("write");
        refused(
            &tmp,
            &seq,
            s(&calib),
            "cx = 6071.928 px is outside the 1241x376 image",
        );
    }
    if let Some(seq) = crate::catalogue::karlsruhe(&tmp.0, "ka", 2) {
        // The principal point of the uncropped images (cy 194.1 of the crop, typed 1941).
        let calib = seq.join("calib.txt");
        let text = std::fs::read_to_string(&calib).expect("calib");
        std::fs::write(&calib, text.replace("1.941291e+02", "1.941291e+03")).expect("write");
        refused(
            &tmp,
            &seq,
            s(&calib),
            "cy = 1941.291 px is outside the 1344x372 image",
        );
    }
    if let Some(seq) = crate::catalogue::euroc(&tmp.0, "e", 3) {
        // fv a tenth of fu.
        let yaml = seq.join("mav0/cam0/sensor.yaml");
        crate::catalogue::edit_line(
            &yaml,
            "intrinsics:",
            "intrinsics: [458.654, 45.7296, 367.215, 248.375]",
            false,
        );
        refused(&tmp, &seq, s(&yaml), "fx / fy = 10.030");
    }
}
