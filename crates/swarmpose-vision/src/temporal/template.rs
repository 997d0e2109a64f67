//! A feature's appearance kept from the frame where its track began, and where it appears
//! in a later image.
//!
//! Along a track, aligning each frame's patch to the previous frame's detected keypoint
//! ([`super::subpixel::align_patch`]) chains the keypoints' errors: the detected position
//! in frame `k` is off by up to half a pixel (FAST detects at whole pixels, and the
//! detected position moves with the corner's apparent size), and the alignment in frame
//! `k + 1` is relative to it. The detected keypoints themselves carry those errors in every
//! frame. Aligning every frame to the *first* frame's patch measures the same physical
//! point in every frame, so the errors neither accumulate nor repeat: what is left is the
//! alignment's own noise and the first keypoint's offset, which is common to all the
//! track's measurements (the point is where that patch's centre is). Over a track the
//! patch grows and shears as the camera moves; [`PatchTemplate::align_affine`] follows
//! that, where a translation-only alignment ([`PatchTemplate::align`]) is pulled off
//! the centre by it.

use crate::features::GrayView;
use crate::image::{sample_bilinear, sample_patch};
use inside::sample_inside;
use nalgebra::{Matrix3, SMatrix, SVector};
use steps::AffineSteps;

/// Half the side of the aligned patch, pixels (a 9x9 patch, as the frame-to-frame
/// alignment of the odometry's refinement).
pub const TEMPLATE_RADIUS: usize = 4;
/// Side of the sampled patch: the aligned patch with a one-pixel border for its gradients.
const SIDE: usize = 2 * TEMPLATE_RADIUS + 3;
/// Side of the aligned patch.
const N: usize = 2 * TEMPLATE_RADIUS + 1;
/// [`TEMPLATE_RADIUS`], pixels.
const R: f32 = TEMPLATE_RADIUS as f32;

/// When an alignment ([`PatchTemplate::align`], [`PatchTemplate::align_affine`]) stops,
/// and what it accepts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlignLimits {
    /// Iterations at most; an alignment that has not settled (to 0.01 px) by then fails.
    pub iterations: usize,
    /// Largest distance of the position found from the start, pixels.
    pub max_move_px: f32,
    /// Smallest zero-mean normalised cross-correlation of the patch found with the
    /// template (the appearance has changed since the template was taken below it);
    /// `None`: not checked.
    pub min_ncc: Option<f32>,
}

/// The image patch around a keypoint of the frame where a track began, with its
/// gradients (inverse compositional Lucas-Kanade). The alignments are blind to a change
/// of exposure between the frames (`I ≈ g T + b`): their steps see only the part of the
/// error outside the span of the template and the constant patch (`project_out`).
#[derive(Debug, Clone)]
pub struct PatchTemplate {
    values: [f32; N * N],
    gx: [f32; N * N],
    gy: [f32; N * N],
    /// The structure tensor `Σ ∇I ∇Iᵀ`: `(xx, xy, yy)`.
    tensor: (f32, f32, f32),
    /// The gradients with their components along the exposure changes projected out
    /// ([`project_out`]), and their structure tensor `(xx, xy, yy)`: the translation's
    /// Gauss-Newton steps.
    pgx: [f32; N * N],
    pgy: [f32; N * N],
    ptensor: (f32, f32, f32),
    /// The template less its mean, of unit norm ([`unit_contrast`]).
    contrast: [f32; N * N],
    /// The affine alignment's steepest-descent images and inverse Hessian, which depend
    /// on the template alone: computed on its first [`PatchTemplate::align_affine`] and
    /// kept while the template lives (a track's), not recomputed on every call; `None`
    /// before.
    affine: Option<AffineSteps>,
}

/// Equal templates: the same patch, gradients and their projections (whether the affine
/// alignment's steps, which follow from them, have been computed yet does not count).
impl PartialEq for PatchTemplate {
    fn eq(&self, other: &Self) -> bool {
        self.values == other.values
            && self.gx == other.gx
            && self.gy == other.gy
            && self.tensor == other.tensor
            && self.pgx == other.pgx
            && self.pgy == other.pgy
            && self.ptensor == other.ptensor
            && self.contrast == other.contrast
    }
}

