//! End-to-end tests of the SURF extractor on synthetic images.

use super::test_images::{gaussian_blob, texture};
use super::*;
use crate::features::Descriptor;

fn view(w: usize, h: usize, data: &[u8]) -> GrayView<'_> {
    GrayView {
        width: w,
        height: h,
        data,
    }
}

/// Rotates by +90° (from `+x` towards `+y`): pixel `(x, y)` goes to `(h − 1 − y, x)`.
fn rotate90(w: usize, h: usize, data: &[u8]) -> Vec<u8> {
    let (nw, nh) = (h, w);
    let mut out = vec![0u8; nw * nh];
    for y in 0..h {
        for x in 0..w {
            out[x * nw + (h - 1 - y)] = data[y * w + x];
        }
    }
    out
}

#[test]
fn names_and_config() {
    assert_eq!(Surf::default().name(), "surf");
    assert_eq!(Surf::upright().name(), "upright-surf");
    let s = Surf::new(SurfConfig {
        octaves: 0,
        intervals: 0,
        initial_step: 0,
        ..SurfConfig::default()
    });
    assert_eq!(
        (
            s.config().octaves,
            s.config().intervals,
            s.config().initial_step
        ),
        (1, 1, 1)
    );
}

#[test]
fn empty_and_tiny_images_give_no_features() {
    let surf = Surf::default();
    assert!(surf.extract(view(0, 0, &[])).is_empty());
    assert!(surf.extract(view(5, 5, &[100; 25])).is_empty());
    assert!(surf.extract(view(64, 64, &[100; 64 * 64])).is_empty());
}

#[test]
fn upright_features_have_zero_angle_and_unit_descriptors() {
    let (w, h) = (129, 97);
    let img = texture(w, h, 3);
    let f = Surf::upright().extract_with_laplacian(view(w, h, &img));
    assert!(f.features.len() > 5, "{}", f.features.len());
    assert_eq!(f.features.descriptors.len(), f.features.len());
    assert_eq!(f.laplacian_positive.len(), f.features.len());
    for (k, d) in f.features.keypoints.iter().zip(&f.features.descriptors) {
        assert_eq!(k.angle, 0.0);
        let n = d.0.iter().map(|v| v * v).sum::<f32>().sqrt();
        assert!((n - 1.0).abs() < 1e-4);
    }
    // Sorted by response, and max_features keeps the strongest.
    let r: Vec<f32> = f.features.keypoints.iter().map(|k| k.response).collect();
    assert!(r.windows(2).all(|p| p[0] >= p[1]));
    let top = Surf::new(SurfConfig {
        max_features: Some(3),
        ..SurfConfig::upright()
    })
    .extract(view(w, h, &img));
    assert_eq!(top.keypoints, f.features.keypoints[..3]);
}

#[test]
fn laplacian_sign_of_blobs() {
    let n = 101;
    let dark = Surf::default().extract_with_laplacian(view(n, n, &gaussian_blob(n, n, 4.0, false)));
    let bright =
        Surf::default().extract_with_laplacian(view(n, n, &gaussian_blob(n, n, 4.0, true)));
    assert!(dark.laplacian_positive[0]);
    assert!(!bright.laplacian_positive[0]);
    assert!(!dark.same_laplacian(0, &bright, 0));
    assert!(dark.same_laplacian(0, &dark, 0));
    assert!(!dark.same_laplacian(0, &dark, 999));
}

#[test]
fn oriented_descriptor_is_invariant_to_a_90_degree_rotation() {
    // Odd sizes keep every octave's sampling grid aligned after the rotation.
    let (w, h) = (161, 129);
    let img = texture(w, h, 21);
    let rot = rotate90(w, h, &img);
    let surf = Surf::default();
    let a = surf.extract(view(w, h, &img));
    let b = surf.extract(view(h, w, &rot));
    assert!(a.len() >= 10, "only {} features", a.len());
    let mut checked = 0;
    let mut close = 0;
    for (ka, da) in a.keypoints.iter().zip(&a.descriptors) {
        let (ex, ey) = ((h - 1) as f32 - ka.y, ka.x);
        let Some((kb, db)) = b
            .keypoints
            .iter()
            .zip(&b.descriptors)
            .find(|(k, _)| (k.x - ex).abs() < 0.01 && (k.y - ey).abs() < 0.01)
        else {
            continue;
        };
        assert!((kb.scale - ka.scale).abs() < 1e-3);
        checked += 1;
        let turn =
            (kb.angle - ka.angle - std::f32::consts::FRAC_PI_2).rem_euclid(std::f32::consts::TAU);
        let turn = turn.min(std::f32::consts::TAU - turn);
        if turn < 1e-3 && da.distance(db) < 0.02 {
            close += 1;
        }
    }
    assert!(
        checked * 10 >= a.len() * 9,
        "{checked} of {} re-detected",
        a.len()
    );
    assert!(close * 10 >= checked * 9, "{close} of {checked} invariant");
}

#[test]
fn upright_descriptor_is_not_rotation_invariant() {
    let (w, h) = (161, 129);
    let img = texture(w, h, 21);
    let rot = rotate90(w, h, &img);
    let surf = Surf::upright();
    let a = surf.extract(view(w, h, &img));
    let b = surf.extract(view(h, w, &rot));
    let mut far = 0;
    let mut checked = 0;
    for (ka, da) in a.keypoints.iter().zip(&a.descriptors) {
        let (ex, ey) = ((h - 1) as f32 - ka.y, ka.x);
        if let Some((_, db)) = b
            .keypoints
            .iter()
            .zip(&b.descriptors)
            .find(|(k, _)| (k.x - ex).abs() < 0.01 && (k.y - ey).abs() < 0.01)
        {
            checked += 1;
            far += usize::from(da.distance(db) > 0.1);
        }
    }
    assert!(checked > 0 && far * 2 > checked, "{far} of {checked}");
}

#[test]
fn extract_selected_describes_the_same_features_as_extract() {
    let (w, h) = (129, 97);
    let img = texture(w, h, 3);
    for surf in [Surf::default(), Surf::new(SurfConfig::odometry())] {
        let all = surf.extract(view(w, h, &img));
        assert!(all.len() > 5, "{}", all.len());
        // Every other feature, plus an index out of range (ignored).
        let select = |k: &[Keypoint]| (0..k.len()).step_by(2).chain([k.len() + 3]).collect();
        let kept = surf.extract_selected(view(w, h, &img), &select);
        assert_eq!(kept.len(), all.len().div_ceil(2));
        for (i, j) in (0..all.len()).step_by(2).enumerate() {
            assert_eq!(kept.keypoints[i], all.keypoints[j]);
            assert_eq!(kept.descriptors[i], all.descriptors[j]);
        }
    }
}

#[test]
fn the_odometry_configuration_is_upright_with_a_lower_threshold() {
    let c = SurfConfig::odometry();
    assert!(c.upright && c.finest_layer_maxima);
    assert_eq!(c.smoothing, 0.0);
    assert!(c.hessian_threshold < SurfConfig::default().hessian_threshold);
    assert_eq!(Surf::new(c).name(), "upright-surf");
}
