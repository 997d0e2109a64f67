//! The bad-input catalogue of the sequence readers (issue 16), each case built from a few
//! frames of the shared sequences copied to a temp dir and broken one way: the exit
//! status and the first words of the message are asserted. Calibration (keys twice,
//! inconsistent rows, implausible baselines, byte-order marks), frames (gaps, strays,
//! duplicates, unpaired), image depth, and the "not usable" status.

use crate::catalogue::{corr, edit_line, euroc, expect, karlsruhe, kitti, line_of, s};
use crate::common::{TempDir, assert_success, correspondences, swarmpose};

#[test]
fn kitti_calibration_twice_or_inconsistent_is_refused() {
    let tmp = TempDir::new("cat-calib");
    let Some(seq) = kitti(&tmp.0, "dup", 2) else {
        return;
    };
    let calib = seq.join("calib.txt");
    let p1 = std::fs::read_to_string(&calib)
        .expect("calib")
        .lines()
        .nth(1)
        .expect("P1")
        .to_owned();
    // The second P1: (the last one used to win silently: 86 % drift).
    edit_line(
        &calib,
        "",
        "P1: 7.188560000000e+02 0 6.071928000000e+02 -3.0e+02 0 7.188560000000e+02 1.852157000000e+02 0 0 0 1 0",
        true,
    );
    expect(
        &corr(&tmp, &seq, &[]),
        2,
        &format!(
            "swarmpose: error: {}:3: 'P1' is given twice (lines 2 and 3)",
            s(&calib)
        ),
    );
    // P1 with another focal length (37.6 % drift before).
    edit_line(&calib, "P1:", &p1, false);
    let lines: Vec<String> = std::fs::read_to_string(&calib)
        .expect("c")
        .lines()
        .take(2)
        .map(str::to_owned)
        .collect();
    std::fs::write(&calib, lines.join("\n") + "\n").expect("w");
    edit_line(
        &calib,
        "P1:",
        "P1: 500 0 6.071928000000e+02 -268.6 0 500 1.852157000000e+02 0 0 0 1 0",
        false,
    );
    expect(
        &corr(&tmp, &seq, &[]),
        2,
        &format!(
            "swarmpose: error: {}:2: P1 fx = 500 differs from P0 fx = 718.856",
            s(&calib)
        ),
    );
    // A baseline of 1.4e-12 m (683 rows of 1e-10 m points before).
    edit_line(
        &calib,
        "P1:",
        "P1: 7.188560000000e+02 0 6.071928000000e+02 -1.0063984e-9 0 7.188560000000e+02 1.852157000000e+02 0 0 0 1 0",
        false,
    );
    expect(
        &corr(&tmp, &seq, &[]),
        2,
        &format!(
            "swarmpose: error: {}:2: P1[0][3] = -1.0063984e-9 gives a baseline of 1.400e-12 m, outside",
            s(&calib)
        ),
    );
    // A baseline of 54 km: refused too.
    edit_line(
        &calib,
        "P1:",
        "P1: 7.188560000000e+02 0 6.071928000000e+02 -3.861448e7 0 7.188560000000e+02 1.852157000000e+02 0 0 0 1 0",
        false,
    );
    expect(
        &corr(&tmp, &seq, &[]),
        2,
        &format!("swarmpose: error: {}:2: P1[0][3]", s(&calib)),
    );
    // An unnamed third row beside named ones, and a key twice that is not P0/P1.
    edit_line(&calib, "P1:", &p1, false);
    edit_line(&calib, "", "Tr: 1 0 0 0 0 1 0 0 0 0 1 0", true);
    edit_line(&calib, "", "Tr: 1 0 0 0 0 1 0 0 0 0 1 0", true);
    expect(
        &corr(&tmp, &seq, &[]),
        2,
        &format!(
            "swarmpose: error: {}:4: 'Tr' is given twice (lines 3 and 4)",
            s(&calib)
        ),
    );
}

#[test]
fn a_byte_order_mark_is_accepted() {
    let tmp = TempDir::new("cat-bom");
    let Some(seq) = kitti(&tmp.0, "bom", 2) else {
        return;
    };
    let calib = seq.join("calib.txt");
    let text = std::fs::read_to_string(&calib).expect("calib");
    std::fs::write(&calib, format!("\u{feff}{text}")).expect("bom");
    let out = corr(&tmp, &seq, &[]);
    assert_success(&out);
}