/// The offset from the patch centre of the aligned patch's sample `k` (row-major), pixels:
/// `(k % N − R, k / N − R)`, small integers (exact), tabulated once rather than divided
/// and converted per sample.
const COORDS: [(f32, f32); N * N] = {
    let mut c = [(0f32, 0f32); N * N];
    let mut k = 0;
    while k < N * N {
        c[k] = ((k % N) as f32 - R, (k / N) as f32 - R);
        k += 1;
    }
    c
};

impl PatchTemplate {
    /// The patch of `image` centred at `at` (pixels, sub-pixel allowed). `None` when the
    /// patch leaves the image or has no texture in one direction (the smaller eigenvalue
    /// of its structure tensor below one grey level squared per pixel).
    #[must_use]
    pub fn sample(image: GrayView<'_>, at: (f32, f32)) -> Option<Self> {
        let mut t = Self::empty();
        t.sample_into(image, at).then_some(t)
    }

    /// A template of zeros: a buffer for [`PatchTemplate::sample_into`].
    #[must_use]
    pub fn empty() -> Self {
        Self {
            values: [0.0; N * N],
            gx: [0.0; N * N],
            gy: [0.0; N * N],
            tensor: (0.0, 0.0, 0.0),
            pgx: [0.0; N * N],
            pgy: [0.0; N * N],
            ptensor: (0.0, 0.0, 0.0),
            contrast: [0.0; N * N],
            affine: None,
        }
    }

    /// [`PatchTemplate::sample`] into `self`, in place (a template is some 4 KB, which
    /// returning it by value copies; issue 34): true when sampled, `self` then being
    /// what [`PatchTemplate::sample`] gives; false where that gives `None`, `self` then
    /// holding an unspecified template.
    #[must_use]
    pub fn sample_into(&mut self, image: GrayView<'_>, at: (f32, f32)) -> bool {
        crate::simd::dispatch(Sample(self, image, at)).is_some()
    }

    /// [`PatchTemplate::sample_into`], inlined into each instruction set's compilation:
    /// every field written (the affine steps forgotten) or `None`.
    #[inline(always)]
    fn sample_in(&mut self, image: GrayView<'_>, at: (f32, f32)) -> Option<()> {
        let mut big = [0f32; SIDE * SIDE];
        sample_patch(image, at.0 - R - 1.0, at.1 - R - 1.0, SIDE, &mut big)?;
        let t = self;
        t.affine = None;
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
        unit_contrast(&t.values, &mut t.contrast)?;
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
        Some(())
    }

    /// Where the patch appears in `image`, starting the search at `start` (pixels): the
    /// position minimising `min_{g,b} Σ (I(p + w) − g T(w) − b)²` (an exposure change
    /// between the images does not move it), or `None` when the patch leaves the
    /// image, or beyond the `limits`: the iterations do not settle, the position moves
    /// too far from `start`, or the patch found differs from the template more than its
    /// contrast allows.
    #[must_use]
    pub fn align(
        &self,
        image: GrayView<'_>,
        start: (f32, f32),
        limits: AlignLimits,
    ) -> Option<(f32, f32)> {
        crate::simd::dispatch(Align(self, image, start, limits))
    }

    /// [`PatchTemplate::align`], inlined into each instruction set's compilation.
    #[inline(always)]
    fn align_in(
        &self,
        image: GrayView<'_>,
        start: (f32, f32),
        limits: AlignLimits,
    ) -> Option<(f32, f32)> {
        let (hxx, hxy, hyy) = self.ptensor;
        let det = hxx * hyy - hxy * hxy;
        let mut patch = [0f32; N * N];
        let (mut px, mut py) = start;
        for _ in 0..limits.iterations {
            sample_patch(image, px - R, py - R, N, &mut patch)?;
            let (mut ex, mut ey) = (0f32, 0f32);
            for (((p, t), gx), gy) in patch.iter().zip(&self.values).zip(&self.pgx).zip(&self.pgy) {
                let e = p - t;
                ex += gx * e;
                ey += gy * e;
            }
            let dx = (hyy * ex - hxy * ey) / det;
            let dy = (hxx * ey - hxy * ex) / det;
            px -= dx;
            py -= dy;
            if (px - start.0).hypot(py - start.1) > limits.max_move_px {
                return None;
            }
            if dx.hypot(dy) < 0.01 {
                let Some(min_ncc) = limits.min_ncc else {
                    return Some((px, py));
                };
                sample_patch(image, px - R, py - R, N, &mut patch)?;
                return (ncc(&patch, &self.values) >= min_ncc).then_some((px, py));
            }
        }
        None
    }
}

