//! FAST-9 corners (Rosten & Drummond) with a 3x3 non-maximum suppression, and the
//! Harris response and intensity-centroid orientation used to rank and orient them.

use super::pack_bits;
use crate::features::GrayView;
use crate::simd;

/// The 16 pixels of the Bresenham circle of radius 3, clockwise from the top (`fast9`
/// reads them as the row slices `p0` to `p15`; the tests, from here).
#[cfg(test)]
const CIRCLE: [(isize, isize); 16] = [
    (0, -3),
    (1, -3),
    (2, -2),
    (3, -1),
    (3, 0),
    (3, 1),
    (2, 2),
    (1, 3),
    (0, 3),
    (-1, 3),
    (-2, 2),
    (-3, 1),
    (-3, 0),
    (-3, -1),
    (-2, -2),
    (-1, -3),
];

/// A FAST corner: integer pixel position and FAST score.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Corner {
    /// Column, pixels.
    pub x: usize,
    /// Row, pixels.
    pub y: usize,
    /// Sum of `|I(p) - I(c)| - threshold` over the circle pixels on the corner's side.
    pub score: u16,
}

/// True when `mask` (16 bits, circular) has a run of at least 9 set bits: runs of 2, 4
/// and 8 by doubling, then the ninth bit (four shifts instead of eight).
#[inline(always)]
fn has_run9(mask: u32) -> bool {
    let m = mask | (mask << 16);
    let r2 = m & (m >> 1);
    let r4 = r2 & (r2 >> 2);
    let r8 = r4 & (r4 >> 4);
    r8 & (m >> 8) != 0
}

/// True when `side` holds for 4 circularly consecutive points of 8.
#[inline(always)]
fn run4(p: [u8; 8], side: impl Fn(u8) -> bool) -> bool {
    let [m0, m1, m2, m3, m4, m5, m6, m7] = [
        side(p[0]),
        side(p[1]),
        side(p[2]),
        side(p[3]),
        side(p[4]),
        side(p[5]),
        side(p[6]),
        side(p[7]),
    ];
    let (m01, m23, m45, m67) = (m0 & m1, m2 & m3, m4 & m5, m6 & m7);
    let (m12, m34, m56, m70) = (m1 & m2, m3 & m4, m5 & m6, m7 & m0);
    (m01 & m23)
        | (m12 & m34)
        | (m23 & m45)
        | (m34 & m56)
        | (m45 & m67)
        | (m56 & m70)
        | (m67 & m01)
        | (m70 & m12)
}

/// Buffers of [`fast9`], reused between calls: the score of every pixel, the corners
/// before the non-maximum suppression and a row's quick rejection.
#[derive(Debug, Clone, Default)]
pub struct FastScratch {
    scores: Vec<u16>,
    /// `scores` holds zeros only: a call leaves it so (it zeroes the scores it wrote), and
    /// the next then clears nothing. False while a call runs (a panic leaves it false).
    scores_zero: bool,
    candidates: Vec<Corner>,
    pass: Vec<u8>,
}

/// FAST-9 corners at least `border` pixels (and at least 3) from every edge, after a
/// 3x3 non-maximum suppression on the score. `scratch` is reused between calls; `out` is
/// cleared and receives the corners in raster order. Compiled for the CPU's best
/// instruction set ([`crate::simd`]).
pub fn fast9(
    img: GrayView<'_>,
    threshold: u8,
    border: usize,
    scratch: &mut FastScratch,
    out: &mut Vec<Corner>,
) {
    simd::dispatch(Fast9(img, threshold, border, scratch, out));
}

/// A call of [`fast9`] for [`simd::dispatch`].
struct Fast9<'a>(
    GrayView<'a>,
    u8,
    usize,
    &'a mut FastScratch,
    &'a mut Vec<Corner>,
);

impl simd::Kernel for Fast9<'_> {
    type Output = ();

    #[inline(always)]
    fn run(self) {
        fast9_in(self.0, self.1, self.2, self.3, self.4);
    }
}

