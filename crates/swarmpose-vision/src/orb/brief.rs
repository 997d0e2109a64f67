//! Steered (rotated) BRIEF: 256 intensity comparisons on a smoothed image over a fixed
//! test pattern, rotated to the keypoint orientation in 30 discrete steps.

use crate::features::{BinaryDescriptor, GrayView};

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

/// The pattern rotated to each of [`ANGLE_STEPS`] orientations, as offsets into an image
/// of a given row stride (pixels): `offsets[step][2 * k]` and `[2 * k + 1]` are test `k`.
#[derive(Debug, Clone)]
pub struct RotatedPattern {
    stride: usize,
    /// Offsets from the top-left corner of the square of side `2 SPAN + 1` around the
    /// keypoint (non-negative, so a table is 2 KiB: the 30 stay in the first-level cache).
    offsets: Vec<[u32; 512]>,
}

/// Half the side of the square holding every rotated test point, pixels.
const SPAN: usize = PATTERN_RADIUS as usize + 1;

impl RotatedPattern {
    /// Builds the rotated offsets for images `stride` pixels wide.
    #[must_use]
    pub fn new(stride: usize) -> Self {
        let pattern = test_pattern();
        let offsets = (0..ANGLE_STEPS)
            .map(|step| {
                let a = step as f64 * std::f64::consts::TAU / ANGLE_STEPS as f64;
                let (s, c) = a.sin_cos();
                let mut o = [0u32; 512];
                for (k, pair) in pattern.iter().enumerate() {
                    for (j, &(x, y)) in pair.iter().enumerate() {
                        let xr = (c * x - s * y).round() as i64 + SPAN as i64;
                        let yr = (s * x + c * y).round() as i64 + SPAN as i64;
                        // Beyond u32 only for images over 150 million pixels wide: an
                        // offset out of the square, which `describe` refuses by panicking.
                        o[2 * k + j] = u32::try_from(yr * stride as i64 + xr).unwrap_or(u32::MAX);
                    }
                }
                o
            })
            .collect();
        Self { stride, offsets }
    }

    /// Row stride (pixels) the offsets were built for.
    #[must_use]
    pub fn stride(&self) -> usize {
        self.stride
    }

    /// Descriptor at `(x, y)` (pixels) for orientation `angle` (radians) on the smoothed
    /// image `smooth`; bit `k` is set when test point 1 is darker than test point 2. The
    /// caller keeps `(x, y)` at least `PATTERN_RADIUS + 1` pixels from every edge (a
    /// point nearer the top or bottom gets an all-zero descriptor).
    #[must_use]
    #[inline(always)]
    pub fn describe(
        &self,
        smooth: GrayView<'_>,
        x: usize,
        y: usize,
        angle: f32,
    ) -> BinaryDescriptor {
        let turns = angle / std::f32::consts::TAU;
        let step = ((turns - turns.floor()) * ANGLE_STEPS as f32).round() as usize % ANGLE_STEPS;
        let o = &self.offsets[step];
        let w = smooth.width;
        let mut out = [0u8; 32];
        // The square around the keypoint (inside the image: the caller's promise).
        let start = y
            .checked_sub(SPAN)
            .and_then(|top| (top * w + x).checked_sub(SPAN));
        let Some(d) = start.and_then(|s| smooth.data.get(s..=s + 2 * SPAN * (w + 1))) else {
            return BinaryDescriptor(out);
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
        let (pattern, tests) = (RotatedPattern::new(w), test_pattern());
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
