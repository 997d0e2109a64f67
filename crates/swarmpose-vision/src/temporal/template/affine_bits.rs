//! [`PatchTemplate::align_affine`] against its definition: the steps recomputed per call,
//! each sample's offset by its formula and each sample checked (before the steps were kept
//! in the template, the offsets tabulated and a patch inside sampled without checks).

use super::inside::{sample_inside, whole_part};
use super::tests::{H, W, image, limits, view, warped};
use super::{AlignLimits, N, PatchTemplate, R, ncc, project_out};
use crate::features::GrayView;
use crate::image::{sample_bilinear, sample_bilinear_inside};
use nalgebra::{Matrix3, SMatrix, SVector};

/// [`PatchTemplate::align_affine`] as it was before its steps were kept in the
/// template: the steepest-descent images and the inverse Hessian recomputed per call.
fn align_affine_by_definition(
    t: &PatchTemplate,
    image: GrayView<'_>,
    start: (f32, f32),
    limits: AlignLimits,
) -> Option<(f32, f32)> {
    let mut sd = [SVector::<f32, 6>::zeros(); N * N];
    for (k, sd) in sd.iter_mut().enumerate() {
        let (x, y) = ((k % N) as f32 - R, (k / N) as f32 - R);
        let (gx, gy) = (t.gx[k], t.gy[k]);
        *sd = SVector::<f32, 6>::from([gx * x, gx * y, gy * x, gy * y, gx, gy]);
    }
    project_out(&mut sd, &t.contrast);
    let h = sd
        .iter()
        .fold(SMatrix::<f32, 6, 6>::zeros(), |h, v| h + *v * v.transpose());
    let h_inv = h.try_inverse()?;
    let mut m = Matrix3::<f32>::new(1.0, 0.0, start.0, 0.0, 1.0, start.1, 0.0, 0.0, 1.0);
    let mut patch = [0f32; N * N];
    for _ in 0..limits.iterations {
        for (k, sample) in patch.iter_mut().enumerate() {
            let (x, y) = ((k % N) as f32 - R, (k / N) as f32 - R);
            let u = m[(0, 0)] * x + m[(0, 1)] * y + m[(0, 2)];
            let v = m[(1, 0)] * x + m[(1, 1)] * y + m[(1, 2)];
            *sample = sample_bilinear(image, u, v)?;
        }
        let mut b = SVector::<f32, 6>::zeros();
        for (k, i) in patch.iter().enumerate() {
            b += sd[k] * (i - t.values[k]);
        }
        let dp = h_inv * b;
        let w = Matrix3::<f32>::new(
            1.0 + dp[0],
            dp[1],
            dp[4],
            dp[2],
            1.0 + dp[3],
            dp[5],
            0.0,
            0.0,
            1.0,
        );
        m *= w.try_inverse()?;
        let det = m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)];
        if !(0.5..=2.0).contains(&det) {
            return None;
        }
        let (px, py) = (m[(0, 2)], m[(1, 2)]);
        if (px - start.0).hypot(py - start.1) > limits.max_move_px {
            return None;
        }
        let linear = dp[0]
            .abs()
            .max(dp[1].abs())
            .max(dp[2].abs())
            .max(dp[3].abs());
        if dp[4].hypot(dp[5]) < 0.01 && linear * R < 0.01 {
            let Some(min_ncc) = limits.min_ncc else {
                return Some((px, py));
            };
            return (ncc(&patch, &t.values) >= min_ncc).then_some((px, py));
        }
    }
    None
}

/// The kept steps give the alignment of the definition bit for bit, on the first call
/// (which computes them) and on later ones (which reuse them), in both compilations
/// ([`crate::simd`]): templates all over a textured image, aligned in shifted, warped,
/// re-exposed and noisy images from starts around the truth, with and without the
/// cross-correlation check.
#[test]
fn kept_affine_steps_give_the_definition_bit_for_bit() {
    let mut rng = crate::test_noise::Lcg(34);
    let source = image((0.0, 0.0));
    let shifted = image((0.83, -0.41));
    let sheared = warped(|x, y| (0.97 * x + 0.04 * y + 1.3, -0.03 * x + 1.05 * y - 0.6));
    let exposed: Vec<u8> = shifted
        .iter()
        .map(|&v| (0.8 * f32::from(v) + 20.0).round() as u8)
        .collect();
    let noisy: Vec<u8> = sheared
        .iter()
        .map(|&v| v.saturating_add((rng.next_u32() >> 29) as u8))
        .collect();
    let (mut sampled, mut found) = (0, 0);
    for cy in (6..H - 6).step_by(5) {
        for cx in (6..W - 6).step_by(5) {
            let at = (cx as f32 + 0.25, cy as f32 - 0.5);
            let Some(mut t) = PatchTemplate::sample(view(&source), at) else {
                continue;
            };
            sampled += 1;
            for img in [&source, &shifted, &sheared, &exposed, &noisy] {
                for _ in 0..3 {
                    let start = (
                        at.0 + (rng.next_u32() >> 24) as f32 / 64.0 - 2.0,
                        at.1 + (rng.next_u32() >> 24) as f32 / 64.0 - 2.0,
                    );
                    for lim in [
                        limits(10, 2.0),
                        AlignLimits {
                            min_ncc: None,
                            ..limits(6, 3.0)
                        },
                    ] {
                        let want = align_affine_by_definition(&t, view(img), start, lim);
                        let got = t.align_affine(view(img), start, lim);
                        let mut copy = t.clone();
                        let base =
                            crate::simd::baseline(|| copy.align_affine(view(img), start, lim));
                        assert_eq!(
                            got.map(|(x, y)| (x.to_bits(), y.to_bits())),
                            base.map(|(x, y)| (x.to_bits(), y.to_bits())),
                            "dispatched and baseline: template at {at:?}, start {start:?}"
                        );
                        assert_eq!(
                            got.map(|(x, y)| (x.to_bits(), y.to_bits())),
                            want.map(|(x, y)| (x.to_bits(), y.to_bits())),
                            "template at {at:?}, start {start:?}, limits {lim:?}"
                        );
                        found += usize::from(got.is_some());
                    }
                }
            }
        }
    }
    assert!(
        sampled > 50 && found > 200,
        "{sampled} templates, {found} found"
    );
}