impl PatchTemplate {
    /// Where the patch appears in `image` under an affine warp (inverse compositional
    /// Lucas-Kanade on the 6 parameters of `x ↦ A x + t` about the patch centre), starting
    /// at `start` with `A = I`: the position of the centre, or `None` as for
    /// [`PatchTemplate::align`], or when the warp's area changes by more than a factor of 2.
    /// The first call computes the steps that depend on the template alone and keeps them
    /// in the template (hence `&mut self`); later calls reuse them.
    #[must_use]
    pub fn align_affine(
        &mut self,
        image: GrayView<'_>,
        start: (f32, f32),
        limits: AlignLimits,
    ) -> Option<(f32, f32)> {
        let AffineSteps { sd, h_inv } = self
            .affine
            .get_or_insert_with(|| AffineSteps::of(&self.gx, &self.gy, &self.contrast));
        let h_inv = h_inv.as_ref()?;
        crate::simd::dispatch(AlignAffine {
            sd,
            h_inv,
            values: &self.values,
            image,
            start,
            limits,
        })
    }
}

/// A call of [`PatchTemplate::sample_into`] for [`crate::simd::dispatch`].
struct Sample<'a>(&'a mut PatchTemplate, GrayView<'a>, (f32, f32));

impl crate::simd::Kernel for Sample<'_> {
    type Output = Option<()>;

    #[inline(always)]
    fn run(self) -> Option<()> {
        self.0.sample_in(self.1, self.2)
    }
}

/// A call of [`PatchTemplate::align`] for [`crate::simd::dispatch`].
struct Align<'a>(&'a PatchTemplate, GrayView<'a>, (f32, f32), AlignLimits);

impl crate::simd::Kernel for Align<'_> {
    type Output = Option<(f32, f32)>;

    #[inline(always)]
    fn run(self) -> Option<(f32, f32)> {
        self.0.align_in(self.1, self.2, self.3)
    }
}

/// The iterations of [`PatchTemplate::align_affine`] for [`crate::simd::dispatch`]: the
/// template's steps and values, the image, the start and the limits.
struct AlignAffine<'a> {
    sd: &'a [SVector<f32, 6>; N * N],
    h_inv: &'a SMatrix<f32, 6, 6>,
    values: &'a [f32; N * N],
    image: GrayView<'a>,
    start: (f32, f32),
    limits: AlignLimits,
}

impl crate::simd::Kernel for AlignAffine<'_> {
    type Output = Option<(f32, f32)>;

    #[inline(always)]
    fn run(self) -> Option<(f32, f32)> {
        let AlignAffine {
            sd,
            h_inv,
            values,
            image,
            start,
            limits,
        } = self;
        // Below these a sample has its four neighbours ([`sample_bilinear`]'s check); exact
        // in f32, and in [`sample_inside`]'s whole parts, up to 2^22 pixels (larger images
        // take the checked path).
        let limited = (2..=1 << 22).contains(&image.width) && (2..=1 << 22).contains(&image.height);
        let (u_max, v_max) = (
            image.width.saturating_sub(1) as f32,
            image.height.saturating_sub(1) as f32,
        );
        let mut m = Matrix3::<f32>::new(1.0, 0.0, start.0, 0.0, 1.0, start.1, 0.0, 0.0, 1.0);
        let mut patch = [0f32; N * N];
        let (mut us, mut vs) = ([0f32; N * N], [0f32; N * N]);
        for _ in 0..limits.iterations {
            // The positions, and whether all are inside (`&`, not `&&`: a NaN fails too):
            // then [`sample_bilinear`] would give `Some` of each, which the samples are
            // without its checks; otherwise it is called, and the first position outside
            // ends the alignment.
            let mut inside = limited;
            for ((pu, pv), &(x, y)) in us.iter_mut().zip(&mut vs).zip(&COORDS) {
                let u = m[(0, 0)] * x + m[(0, 1)] * y + m[(0, 2)];
                let v = m[(1, 0)] * x + m[(1, 1)] * y + m[(1, 2)];
                inside &= (u >= 0.0) & (v >= 0.0) & (u < u_max) & (v < v_max);
                (*pu, *pv) = (u, v);
            }
            if inside {
                sample_inside(image, (&us, &vs), &mut patch);
            } else {
                for ((sample, &u), &v) in patch.iter_mut().zip(&us).zip(&vs) {
                    *sample = sample_bilinear(image, u, v)?;
                }
            }
            let mut b = SVector::<f32, 6>::zeros();
            for (k, i) in patch.iter().enumerate() {
                b += sd[k] * (i - values[k]);
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
                return (ncc(&patch, values) >= min_ncc).then_some((px, py));
            }
        }
        None
    }
}

