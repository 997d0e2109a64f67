//! Tests of FAST, the Harris response and the orientation: each against its definition.

use super::*;

/// [`has_run9`] against its definition (9 shifted copies), on every 16-bit mask.
#[test]
fn run9_on_every_mask() {
    let by_definition = |mask: u32| {
        let m = mask | (mask << 16);
        (0..9).fold(m, |r, k| r & (m >> k)) != 0
    };
    let runs = (0..1u32 << 16).filter(|&m| has_run9(m)).count();
    assert!(runs > 1000, "{runs}");
    for mask in 0..1u32 << 16 {
        assert_eq!(has_run9(mask), by_definition(mask), "{mask:016b}");
    }
}

/// [`has_run9_both`] is [`has_run9`] of each mask, on every 16-bit mask beside masks
/// of the other side that would leak runs into it (none, all, itself, its complement,
/// a seeded random one), and with bits above the 16th set.
#[test]
fn run9_both_is_run9_of_each() {
    let noise = crate::test_noise::noise_bytes(2 << 16, 5);
    for mask in 0..1u32 << 16 {
        let random =
            u32::from(noise[2 * mask as usize]) << 8 | u32::from(noise[2 * mask as usize + 1]);
        for other in [0, 0xffff, mask, !mask & 0xffff, random, u32::MAX] {
            let want = (has_run9(mask), has_run9(other & 0xffff));
            assert_eq!(has_run9_both(mask, other), want, "{mask:016b} {other:032b}");
            let swapped = (want.1, want.0);
            assert_eq!(
                has_run9_both(other, mask),
                swapped,
                "{other:032b} {mask:016b}"
            );
        }
    }
}

/// The quick rejection as it was (issue 34, before the runs' minima and maxima): `side`
/// for 4 circularly consecutive points of 8, by pairs of pairs.
fn run4(p: [u8; 8], side: impl Fn(u8) -> bool) -> bool {
    (0..8).any(|i| (0..4).all(|j| side(p[(i + j) % 8])))
}

/// [`runs4`]'s brightest and darkest runs decide as [`run4`] does, for every
/// threshold, on seeded random points, on points of a few levels (ties) and at 0 and 255.
#[test]
fn runs4_decide_as_run4() {
    let noise = crate::test_noise::noise_bytes(8 * 6000, 3);
    let mut checked = [0usize; 2];
    for (i, eight) in noise.chunks_exact(8).enumerate() {
        let mut p: [u8; 8] = std::array::from_fn(|j| eight[j]);
        if i % 3 == 1 {
            // Few levels: many ties with each other and with the thresholds.
            p = p.map(|v| [0, 40, 41, 255][usize::from(v % 4)]);
        }
        let (brightest, darkest) = runs4(p);
        for t in [0u8, 1, 40, 41, 42, 128, 254, 255] {
            let bright = run4(p, |v| v > t);
            let dark = run4(p, |v| v < t);
            assert_eq!(brightest > t, bright, "{p:?} > {t}");
            assert_eq!(darkest < t, dark, "{p:?} < {t}");
            checked[usize::from(bright)] += 1;
        }
    }
    assert!(checked[0] > 1000 && checked[1] > 1000, "{checked:?}");
}

/// [`harris`] as it was before issue 34: the sums in `f32`, in raster order.
fn harris_in_floats(img: GrayView<'_>, x: usize, y: usize) -> f32 {
    let (w, d) = (img.width, img.data);
    let (mut sxx, mut syy, mut sxy) = (0f32, 0f32, 0f32);
    for yy in y - 3..=y + 3 {
        for k in 0..7 {
            let at = |yy: usize, xx: usize| f32::from(d[yy * w + xx]);
            let gx = at(yy, x - 3 + k + 1) - at(yy, x - 3 + k - 1);
            let gy = at(yy + 1, x - 3 + k) - at(yy - 1, x - 3 + k);
            sxx += gx * gx;
            syy += gy * gy;
            sxy += gx * gy;
        }
    }
    let scale = 1.0 / (255.0 * 255.0 * 49.0);
    let (sxx, syy, sxy) = (sxx * scale, syy * scale, sxy * scale);
    sxx * syy - sxy * sxy - 0.04 * (sxx + syy) * (sxx + syy)
}