/// [`fast9`], inlined into each instruction set's compilation.
#[inline(always)]
fn fast9_in(
    img: GrayView<'_>,
    threshold: u8,
    border: usize,
    scratch: &mut FastScratch,
    out: &mut Vec<Corner>,
) {
    let (w, h) = (img.width, img.height);
    let border = border.max(3);
    out.clear();
    if w <= 2 * border || h <= 2 * border {
        return;
    }
    let FastScratch {
        scores,
        scores_zero,
        candidates,
        pass,
    } = scratch;
    // All zeros, cleared only when a call did not finish.
    if !*scores_zero {
        scores.clear();
    }
    scores.resize(w * h, 0);
    *scores_zero = false;
    let d = img.data;
    candidates.clear();
    // The corners found so far are `candidates[..count]`; the vector is kept 8 longer
    // than that, as slots for the next chunk's.
    let mut count = 0;
    let (x0, n) = (border, w - 2 * border);
    pass.clear();
    pass.resize(n, 0);
    for y in border..h - border {
        // Quick rejection: an arc of 9 of the 16 circle points covers 4 or 5
        // consecutive even points (every other one, clockwise from the top) and 4 or 5
        // consecutive odd ones, all on the arc's side. Over the whole row first, on
        // slices of one length (no bounds checks, vectorised).
        let row = |dy: isize, dx: isize| {
            let start = (y as isize + dy) as usize * w + (x0 as isize + dx) as usize;
            &d[start..][..n]
        };
        let (p0, p2, p4, p6) = (row(-3, 0), row(-2, 2), row(0, 3), row(2, 2));
        let (p8, p10, p12, p14) = (row(3, 0), row(2, -2), row(0, -3), row(-2, -2));
        let (p1, p3, p5, p7) = (row(-3, 1), row(-1, 3), row(1, 3), row(3, 1));
        let (p9, p11, p13, p15) = (row(3, -1), row(1, -3), row(-1, -3), row(-3, -1));
        let mid = row(0, 0);
        let pass = &mut pass[..n];
        for k in 0..n {
            let c = mid[k];
            let hi8 = c.saturating_add(threshold);
            let lo8 = c.saturating_sub(threshold);
            let even = [p0[k], p2[k], p4[k], p6[k], p8[k], p10[k], p12[k], p14[k]];
            let odd = [p1[k], p3[k], p5[k], p7[k], p9[k], p11[k], p13[k], p15[k]];
            let bright = run4(even, |p| p > hi8) & run4(odd, |p| p > hi8);
            let dark = run4(even, |p| p < lo8) & run4(odd, |p| p < lo8);
            pass[k] = u8::from(bright | dark);
        }
        // The pixels that passed, eight flags at a time (most of a row fails): each flag
        // is 0 or 1, one bit of its byte, cleared in turn lowest first (raster order).
        // Without a branch on the full test (it is unpredictable): every pixel that
        // passed is scored, a score of 0 written for one that is no corner (as the
        // cleared buffer holds), and kept by advancing the count of `found`.
        let chunks = pass.chunks_exact(8);
        let last = (n - chunks.remainder().len(), chunks.remainder());
        for (base, flags) in (0..n).step_by(8).zip(chunks).chain(std::iter::once(last)) {
            // Little-endian: flag j in byte j (no call to copy a slice of unknown length).
            let mut word = flags
                .iter()
                .rev()
                .fold(0u64, |w, &f| (w << 8) | u64::from(f));
            if word == 0 {
                continue;
            }
            if candidates.len() < count + 8 {
                candidates.resize(
                    count + 8,
                    Corner {
                        x: 0,
                        y: 0,
                        score: 0,
                    },
                );
            }
            let found = &mut candidates[count..count + 8];
            let mut kept = 0;
            while word != 0 {
                let k = base + (word.trailing_zeros() / 8) as usize;
                word &= word - 1;
                let x = x0 + k;
                let c = mid[k];
                let hi8 = c.saturating_add(threshold);
                let lo8 = c.saturating_sub(threshold);
                // The circle, clockwise from the top, from the row slices above.
                let ring = [
                    p0[k], p1[k], p2[k], p3[k], p4[k], p5[k], p6[k], p7[k], p8[k], p9[k], p10[k],
                    p11[k], p12[k], p13[k], p14[k], p15[k],
                ];
                // The sides as flags (one byte each, 0 or 1), packed into 16-bit masks,
                // point `j` in bit `j`.
                let (mut above, mut below) = ([0u8; 16], [0u8; 16]);
                let (mut sb, mut sd) = (0u32, 0u32);
                for ((a, b), &p) in above.iter_mut().zip(&mut below).zip(&ring) {
                    *a = u8::from(p > hi8);
                    *b = u8::from(p < lo8);
                    sb += u32::from(p.saturating_sub(hi8));
                    sd += u32::from(lo8.saturating_sub(p));
                }
                let mask = |flags: &[u8; 16]| {
                    u32::from(pack_bits(&flags[..8])) | u32::from(pack_bits(&flags[8..])) << 8
                };
                let (bright, dark) = (mask(&above), mask(&below));
                let (is_bright, is_dark) = (has_run9(bright), has_run9(dark));
                let score = match (is_bright, is_dark) {
                    (true, true) => sb.max(sd),
                    (true, false) => sb,
                    _ => sd,
                };
                let corner = is_bright | is_dark;
                let s = u16::from(corner) * score.clamp(1, u32::from(u16::MAX)) as u16;
                scores[y * w + x] = s;
                found[kept & 7] = Corner { x, y, score: s };
                kept += usize::from(corner);
            }
            count += kept;
        }
    }
    candidates.truncate(count);
    for &c in candidates.iter() {
        let i = c.y * w + c.x;
        let s = c.score;
        // Strictly greater than the neighbours before it, at least the ones after: one
        // winner per plateau.
        let before = [i - w - 1, i - w, i - w + 1, i - 1];
        let after = [i + 1, i + w - 1, i + w, i + w + 1];
        if before.iter().all(|&j| scores[j] < s) && after.iter().all(|&j| scores[j] <= s) {
            out.push(c);
        }
    }
    // The only nonzero scores are the candidates': back to all zeros.
    for c in candidates.iter() {
        scores[c.y * w + c.x] = 0;
    }
    *scores_zero = true;
}

