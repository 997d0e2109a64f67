//! Feature detection and description behind one trait.
//!
//! Image coordinates are in pixels with the origin at the centre of the top-left pixel,
//! `x` to the right (column) and `y` down (row).

/// A detected interest point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Keypoint {
    /// Column, pixels (sub-pixel).
    pub x: f32,
    /// Row, pixels (sub-pixel).
    pub y: f32,
    /// Characteristic scale, pixels (for SURF `1.2 * filter size / 9`; for a
    /// single-scale corner the patch radius).
    pub scale: f32,
    /// Orientation, radians, `atan2(dy, dx)` in image coordinates: measured from `+x`
    /// towards `+y` (clockwise on screen, since `y` points down); 0 for upright
    /// (non-oriented) features.
    pub angle: f32,
    /// Detector response: larger is stronger.
    pub response: f32,
    /// Pyramid octave (or 0 for single-scale detectors).
    pub octave: u8,
}

/// A feature descriptor with a distance between two of them (smaller is more alike).
pub trait Descriptor: Clone + Send + Sync + 'static {
    /// Distance between descriptors: Hamming distance for binary descriptors, Euclidean
    /// for real-valued ones.
    fn distance(&self, other: &Self) -> f32;

    /// The distances to each of `others` into `out` (`out[k]` that to `others[k]`, as
    /// [`Descriptor::distance`] gives it; the shorter of the two slices counts). For a
    /// search's candidates at once: descriptors that can compute several at a time do.
    #[inline(always)]
    fn distances(&self, others: &[Self], out: &mut [f32]) {
        for (o, d) in others.iter().zip(out) {
            *d = self.distance(o);
        }
    }
}

/// A 256-bit binary descriptor (ORB/BRIEF style); distance = Hamming.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BinaryDescriptor(pub [u8; 32]);

impl Descriptor for BinaryDescriptor {
    #[inline(always)]
    fn distance(&self, other: &Self) -> f32 {
        // Four 64-bit words: one popcount each.
        let mut n = 0u32;
        for (a, b) in self.0.chunks_exact(8).zip(other.0.chunks_exact(8)) {
            let mut wa = [0u8; 8];
            let mut wb = [0u8; 8];
            wa.copy_from_slice(a);
            wb.copy_from_slice(b);
            n += (u64::from_le_bytes(wa) ^ u64::from_le_bytes(wb)).count_ones();
        }
        n as f32
    }

    /// Four 64-bit XORs and population counts per candidate, over a contiguous run of
    /// candidates that the compiler vectorises (with AVX2: byte-table population counts,
    /// several candidates at a time); the same integers as [`Descriptor::distance`].
    #[inline(always)]
    fn distances(&self, others: &[Self], out: &mut [f32]) {
        let a = self.words();
        for (o, d) in others.iter().zip(out) {
            let b = o.words();
            let n = (a[0] ^ b[0]).count_ones()
                + (a[1] ^ b[1]).count_ones()
                + (a[2] ^ b[2]).count_ones()
                + (a[3] ^ b[3]).count_ones();
            *d = n as f32;
        }
    }
}

impl BinaryDescriptor {
    /// The 256 bits as four little-endian 64-bit words.
    #[inline(always)]
    fn words(&self) -> [u64; 4] {
        let w = |k: usize| {
            let mut b = [0u8; 8];
            b.copy_from_slice(&self.0[8 * k..8 * k + 8]);
            u64::from_le_bytes(b)
        };
        [w(0), w(1), w(2), w(3)]
    }
}

/// A 64-dimensional real descriptor (SURF), unit length; distance = Euclidean.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FloatDescriptor64(pub [f32; 64]);

impl Descriptor for FloatDescriptor64 {
    #[inline]
    fn distance(&self, other: &Self) -> f32 {
        self.0
            .iter()
            .zip(&other.0)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f32>()
            .sqrt()
    }
}

/// Keypoints and their descriptors, index-aligned.
#[derive(Debug, Clone, PartialEq)]
pub struct Features<D> {
    /// The keypoints.
    pub keypoints: Vec<Keypoint>,
    /// `descriptors[i]` describes `keypoints[i]`.
    pub descriptors: Vec<D>,
}

// By hand: empty features exist for any descriptor type (a derive would require
// `D: Default`).
impl<D> Default for Features<D> {
    fn default() -> Self {
        Self {
            keypoints: Vec::new(),
            descriptors: Vec::new(),
        }
    }
}

impl<D> Features<D> {
    /// Number of features.
    #[must_use]
    pub fn len(&self) -> usize {
        self.keypoints.len()
    }

    /// True when there are none.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.keypoints.is_empty()
    }
}

/// A borrowed 8-bit grayscale image, row-major, `width * height` bytes.
#[derive(Debug, Clone, Copy)]
pub struct GrayView<'a> {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// Pixels, row-major: pixel `(x, y)` is `data[y * width + x]`.
    pub data: &'a [u8],
}

/// Detects and describes features in a grayscale image.
pub trait FeatureExtractor: Send + Sync {
    /// The descriptor this extractor produces.
    type Descriptor: Descriptor;

    /// Short name (`surf`, `upright-surf`, `orb`).
    fn name(&self) -> &'static str;

    /// Detects and describes features. Deterministic: one image, one answer.
    fn extract(&self, image: GrayView<'_>) -> Features<Self::Descriptor>;

    /// Detects features and keeps those that `select` chooses: it receives the detected
    /// keypoints and returns the indices to keep (out-of-range indices are ignored). The
    /// result is that of [`FeatureExtractor::extract`] restricted to those indices, in
    /// their order; extractors that can detect without describing override it to
    /// describe only the features kept (as SURF does, for bucketing).
    fn extract_selected(
        &self,
        image: GrayView<'_>,
        select: &dyn Fn(&[Keypoint]) -> Vec<usize>,
    ) -> Features<Self::Descriptor> {
        let all = self.extract(image);
        let mut out = Features {
            keypoints: Vec::new(),
            descriptors: Vec::new(),
        };
        for i in select(&all.keypoints) {
            if let (Some(k), Some(d)) = (all.keypoints.get(i), all.descriptors.get(i)) {
                out.keypoints.push(*k);
                out.descriptors.push(d.clone());
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances() {
        let a = BinaryDescriptor([0u8; 32]);
        let mut b = a;
        b.0[3] = 0b1011;
        assert_eq!(a.distance(&b), 3.0);
        let mut x = FloatDescriptor64([0.0; 64]);
        let mut y = x;
        x.0[0] = 3.0;
        y.0[1] = 4.0;
        assert_eq!(x.distance(&y), 5.0);
    }
}
