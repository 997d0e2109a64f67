//! Every dispatched kernel against its baseline compilation, on random images: the
//! results must be identical (the same corners, scores, descriptors, matches and
//! disparities, bit for bit).

use proptest::prelude::*;

use super::baseline;
use crate::features::{FeatureExtractor, GrayView};
use crate::image::blur5;
use crate::orb::fast::{FastScratch, fast9};
use crate::orb::{OrbConfig, OrbExtractor};
use crate::stereo::{RectifiedStereo, StereoConfig, match_stereo};
use crate::temporal::{TemporalConfig, mutual_matches};

/// A random image `w` x `h`: blocks of `cell` pixels of random gray levels plus noise of
/// amplitude `noise`, from `seed` (an LCG: the same image on every platform).
fn image(w: usize, h: usize, cell: usize, noise: u8, seed: u64) -> Vec<u8> {
    let mut s = seed | 1;
    let mut next = move || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (s >> 56) as u8
    };
    let (cw, ch) = (w / cell + 1, h / cell + 1);
    let cells: Vec<u8> = (0..cw * ch).map(|_| next()).collect();
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let n = if noise == 0 { 0 } else { next() % noise };
            cells[(y / cell) * cw + x / cell].saturating_add(n)
        })
        .collect()
}

/// The same image shifted `dx` pixels to the left (a stereo partner), the last columns
/// repeated.
fn shifted(data: &[u8], w: usize, dx: usize) -> Vec<u8> {
    data.chunks_exact(w)
        .flat_map(|row| (0..w).map(move |x| row[(x + dx).min(w - 1)]))
        .collect()
}

fn view(data: &[u8], w: usize) -> GrayView<'_> {
    GrayView {
        width: w,
        height: data.len() / w,
        data,
    }
}

/// Sizes, texture and seed of a random image.
fn images() -> impl Strategy<Value = (usize, usize, usize, u8, u64)> {
    (8usize..140, 8usize..100, 1usize..8, 0u8..80, any::<u64>())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn fast9_is_the_same((w, h, cell, noise, seed) in images(), t in 1u8..80, border in 0usize..20) {
        let data = image(w, h, cell, noise, seed);
        let run = || {
            let (mut s, mut out) = (FastScratch::default(), Vec::new());
            fast9(view(&data, w), t, border, &mut s, &mut out);
            out
        };
        prop_assert_eq!(run(), baseline(run));
    }

    #[test]
    fn blur5_is_the_same((w, h, cell, noise, seed) in images()) {
        let data = image(w, h, cell, noise, seed);
        let run = || {
            let (mut tmp, mut out) = (Vec::new(), Vec::new());
            blur5(view(&data, w), &mut tmp, &mut out);
            out
        };
        prop_assert_eq!(run(), baseline(run));
    }

    /// FAST, Harris ranking, bucketing, orientation, blur and steered BRIEF together.
    #[test]
    fn orb_features_are_the_same((w, h, cell, noise, seed) in images(), oriented in any::<bool>()) {
        let data = image(w + 40, h + 40, cell, noise, seed);
        let orb = OrbExtractor::new(OrbConfig { oriented, ..OrbConfig::default() });
        let run = || orb.extract(view(&data, w + 40));
        prop_assert_eq!(run(), baseline(run));
    }

    /// Stereo matching (row buckets, Hamming distances, sub-pixel disparity) and the
    /// temporal matching between an image and its shifted copy.
    #[test]
    fn matching_is_the_same((w, h, cell, noise, seed) in images(), dx in 1usize..12) {
        let (w, h) = (w + 40, h + 40);
        let left = image(w, h, cell, noise, seed);
        let right = shifted(&left, w, dx);
        let orb = OrbExtractor::default();
        let (fl, fr) = (orb.extract(view(&left, w)), orb.extract(view(&right, w)));
        let rig = RectifiedStereo { fx: 100.0, fy: 100.0, cx: w as f64 / 2.0, cy: h as f64 / 2.0, baseline_m: 0.5 };
        let config = StereoConfig { min_point_disparity_px: 0.0, ..StereoConfig::default() };
        let stereo = || match_stereo(&fl, &fr, view(&left, w), view(&right, w), &rig, &config);
        // Compared as printed (Rust prints a float exactly): the unmeasured row offsets are
        // NaN, which `==` never equals.
        prop_assert_eq!(format!("{:?}", stereo()), format!("{:?}", baseline(stereo)));
        let temporal = || mutual_matches(&fl.keypoints, &fl.descriptors, &fr.keypoints, &fr.descriptors, &TemporalConfig::default());
        prop_assert_eq!(temporal(), baseline(temporal));
    }
}

/// The comparisons above compare something: the random images give corners and matches.
#[test]
fn random_images_give_corners_and_matches() {
    let (w, h) = (160, 120);
    let left = image(w, h, 4, 10, 7);
    let right = shifted(&left, w, 5);
    let orb = OrbExtractor::default();
    let (fl, fr) = (orb.extract(view(&left, w)), orb.extract(view(&right, w)));
    assert!(fl.len() > 50, "{} features", fl.len());
    let matches = mutual_matches(
        &fl.keypoints,
        &fl.descriptors,
        &fr.keypoints,
        &fr.descriptors,
        &TemporalConfig::default(),
    );
    assert!(matches.len() > 20, "{} matches", matches.len());
}