#[test]
fn kitti_frames_are_what_they_are_named() {
    let tmp = TempDir::new("cat-frames");
    let Some(seq) = kitti(&tmp.0, "gap", 8) else {
        return;
    };
    // Frame 6 removed from both folders: named, not renumbered.
    for side in ["image_0", "image_1"] {
        std::fs::remove_file(seq.join(side).join("000006.png")).expect("rm");
    }
    let gap = seq.join("image_0/000006.png");
    expect(
        &corr(&tmp, &seq, &[]),
        2,
        &format!(
            "swarmpose: error: {}: missing: frame 7 comes after frame 5",
            s(&gap)
        ),
    );
    let out = swarmpose(
        &["odometry", s(&seq), "--out", s(&tmp.0.join("o")), "--quiet"],
        None,
    );
    expect(&out, 2, &format!("swarmpose: error: {}: missing", s(&gap)));
    assert!(!tmp.0.join("o").exists(), "nothing written on bad input");
    // A stray copy beside the frames.
    let seq = kitti(&tmp.0, "stray", 4).expect("data");
    std::fs::copy(
        seq.join("image_0/000003.png"),
        seq.join("image_0/000003_copy.png"),
    )
    .expect("cp");
    expect(
        &corr(&tmp, &seq, &[]),
        2,
        &format!(
            "swarmpose: error: {}: not a frame image",
            s(&seq.join("image_0/000003_copy.png"))
        ),
    );
    // The same number twice.
    let seq = kitti(&tmp.0, "twice", 4).expect("data");
    std::fs::copy(seq.join("image_0/000003.png"), seq.join("image_0/0003.png")).expect("cp");
    expect(&corr(&tmp, &seq, &[]), 2, "swarmpose: error: ");
    let e = String::from_utf8_lossy(&corr(&tmp, &seq, &[]).stderr).into_owned();
    assert!(e.contains("frame number 3 again"), "{e}");
    // A right image missing: the first frame on one side only is named.
    let seq = kitti(&tmp.0, "unpaired", 6).expect("data");
    std::fs::remove_file(seq.join("image_1/000004.png")).expect("rm");
    std::fs::remove_file(seq.join("image_1/000005.png")).expect("rm");
    expect(
        &corr(&tmp, &seq, &[]),
        2,
        &format!(
            "swarmpose: error: {}: frame 4 has no partner in {} (6 left and 4 right frames)",
            s(&seq.join("image_0/000004.png")),
            s(&seq.join("image_1"))
        ),
    );
}