/// [`harris`] as it was before its rows were read as 8 lanes: the sums as integers, pixel
/// by pixel in raster order.
fn harris_scalar(img: GrayView<'_>, x: usize, y: usize) -> f32 {
    let w = img.width;
    let d = img.data;
    let (mut sxx, mut syy, mut sxy) = (0i32, 0i32, 0i32);
    for yy in y - 3..=y + 3 {
        let here = &d[yy * w + x - 4..][..9];
        let above = &d[(yy - 1) * w + x - 3..][..7];
        let below = &d[(yy + 1) * w + x - 3..][..7];
        for k in 0..7 {
            let gx = i32::from(here[k + 2]) - i32::from(here[k]);
            let gy = i32::from(below[k]) - i32::from(above[k]);
            sxx += gx * gx;
            syy += gy * gy;
            sxy += gx * gy;
        }
    }
    let scale = 1.0 / (255.0 * 255.0 * 49.0);
    let (sxx, syy, sxy) = (sxx as f32 * scale, syy as f32 * scale, sxy as f32 * scale);
    sxx * syy - sxy * sxy - 0.04 * (sxx + syy) * (sxx + syy)
}

/// [`harris`] gives the bits of [`harris_in_floats`] and of [`harris_scalar`] at every
/// pixel 4 from the edges (at the last column, the eighth lane reads the next row's first
/// pixel) of seeded random images, of flat ones (all zero sums) and of the extremes
/// (stripes and checkerboards of 0 and 255: the largest sums, of both signs).
#[test]
fn harris_is_the_sums_in_floats() {
    let (w, h) = (41, 23);
    let noise = crate::test_noise::noise_bytes(w * h, 17);
    let images: [Vec<u8>; 6] = [
        noise.clone(),
        noise
            .iter()
            .map(|&v| if v < 128 { 0 } else { 255 })
            .collect(),
        vec![77; w * h],
        (0..w * h)
            .map(|i| if (i % w + i / w) % 2 == 0 { 0 } else { 255 })
            .collect(),
        (0..w * h)
            .map(|i| {
                if (i % w / 2 + i / w / 2) % 2 == 0 {
                    0
                } else {
                    255
                }
            })
            .collect(),
        (0..w * h)
            .map(|i| if (i % w + i / w) % 4 < 2 { 255 } else { 0 })
            .collect(),
    ];
    let mut signs = [0usize; 3];
    for data in &images {
        let img = GrayView {
            width: w,
            height: h,
            data,
        };
        for y in 4..h - 4 {
            for x in 4..w - 4 {
                let (got, want) = (harris(img, x, y), harris_in_floats(img, x, y));
                assert_eq!(got.to_bits(), want.to_bits(), "({x}, {y})");
                let scalar = harris_scalar(img, x, y);
                assert_eq!(got.to_bits(), scalar.to_bits(), "({x}, {y})");
                signs[usize::from(want > 0.0) + usize::from(want >= 0.0)] += 1;
            }
        }
    }
    assert!(signs.iter().all(|&n| n > 100), "{signs:?}");
}

/// [`compass_pass`] rejects no pixel that [`quick_pass`] passes, and rejects some, on
/// seeded random circles (also of a few levels, many ties) at thresholds 0 to 255.
#[test]
fn compass_rejects_only_what_quick_pass_rejects() {
    let noise = crate::test_noise::noise_bytes(17 * 20_000, 9);
    let (mut rejected, mut passed) = ([0usize; 2], 0);
    for (k, p) in noise.chunks_exact(17).enumerate() {
        let p: [u8; 17] = std::array::from_fn(|i| {
            if k % 2 == 0 {
                p[i]
            } else {
                [0, 100, 101, 255][usize::from(p[i] % 4)]
            }
        });
        let even: [u8; 8] = std::array::from_fn(|i| p[1 + 2 * i]);
        let odd: [u8; 8] = std::array::from_fn(|i| p[2 + 2 * i]);
        let compass = [even[0], even[2], even[4], even[6]];
        for t in [0u8, 1, 12, 50, 100, 255] {
            let quick = quick_pass(p[0], t, even, odd);
            let coarse = compass_pass(p[0], t, compass);
            assert!(quick <= coarse, "{p:?} {t}");
            rejected[usize::from(quick)] += usize::from(coarse == 0);
            passed += usize::from(quick);
        }
    }
    assert!(
        rejected[0] > 1000 && rejected[1] == 0 && passed > 1000,
        "{rejected:?} {passed}"
    );
}

#[test]
fn run9() {
    assert!(has_run9(0b1_1111_1111));
    assert!(!has_run9(0b1111_1111));
    // Wrapping run: bits 12..16 and 0..4.
    assert!(has_run9(0xf00f | 0x0800));
}