/// Harris corner response `det(M) - 0.04 trace(M)^2` of the structure tensor summed over
/// a 7x7 window at `(x, y)`, with central-difference gradients (intensity units / 255).
/// The caller keeps the window and its gradients inside the image (4 pixels).
#[must_use]
#[inline(always)]
pub fn harris(img: GrayView<'_>, x: usize, y: usize) -> f32 {
    let w = img.width;
    let d = img.data;
    let (mut sxx, mut syy, mut sxy) = (0f32, 0f32, 0f32);
    for yy in y - 3..=y + 3 {
        // The window's row with a pixel either side, and the rows above and below.
        let here = &d[yy * w + x - 4..][..9];
        let above = &d[(yy - 1) * w + x - 3..][..7];
        let below = &d[(yy + 1) * w + x - 3..][..7];
        for k in 0..7 {
            let gx = f32::from(here[k + 2]) - f32::from(here[k]);
            let gy = f32::from(below[k]) - f32::from(above[k]);
            sxx += gx * gx;
            syy += gy * gy;
            sxy += gx * gy;
        }
    }
    let scale = 1.0 / (255.0 * 255.0 * 49.0);
    let (sxx, syy, sxy) = (sxx * scale, syy * scale, sxy * scale);
    sxx * syy - sxy * sxy - 0.04 * (sxx + syy) * (sxx + syy)
}

/// Half-widths of the rows of a disc of radius `r` pixels: `u_max[v]` for `v = 0..=r`.
#[must_use]
pub fn disc_half_widths(r: usize) -> Vec<usize> {
    (0..=r)
        .map(|v| {
            let rr = (r * r) as f64 + 0.25 * r as f64;
            ((rr - (v * v) as f64).max(0.0)).sqrt().floor() as usize
        })
        .collect()
}

/// Orientation of the intensity centroid over the disc given by `u_max` around
/// `(x, y)`: `atan2(m01, m10)` radians, image axes (x right, y down). The caller keeps
/// the disc inside the image.
#[must_use]
#[inline(always)]
pub fn centroid_angle(img: GrayView<'_>, x: usize, y: usize, u_max: &[usize]) -> f32 {
    let w = img.width as isize;
    let d = img.data;
    let c = (y * img.width + x) as isize;
    let (mut m10, mut m01) = (0i64, 0i64);
    let r = u_max.len() as isize - 1;
    for u in -r..=r {
        m10 += i64::from(u as i32) * i64::from(d[(c + u) as usize]);
    }
    for v in 1..=r {
        let um = u_max[v as usize] as isize;
        let mut vsum = 0i64;
        for u in -um..=um {
            let below = i64::from(d[(c + v * w + u) as usize]);
            let above = i64::from(d[(c - v * w + u) as usize]);
            vsum += below - above;
            m10 += i64::from(u as i32) * (below + above);
        }
        m01 += v as i64 * vsum;
    }
    (m01 as f32).atan2(m10 as f32)
}

#[cfg(test)]
mod tests {
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
}