#[test]
fn twelve_bit_data_in_16_bit_pngs_is_scaled_by_its_depth() {
    let tmp = TempDir::new("cat-depth");
    let Some(seq) = kitti(&tmp.0, "deep", 2) else {
        return;
    };
    let eight = corr(&tmp, &seq, &["--no-covariance"]);
    assert_eq!(eight.status.code(), Some(0));
    let rows8 = std::fs::read_to_string(tmp.0.join("c.csv"))
        .expect("csv")
        .lines()
        .count();
    for side in ["image_0", "image_1"] {
        for i in 0..2 {
            let p = seq.join(side).join(format!("{i:06}.png"));
            let img = image::open(&p).expect("png").into_luma8();
            let wide: Vec<u8> = img
                .as_raw()
                .iter()
                .flat_map(|&v| (u16::from(v) * 16).to_be_bytes())
                .collect();
            let buf = image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_raw(
                img.width(),
                img.height(),
                wide.chunks(2)
                    .map(|b| u16::from_be_bytes([b[0], b[1]]))
                    .collect(),
            )
            .expect("buffer");
            buf.save(&p).expect("save 16-bit");
        }
    }
    let out = corr(&tmp, &seq, &["--no-covariance"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.starts_with(&format!(
            "swarmpose: warning: {}: a 16-bit PNG whose values all fit in 12 bits",
            s(&seq.join("image_0/000000.png"))
        )),
        "{stderr}"
    );
    // Scaled by 4095 the images are the 8-bit ones to within 0.4 %: about as many
    // correspondences (scaled by 65535 they were near-black and gave none).
    let rows16 = std::fs::read_to_string(tmp.0.join("c.csv"))
        .expect("csv")
        .lines()
        .count();
    assert!(
        rows16 * 10 >= rows8 * 9,
        "{rows16} rows vs {rows8} from the 8-bit images"
    );
}

#[test]
fn correspondences_with_no_row_and_a_report_of_another_csv() {
    let tmp = TempDir::new("cat-corr");
    let Some(seq) = kitti(&tmp.0, "black", 4) else {
        return;
    };
    // The report of frames 0-1 does not belong to frames 2-3: refused before writing.
    let c01 = tmp.0.join("c01.csv");
    let out = correspondences(&seq, ("0", "1"), &c01, &[]);
    assert_eq!(out.status.code(), Some(0));
    let report = swarmpose(&["register", s(&c01), "--method", "svd"], None);
    assert_eq!(report.status.code(), Some(0));
    let r01 = tmp.0.join("r01.json");
    std::fs::write(&r01, &report.stdout).expect("report");
    let png = tmp.0.join("draw/m.png");
    let drawn = ["--draw", s(&png), "--inliers", s(&r01)];
    let good = correspondences(&seq, ("0", "1"), &c01, &drawn);
    assert_success(&good);
    assert!(png.is_file(), "the drawing's folder is created");
    let c23 = tmp.0.join("c23.csv");
    let out = correspondences(&seq, ("2", "3"), &c23, &drawn);
    expect(&out, 2, &format!("swarmpose: error: {}: ", s(&r01)));
    assert!(String::from_utf8_lossy(&out.stderr).contains("another CSV"));
    assert!(!c23.exists(), "nothing written");
    // All-black frames: 0 correspondences is "not usable" (exit 3), the CSV has its header.
    for side in ["image_0", "image_1"] {
        for i in 0..4 {
            let p = seq.join(side).join(format!("{i:06}.png"));
            let (w, h) = image::image_dimensions(&p).expect("size");
            image::GrayImage::new(w, h).save(&p).expect("black");
        }
    }
    let out = corr(&tmp, &seq, &[]);
    expect(
        &out,
        3,
        "swarmpose: error: not usable: no correspondence between frames 0 and 1",
    );
    assert_eq!(
        std::fs::read_to_string(tmp.0.join("c.csv"))
            .expect("csv")
            .lines()
            .count(),
        1
    );
}

#[test]
fn euroc_lists_and_sensor_files() {
    let tmp = TempDir::new("cat-euroc");
    let Some(seq) = euroc(&tmp.0, "ok", 6) else {
        return;
    };
    let out = corr(&tmp, &seq, &["--no-covariance"]);
    assert_success(&out);
    let cam0 = seq.join("mav0/cam0");
    let cam1 = seq.join("mav0/cam1");
    // A byte-order mark in sensor.yaml is accepted.
    let yaml = cam0.join("sensor.yaml");
    let text = std::fs::read_to_string(&yaml).expect("yaml");
    std::fs::write(&yaml, format!("\u{feff}{text}")).expect("bom");
    assert_eq!(
        corr(&tmp, &seq, &["--no-covariance"]).status.code(),
        Some(0)
    );
    // A key given twice.
    std::fs::write(
        &yaml,
        format!("{text}intrinsics: [400.0, 400.0, 360.0, 240.0]\n"),
    )
    .expect("dup");
    let first = line_of(&yaml, "intrinsics:");
    let second = text.lines().count() + 1;
    expect(
        &corr(&tmp, &seq, &[]),
        2,
        &format!(
            "swarmpose: error: {}:{second}: 'intrinsics' is given twice (lines {first} and {second})",
            s(&yaml)
        ),
    );
    std::fs::write(&yaml, &text).expect("restore");
    // A row missing from cam1's list: the first frame on one side only is named.
    let list1 = std::fs::read_to_string(cam1.join("data.csv")).expect("list");
    let rows: Vec<&str> = list1.lines().collect();
    let dropped: Vec<&str> = rows
        .iter()
        .enumerate()
        .filter(|(k, _)| *k != 3)
        .map(|x| *x.1)
        .collect();
    std::fs::write(cam1.join("data.csv"), dropped.join("\n") + "\n").expect("w");
    let ts = rows[3].split(',').next().expect("ts");
    expect(
        &corr(&tmp, &seq, &[]),
        2,
        &format!(
            "swarmpose: error: {}: frame {ts} has no partner in {}",
            s(&cam0.join("data").join(format!("{ts}.png"))),
            s(&cam1.join("data.csv"))
        ),
    );
    // The same row missing from both: a gap in the timestamps, refused (never renumbered).
    let list0 = std::fs::read_to_string(cam0.join("data.csv")).expect("list");
    let dropped0: Vec<&str> = list0
        .lines()
        .enumerate()
        .filter(|(k, _)| *k != 3)
        .map(|x| x.1)
        .collect();
    std::fs::write(cam0.join("data.csv"), dropped0.join("\n") + "\n").expect("w");
    expect(
        &corr(&tmp, &seq, &[]),
        2,
        &format!("swarmpose: error: {}: row 3 (", s(&cam0.join("data.csv"))),
    );
}

#[test]
fn karlsruhe_calibration_twice_or_inconsistent_is_refused() {
    let tmp = TempDir::new("cat-karlsruhe");
    let Some(seq) = karlsruhe(&tmp.0, "k", 2) else {
        return;
    };
    let calib = seq.join("calib.txt");
    let p2 = line_of(&calib, "P2_roi:");
    let n = std::fs::read_to_string(&calib).expect("c").lines().count();
    edit_line(
        &calib,
        "",
        "P2_roi: 6.452401e+02 0 6.359587e+02 -3.682632e+02 0 6.452401e+02 1.941291e+02 0 0 0 1 0",
        true,
    );
    expect(
        &corr(&tmp, &seq, &[]),
        2,
        &format!(
            "swarmpose: error: {}:{}: 'P2_roi' is given twice (lines {p2} and {})",
            s(&calib),
            n + 1,
            n + 1
        ),
    );
    let seq = karlsruhe(&tmp.0, "k2", 2).expect("data");
    let calib = seq.join("calib.txt");
    edit_line(
        &calib,
        "P2_roi:",
        "P2_roi: 5.0e+02 0 6.359587e+02 -2.85e+02 0 5.0e+02 1.941291e+02 0 0 0 1 0",
        false,
    );
    expect(
        &corr(&tmp, &seq, &[]),
        2,
        &format!(
            "swarmpose: error: {}:{p2}: P2_roi fx = 500 differs from P1_roi fx = 645.2401",
            s(&calib)
        ),
    );
}
