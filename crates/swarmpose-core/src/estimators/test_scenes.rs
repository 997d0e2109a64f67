//! Test scenes shared by the estimators' tests.

use nalgebra::{
    Isometry3, Matrix3, Point3, Rotation3, Translation3, Unit, UnitQuaternion, Vector3,
};
use rand::RngExt;
use rand_distr::{Distribution, StandardNormal};

use crate::geometry::Correspondences;
use crate::rng::{SeededRng, seeded};

/// 200 stereo-like points, 4 to 40 m deep: noise σ = 0.002 z² m along the viewing ray
/// and 0.002 z m across it, with the matching covariances attached; every
/// `wrong_every`-th correspondence is a wrong match.
pub(crate) fn stereo_scene(
    seed: u64,
    wrong_every: usize,
) -> (Correspondences, Isometry3<f64>, Vec<bool>) {
    let mut rng = seeded(seed);
    let truth = Isometry3::from_parts(
        Translation3::new(0.1, -0.05, 1.0),
        UnitQuaternion::from_euler_angles(0.01, 0.05, -0.02),
    );
    let (mut src, mut dst, mut sc, mut dc, mut inlier) = (vec![], vec![], vec![], vec![], vec![]);
    let cov_at = |p: &Point3<f64>| {
        let ray = Unit::new_normalize(p.coords);
        let along = (0.002 * p.z * p.z).powi(2);
        let lateral = (0.002 * p.z).powi(2);
        let rot =
            Rotation3::rotation_between(&Vector3::z(), &ray).unwrap_or_else(Rotation3::identity);
        rot.matrix()
            * Matrix3::from_diagonal(&Vector3::new(lateral, lateral, along))
            * rot.matrix().transpose()
    };
    let noisy = |p: Point3<f64>, c: &Matrix3<f64>, rng: &mut crate::rng::SeededRng| {
        let l = c.cholesky().map(|ch| ch.l()).unwrap_or_else(Matrix3::zeros);
        let z = Vector3::from_fn(|_, _| StandardNormal.sample(rng));
        p + l * z
    };
    for k in 0..200 {
        let s = Point3::new(
            rng.random_range(-8.0..8.0),
            rng.random_range(-2.0..2.0),
            rng.random_range(4.0..40.0),
        );
        let d = truth * s;
        let (cs, cd) = (cov_at(&s), cov_at(&d));
        sc.push(cs);
        dc.push(cd);
        let wrong = k % wrong_every == 0;
        inlier.push(!wrong);
        src.push(noisy(s, &cs, &mut rng));
        // A wrong match lands at least 1 m off sideways (many lateral σ away even at
        // 40 m; along the ray, depth noise of metres would hide it).
        let side = if rng.random::<bool>() { 1.0 } else { -1.0 };
        let off = Vector3::new(
            side * rng.random_range(1.0..3.0),
            0.0,
            rng.random_range(-5.0..5.0),
        );
        dst.push(if wrong {
            d + off
        } else {
            noisy(d, &cd, &mut rng)
        });
    }
    let data = Correspondences::new(src, dst)
        .and_then(|c| c.with_noise_covariance(sc, dc))
        .expect("valid");
    (data, truth, inlier)
}

/// `points` with each one from index `kept` on moved by `offset(index)` (metres): wrong
/// matches after `kept` right ones.
pub(crate) fn moved_after(
    points: &[Point3<f64>],
    kept: usize,
    offset: impl Fn(usize) -> Vector3<f64>,
) -> Vec<Point3<f64>> {
    points
        .iter()
        .enumerate()
        .map(|(k, p)| if k < kept { *p } else { p + offset(k) })
        .collect()
}

/// Two independent clouds of `n` random points each (source first, then destination;
/// each point's x, y drawn from `xy` and z from `z`, metres), for the tests comparing a
/// kernel with its reference on arbitrary data.
pub(crate) fn random_clouds(
    rng: &mut SeededRng,
    n: usize,
    xy: std::ops::Range<f64>,
    z: std::ops::Range<f64>,
) -> (Vec<Point3<f64>>, Vec<Point3<f64>>) {
    let mut point = || {
        Point3::new(
            rng.random_range(xy.clone()),
            rng.random_range(xy.clone()),
            rng.random_range(z.clone()),
        )
    };
    let src = (0..n).map(|_| point()).collect();
    let dst = (0..n).map(|_| point()).collect();
    (src, dst)
}