/// The patch's values less their mean, scaled to unit norm, into `out` (`None` for a flat
/// patch, `out` then unspecified): with the constant patch, an orthogonal basis of the
/// exposure changes `g T + b`.
#[inline(always)]
fn unit_contrast(values: &[f32; N * N], out: &mut [f32; N * N]) -> Option<()> {
    let mean = values.iter().sum::<f32>() / (N * N) as f32;
    for (o, v) in out.iter_mut().zip(values) {
        *o = v - mean;
    }
    let norm = out.iter().map(|v| v * v).sum::<f32>().sqrt();
    if norm <= 0.0 {
        return None;
    }
    for v in out.iter_mut() {
        *v /= norm;
    }
    Some(())
}

/// `images` (one steepest-descent vector per pixel) less their components along the
/// constant patch and along `contrast` (the template's [`unit_contrast`]): the
/// Gauss-Newton steps they give ignore any change `g T + b` of the image's exposure
/// (Baker and Matthews' "project out" alignment with a linear appearance model).
#[inline(always)]
fn project_out<const P: usize>(images: &mut [SVector<f32, P>; N * N], contrast: &[f32; N * N]) {
    let n = (N * N) as f32;
    let mean = images.iter().sum::<SVector<f32, P>>() / n;
    let along = images
        .iter()
        .zip(contrast)
        .map(|(v, c)| *v * *c)
        .sum::<SVector<f32, P>>();
    for (v, c) in images.iter_mut().zip(contrast) {
        *v -= mean + along * *c;
    }
}

/// Zero-mean normalised cross-correlation of two patches (0 when one is flat).
fn ncc(a: &[f32; N * N], b: &[f32; N * N]) -> f32 {
    let n = (N * N) as f32;
    let ma = a.iter().sum::<f32>() / n;
    let mb = b.iter().sum::<f32>() / n;
    let (mut ab, mut aa, mut bb) = (0f32, 0f32, 0f32);
    for (x, y) in a.iter().zip(b) {
        let (x, y) = (x - ma, y - mb);
        ab += x * y;
        aa += x * x;
        bb += y * y;
    }
    if aa <= 0.0 || bb <= 0.0 {
        0.0
    } else {
        ab / (aa * bb).sqrt()
    }
}

mod inside;
mod steps;

#[cfg(test)]
mod affine_bits;

#[cfg(test)]
mod sample_bits;

#[cfg(test)]
mod tests {
    use super::*;

    /// Width and height of the test images, pixels.
    pub(super) const W: usize = 80;
    pub(super) const H: usize = 60;

