//! A keyframe's measurement of a track as the window's solver sees it: the relative poses
//! `T_ja` of the window's keyframes (each keyframe's `T_kw`, world to camera, a
//! [`crate::nls::pose::Pose`] perturbed as `E(ξ) T_kw`), and the whitened residual of a
//! measurement with its Jacobians (see [`super::solve`] for their derivation).

use nalgebra::{Matrix3, Vector3};

use crate::nls::pose::Pose;
use crate::nls::products::mul;
use crate::refine::Prepared;
use crate::refine::model::{Matrix3x6, Matrix3xK, Parts, StereoObservation};

/// A relative pose `T_ja`: rotation and translation (`P_j = R P_a + t`, metres).
pub(super) type Relative = (Matrix3<f64>, Vector3<f64>);

/// The relative poses `T_ja` of every pair of keyframes, row-major by `(j, a)`.
pub(super) fn relative_poses(poses: &[Pose], out: &mut Vec<Relative>) {
    out.clear();
    for j in poses {
        for a in poses {
            out.push(j.relative_to(a));
        }
    }
}

/// One measurement linearised: whitened residual, `∂e/∂p`, and `∂e/∂ξ` for the observing
/// keyframe (`j`) and the anchor (`a`), `None` for the anchor's own measurement.
pub(super) struct Jac {
    pub(super) residual: Vector3<f64>,
    pub(super) d_point: Matrix3<f64>,
    pub(super) d_correction: Matrix3xK,
    pub(super) poses: Option<(Matrix3x6, Matrix3x6)>,
}

/// The measurement `z` in keyframe `slot` of the point `p` anchored in keyframe `anchor`,
/// `rel` from [`relative_poses`] over `n` keyframes, with `model`'s constants computed
/// once ([`Prepared`]: the same bits as [`crate::refine::model::StereoModel`]'s
/// methods). Inlined: its large result is then built where it is used, not copied
/// (issue 34).
#[inline(always)]
pub(super) fn linearize(
    model: &Prepared,
    (rel, n): (&[Relative], usize),
    anchor: usize,
    slot: usize,
    p: &Vector3<f64>,
    z: &StereoObservation,
) -> Option<Jac> {
    if slot == anchor {
        let l = model.in_reference_parts(p, z, Parts::All);
        return Some(Jac {
            residual: l.residual,
            d_point: l.d_point,
            d_correction: l.d_correction,
            poses: None,
        });
    }
    let (rot, trans) = &rel[slot * n + anchor];
    let l = model.in_current_parts(rot, trans, p, z, Parts::All)?;
    let mut dh_da = Matrix3x6::zeros();
    dh_da.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-rot * p.z));
    dh_da
        .fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&mul3(rot, &Vector3::new(p.x, p.y, 1.0).cross_matrix()));
    Some(Jac {
        residual: l.residual,
        d_point: l.d_point,
        d_correction: l.d_correction,
        // nalgebra's `l.d_h * dh_da` bit for bit, without its generic product.
        poses: Some((l.d_pose, mul(&l.d_h, &dh_da))),
    })
}

/// `a b` for 3x3 matrices with the operations of nalgebra's product in its order (entry
/// `(i, j)` is `(a[(i,0)] b[(0,j)] + a[(i,1)] b[(1,j)]) + a[(i,2)] b[(2,j)]`): the same
/// bits, written out because LLVM compiled nalgebra's generic product here, in some
/// builds, with an AVX register move (`vmovq xmm, xmm`) that valgrind cannot decode, which
/// stopped the instruction counts of `cachegrind` on the whole run.
#[inline(always)]
fn mul3(a: &Matrix3<f64>, b: &Matrix3<f64>) -> Matrix3<f64> {
    Matrix3::from_fn(|i, j| a[(i, 0)] * b[(0, j)] + a[(i, 1)] * b[(1, j)] + a[(i, 2)] * b[(2, j)])
}

