//! Broken sequences give one clear error naming the file at fault: missing images, a
//! left/right count mismatch, images of different sizes, a malformed calibration line,
//! an unreadable PNG.

use std::path::{Path, PathBuf};

use swarmpose_datasets::{GrayImage, open};

/// A temporary KITTI-layout sequence, removed on drop.
struct Kitti(PathBuf);

impl Kitti {
    fn new(tag: &str, frames: usize) -> Self {
        let dir =
            std::env::temp_dir().join(format!("swarmpose-datasets-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        for side in ["image_0", "image_1"] {
            std::fs::create_dir_all(dir.join(side)).expect("mkdir");
            for i in 0..frames {
                write_png(&dir.join(side).join(format!("{i:06}.png")), 40, 30);
            }
        }
        std::fs::write(
            dir.join("calib.txt"),
            "P0: 700 0 20 0 0 700 15 0 0 0 1 0\nP1: 700 0 20 -350 0 700 15 0 0 0 1 0\n",
        )
        .expect("calib");
        Self(dir)
    }

    fn path(&self, rel: &str) -> PathBuf {
        self.0.join(rel)
    }
}

impl Drop for Kitti {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn write_png(path: &Path, w: usize, h: usize) {
    let data = (0..w * h).map(|i| (i * 7 % 251) as u8).collect();
    GrayImage::from_raw(w, h, data)
        .expect("size")
        .save_png(path)
        .expect("png");
}

/// The error message of opening `dir` and loading every frame.
fn error_of(dir: &Path) -> String {
    match open(dir) {
        Err(e) => e.to_string(),
        Ok(seq) => (0..seq.len())
            .find_map(|i| seq.frame(i).err())
            .map(|e| e.to_string())
            .unwrap_or_default(),
    }
}

#[test]
fn a_good_sequence_loads() {
    let k = Kitti::new("good", 2);
    let seq = open(&k.0).expect("open");
    assert_eq!((seq.layout(), seq.len()), ("kitti", 2));
    let c = seq.calibration();
    assert!((c.baseline_m - 0.5).abs() < 1e-12 && c.fx == 700.0 && c.cy == 15.0);
    assert!(seq.ground_truth().is_none());
    assert_eq!(seq.frame(1).expect("frame").left.width, 40);
    let e = seq.frame(2).expect_err("out of range").to_string();
    assert!(e.contains("frame 2 out of range"), "{e}");
}

#[test]
fn missing_images_name_the_directory() {
    let k = Kitti::new("missing", 0);
    let e = error_of(&k.0);
    assert!(
        e.contains("no stereo frames") && e.contains(&*k.0.to_string_lossy()),
        "{e}"
    );
    let k = Kitti::new("missing-file", 2);
    std::fs::remove_file(k.path("image_1/000001.png")).expect("rm");
    write_png(&k.path("image_1/000009.png"), 40, 30);
    let e = error_of(&k.0);
    assert!(
        e.contains("image_1/000001.png") && e.contains("missing"),
        "{e}"
    );
}

#[test]
fn a_count_mismatch_names_the_first_frame_on_one_side_only() {
    let k = Kitti::new("count", 3);
    std::fs::remove_file(k.path("image_1/000002.png")).expect("rm");
    let e = error_of(&k.0);
    assert!(
        e.contains("image_0/000002.png: frame 2 has no partner in")
            && e.contains("image_1 (3 left and 2 right frames)"),
        "{e}"
    );
}

#[test]
fn frames_are_what_they_are_named() {
    // A frame missing from both folders: the gap is named, not renumbered.
    let k = Kitti::new("gap", 8);
    for side in ["image_0", "image_1"] {
        std::fs::remove_file(k.path(&format!("{side}/000006.png"))).expect("rm");
    }
    let e = error_of(&k.0);
    assert!(
        e.contains("image_0/000006.png: missing: frame 7 comes after frame 5"),
        "{e}"
    );
    // A stray copy is not a frame.
    let k = Kitti::new("stray", 4);
    write_png(&k.path("image_0/000003_copy.png"), 40, 30);
    let e = error_of(&k.0);
    assert!(
        e.contains("image_0/000003_copy.png: not a frame image"),
        "{e}"
    );
    // The same number twice.
    let k = Kitti::new("dup", 4);
    write_png(&k.path("image_0/0003.png"), 40, 30);
    let e = error_of(&k.0);
    assert!(e.contains("frame number 3 again"), "{e}");
}

#[test]
fn an_inconsistent_calibration_is_refused() {
    let k = Kitti::new("calib-dup", 1);
    let p0 = "P0: 700 0 20 0 0 700 15 0 0 0 1 0";
    let p1 = "P1: 700 0 20 -350 0 700 15 0 0 0 1 0";
    std::fs::write(k.path("calib.txt"), format!("{p0}\n{p1}\n{p1}\n")).expect("calib");
    let e = error_of(&k.0);
    assert!(
        e.contains("calib.txt:3: 'P1' is given twice (lines 2 and 3)"),
        "{e}"
    );
    std::fs::write(
        k.path("calib.txt"),
        format!("{p0}\nP1: 500 0 20 -250 0 500 15 0 0 0 1 0\n"),
    )
    .expect("calib");
    let e = error_of(&k.0);
    assert!(
        e.contains("calib.txt:2: P1 fx = 500 differs from P0 fx = 700"),
        "{e}"
    );
    std::fs::write(
        k.path("calib.txt"),
        format!("{p0}\nP1: 700 0 20 -9.8e-10 0 700 15 0 0 0 1 0\n"),
    )
    .expect("calib");
    let e = error_of(&k.0);
    assert!(
        e.contains("calib.txt:2: P1[0][3] = -9.8e-10 gives a baseline of 1.400e-12 m"),
        "{e}"
    );
    // A byte-order mark is accepted.
    std::fs::write(k.path("calib.txt"), format!("\u{feff}{p0}\n{p1}\n")).expect("calib");
    assert!(open(&k.0).is_ok());
}

#[test]
fn images_of_different_sizes_name_the_files() {
    let k = Kitti::new("size", 2);
    write_png(&k.path("image_1/000001.png"), 41, 30);
    let e = error_of(&k.0);
    assert!(
        e.contains("size mismatch") && e.contains("image_1/000001.png") && e.contains("41x30"),
        "{e}"
    );
    let k = Kitti::new("size2", 2);
    write_png(&k.path("image_0/000001.png"), 40, 31);
    write_png(&k.path("image_1/000001.png"), 40, 31);
    let e = error_of(&k.0);
    assert!(
        e.contains("image_0/000001.png") && e.contains("40x31"),
        "{e}"
    );
}

#[test]
fn a_malformed_calibration_line_is_named() {
    let k = Kitti::new("calib", 1);
    std::fs::write(
        k.path("calib.txt"),
        "P0: 700 0 20 0 0 700 15 0 0 0 1 0\nP1: 700 0 20 -350 0 x 15 0 0 0 1 0\n",
    )
    .expect("calib");
    let e = error_of(&k.0);
    assert!(e.contains("calib.txt:2") && e.contains("'x'"), "{e}");
    std::fs::write(k.path("calib.txt"), "P0: 700 0 20 0\nP1: 1 2\n").expect("calib");
    let e = error_of(&k.0);
    assert!(e.contains("calib.txt:1") && e.contains("12 numbers"), "{e}");
    std::fs::remove_file(k.path("calib.txt")).expect("rm");
    let e = error_of(&k.0);
    assert!(e.contains("calib.txt") && e.contains("missing"), "{e}");
}

#[test]
fn an_unreadable_png_is_named() {
    let k = Kitti::new("png", 2);
    std::fs::write(k.path("image_1/000001.png"), b"\x89PNG\r\n\x1a\nbroken").expect("write");
    let e = error_of(&k.0);
    assert!(e.contains("image_1/000001.png") && e.contains("PNG"), "{e}");
}

#[test]
fn an_unknown_layout_says_what_was_expected() {
    let k = Kitti::new("layout", 1);
    let e = error_of(&k.path("image_0"));
    assert!(e.contains("unknown sequence layout"), "{e}");
}

#[test]
fn a_ground_truth_pose_that_is_not_a_rotation_is_named() {
    let dir = std::env::temp_dir().join(format!("swarmpose-poses-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("poses.txt");
    std::fs::write(&path, "1 0 0 0 0 1 0 0 0 0 1 0\n0 0 0 1 0 0 0 2 0 0 0 3\n").expect("write");
    let err = swarmpose_datasets::kitti::read_poses(&path).expect_err("not a rotation");
    let text = err.to_string();
    assert!(
        text.contains("poses.txt") && text.contains(":2") && text.contains("not a rotation"),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_problem_of_the_whole_file_names_no_line() {
    // These were "FILE:0: ...", a line that does not exist.
    let k = Kitti::new("whole", 3);
    std::fs::write(k.path("calib.txt"), "P0: 700 0 20 0 0 700 15 0 0 0 1 0\n").expect("calib");
    let e = error_of(&k.0);
    let calib = k.path("calib.txt");
    assert!(
        e.starts_with(&format!("{}: needs the P0: and P1:", calib.display())),
        "{e}"
    );
    let k = Kitti::new("whole-poses", 3);
    std::fs::write(k.path("poses.txt"), "1 0 0 0 0 1 0 0 0 0 1 0\n").expect("poses");
    let e = error_of(&k.0);
    let poses = k.path("poses.txt");
    assert_eq!(e, format!("{}: 1 poses for 3 frames", poses.display()));
}