/// FAST-9 by its definition at every pixel (no quick rejection), then the same
/// non-maximum suppression.
fn fast9_by_definition(img: GrayView<'_>, t: u8, border: usize) -> Vec<Corner> {
    let (w, h) = (img.width, img.height);
    let mut scores = vec![0u16; w * h];
    for y in border..h - border {
        for x in border..w - border {
            let c = img.data[y * w + x];
            let (hi, lo) = (c.saturating_add(t), c.saturating_sub(t));
            let ring = CIRCLE.map(|(dx, dy)| {
                img.data[(y as isize + dy) as usize * w + (x as isize + dx) as usize]
            });
            let (mut b, mut d, mut sb, mut sd) = (0u32, 0u32, 0u32, 0u32);
            for (k, &p) in ring.iter().enumerate() {
                b |= u32::from(p > hi) << k;
                d |= u32::from(p < lo) << k;
                sb += u32::from(p.saturating_sub(hi));
                sd += u32::from(lo.saturating_sub(p));
            }
            let s = match (has_run9(b), has_run9(d)) {
                (true, true) => sb.max(sd),
                (true, false) => sb,
                (false, true) => sd,
                (false, false) => continue,
            };
            scores[y * w + x] = s.clamp(1, u32::from(u16::MAX)) as u16;
        }
    }
    let mut out = Vec::new();
    for y in border..h - border {
        for x in border..w - border {
            let (i, s) = (y * w + x, scores[y * w + x]);
            let before = [i - w - 1, i - w, i - w + 1, i - 1];
            let after = [i + 1, i + w - 1, i + w, i + w + 1];
            if s > 0
                && before.iter().all(|&j| scores[j] < s)
                && after.iter().all(|&j| scores[j] <= s)
            {
                out.push(Corner { x, y, score: s });
            }
        }
    }
    out
}

#[test]
fn quick_rejection_drops_no_corner() {
    let (w, h) = (97, 61);
    let mut data = crate::test_noise::noise_bytes(w * h, 11);
    // Smooth half of it, so that there are both noise and blobs.
    for i in (w..w * h / 2).rev() {
        data[i] = (u16::from(data[i]) + u16::from(data[i - w])).div_ceil(2) as u8;
    }
    let img = GrayView {
        width: w,
        height: h,
        data: &data,
    };
    for t in [1, 10, 20, 60, 250] {
        let (mut s, mut out) = (FastScratch::default(), Vec::new());
        fast9(img, t, 3, &mut s, &mut out);
        assert!(t > 60 || out.len() > 20, "{} corners at {t}", out.len());
        assert_eq!(out, fast9_by_definition(img, t, 3), "threshold {t}");
    }
}

/// One scratch reused over images of other sizes, thresholds and borders, and one
/// left by an interrupted call (scores not zero), give the corners by definition; a
/// finished call leaves the scores all zero.
#[test]
fn reused_scratch_gives_the_corners_by_definition() {
    let mut s = FastScratch::default();
    let mut out = Vec::new();
    for (i, (w, h, t, border)) in [
        (97, 61, 10, 3),
        (61, 97, 20, 5),
        (50, 40, 5, 3),
        (97, 61, 1, 8),
        // Rows of 27 and 32 pixels: narrower than a chunk, and one chunk.
        (33, 40, 10, 3),
        (38, 40, 10, 3),
    ]
    .into_iter()
    .enumerate()
    {
        let data = crate::test_noise::noise_bytes(w * h, 20 + i as u32);
        let img = GrayView {
            width: w,
            height: h,
            data: &data,
        };
        fast9(img, t, border, &mut s, &mut out);
        assert!(out.len() > 20, "{}", out.len());
        assert_eq!(out, fast9_by_definition(img, t, border), "image {i}");
        assert!(
            s.scores_zero && s.scores.iter().all(|&v| v == 0),
            "image {i}"
        );
    }
    // As a panic would leave it.
    s.scores.iter_mut().for_each(|v| *v = 900);
    s.scores_zero = false;
    let data = crate::test_noise::noise_bytes(97 * 61, 30);
    let img = GrayView {
        width: 97,
        height: 61,
        data: &data,
    };
    fast9(img, 10, 3, &mut s, &mut out);
    assert_eq!(out, fast9_by_definition(img, 10, 3));
}

#[test]
fn finds_a_square_corner() {
    let (w, h) = (40, 40);
    let mut data = vec![20u8; w * h];
    for y in 20..h {
        for x in 20..w {
            data[y * w + x] = 200;
        }
    }
    let img = GrayView {
        width: w,
        height: h,
        data: &data,
    };
    let (mut s, mut out) = (FastScratch::default(), Vec::new());
    fast9(img, 20, 3, &mut s, &mut out);
    assert!(!out.is_empty());
    assert!(
        out.iter()
            .all(|c| c.x.abs_diff(20) <= 1 && c.y.abs_diff(20) <= 1)
    );
    // The bright quadrant is down-right: the centroid points there.
    let a = centroid_angle(img, 20, 20, &disc_half_widths(8));
    assert!((a - std::f32::consts::FRAC_PI_4).abs() < 0.2, "{a}");
}