/// [`linearize`]'s whitened residual and `∂e/∂p` alone, the same bits (the other
/// Jacobians not computed: [`Parts::Point`]), or `None` when [`linearize`] gives none.
#[inline(always)]
pub(super) fn linearize_point(
    model: &Prepared,
    (rel, n): (&[Relative], usize),
    anchor: usize,
    slot: usize,
    p: &Vector3<f64>,
    z: &StereoObservation,
) -> Option<(Vector3<f64>, Matrix3<f64>)> {
    let l = if slot == anchor {
        model.in_reference_parts(p, z, Parts::Point)
    } else {
        let (rot, trans) = &rel[slot * n + anchor];
        model.in_current_parts(rot, trans, p, z, Parts::Point)?
    };
    Some((l.residual, l.d_point))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::refine::model::StereoModel;

    #[test]
    fn mul3_is_nalgebras_product_bit_for_bit() {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            match state >> 60 {
                0 => 0.0,
                1 => -0.0,
                2 => 1.0,
                _ => (state >> 11) as f64 / (1u64 << 53) as f64 * 20.0 - 10.0,
            }
        };
        for _ in 0..2000 {
            let a = Matrix3::from_fn(|_, _| next());
            let p = Vector3::new(next(), next(), 1.0);
            for b in [Matrix3::from_fn(|_, _| next()), p.cross_matrix()] {
                let (got, want) = (mul3(&a, &b), a * b);
                for (g, w) in got.iter().zip(want.iter()) {
                    assert_eq!(g.to_bits(), w.to_bits(), "{a} {b}");
                }
            }
        }
    }

    /// `linearize` as it was before the window used [`Prepared`] (issue 34, round six):
    /// [`StereoModel`]'s methods, their constants computed per measurement.
    fn linearize_before(
        model: &StereoModel,
        (rel, n): (&[Relative], usize),
        anchor: usize,
        slot: usize,
        p: &Vector3<f64>,
        z: &StereoObservation,
    ) -> Option<Jac> {
        if slot == anchor {
            let l = model.in_reference(p, z);
            return Some(Jac {
                residual: l.residual,
                d_point: l.d_point,
                d_correction: l.d_correction,
                poses: None,
            });
        }
        let (rot, trans) = &rel[slot * n + anchor];
        let l = model.in_current(rot, trans, p, z)?;
        let mut dh_da = Matrix3x6::zeros();
        dh_da.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-rot * p.z));
        dh_da
            .fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&mul3(rot, &Vector3::new(p.x, p.y, 1.0).cross_matrix()));
        Some(Jac {
            residual: l.residual,
            d_point: l.d_point,
            d_correction: l.d_correction,
            poses: Some((l.d_pose, mul(&l.d_h, &dh_da))),
        })
    }

    /// The same bits, or both NaN.
    fn same(a: &[f64], b: &[f64]) -> bool {
        a.len() == b.len()
            && a.iter()
                .zip(b)
                .all(|(x, y)| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()))
    }

    fn same_jac(a: &Jac, b: &Jac) -> bool {
        let poses = match (&a.poses, &b.poses) {
            (None, None) => true,
            (Some((a1, a2)), Some((b1, b2))) => {
                same(a1.as_slice(), b1.as_slice()) && same(a2.as_slice(), b2.as_slice())
            }
            _ => false,
        };
        poses
            && same(a.residual.as_slice(), b.residual.as_slice())
            && same(a.d_point.as_slice(), b.d_point.as_slice())
            && same(a.d_correction.as_slice(), b.d_correction.as_slice())
    }

    /// The window's linearisation and residuals with [`Prepared`] are the old ones with
    /// [`StereoModel`] bit for bit, on seeded random models, poses, points and
    /// measurements with zeros of both signs and NaNs.
    #[test]
    fn prepared_linearize_is_the_old_one_bit_for_bit() {
        use nalgebra::Rotation3;
        use rand::{RngExt, SeedableRng};
        use rand_chacha::ChaCha8Rng;
        use swarmpose_vision::frontend::{CORRECTION_TERMS, DisparityCorrection};
        let mut rng = ChaCha8Rng::seed_from_u64(3934);
        let value = |rng: &mut ChaCha8Rng, scale: f64| match rng.random_range(0..30) {
            0 => 0.0,
            1 => -0.0,
            2 => f64::NAN,
            _ => rng.random_range(-scale..scale),
        };
        let mut compared = 0;
        for _ in 0..5000 {
            let c: [f64; CORRECTION_TERMS] = std::array::from_fn(|_| value(&mut rng, 2.0));
            let model = crate::refine::model::test_model(DisparityCorrection::from_coefficients(c));
            let prepared = Prepared::new(&model);
            let rel: Vec<Relative> = (0..4)
                .map(|_| {
                    let (a, b) = (rng.random_range(-0.1..0.1), rng.random_range(-0.1..0.1));
                    let rot = *Rotation3::from_euler_angles(a, b, value(&mut rng, 0.1)).matrix();
                    let t = [
                        value(&mut rng, 0.3),
                        value(&mut rng, 0.3),
                        value(&mut rng, 1.0),
                    ];
                    (rot, Vector3::from(t))
                })
                .collect();
            let p = Vector3::new(
                value(&mut rng, 0.8),
                value(&mut rng, 0.3),
                value(&mut rng, 0.5),
            );
            let z = StereoObservation {
                u: value(&mut rng, 1200.0),
                v: value(&mut rng, 370.0),
                d: value(&mut rng, 80.0),
            };
            let (anchor, slot) = (rng.random_range(0..2), rng.random_range(0..2));
            let got = linearize(&prepared, (&rel, 2), anchor, slot, &p, &z);
            let want = linearize_before(&model, (&rel, 2), anchor, slot, &p, &z);
            match (&got, &want) {
                (Some(g), Some(w)) => {
                    assert!(same_jac(g, w), "{p:?} {z:?}");
                    compared += 1;
                }
                (None, None) => {}
                _ => panic!("one in view, not the other: {p:?} {z:?}"),
            }
            let (rot, trans) = &rel[slot * 2 + anchor];
            let r2 = [
                prepared.residual2_in_reference(&p, &z),
                model.residual2_in_reference(&p, &z),
            ];
            assert!(same(&r2[..1], &r2[1..]));
            let (g, w) = (
                prepared.residual2_in_current(rot, trans, &p, &z),
                model.residual2_in_current(rot, trans, &p, &z),
            );
            assert!(same(g.as_slice(), w.as_slice()));
        }
        assert!(compared > 2500, "{compared}");
    }
}