    pub(super) fn view(data: &[u8]) -> GrayView<'_> {
        GrayView {
            width: W,
            height: H,
            data,
        }
    }

    /// A textured image whose pixel `(x, y)` shows the pattern at `source(x, y)`.
    pub(super) fn warped(source: impl Fn(f32, f32) -> (f32, f32)) -> Vec<u8> {
        let pattern = |(x, y): (f32, f32)| {
            128.0 + 60.0 * (0.31 * x).sin() * (0.23 * y).cos() + 30.0 * (0.17 * (x + y)).sin()
        };
        (0..H)
            .flat_map(|y| (0..W).map(move |x| (x, y)))
            .map(|(x, y)| pattern(source(x as f32, y as f32)).round() as u8)
            .collect()
    }

    /// The pattern shifted by `shift` pixels.
    pub(super) fn image(shift: (f32, f32)) -> Vec<u8> {
        warped(|x, y| (x - shift.0, y - shift.1))
    }

    /// Alignment limits with the cross-correlation checked at 0.9.
    pub(super) fn limits(iterations: usize, max_move_px: f32) -> AlignLimits {
        AlignLimits {
            iterations,
            max_move_px,
            min_ncc: Some(0.9),
        }
    }

    /// The template at the centre `(40, 30)` of the unshifted pattern.
    fn centre_template() -> PatchTemplate {
        PatchTemplate::sample(view(&image((0.0, 0.0))), (40.0, 30.0)).expect("textured")
    }

    /// A template taken in one image is found, to a fraction of a pixel, in images
    /// shifted by known amounts, each time from the template (no chaining).
    #[test]
    fn shifted_copies_are_found_from_the_first_patch() {
        let t = centre_template();
        for shift in [(0.3f32, -0.2f32), (1.37, -0.62), (-1.1, 0.9)] {
            let img = image(shift);
            let (x, y) = t
                .align(view(&img), (40.0, 30.0), limits(20, 2.0))
                .expect("found");
            assert!(
                (x - 40.0 - shift.0).abs() < 0.05 && (y - 30.0 - shift.1).abs() < 0.05,
                "shift {shift:?}: found ({x}, {y})"
            );
        }
    }

    /// Found to the same precision when the second image's exposure differs (gain 1.15
    /// or 0.7, offset −20 or +15 grey levels, no clipping): both alignments project the
    /// exposure out of their steps.
    #[test]
    fn an_exposure_change_does_not_move_the_patch() {
        let mut t = centre_template();
        let shift = (1.37f32, -0.62f32);
        for (gain, offset) in [(1.15f32, -20.0f32), (0.7, 15.0)] {
            let img: Vec<u8> = image(shift)
                .iter()
                .map(|&v| (gain * f32::from(v) + offset).round().clamp(0.0, 255.0) as u8)
                .collect();
            for affine in [false, true] {
                let found = if affine {
                    t.align_affine(view(&img), (41.0, 30.0), limits(30, 3.0))
                } else {
                    t.align(view(&img), (41.0, 30.0), limits(30, 3.0))
                };
                let (x, y) = found.expect("found");
                assert!(
                    (x - 40.0 - shift.0).abs() < 0.03 && (y - 30.0 - shift.1).abs() < 0.03,
                    "gain {gain}, offset {offset}, affine {affine}: found ({x}, {y})"
                );
            }
        }
    }

    /// A patch seen 8 % larger, slightly sheared and shifted is found by the affine
    /// alignment, to a fraction of a pixel, from a start one pixel off.
    #[test]
    fn an_affine_copy_is_found() {
        // The second image shows the first through x' = c + A (x - c) + t.
        let (c, t) = ((40.0f32, 30.0f32), (0.7f32, -0.4f32));
        let a = [[1.08f32, 0.03], [-0.02, 1.06]];
        let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        let second = warped(|x, y| {
            let (dx, dy) = (x - c.0 - t.0, y - c.1 - t.1);
            let sx = (a[1][1] * dx - a[0][1] * dy) / det + c.0;
            let sy = (-a[1][0] * dx + a[0][0] * dy) / det + c.1;
            (sx, sy)
        });
        let (x, y) = centre_template()
            .align_affine(view(&second), (c.0 + 1.5, c.1), limits(30, 3.0))
            .expect("found");
        assert!(
            (x - c.0 - t.0).abs() < 0.05 && (y - c.1 - t.1).abs() < 0.05,
            "found ({x}, {y}), expected ({}, {})",
            c.0 + t.0,
            c.1 + t.1
        );
    }

    /// A flat patch is no template, a patch that is not there is not found, and a patch
    /// near the border is not sampled.
    #[test]
    fn flat_absent_or_clipped_patches_are_refused() {
        let flat = vec![100u8; W * H];
        assert!(PatchTemplate::sample(view(&flat), (40.0, 30.0)).is_none());
        let t = centre_template();
        let noise: Vec<u8> = (0..W * H).map(|i| ((i * 7919) % 251) as u8).collect();
        assert!(
            t.align(view(&noise), (40.0, 30.0), limits(20, 2.0))
                .is_none()
        );
        assert!(PatchTemplate::sample(view(&image((0.0, 0.0))), (2.0, 2.0)).is_none());
    }
}
