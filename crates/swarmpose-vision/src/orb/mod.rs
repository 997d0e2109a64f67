//! ORB-style binary features: FAST-9 corners ranked by the Harris response, oriented
//! by the intensity centroid, bucketed over the image, and described by steered BRIEF
//! on a smoothed image (Rublee et al. 2011, single scale).
//!
//! Single scale is enough between consecutive video frames and across a rectified
//! stereo pair; use SURF for large scale changes.

pub mod brief;
pub mod fast;

use std::sync::{Mutex, TryLockError};

use crate::bucketing::{BucketConfig, BucketScratch, bucket_indices_into};
use crate::features::{BinaryDescriptor, FeatureExtractor, Features, GrayView, Keypoint};
use crate::image::blur5;
use crate::simd;

use brief::{PATTERN_RADIUS, RotatedPattern, Square};
use fast::{Corner, FastScratch, centroid_angle, disc_half_widths, fast9, harris};

/// Radius of the orientation disc, pixels (ORB's half patch size).
pub const ORIENTATION_RADIUS: usize = 15;

/// Settings of [`OrbExtractor`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
pub struct OrbConfig {
    /// FAST intensity threshold, gray levels (default 20).
    pub fast_threshold: u8,
    /// Bucketing of the detected corners (by Harris response); `None` keeps all.
    pub bucketing: Option<BucketConfig>,
    /// Most features overall after bucketing, strongest first (default 4000).
    pub max_features: usize,
    /// Orient the descriptor by the intensity centroid (ORB); `false` gives upright
    /// BRIEF, which is more distinctive when the camera does not roll (default true).
    pub oriented: bool,
}

impl Default for OrbConfig {
    fn default() -> Self {
        Self {
            fast_threshold: 20,
            bucketing: Some(BucketConfig::default()),
            max_features: 4000,
            oriented: true,
        }
    }
}

/// The fast binary detector/descriptor.
#[derive(Debug, Clone, Default)]
pub struct OrbExtractor {
    /// Settings.
    pub config: OrbConfig,
    buffers: Buffers,
}

/// The detector's and descriptor's working memory: FAST scores and corners, the
/// keypoints before bucketing, the smoothed image and the rotated test pattern.
#[derive(Default)]
struct Scratch {
    fast: FastScratch,
    corners: Vec<Corner>,
    keypoints: Vec<Keypoint>,
    bucket: BucketScratch,
    kept: Vec<usize>,
    blur: Vec<u16>,
    smooth: Vec<u8>,
    pattern: Option<RotatedPattern>,
}

/// [`Scratch`] kept by an extractor between images, so that extracting allocates little
/// more than its results. A call made while another thread uses them works in buffers of
/// its own (an extractor shared between threads never waits). A clone starts empty.
#[derive(Default)]
struct Buffers(Mutex<Scratch>);

impl Buffers {
    fn with<R>(&self, f: impl FnOnce(&mut Scratch) -> R) -> R {
        match self.0.try_lock() {
            Ok(mut s) => f(&mut s),
            // Every use starts by clearing what it uses: a panic's leftovers do no harm.
            Err(TryLockError::Poisoned(p)) => f(&mut p.into_inner()),
            Err(TryLockError::WouldBlock) => f(&mut Scratch::default()),
        }
    }
}

impl Clone for Buffers {
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl std::fmt::Debug for Buffers {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Buffers")
    }
}

/// Distance of keypoints from every edge, pixels: the orientation disc and the rotated
/// test pattern stay inside.
pub const BORDER: usize = {
    let p = PATTERN_RADIUS as usize + 2;
    if p > ORIENTATION_RADIUS + 1 {
        p
    } else {
        ORIENTATION_RADIUS + 1
    }
};

impl OrbExtractor {
    /// An extractor with these settings.
    #[must_use]
    pub fn new(config: OrbConfig) -> Self {
        Self {
            config,
            buffers: Buffers::default(),
        }
    }

