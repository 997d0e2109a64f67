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
#[cfg(test)]
fn has_run9(mask: u32) -> bool {
    let m = mask | (mask << 16);
    let r2 = m & (m >> 1);
    let r4 = r2 & (r2 >> 2);
    let r8 = r4 & (r4 >> 4);
    r8 & (m >> 8) != 0
}

/// [`has_run9`] of `bright` and of `dark` (16 bits each) at once: both masks doubled in
/// the halves of one 64-bit word, and the runs kept only where they start in the first 16
/// bits of a half (they end by bit 23, inside the half).
#[inline(always)]
fn has_run9_both(bright: u32, dark: u32) -> (bool, bool) {
    let (b, d) = (u64::from(bright & 0xffff), u64::from(dark & 0xffff));
    let m = b | (b << 16) | (d << 32) | (d << 48);
    let r2 = m & (m >> 1);
    let r4 = r2 & (r2 >> 2);
    let r8 = r4 & (r4 >> 4);
    let r9 = r8 & (m >> 8) & 0x0000_ffff_0000_ffff;
    (r9 & 0xffff != 0, r9 >> 32 != 0)
}

/// The brightest and the darkest run of 4 circularly consecutive points of 8: the largest
/// minimum and the smallest maximum of the 8 runs (pairs, then pairs of pairs). `side(p)`
/// holds for 4 consecutive points exactly when `min > hi` (`p > hi`) or `max < lo`
/// (`p < lo`) for one run, that is for the brightest or the darkest.
#[inline(always)]
fn runs4(p: [u8; 8]) -> (u8, u8) {
    (runs4_min(p), runs4_max(p))
}

/// The brightest run of 4 of [`runs4`].
#[inline(always)]
fn runs4_min(p: [u8; 8]) -> u8 {
    let at = |i: usize| p[i % 8];
    let pair: [u8; 8] = std::array::from_fn(|i| at(i).min(at(i + 1)));
    (0..8).fold(0, |b, i| b.max(pair[i].min(pair[(i + 2) % 8])))
}

/// The darkest run of 4 of [`runs4`].
#[inline(always)]
fn runs4_max(p: [u8; 8]) -> u8 {
    let at = |i: usize| p[i % 8];
    let pair: [u8; 8] = std::array::from_fn(|i| at(i).max(at(i + 1)));
    (0..8).fold(u8::MAX, |d, i| d.min(pair[i].max(pair[(i + 2) % 8])))
}

/// 1 when 2 consecutive of the compass points (circle points 0, 4, 8 and 12) are both
/// brighter than `c + threshold` or both darker than `c - threshold`, else 0: a pixel
/// without is rejected by [`quick_pass`] too (4 consecutive even points hold 2
/// consecutive compass points).
#[inline(always)]
fn compass_pass(c: u8, threshold: u8, [n, e, s, w]: [u8; 4]) -> u8 {
    let (hi8, lo8) = (c.saturating_add(threshold), c.saturating_sub(threshold));
    let bright = n.min(e).max(e.min(s)).max(s.min(w)).max(w.min(n));
    let dark = n.max(e).min(e.max(s)).min(s.max(w)).min(w.max(n));
    u8::from(bright > hi8) | u8::from(dark < lo8)
}

/// Pixels of a row tested at once by the quick rejection of [`fast9`].
const CHUNK: usize = 32;

