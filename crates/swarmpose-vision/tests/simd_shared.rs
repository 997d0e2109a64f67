//! The front end's vector kernels against their baseline compilation
//! ([`swarmpose_vision::simd::baseline`]) on the shared real sequences (issue 34: "SIMD and
//! scalar paths give identical features on every shared sequence"): ORB features (FAST,
//! Harris ranking, bucketing, orientation, blur, steered BRIEF) on every image of
//! kitti_vo_seq2 (both cameras), every 5th of the Karlsruhe sequence and every 3rd of the
//! EuRoC clip (both cameras); stereo and temporal matching on every 5th KITTI pair. The
//! random images are in the crate's own tests (`src/simd/tests.rs`). A sequence that is
//! absent is skipped with a message (a failure under `CI=true`).

use std::path::{Path, PathBuf};

use swarmpose_vision::features::{FeatureExtractor, Features, GrayView};
use swarmpose_vision::image::GrayImage;
use swarmpose_vision::orb::OrbExtractor;
use swarmpose_vision::simd::baseline;
use swarmpose_vision::stereo::{RectifiedStereo, StereoConfig, match_stereo};
use swarmpose_vision::temporal::{TemporalConfig, mutual_matches};

/// The PNG files of `dir`, sorted, every `step`-th.
fn pngs(dir: &Path, step: usize) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "png"))
        .collect();
    files.sort();
    files.into_iter().step_by(step).collect()
}

fn load(path: &Path) -> GrayImage {
    GrayImage::load_png(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The ORB features of `img`, dispatched and baseline; asserts they are equal and that
/// there are some (the comparison compares something).
fn same_features(
    orb: &OrbExtractor,
    img: &GrayImage,
    what: &Path,
) -> Features<swarmpose_vision::features::BinaryDescriptor> {
    let run = || orb.extract(img.view());
    let fast = run();
    let base = baseline(run);
    assert!(
        fast.len() > 50,
        "{}: {} features",
        what.display(),
        fast.len()
    );
    assert!(
        fast == base,
        "{}: the dispatched and baseline features differ",
        what.display()
    );
    fast
}

/// Every image of the folders `dirs` of the sequence `name`, every `step`-th.
fn features_of(name: &str, dirs: &[&str], step: usize) -> usize {
    let Some(root) = swarmpose_testdata::dataset_for_test(name) else {
        return 0;
    };
    let orb = OrbExtractor::default();
    let mut n = 0;
    for dir in dirs {
        let files = pngs(&root.join(dir), step);
        assert!(!files.is_empty(), "{name}/{dir}: no PNG");
        for f in &files {
            same_features(&orb, &load(f), f);
            n += 1;
        }
    }
    n
}

#[test]
fn kitti_features_are_the_same() {
    let n = features_of("kitti_vo_seq2", &["image_0", "image_1"], 1);
    assert!(n == 0 || n == 102, "{n} images");
}

#[test]
fn karlsruhe_features_are_the_same() {
    features_of(
        "karlsruhe_2010_03_09_drive_0023",
        &["2010_03_09_drive_0023_Images"],
        5,
    );
}

#[test]
fn euroc_features_are_the_same() {
    features_of(
        "euroc_v1_01_easy_micro",
        &["mav0/cam0/data", "mav0/cam1/data"],
        3,
    );
}

/// Stereo matching (left and right of a pair) and temporal matching (left of a pair
/// and of the next), dispatched and baseline, on every 5th KITTI pair.
#[test]
fn kitti_matching_is_the_same() {
    let Some(root) = swarmpose_testdata::dataset_for_test("kitti_vo_seq2") else {
        return;
    };
    let (lefts, rights) = (
        pngs(&root.join("image_0"), 5),
        pngs(&root.join("image_1"), 5),
    );
    assert_eq!(lefts.len(), rights.len());
    let orb = OrbExtractor::default();
    // KITTI odometry sequences 00-02's rectified camera (calib.txt, P0 and P1).
    let rig = RectifiedStereo {
        fx: 718.856,
        fy: 718.856,
        cx: 607.1928,
        cy: 185.2157,
        baseline_m: 0.537_150_6,
    };
    let config = StereoConfig::default();
    let mut previous: Option<Features<_>> = None;
    for (l, r) in lefts.iter().zip(&rights) {
        let (li, ri) = (load(l), load(r));
        let (fl, fr) = (same_features(&orb, &li, l), same_features(&orb, &ri, r));
        let (lv, rv): (GrayView<'_>, GrayView<'_>) = (li.view(), ri.view());
        let stereo = || match_stereo(&fl, &fr, lv, rv, &rig, &config);
        let s = stereo();
        assert!(s.len() > 50, "{}: {} stereo matches", l.display(), s.len());
        // Compared as printed (exact for floats): unmeasured row offsets are NaN.
        assert_eq!(
            format!("{s:?}"),
            format!("{:?}", baseline(stereo)),
            "{}",
            l.display()
        );
        if let Some(p) = &previous {
            let temporal = || {
                mutual_matches(
                    &p.keypoints,
                    &p.descriptors,
                    &fl.keypoints,
                    &fl.descriptors,
                    &TemporalConfig::default(),
                )
            };
            let t = temporal();
            assert!(
                t.len() > 50,
                "{}: {} temporal matches",
                l.display(),
                t.len()
            );
            assert_eq!(t, baseline(temporal), "{}", l.display());
        }
        previous = Some(fl);
    }
}