    /// Detection: FAST-9 corners, Harris response, bucketing, cap, orientation.
    /// Keypoints are at integer pixels, [`BORDER`] away from every edge.
    #[must_use]
    pub fn detect(&self, image: GrayView<'_>) -> Vec<Keypoint> {
        self.buffers
            .with(|s| simd::dispatch(Detect(self, image, s)))
    }

    #[inline(always)]
    fn detect_in(&self, image: GrayView<'_>, s: &mut Scratch) -> Vec<Keypoint> {
        fast9(
            image,
            self.config.fast_threshold,
            BORDER,
            &mut s.fast,
            &mut s.corners,
        );
        let rank = self.config.bucketing.is_some() || s.corners.len() > self.config.max_features;
        let keypoint = |c: &Corner| Keypoint {
            x: c.x as f32,
            y: c.y as f32,
            scale: ORIENTATION_RADIUS as f32,
            angle: 0.0,
            // Harris only ranks corners for bucketing and the cap.
            response: if rank {
                harris(image, c.x, c.y)
            } else {
                f32::from(c.score)
            },
            octave: 0,
        };
        let mut kps: Vec<Keypoint> = match &self.config.bucketing {
            Some(b) => {
                s.keypoints.clear();
                // A loop, not an iterator's fold: compiled inside this dispatched kernel.
                for c in &s.corners {
                    s.keypoints.push(keypoint(c));
                }
                let size = (image.width, image.height);
                bucket_indices_into(&s.keypoints, size, b, &mut s.bucket, &mut s.kept);
                s.kept.iter().map(|&i| s.keypoints[i]).collect()
            }
            None => s.corners.iter().map(keypoint).collect(),
        };
        if kps.len() > self.config.max_features {
            kps.sort_by(|a, b| b.response.total_cmp(&a.response));
            kps.truncate(self.config.max_features);
            kps.sort_by(|a, b| {
                (a.y, a.x)
                    .partial_cmp(&(b.y, b.x))
                    .unwrap_or(std::cmp::Ordering::Equal)
            });
        }
        if self.config.oriented {
            let u_max = disc_half_widths(ORIENTATION_RADIUS);
            for k in &mut kps {
                k.angle = centroid_angle(image, k.x as usize, k.y as usize, &u_max);
            }
        }
        kps
    }

    /// Description: smooth the image, then steered BRIEF at each keypoint (rounded to
    /// the nearest pixel). Keypoints from [`OrbExtractor::detect`] are all described;
    /// any closer than [`BORDER`] to an edge get an all-zero descriptor.
    #[must_use]
    pub fn describe(&self, image: GrayView<'_>, keypoints: &[Keypoint]) -> Vec<BinaryDescriptor> {
        self.buffers
            .with(|s| simd::dispatch(Describe(image, keypoints, s)))
    }
}

/// The first 8 bytes of `flags` (each 0 or 1) as the bits of one byte, flag `j` in bit
/// `j`: one multiplication puts flag `j` (bit `8 j` of the little-endian word) in bit
/// `56 + j`, with no carry (every partial product is a distinct power of two).
#[inline(always)]
fn pack_bits(flags: &[u8]) -> u8 {
    let mut word = [0u8; 8];
    for (w, &f) in word.iter_mut().zip(flags) {
        *w = f;
    }
    (u64::from_le_bytes(word).wrapping_mul(0x0102_0408_1020_4080) >> 56) as u8
}

/// A call of [`OrbExtractor::detect`] for [`simd::dispatch`].
struct Detect<'a>(&'a OrbExtractor, GrayView<'a>, &'a mut Scratch);

impl simd::Kernel for Detect<'_> {
    type Output = Vec<Keypoint>;

    #[inline(always)]
    fn run(self) -> Vec<Keypoint> {
        self.0.detect_in(self.1, self.2)
    }
}

/// A call of [`OrbExtractor::describe`] for [`simd::dispatch`].
struct Describe<'a>(GrayView<'a>, &'a [Keypoint], &'a mut Scratch);

