//! The steps of [`super::PatchTemplate::align_affine`] that follow from the template
//! alone, computed once per template ([`AffineSteps::of`]): compiled for the CPU's best
//! instruction set, the Hessian of the steepest-descent images summed column by column
//! with the operations of nalgebra's `fold(h + v vᵀ)` (issue 34).

use super::{COORDS, N, project_out};
use nalgebra::{SMatrix, SVector};

/// The steps of [`super::PatchTemplate::align_affine`] that follow from the template alone.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct AffineSteps {
    /// The steepest-descent images `∇T ∂W/∂p` with the exposure changes projected out.
    pub(super) sd: [SVector<f32, 6>; N * N],
    /// The inverse of their Hessian `Σ sd sdᵀ`; `None` when it is singular (no affine
    /// alignment).
    pub(super) h_inv: Option<SMatrix<f32, 6, 6>>,
}

impl AffineSteps {
    /// The steps of the template whose gradients are `(gx, gy)` and whose contrast is
    /// `contrast`. Compiled for the CPU's best instruction set
    /// ([`crate::simd::dispatch`]): the same IEEE operations, fewer instructions.
    pub(super) fn of(gx: &[f32; N * N], gy: &[f32; N * N], contrast: &[f32; N * N]) -> Self {
        crate::simd::dispatch(Steps(gx, gy, contrast))
    }
}

/// A call of [`AffineSteps::of`] for [`crate::simd::dispatch`].
struct Steps<'a>(&'a [f32; N * N], &'a [f32; N * N], &'a [f32; N * N]);

impl crate::simd::Kernel for Steps<'_> {
    type Output = AffineSteps;

    #[inline(always)]
    fn run(self) -> AffineSteps {
        let Steps(gx, gy, contrast) = self;
        // Each written once (no buffer of zeros first, which `rep stosb` fills a byte at a
        // time).
        let mut sd: [SVector<f32, 6>; N * N] = std::array::from_fn(|k| {
            let ((gx, gy), (x, y)) = ((gx[k], gy[k]), COORDS[k]);
            SVector::<f32, 6>::from([gx * x, gx * y, gy * x, gy * y, gx, gy])
        });
        project_out(&mut sd, contrast);
        AffineSteps {
            sd,
            h_inv: hessian(&sd).try_inverse(),
        }
    }
}

/// `Σ v vᵀ` over `sd` in order from zeros, the same bits as nalgebra's
/// `sd.iter().fold(zeros, |h, v| h + *v * v.transpose())`: entry `(i, j)` adds
/// `v[i] v[j]` to its running sum in the order of `sd`, as there, but a column `j` at a
/// time, without the outer product's temporaries (a few vector multiplies and adds per
/// image and column).
#[inline(always)]
fn hessian(sd: &[SVector<f32, 6>; N * N]) -> SMatrix<f32, 6, 6> {
    let mut h = SMatrix::<f32, 6, 6>::zeros();
    for (j, out) in h.column_iter_mut().enumerate() {
        let mut col = [0f32; 6];
        for v in sd {
            let s = v[j];
            for (c, &x) in col.iter_mut().zip(v.iter()) {
                *c += x * s;
            }
        }
        for (o, c) in out.into_iter().zip(col) {
            *o = c;
        }
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Hessian as it was summed before (nalgebra's outer products, folded).
    fn hessian_by_fold(sd: &[SVector<f32, 6>; N * N]) -> SMatrix<f32, 6, 6> {
        sd.iter()
            .fold(SMatrix::<f32, 6, 6>::zeros(), |h, v| h + *v * v.transpose())
    }

    /// [`AffineSteps::of`] as it was before (nalgebra's fold, not dispatched).
    fn steps_before(gx: &[f32; N * N], gy: &[f32; N * N], contrast: &[f32; N * N]) -> AffineSteps {
        let mut sd = [SVector::<f32, 6>::zeros(); N * N];
        for (k, (sd, &(x, y))) in sd.iter_mut().zip(&COORDS).enumerate() {
            let (gx, gy) = (gx[k], gy[k]);
            *sd = SVector::<f32, 6>::from([gx * x, gx * y, gy * x, gy * y, gx, gy]);
        }
        project_out(&mut sd, contrast);
        AffineSteps {
            sd,
            h_inv: hessian_by_fold(&sd).try_inverse(),
        }
    }

    /// Seeded draws: mostly in [-50, 50), with zeros of both signs, ties and, when
    /// `nan`, NaN.
    fn draws(seed: u64, nan: bool) -> impl FnMut() -> f32 {
        let mut state = seed;
        move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            match state >> 59 {
                0 => 0.0,
                1 => -0.0,
                2 => 1.5,
                3 if nan => f32::NAN,
                _ => (state >> 40) as f32 / (1u64 << 24) as f32 * 100.0 - 50.0,
            }
        }
    }

    /// Entries equal bit for bit, or both NaN (a NaN's payload is not kept by LLVM's
    /// commuted products anyway).
    fn same(a: f32, b: f32) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    #[test]
    fn hessian_is_the_fold_bit_for_bit() {
        for (seed, nan) in (0..400u64).map(|s| (s, s % 4 == 3)) {
            let mut next = draws(seed, nan);
            let sd: [SVector<f32, 6>; N * N] =
                std::array::from_fn(|_| SVector::<f32, 6>::from_fn(|_, _| next()));
            let (got, want) = (hessian(&sd), hessian_by_fold(&sd));
            for (g, w) in got.iter().zip(want.iter()) {
                assert!(same(*g, *w), "seed {seed}: {g} against {w}");
                if !nan {
                    assert_eq!(g.to_bits(), w.to_bits(), "seed {seed}");
                }
            }
        }
    }

    #[test]
    fn steps_are_the_old_steps_bit_for_bit() {
        for seed in 0..300u64 {
            let mut next = draws(seed, false);
            let gx: [f32; N * N] = std::array::from_fn(|_| next());
            let gy: [f32; N * N] = std::array::from_fn(|_| next());
            let contrast: [f32; N * N] = std::array::from_fn(|_| next() / 50.0);
            let want = steps_before(&gx, &gy, &contrast);
            for got in [
                AffineSteps::of(&gx, &gy, &contrast),
                crate::simd::baseline(|| AffineSteps::of(&gx, &gy, &contrast)),
            ] {
                for (g, w) in got.sd.iter().zip(&want.sd) {
                    assert!(g.iter().zip(w.iter()).all(|(a, b)| same(*a, *b)));
                }
                match (got.h_inv, want.h_inv) {
                    (Some(g), Some(w)) => {
                        assert!(g.iter().zip(w.iter()).all(|(a, b)| same(*a, *b)));
                    }
                    (g, w) => assert_eq!(g.is_none(), w.is_none(), "seed {seed}"),
                }
            }
        }
    }
}
