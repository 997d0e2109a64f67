//! [`super::sample_bilinear`] and [`super::sample_patch`] against their definitions through
//! `usize` (before their conversions went through `i64`): bit for bit.

use super::{sample_bilinear, sample_patch};
use crate::features::GrayView;
use crate::test_noise::{Lcg, noise_bytes};

/// [`sample_bilinear`] with the pixel found through `usize`.
fn bilinear_by_definition(img: GrayView<'_>, x: f32, y: f32) -> Option<f32> {
    if !(x >= 0.0 && y >= 0.0) {
        return None;
    }
    let (x0, y0) = (x as usize, y as usize);
    if x0 + 1 >= img.width || y0 + 1 >= img.height {
        if x0 < img.width && y0 < img.height && x == x0 as f32 && y == y0 as f32 {
            return Some(f32::from(img.data[y0 * img.width + x0]));
        }
        return None;
    }
    let (fx, fy) = (x - x0 as f32, y - y0 as f32);
    let i = y0 * img.width + x0;
    let d = img.data;
    let top = f32::from(d[i]) * (1.0 - fx) + f32::from(d[i + 1]) * fx;
    let bot = f32::from(d[i + img.width]) * (1.0 - fx) + f32::from(d[i + img.width + 1]) * fx;
    Some(top * (1.0 - fy) + bot * fy)
}

/// [`sample_patch`] with the top-left pixel found through `floor` and `usize`.
fn patch_by_definition(
    img: GrayView<'_>,
    x0: f32,
    y0: f32,
    n: usize,
    out: &mut [f32],
) -> Option<()> {
    if !(x0 >= 0.0 && y0 >= 0.0) {
        return None;
    }
    let (xi, yi) = (x0.floor() as usize, y0.floor() as usize);
    if xi + n >= img.width || yi + n >= img.height {
        return None;
    }
    let (fx, fy) = (x0 - xi as f32, y0 - yi as f32);
    let (w00, w10, w01, w11) = (
        (1.0 - fx) * (1.0 - fy),
        fx * (1.0 - fy),
        (1.0 - fx) * fy,
        fx * fy,
    );
    for j in 0..n {
        for i in 0..n {
            let (t, b) = (
                (yi + j) * img.width + xi + i,
                (yi + j + 1) * img.width + xi + i,
            );
            let d = img.data;
            out[j * n + i] = w00 * f32::from(d[t])
                + w10 * f32::from(d[t + 1])
                + w01 * f32::from(d[b])
                + w11 * f32::from(d[b + 1]);
        }
    }
    Some(())
}

/// Sides of the patches compared: below, at and above the blocks of
/// [`super::PATCH_LANES`] samples, multiples and not (the last block overlapping).
const PATCH_SIDES: [usize; 8] = [1, 5, 7, 8, 9, 11, 16, 17];

/// Random positions over a noise image and just outside it, whole pixels, the last row
/// and column, negative, NaN and infinite or huge coordinates: the same samples, bit for
/// bit, and the same refusals (huge coordinates outside any image are refused, not
/// passed to `usize`, where `x0 + 1` may overflow).
#[test]
fn samples_are_their_definitions_bit_for_bit() {
    let (w, h) = (37usize, 23usize);
    let data = noise_bytes(w * h, 34);
    let img = GrayView {
        width: w,
        height: h,
        data: &data,
    };
    let mut g = Lcg(7);
    let mut coord = |span: usize| -> f32 {
        match g.next_u32() % 8 {
            0 => (g.next_u32() % (span as u32 + 2)) as f32,
            1 => -((g.next_u32() >> 20) as f32) / 4096.0,
            _ => (g.next_u32() >> 8) as f32 / (1u32 << 24) as f32 * (span as f32 + 1.5),
        }
    };
    let (mut inside, mut patches) = (0, 0);
    for _ in 0..20_000 {
        let (x, y) = (coord(w), coord(h));
        let got = sample_bilinear(img, x, y);
        assert_eq!(
            got.map(f32::to_bits),
            bilinear_by_definition(img, x, y).map(f32::to_bits),
            "({x}, {y})"
        );
        inside += usize::from(got.is_some());
        for n in PATCH_SIDES {
            let (mut a, mut b) = ([0f32; 17 * 17], [0f32; 17 * 17]);
            let got = sample_patch(img, x, y, n, &mut a);
            assert_eq!(
                got,
                patch_by_definition(img, x, y, n, &mut b),
                "({x}, {y}), {n}"
            );
            assert_eq!(a.map(f32::to_bits), b.map(f32::to_bits), "({x}, {y}), {n}");
            patches += usize::from(got.is_some());
        }
    }
    assert!(
        inside > 10_000 && patches > 25_000,
        "{inside} samples, {patches} patches"
    );
    for (x, y) in [
        (36.0f32, 22.0f32),
        (36.0, 21.5),
        (35.999_996, 22.0),
        (f32::NAN, 1.0),
        (1.0, f32::NAN),
        (-0.0, 0.0),
        (1e10, 2.0),
        (2.0, 1e19),
    ] {
        assert_eq!(
            sample_bilinear(img, x, y).map(f32::to_bits),
            bilinear_by_definition(img, x, y).map(f32::to_bits),
            "({x}, {y})"
        );
    }
    for (x, y) in [(f32::INFINITY, 2.0), (2.0, 1e30)] {
        assert_eq!(sample_bilinear(img, x, y), None, "({x}, {y})");
        assert_eq!(
            sample_patch(img, x, y, 3, &mut [0f32; 9]),
            None,
            "({x}, {y})"
        );
    }
}

/// [`sample_patch`] inlined into a dispatched kernel.
struct Patches<'a>(GrayView<'a>, &'a [(f32, f32)]);

impl crate::simd::Kernel for Patches<'_> {
    type Output = Vec<Option<Vec<u32>>>;

    #[inline(always)]
    fn run(self) -> Self::Output {
        let mut out = Vec::new();
        for &(x, y) in self.1 {
            for n in PATCH_SIDES {
                let mut p = [0f32; 17 * 17];
                let got = sample_patch(self.0, x, y, n, &mut p);
                out.push(got.map(|()| p[..n * n].iter().map(|v| v.to_bits()).collect()));
            }
        }
        out
    }
}

/// The dispatched compilation of [`sample_patch`] (vector blocks) gives its baseline's
/// samples, bit for bit, at random sub-pixel and whole-pixel positions up to the edges.
#[test]
fn patches_are_the_same_dispatched() {
    let (w, h) = (41usize, 29usize);
    let data = noise_bytes(w * h, 36);
    let img = GrayView {
        width: w,
        height: h,
        data: &data,
    };
    let mut g = Lcg(36);
    let positions: Vec<(f32, f32)> = (0..3_000)
        .map(|k| {
            let mut c = |span: usize| match k % 3 {
                0 => (g.next_u32() % span as u32) as f32,
                _ => (g.next_u32() >> 8) as f32 / (1u32 << 24) as f32 * span as f32,
            };
            (c(w - 7), c(h - 7))
        })
        .collect();
    let run = || crate::simd::dispatch(Patches(img, &positions));
    let (got, base) = (run(), crate::simd::baseline(run));
    assert_eq!(got, base);
    let sampled = got.iter().filter(|p| p.is_some()).count();
    assert!(sampled > 10_000, "{sampled} patches");
}