impl simd::Kernel for Describe<'_> {
    type Output = Vec<BinaryDescriptor>;

    #[inline(always)]
    fn run(self) -> Vec<BinaryDescriptor> {
        describe_in(self.0, self.1, self.2)
    }
}

/// [`OrbExtractor::describe`] in the buffers `s`.
#[inline(always)]
fn describe_in(
    image: GrayView<'_>,
    keypoints: &[Keypoint],
    s: &mut Scratch,
) -> Vec<BinaryDescriptor> {
    blur5(image, &mut s.blur, &mut s.smooth);
    let view = GrayView {
        width: image.width,
        height: image.height,
        data: &s.smooth,
    };
    // The pattern's offsets are into a copy of the keypoint's square: built once.
    let pattern = s.pattern.get_or_insert_with(RotatedPattern::new);
    let mut square = Square::default();
    let inside = |k: &Keypoint| {
        let (x, y) = (k.x.round(), k.y.round());
        x >= BORDER as f32
            && y >= BORDER as f32
            && x + (BORDER as f32) < image.width as f32
            && y + (BORDER as f32) < image.height as f32
    };
    // A loop, not an iterator's fold: compiled inside this dispatched kernel.
    let mut out = Vec::with_capacity(keypoints.len());
    for k in keypoints {
        out.push(if inside(k) {
            let (x, y) = (k.x.round() as usize, k.y.round() as usize);
            pattern.describe_with(view, x, y, k.angle, &mut square)
        } else {
            // Too close to the border for the pattern: an all-zero descriptor (rarely
            // the nearest neighbour of anything real).
            BinaryDescriptor([0; 32])
        });
    }
    out
}

impl FeatureExtractor for OrbExtractor {
    type Descriptor = BinaryDescriptor;

    fn name(&self) -> &'static str {
        "orb"
    }

    fn extract(&self, image: GrayView<'_>) -> Features<BinaryDescriptor> {
        let keypoints = self.detect(image);
        let descriptors = self.describe(image, &keypoints);
        Features {
            keypoints,
            descriptors,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::Descriptor;

    /// A deterministic blocky texture.
    fn texture(w: usize, h: usize, seed: u32) -> Vec<u8> {
        let cells = crate::test_noise::noise_bytes((w / 4 + 1) * (h / 4 + 1), seed);
        (0..w * h)
            .map(|i| cells[(i / w / 4) * (w / 4 + 1) + (i % w) / 4])
            .collect()
    }

    /// [`pack_bits`] on every byte: flag `j` lands in bit `j`.
    #[test]
    fn pack_bits_is_bit_by_bit() {
        for byte in 0..=255u8 {
            let flags: Vec<u8> = (0..8).map(|j| (byte >> j) & 1).collect();
            assert_eq!(pack_bits(&flags), byte);
        }
    }

    #[test]
    fn shifted_image_gives_the_same_descriptors() {
        let (w, h) = (160, 120);
        let a = texture(w, h, 3);
        let mut b = vec![0u8; w * h];
        for y in 0..h {
            for x in 5..w {
                b[y * w + x] = a[y * w + x - 5];
            }
        }
        let orb = OrbExtractor::default();
        let fa = orb.extract(GrayView {
            width: w,
            height: h,
            data: &a,
        });
        let fb = orb.extract(GrayView {
            width: w,
            height: h,
            data: &b,
        });
        assert!(fa.len() > 50, "{}", fa.len());
        let mut same = 0;
        for (k, d) in fa.keypoints.iter().zip(&fa.descriptors) {
            let j = fb
                .keypoints
                .iter()
                .position(|q| q.x == k.x + 5.0 && q.y == k.y);
            if j.is_some_and(|j| d.distance(&fb.descriptors[j]) == 0.0) {
                same += 1;
            }
        }
        assert!(same > fa.len() / 2, "{same} of {}", fa.len());
    }
}