/// The patch sampled in three loops is [`sample_bilinear_inside`] at each position, bit
/// for bit: random positions inside a noise image, whole and half pixels, the first row
/// and column (zeros of both signs) and the last positions inside (just below `width - 1`,
/// `height - 1`); and the whole parts below 2^22 against the conversion.
#[test]
fn sampled_inside_is_sample_bilinear_inside() {
    let mut rng = crate::test_noise::Lcg(36);
    let data = crate::test_noise::noise_bytes(W * H, 37);
    let img = view(&data);
    let (u_max, v_max) = ((W - 1) as f32, (H - 1) as f32);
    let mut edges = vec![
        (0.0, 0.0),
        (u_max.next_down(), v_max.next_down()),
        (0.0, v_max.next_down()),
        (u_max.next_down(), 0.0),
        (3.0, 4.5),
        (f32::from_bits(1), 7.0),
        (-0.0, -0.0),
        (0.5, 1.5),
        (2.5, 1.0f32.next_down()),
    ];
    edges.resize(N * N, (1.0, 1.0));
    let mut sets = vec![edges];
    for _ in 0..40 {
        let mut at = [(0f32, 0f32); N * N];
        for p in &mut at {
            let (a, b) = (rng.next_u32() >> 8, rng.next_u32() >> 8);
            // Within [0, 1) of the range, in steps of 2^-24 (whole and half pixels too).
            let (s, t) = (a as f32 / (1 << 24) as f32, b as f32 / (1 << 24) as f32);
            *p = (
                (s * u_max).min(u_max.next_down()),
                (t * v_max).min(v_max.next_down()),
            );
            if a % 5 == 0 {
                *p = (p.0.floor(), (p.1 * 2.0).floor() / 2.0);
            }
        }
        sets.push(at.to_vec());
    }
    for at in sets {
        let (mut us, mut vs) = ([0f32; N * N], [0f32; N * N]);
        for ((u, v), &p) in us.iter_mut().zip(&mut vs).zip(&at) {
            (*u, *v) = p;
        }
        let mut got = [0f32; N * N];
        sample_inside(img, (&us, &vs), &mut got);
        for (&(u, v), g) in at.iter().zip(&got) {
            assert_eq!(
                g.to_bits(),
                sample_bilinear_inside(img, u, v).to_bits(),
                "({u}, {v})"
            );
        }
    }
    // Whole parts: every half and quarter pixel up to 2^12, random positions up to 2^22
    // (all of its binades), the largest below 2^22.
    let mut us: Vec<f32> = (0..1 << 14).map(|k| k as f32 * 0.25).collect();
    us.extend((0..20_000).map(|_| {
        let r = rng.next_u32();
        f32::from_bits(r % 0x4a80_0000)
    }));
    us.push(((1u32 << 22) as f32).next_down());
    us.extend([0.0, -0.0, 0.5f32.next_down(), 0.5, 1.0f32.next_down()]);
    for u in us {
        if !(0.0..(1u32 << 22) as f32).contains(&u) {
            continue;
        }
        let (t, r) = whole_part(u);
        assert_eq!(
            (t, r.to_bits()),
            (u as i32, (u as i64 as f32).to_bits()),
            "{u}"
        );
    }
}

/// The translation alignment and the sampling of templates give the same bits in both
/// compilations ([`crate::simd`]): templates all over a textured image (printed, which
/// tells signed zeros apart), aligned in shifted, re-exposed and noisy images from starts
/// around the truth.
#[test]
fn sample_and_align_are_their_baseline() {
    let mut rng = crate::test_noise::Lcg(39);
    let source = image((0.0, 0.0));
    let shifted = image((-0.62, 0.37));
    let noisy: Vec<u8> = shifted
        .iter()
        .map(|&v| v.saturating_add((rng.next_u32() >> 29) as u8))
        .collect();
    let (mut sampled, mut found) = (0, 0);
    for cy in (3..H - 3).step_by(4) {
        for cx in (3..W - 3).step_by(4) {
            let at = (cx as f32 + 0.5, cy as f32 - 0.25);
            let t = PatchTemplate::sample(view(&source), at);
            let base = crate::simd::baseline(|| PatchTemplate::sample(view(&source), at));
            assert_eq!(format!("{t:?}"), format!("{base:?}"), "template at {at:?}");
            let Some(t) = t else {
                continue;
            };
            sampled += 1;
            for img in [&source, &shifted, &noisy] {
                let start = (
                    at.0 + (rng.next_u32() >> 24) as f32 / 64.0 - 2.0,
                    at.1 + (rng.next_u32() >> 24) as f32 / 64.0 - 2.0,
                );
                let got = t.align(view(img), start, limits(10, 2.5));
                let base = crate::simd::baseline(|| t.align(view(img), start, limits(10, 2.5)));
                assert_eq!(
                    got.map(|(x, y)| (x.to_bits(), y.to_bits())),
                    base.map(|(x, y)| (x.to_bits(), y.to_bits())),
                    "template at {at:?}, start {start:?}"
                );
                found += usize::from(got.is_some());
            }
        }
    }
    assert!(
        sampled > 50 && found > 50,
        "{sampled} templates, {found} found"
    );
}
