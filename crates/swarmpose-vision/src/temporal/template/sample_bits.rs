//! [`PatchTemplate::sample`] and [`PatchTemplate::sample_into`] (in place, issue 34)
//! against the sampling as it was, which built the template by value.

use super::tests::{H, W, image, limits, view};
use super::{N, PatchTemplate, R, SIDE, project_out};
use crate::features::GrayView;
use crate::image::sample_patch;
use nalgebra::SVector;

/// `unit_contrast` as it was: by value.
fn unit_contrast_before(values: &[f32; N * N]) -> Option<[f32; N * N]> {
    let mean = values.iter().sum::<f32>() / (N * N) as f32;
    let mut out = values.map(|v| v - mean);
    let norm = out.iter().map(|v| v * v).sum::<f32>().sqrt();
    if norm <= 0.0 {
        return None;
    }
    for v in &mut out {
        *v /= norm;
    }
    Some(out)
}

/// `PatchTemplate::sample` as it was: the template built on the stack and returned.
fn sample_before(image: GrayView<'_>, at: (f32, f32)) -> Option<PatchTemplate> {
    let mut big = [0f32; SIDE * SIDE];
    sample_patch(image, at.0 - R - 1.0, at.1 - R - 1.0, SIDE, &mut big)?;
    let mut t = PatchTemplate::empty();
    let (mut hxx, mut hxy, mut hyy) = (0f32, 0f32, 0f32);
    for j in 0..N {
        for i in 0..N {
            let c = (j + 1) * SIDE + i + 1;
            let k = j * N + i;
            t.values[k] = big[c];
            let gx = 0.5 * (big[c + 1] - big[c - 1]);
            let gy = 0.5 * (big[c + SIDE] - big[c - SIDE]);
            t.gx[k] = gx;
            t.gy[k] = gy;
            hxx += gx * gx;
            hxy += gx * gy;
            hyy += gy * gy;
        }
    }
    let det = hxx * hyy - hxy * hxy;
    let trace = hxx + hyy;
    let min_eig = 0.5 * (trace - ((hxx - hyy).powi(2) + 4.0 * hxy * hxy).sqrt());
    if det <= 0.0 || min_eig < (N * N) as f32 {
        return None;
    }
    t.tensor = (hxx, hxy, hyy);
    t.contrast = unit_contrast_before(&t.values)?;
    let mut g = [SVector::<f32, 2>::zeros(); N * N];
    for (k, g) in g.iter_mut().enumerate() {
        *g = SVector::<f32, 2>::new(t.gx[k], t.gy[k]);
    }
    project_out(&mut g, &t.contrast);
    let (mut pxx, mut pxy, mut pyy) = (0f32, 0f32, 0f32);
    for (k, g) in g.iter().enumerate() {
        t.pgx[k] = g.x;
        t.pgy[k] = g.y;
        pxx += g.x * g.x;
        pxy += g.x * g.y;
        pyy += g.y * g.y;
    }
    if pxx * pyy - pxy * pxy <= 0.0 {
        return None;
    }
    t.ptensor = (pxx, pxy, pyy);
    Some(t)
}

/// The same templates bit for bit (`Debug` prints every bit of an `f32`, signed zeros
/// apart), or `None` in the same places, on a textured image with flat and saturated
/// areas and at the borders; sampled in place into a template that held another patch
/// with its affine steps computed (and, on the dispatch's baseline, into a fresh one).
#[test]
fn sampled_in_place_is_the_sample_by_value() {
    let mut textured = image((0.3, -0.2));
    for (i, v) in textured.iter_mut().enumerate() {
        let (x, y) = (i % W, i / W);
        if x > 60 && y < 20 {
            *v = 0; // flat
        } else if x < 15 && y > 45 {
            *v = 255;
        }
    }
    let mut used = PatchTemplate::sample(view(&image((0.0, 0.0))), (40.0, 30.0)).expect("in");
    let (mut some, mut none) = (0, 0);
    for cy in (0..H + 4).step_by(3) {
        for cx in (0..W + 4).step_by(3) {
            let at = (cx as f32 - 2.25, cy as f32 - 1.5);
            let want = sample_before(view(&textured), at);
            let got = PatchTemplate::sample(view(&textured), at);
            assert_eq!(format!("{got:?}"), format!("{want:?}"), "at {at:?}");
            let _ = used.align_affine(view(&textured), (40.0, 30.0), limits(10, 2.5));
            let sampled = used.sample_into(view(&textured), at);
            assert_eq!(sampled, want.is_some(), "at {at:?}");
            let mut fresh = PatchTemplate::empty();
            let base = crate::simd::baseline(|| fresh.sample_into(view(&textured), at));
            assert_eq!(base, sampled, "at {at:?}");
            let Some(want) = want else {
                none += 1;
                // Whatever it holds, `used` stays usable.
                used = PatchTemplate::sample(view(&image((0.0, 0.0))), (40.0, 30.0)).expect("in");
                continue;
            };
            some += 1;
            assert_eq!(format!("{used:?}"), format!("{want:?}"), "at {at:?}");
            assert_eq!(format!("{fresh:?}"), format!("{want:?}"), "at {at:?}");
        }
    }
    assert!(some > 100 && none > 50, "{some} sampled, {none} not");
}