/// The quick rejection of [`fast9`] at a pixel of intensity `c`: 1 when a run of 4
/// consecutive even circle points (clockwise from the top) and one of 4 odd ones are all
/// brighter than `c + threshold`, or all darker than `c - threshold` (saturated); else 0.
#[inline(always)]
fn quick_pass(c: u8, threshold: u8, even: [u8; 8], odd: [u8; 8]) -> u8 {
    let (hi8, lo8) = (c.saturating_add(threshold), c.saturating_sub(threshold));
    let ((be, de), (bo, d_o)) = (runs4(even), runs4(odd));
    u8::from((be.min(bo) > hi8) | (de.max(d_o) < lo8))
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
fn fast9_in<'a>(
    img: GrayView<'a>,
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
        // Chunks of 32 pixels (arrays of one length: no remainder loop, no aliasing check),
        // the last one overlapping the one before it when the row is no multiple of 32
        // (its flags written twice, the same); a row narrower than 32 pixel by pixel.
        let whole = n / CHUNK * CHUNK;
        let last = (n > whole && n >= CHUNK).then(|| n - CHUNK);
        for k0 in (0..whole).step_by(CHUNK).chain(last) {
            let chunk = |p: &'a [u8]| -> &'a [u8; CHUNK] {
                p[k0..][..CHUNK].try_into().unwrap_or(&[0; CHUNK])
            };
            let (q0, q2, q4, q6) = (chunk(p0), chunk(p2), chunk(p4), chunk(p6));
            let (q8, q10, q12, q14) = (chunk(p8), chunk(p10), chunk(p12), chunk(p14));
            let (q1, q3, q5, q7) = (chunk(p1), chunk(p3), chunk(p5), chunk(p7));
            let (q9, q11, q13, q15) = (chunk(p9), chunk(p11), chunk(p13), chunk(p15));
            let c = chunk(mid);
            // First the 4 points of the compass (0, 4, 8, 12): 4 consecutive even points
            // hold 2 consecutive of them, so a chunk where no 2 are on one side has no
            // pixel passing (a third of KITTI's chunks).
            let mut any = 0u8;
            for i in 0..CHUNK {
                any |= compass_pass(c[i], threshold, [q0[i], q4[i], q8[i], q12[i]]);
            }
            if any == 0 {
                pass[k0..][..CHUNK].fill(0);
                continue;
            }
            // Bright, then dark (fewer values live at once).
            let (mut brightest, mut darkest) = ([0u8; CHUNK], [0u8; CHUNK]);
            for i in 0..CHUNK {
                let even = [q0[i], q2[i], q4[i], q6[i], q8[i], q10[i], q12[i], q14[i]];
                let odd = [q1[i], q3[i], q5[i], q7[i], q9[i], q11[i], q13[i], q15[i]];
                brightest[i] = runs4_min(even).min(runs4_min(odd));
            }
            for i in 0..CHUNK {
                let even = [q0[i], q2[i], q4[i], q6[i], q8[i], q10[i], q12[i], q14[i]];
                let odd = [q1[i], q3[i], q5[i], q7[i], q9[i], q11[i], q13[i], q15[i]];
                darkest[i] = runs4_max(even).max(runs4_max(odd));
            }
            let mut out = [0u8; CHUNK];
            for i in 0..CHUNK {
                let (hi8, lo8) = (
                    c[i].saturating_add(threshold),
                    c[i].saturating_sub(threshold),
                );
                out[i] = u8::from((brightest[i] > hi8) | (darkest[i] < lo8));
            }
            pass[k0..][..CHUNK].copy_from_slice(&out);
        }
        if n < CHUNK {
            for k in 0..n {
                let even = [p0[k], p2[k], p4[k], p6[k], p8[k], p10[k], p12[k], p14[k]];
                let odd = [p1[k], p3[k], p5[k], p7[k], p9[k], p11[k], p13[k], p15[k]];
                pass[k] = quick_pass(mid[k], threshold, even, odd);
            }
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
                let (is_bright, is_dark) = has_run9_both(bright, dark);
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
///
/// The sums are of integers: each product of two gradients is at most 255², and 49 of them
/// at most 3 186 225, below 2²⁴, so that summing them in `f32` (as this function did until
/// issue 34) is exact in any order and gives the integer sum (never `-0`, starting from
/// `+0`): summed as integers, converted once. Each row is read as [`HARRIS_LANES`]
/// columns whose products are summed in vector registers, all 8: the eighth column's are
/// then subtracted (a mask on it had the compiler sum three columns one by one). Its pixels
/// lie at most 5 past the window's centre, inside the image's buffer (the next row's first
/// pixel at worst).
#[must_use]
#[inline(always)]
pub fn harris(img: GrayView<'_>, x: usize, y: usize) -> f32 {
    let w = img.width;
    let d = img.data;
    let (mut sxx, mut syy) = ([0i32; HARRIS_LANES], [0i32; HARRIS_LANES]);
    let (mut sxy, mut past) = ([0i32; HARRIS_LANES], [0i32; 3]);
    for yy in y - 3..=y + 3 {
        // The window's row with a pixel either side, and the rows above and below.
        let here = &d[yy * w + x - 4..][..HARRIS_LANES + 2];
        let above = &d[(yy - 1) * w + x - 3..][..HARRIS_LANES];
        let below = &d[(yy + 1) * w + x - 3..][..HARRIS_LANES];
        let gradient = |k: usize| {
            (
                i32::from(here[k + 2]) - i32::from(here[k]),
                i32::from(below[k]) - i32::from(above[k]),
            )
        };
        for k in 0..HARRIS_LANES {
            let (gx, gy) = gradient(k);
            sxx[k] += gx * gx;
            syy[k] += gy * gy;
            sxy[k] += gx * gy;
        }
        let (gx, gy) = gradient(7);
        past[0] += gx * gx;
        past[1] += gy * gy;
        past[2] += gx * gy;
    }
    let total = |s: [i32; HARRIS_LANES], p: i32| s.iter().sum::<i32>() - p;
    let (sxx, syy, sxy) = (
        total(sxx, past[0]),
        total(syy, past[1]),
        total(sxy, past[2]),
    );
    let scale = 1.0 / (255.0 * 255.0 * 49.0);
    let (sxx, syy, sxy) = (sxx as f32 * scale, syy as f32 * scale, sxy as f32 * scale);
    sxx * syy - sxy * sxy - 0.04 * (sxx + syy) * (sxx + syy)
}

/// Columns of a row of [`harris`]'s window read at once (7 and one subtracted).
const HARRIS_LANES: usize = 8;

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
mod tests;
