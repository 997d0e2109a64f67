//! Steered (rotated) BRIEF: 256 intensity comparisons on a smoothed image over a fixed
//! test pattern, rotated to the keypoint orientation in 30 discrete steps.

use super::pack_bits;
use crate::features::{BinaryDescriptor, GrayView};

mod upright;

/// Radius of the disc holding every test point, pixels. A rotated point stays within
/// `PATTERN_RADIUS + 1` of the keypoint.
pub const PATTERN_RADIUS: f64 = 13.0;

/// Number of discrete orientations of the rotated pattern (12 degrees each).
pub const ANGLE_STEPS: usize = 30;

/// Seed of the fixed test pattern. Changing it changes every descriptor.
const PATTERN_SEED: u64 = 0x5157_4152_4d50_4f53;

/// SplitMix64: a tiny fixed generator so the pattern is identical on every build.
fn splitmix(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Uniform in `[0, 1)`.
fn unit(state: &mut u64) -> f64 {
    (splitmix(state) >> 11) as f64 / (1u64 << 53) as f64
}

/// The 256 test pairs `((x1, y1), (x2, y2))`, pixels relative to the keypoint: both
/// points isotropic Gaussian with σ = 31/5 (BRIEF's G II for a 31-pixel patch), drawn
/// from a fixed seed and kept inside [`PATTERN_RADIUS`].
#[must_use]
pub fn test_pattern() -> Vec<[(f64, f64); 2]> {
    let mut s = PATTERN_SEED;
    let sigma = 31.0 / 5.0;
    let point = |s: &mut u64| loop {
        // Box-Muller.
        let (u1, u2) = (unit(s).max(1e-12), unit(s));
        let r = (-2.0 * u1.ln()).sqrt() * sigma;
        let (x, y) = (
            r * (std::f64::consts::TAU * u2).cos(),
            r * (std::f64::consts::TAU * u2).sin(),
        );
        if x * x + y * y <= PATTERN_RADIUS * PATTERN_RADIUS {
            return (x, y);
        }
    };
    (0..256)
        .map(|_| {
            loop {
                let a = point(&mut s);
                let b = point(&mut s);
                // Identical rounded points would give a constant bit.
                if (a.0.round(), a.1.round()) != (b.0.round(), b.1.round()) {
                    return [a, b];
                }
            }
        })
        .collect()
}

/// Half the side of the square holding every rotated test point, pixels.
const SPAN: usize = PATTERN_RADIUS as usize + 1;

/// Side of the square holding every rotated test point, pixels.
const SIDE: usize = 2 * SPAN + 1;

/// Row stride of a [`Square`], bytes: one row is one 32-byte copy.
const SQUARE_STRIDE: usize = 32;

/// The smoothed pixels around a keypoint, copied for [`RotatedPattern::describe_with`]:
/// row `r` of the image's square of side `2 SPAN + 1` in row `r`, columns `0..=2 SPAN`
/// (the other bytes are never read). A fixed size, so that the 512 test reads need no
/// bounds check; reused from one keypoint to the next.
#[derive(Debug, Clone)]
pub struct Square([u8; SQUARE_STRIDE * SQUARE_STRIDE]);

impl Default for Square {
    fn default() -> Self {
        Self([0; SQUARE_STRIDE * SQUARE_STRIDE])
    }
}

impl Square {
    /// Copies the square of side `2 SPAN + 1` whose top-left pixel is at `start` in `data`
    /// (rows `width` apart); `false` when it does not fit in `data`. Rows are copied 32
    /// bytes at a time (the last one 29): the bytes past column `2 SPAN` are never read.
    #[inline(always)]
    fn fill(&mut self, data: &[u8], width: usize, start: usize) -> bool {
        let Some(mut rest) = data.get(start..=start + 2 * SPAN * (width + 1)) else {
            return false;
        };
        let (rows, last) = self.0.split_at_mut((SIDE - 1) * SQUARE_STRIDE);
        for row in rows.chunks_exact_mut(SQUARE_STRIDE) {
            // Only an image narrower than 3 pixels lacks the 3 bytes after a row.
            let Some(src) = rest.get(..SQUARE_STRIDE) else {
                return false;
            };
            row.copy_from_slice(src);
            rest = rest.get(width..).unwrap_or_default();
        }
        match (last.get_mut(..SIDE), rest.get(..SIDE)) {
            (Some(dst), Some(src)) => {
                dst.copy_from_slice(src);
                true
            }
            _ => false,
        }
    }
}

/// The pattern rotated to each of [`ANGLE_STEPS`] orientations, as offsets into a
/// [`Square`] (`row * 32 + column`, below 1024): `first[step][k]` and `second[step][k]`
/// are the two points of test `k`. Independent of the image (1 KiB a step).
#[derive(Debug, Clone)]
pub struct RotatedPattern {
    first: Vec<[u16; 256]>,
    second: Vec<[u16; 256]>,
}

impl Default for RotatedPattern {
    fn default() -> Self {
        Self::new()
    }
}

impl RotatedPattern {
    /// Builds the rotated offsets.
    #[must_use]
    pub fn new() -> Self {
        let pattern = test_pattern();
        let (mut first, mut second) = (Vec::new(), Vec::new());
        for step in 0..ANGLE_STEPS {
            let a = step as f64 * std::f64::consts::TAU / ANGLE_STEPS as f64;
            let (s, c) = a.sin_cos();
            let mut o = [[0u16; 256]; 2];
            for (k, pair) in pattern.iter().enumerate() {
                for (j, &(x, y)) in pair.iter().enumerate() {
                    let xr = (c * x - s * y).round() as i64 + SPAN as i64;
                    let yr = (s * x + c * y).round() as i64 + SPAN as i64;
                    // Within `0..=2 SPAN` already (the points are inside PATTERN_RADIUS,
                    // and rounding moves them by less than a pixel): the clamp changes no
                    // offset (`offsets_are_the_rotated_pattern`), it only keeps every one
                    // inside the square whatever the pattern.
                    let (xr, yr) = (xr.clamp(0, 2 * SPAN as i64), yr.clamp(0, 2 * SPAN as i64));
                    o[j][k] = (yr as u16) * SQUARE_STRIDE as u16 + xr as u16;
                }
            }
            first.push(o[0]);
            second.push(o[1]);
        }
        Self { first, second }
    }

    /// Descriptor at `(x, y)` (pixels) for orientation `angle` (radians) on the smoothed
    /// image `smooth`; bit `k` is set when test point 1 is darker than test point 2. The
    /// caller keeps `(x, y)` at least `PATTERN_RADIUS + 1` pixels from every edge (a
    /// point nearer the top or bottom, or in an image narrower than 3 pixels, gets an
    /// all-zero descriptor; one nearer the left or right reads the neighbouring rows).
    #[must_use]
    pub fn describe(
        &self,
        smooth: GrayView<'_>,
        x: usize,
        y: usize,
        angle: f32,
    ) -> BinaryDescriptor {
        self.describe_with(smooth, x, y, angle, &mut Square::default())
    }

    /// [`RotatedPattern::describe`] with the pixels copied into `square` (reused between
    /// calls: nothing of it is read before it is written).
    #[must_use]
    #[inline(always)]
    pub fn describe_with(
        &self,
        smooth: GrayView<'_>,
        x: usize,
        y: usize,
        angle: f32,
        square: &mut Square,
    ) -> BinaryDescriptor {
        let turns = angle / std::f32::consts::TAU;
        let step = ((turns - turns.floor()) * ANGLE_STEPS as f32).round() as usize % ANGLE_STEPS;
        let mut out = [0u8; 32];
        let (Some(first), Some(second)) = (self.first.get(step), self.second.get(step)) else {
            return BinaryDescriptor(out);
        };
        // The square around the keypoint (inside the image: the caller's promise).
        let start = y
            .checked_sub(SPAN)
            .and_then(|top| (top * smooth.width + x).checked_sub(SPAN));
        if !start.is_some_and(|s| square.fill(smooth.data, smooth.width, s)) {
            return BinaryDescriptor(out);
        }
        let d = &square.0;
        // The 256 comparisons (one byte each, 0 or 1), then packed eight to a byte.
        let mut darker = [0u8; 256];
        if step == 0 {
            // The same offsets as constants (the default, upright descriptor).
            upright::compare(d, &mut darker);
        } else {
            for ((t, &p), &q) in darker.iter_mut().zip(first).zip(second) {
                *t = u8::from(d[usize::from(p) & 1023] < d[usize::from(q) & 1023]);
            }
        }
        for (byte, eight) in out.iter_mut().zip(darker.chunks_exact(8)) {
            *byte = pack_bits(eight);
        }
        BinaryDescriptor(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`RotatedPattern::describe`] against the rotated pattern read pixel by pixel, at
    /// every 7th column of every row where the square fits, at many angles.
    #[test]
    fn describe_is_its_definition() {
        let (w, h) = (97usize, 73usize);
        let img = crate::test_noise::noise_bytes(w * h, 7);
        let view = GrayView {
            width: w,
            height: h,
            data: &img,
        };
        let (pattern, tests) = (RotatedPattern::new(), test_pattern());
        let mut checked = 0;
        for y in SPAN..h - SPAN {
            for x in (SPAN..w - SPAN).step_by(7) {
                let angle = (x * 31 + y * 17) as f32 * 0.01 - 3.0;
                let turns = angle / std::f32::consts::TAU;
                let step =
                    ((turns - turns.floor()) * ANGLE_STEPS as f32).round() as usize % ANGLE_STEPS;
                let a = step as f64 * std::f64::consts::TAU / ANGLE_STEPS as f64;
                let (sn, cs) = a.sin_cos();
                let at = |(px, py): (f64, f64)| {
                    let xr = (cs * px - sn * py).round() as isize;
                    let yr = (sn * px + cs * py).round() as isize;
                    img[((y as isize + yr) * w as isize + x as isize + xr) as usize]
                };
                let mut want = [0u8; 32];
                for (k, [p, q]) in tests.iter().enumerate() {
                    want[k / 8] |= u8::from(at(*p) < at(*q)) << (k % 8);
                }
                assert_eq!(pattern.describe(view, x, y, angle).0, want, "({x}, {y})");
                checked += 1;
            }
        }
        assert!(checked > 400, "{checked}");
    }

    /// The offsets of the descriptor as computed before the square copy (issue 34): into
    /// the image itself, of row stride `w`.
    fn offsets_in_image(w: usize) -> Vec<[u32; 512]> {
        (0..ANGLE_STEPS)
            .map(|step| {
                let a = step as f64 * std::f64::consts::TAU / ANGLE_STEPS as f64;
                let (s, c) = a.sin_cos();
                let mut o = [0u32; 512];
                for (k, pair) in test_pattern().iter().enumerate() {
                    for (j, &(x, y)) in pair.iter().enumerate() {
                        let xr = (c * x - s * y).round() as i64 + SPAN as i64;
                        let yr = (s * x + c * y).round() as i64 + SPAN as i64;
                        o[2 * k + j] = u32::try_from(yr * w as i64 + xr).unwrap_or(u32::MAX);
                    }
                }
                o
            })
            .collect()
    }

    /// The descriptor as computed before the square copy, from [`offsets_in_image`]:
    /// each read from the image bounds-checked.
    fn describe_in_image(
        offsets: &[[u32; 512]],
        smooth: GrayView<'_>,
        x: usize,
        y: usize,
        angle: f32,
    ) -> [u8; 32] {
        let w = smooth.width;
        let turns = angle / std::f32::consts::TAU;
        let step = ((turns - turns.floor()) * ANGLE_STEPS as f32).round() as usize % ANGLE_STEPS;
        let o = &offsets[step];
        let mut out = [0u8; 32];
        let start = y
            .checked_sub(SPAN)
            .and_then(|top| (top * w + x).checked_sub(SPAN));
        let Some(d) = start.and_then(|s| smooth.data.get(s..=s + 2 * SPAN * (w + 1))) else {
            return out;
        };
        for (byte, chunk) in out.iter_mut().zip(o.chunks_exact(16)) {
            let mut b = 0u8;
            for bit in 0..8 {
                let p = d[chunk[2 * bit] as usize];
                let q = d[chunk[2 * bit + 1] as usize];
                b |= u8::from(p < q) << bit;
            }
            *byte = b;
        }
        out
    }

    /// [`RotatedPattern::describe_with`] gives the descriptor read from the image itself,
    /// byte for byte: at every pixel of seeded random images (the edges included, where
    /// both give all zeros or read the rows' neighbours), at every angle step, with one
    /// square reused from call to call (filled with noise first).
    #[test]
    fn describe_is_the_describe_in_the_image() {
        let pattern = RotatedPattern::new();
        let mut square = Square::default();
        let noise = crate::test_noise::noise_bytes(square.0.len(), 99);
        square.0.copy_from_slice(&noise);
        let mut checked = [0usize; 2];
        for (w, h, seed) in [
            (3, 40, 1),
            (29, 31, 2),
            (30, 33, 3),
            (31, 29, 4),
            (64, 45, 5),
        ] {
            let img = crate::test_noise::noise_bytes(w * h, seed);
            let offsets = offsets_in_image(w);
            let view = GrayView {
                width: w,
                height: h,
                data: &img,
            };
            for step in 0..ANGLE_STEPS {
                // On the step, and either side of the rounding between two steps.
                let centre = step as f32 * std::f32::consts::TAU / ANGLE_STEPS as f32;
                let half = 0.5 * std::f32::consts::TAU / ANGLE_STEPS as f32;
                for angle in [centre, centre + half * 0.999, centre - half * 1.001 - 12.0] {
                    for y in 0..h {
                        for x in 0..w {
                            let want = describe_in_image(&offsets, view, x, y, angle);
                            let got = pattern.describe_with(view, x, y, angle, &mut square);
                            assert_eq!(got.0, want, "{w}x{h} ({x}, {y}) angle {angle}");
                            checked[usize::from(want != [0; 32])] += 1;
                        }
                    }
                }
            }
        }
        // Both kinds: squares outside the image, and real descriptors.
        assert!(checked[0] > 1000 && checked[1] > 10_000, "{checked:?}");
    }

    /// The clamp in [`RotatedPattern::new`] changes no offset: every rotated point is
    /// inside the square.
    #[test]
    fn offsets_are_the_rotated_pattern() {
        let pattern = RotatedPattern::new();
        for step in 0..ANGLE_STEPS {
            let a = step as f64 * std::f64::consts::TAU / ANGLE_STEPS as f64;
            let (s, c) = a.sin_cos();
            for (k, pair) in test_pattern().iter().enumerate() {
                for (j, &(x, y)) in pair.iter().enumerate() {
                    let xr = (c * x - s * y).round() as i64 + SPAN as i64;
                    let yr = (s * x + c * y).round() as i64 + SPAN as i64;
                    assert!((0..SIDE as i64).contains(&xr) && (0..SIDE as i64).contains(&yr));
                    let o = [pattern.first[step][k], pattern.second[step][k]][j];
                    assert_eq!(i64::from(o), yr * SQUARE_STRIDE as i64 + xr);
                }
            }
        }
    }

    /// The constant offsets of the upright pattern are the rotated pattern's first step.
    #[test]
    fn upright_is_the_first_step() {
        let pattern = RotatedPattern::new();
        assert_eq!(pattern.first[0], upright::FIRST);
        assert_eq!(pattern.second[0], upright::SECOND);
    }

    #[test]
    fn pattern_is_fixed_and_inside() {
        let a = test_pattern();
        assert_eq!(a, test_pattern());
        assert_eq!(a.len(), 256);
        for pair in &a {
            for &(x, y) in pair {
                assert!(x * x + y * y <= PATTERN_RADIUS * PATTERN_RADIUS);
            }
        }
    }
}
