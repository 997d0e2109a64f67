//! The problem ported to `tiny-solver` 0.18.8: its `Problem`, one residual block per
//! stereo measurement with its `HuberLoss` (k = 2.5), its `LevenbergMarquardtOptimizer`
//! with sparse Cholesky (no point elimination: the crate has none), and derivatives by its
//! automatic differentiation (`num-dual`), the only way the crate takes them.
//!
//! The same parametrisation as swarmpose's window: each pose `T_kw` (world to camera) is
//! a 12-vector (rotation matrix row by row, translation) on a custom manifold whose
//! `plus` is the window's left perturbation `T ← E(ξ) T`, `E(ξ): P ↦ Exp(ω) P + ν`; each
//! point is `(x, y, ρ)` in its first keyframe; keyframe 0 is not a variable (held fixed,
//! as in the window). The residual is the window's: `(u, v, d)` predicted minus measured,
//! whitened by 0.5 / 0.5 / 0.25 px (no disparity correction).

use std::collections::HashMap;
use std::num::NonZero;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use tiny_solver::factors::Factor;
use tiny_solver::loss_functions::HuberLoss;
use tiny_solver::manifold::{AutoDiffManifold, Manifold};
use tiny_solver::na;
use tiny_solver::{LevenbergMarquardtOptimizer, OptimizerOptions, Problem, optimizer::Optimizer};

use crate::problem::{self, HUBER_K, PoseCw};

/// A constant of the generic scalar type.
fn c<T: na::RealField>(x: f64) -> T {
    na::convert::<f64, T>(x)
}

/// `[v]×`.
fn hat<T: na::RealField>(v: &na::Vector3<T>) -> na::Matrix3<T> {
    let z = T::zero();
    na::Matrix3::new(
        z.clone(),
        -v[2].clone(),
        v[1].clone(),
        v[2].clone(),
        z.clone(),
        -v[0].clone(),
        -v[1].clone(),
        v[0].clone(),
        z,
    )
}

/// `Exp(ω)` (Rodrigues; second order below 1e-10 rad, exact in value and first
/// derivative at 0, where the automatic derivatives are taken).
fn exp_so3<T: na::RealField>(w: &na::Vector3<T>) -> na::Matrix3<T> {
    let theta2 = w.norm_squared();
    let k = hat(w);
    let k2 = &k * &k;
    if theta2 < c(1e-20) {
        return na::Matrix3::identity() + k + k2 * c::<T>(0.5);
    }
    let theta = theta2.clone().sqrt();
    let a = theta.clone().sin() / theta.clone();
    let b = (T::one() - theta.cos()) / theta2;
    na::Matrix3::identity() + k * a + k2 * b
}

/// A pose parameter block: rotation row by row, then translation.
fn unpack<T: na::RealField>(x: &na::DVectorView<T>) -> (na::Matrix3<T>, na::Vector3<T>) {
    let r = na::Matrix3::from_fn(|i, j| x[3 * i + j].clone());
    let t = na::Vector3::new(x[9].clone(), x[10].clone(), x[11].clone());
    (r, t)
}

fn pack<T: na::RealField>(r: &na::Matrix3<T>, t: &na::Vector3<T>) -> na::DVector<T> {
    na::DVector::from_fn(12, |i, _| {
        if i < 9 {
            r[(i / 3, i % 3)].clone()
        } else {
            t[i - 9].clone()
        }
    })
}

/// The window's pose manifold: `T ← E(ξ) T`, `ξ = (ν, ω)`.
struct LeftSe3;

impl<T: na::RealField> AutoDiffManifold<T> for LeftSe3 {
    fn plus(&self, x: na::DVectorView<T>, delta: na::DVectorView<T>) -> na::DVector<T> {
        let (r, t) = unpack(&x);
        let nu = na::Vector3::new(delta[0].clone(), delta[1].clone(), delta[2].clone());
        let e = exp_so3(&na::Vector3::new(
            delta[3].clone(),
            delta[4].clone(),
            delta[5].clone(),
        ));
        pack(&(&e * r), &(&e * t + nu))
    }

    fn minus(&self, y: na::DVectorView<T>, x: na::DVectorView<T>) -> na::DVector<T> {
        let ((ry, ty), (rx, tx)) = (unpack(&y), unpack(&x));
        let e = ry * rx.transpose();
        // log(E): ω = θ / (2 sin θ) vee(E − Eᵀ), first order for small θ.
        let vee = na::Vector3::new(
            e[(2, 1)].clone() - e[(1, 2)].clone(),
            e[(0, 2)].clone() - e[(2, 0)].clone(),
            e[(1, 0)].clone() - e[(0, 1)].clone(),
        ) * c::<T>(0.5);
        let cos = ((e.trace() - T::one()) * c::<T>(0.5)).clamp(-T::one(), T::one());
        let theta = cos.acos();
        let w = if theta < c(1e-8) {
            vee
        } else {
            vee * (theta.clone() / theta.sin())
        };
        let nu = ty - e * tx;
        na::DVector::from_fn(6, |i, _| {
            if i < 3 {
                nu[i].clone()
            } else {
                w[i - 3].clone()
            }
        })
    }
}

impl Manifold for LeftSe3 {
    fn tangent_size(&self) -> NonZero<usize> {
        NonZero::new(6).unwrap_or(NonZero::<usize>::MIN)
    }
}

/// The rig and noise, as plain numbers.
#[derive(Clone, Copy)]
struct Rig {
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
    fb: f64,
    /// Whitening: 1 / σ for `u`, `v` and `d`.
    wp: f64,
    wd: f64,
}

impl Rig {
    /// Whitened residual of the point `h = ρ P_B` (`h = (x, y, 1)` in its anchor) with
    /// inverse depth `ρ`, against the measurement `z`.
    fn residual<T: na::RealField>(
        &self,
        h: &na::Vector3<T>,
        rho: T,
        z: &[f64; 3],
    ) -> na::DVector<T> {
        let iz = T::one() / h[2].clone();
        let u = (h[0].clone() * iz.clone() * c::<T>(self.fx) + c::<T>(self.cx - z[0]))
            * c::<T>(self.wp);
        let v = (h[1].clone() * iz.clone() * c::<T>(self.fy) + c::<T>(self.cy - z[1]))
            * c::<T>(self.wp);
        let d = (rho * iz * c::<T>(self.fb) - c::<T>(z[2])) * c::<T>(self.wd);
        na::DVector::from_vec(vec![u, v, d])
    }
}

/// A measurement in the anchor keyframe: `params = [point]`.
struct Anchor {
    rig: Rig,
    z: [f64; 3],
}

impl<T: na::RealField> Factor<T> for Anchor {
    fn residual_func(&self, params: &[na::DVector<T>]) -> na::DVector<T> {
        let p = &params[0];
        let h = na::Vector3::new(p[0].clone(), p[1].clone(), T::one());
        self.rig.residual(&h, p[2].clone(), &self.z)
    }
}

/// A measurement in keyframe `j` of a point anchored in keyframe `a`:
/// `params = [T_jw, T_aw, point]`, or `[T_jw, point]` with `T_aw` the fixed keyframe 0's.
struct Seen {
    rig: Rig,
    z: [f64; 3],
    /// The fixed anchor pose, when the anchor is keyframe 0.
    fixed_anchor: Option<(na::Matrix3<f64>, na::Vector3<f64>)>,
    /// Counts the evaluations with derivatives (one per iteration) on one block.
    jacobians: Option<Arc<AtomicUsize>>,
}

impl Seen {
    fn eval<T: na::RealField>(&self, params: &[na::DVector<T>]) -> na::DVector<T> {
        let (rj, tj) = unpack(&params[0].as_view());
        let ((ra, ta), p) = match &self.fixed_anchor {
            Some((r, t)) => ((r.cast::<T>(), t.cast::<T>()), &params[1]),
            None => (unpack(&params[1].as_view()), &params[2]),
        };
        let rot = &rj * ra.transpose();
        let trans = tj - &rot * ta;
        let rho = p[2].clone();
        let h = rot * na::Vector3::new(p[0].clone(), p[1].clone(), T::one()) + trans * rho.clone();
        self.rig.residual(&h, rho, &self.z)
    }
}

impl Factor<f64> for Seen {
    fn residual_func(&self, params: &[na::DVector<f64>]) -> na::DVector<f64> {
        self.eval(params)
    }
}

impl Factor<num_dual::DualDVec64> for Seen {
    fn residual_func(
        &self,
        params: &[na::DVector<num_dual::DualDVec64>],
    ) -> na::DVector<num_dual::DualDVec64> {
        if let Some(n) = &self.jacobians {
            n.fetch_add(1, Ordering::Relaxed);
        }
        self.eval(params)
    }
}

/// What a solve gave.
pub struct Solved {
    /// `T_kw` of every keyframe.
    pub poses: Vec<PoseCw>,
    pub points: Vec<nalgebra::Vector3<f64>>,
    /// Iterations of the optimizer's loop (each evaluates the Jacobian once; a rejected
    /// step is an iteration, as the crate counts them).
    pub iterations: usize,
    /// Seconds spent building the problem (the rest of the time is the optimizer's).
    pub build_s: f64,
}

fn pose_name(k: usize) -> String {
    format!("T{k}")
}

fn point_name(i: usize) -> String {
    format!("p{i}")
}

/// Builds and solves the problem with at most `max_iterations` iterations, stopping when
/// the cost decreases by less than `1e-6` of itself (the window's rule).
pub fn solve(p: &problem::Problem, max_iterations: usize) -> Option<Solved> {
    let start = std::time::Instant::now();
    let r = &p.model.rig;
    let rig = Rig {
        fx: r.fx,
        fy: r.fy,
        cx: r.cx,
        cy: r.cy,
        fb: r.fx * r.baseline_m,
        wp: 1.0 / p.model.noise.position_px,
        wd: 1.0 / p.model.noise.disparity_px,
    };
    let poses0: Vec<PoseCw> = p.initial.iter().map(problem::pose_cw).collect();
    let to_na = |(rot, t): &PoseCw| {
        (
            na::Matrix3::from_fn(|i, j| rot[(i, j)]),
            na::Vector3::new(t[0], t[1], t[2]),
        )
    };
    let mut values: HashMap<String, na::DVector<f64>> = HashMap::new();
    let mut prob = Problem::new();
    for (k, pose) in poses0.iter().enumerate().skip(1) {
        let (rot, t) = to_na(pose);
        values.insert(pose_name(k), pack(&rot, &t));
        prob.set_variable_manifold(&pose_name(k), Arc::new(LeftSe3));
    }
    let counter = Arc::new(AtomicUsize::new(0));
    let points0 = p.initial_points();
    for (i, (t, x)) in p.tracks.iter().zip(&points0).enumerate() {
        let pn = point_name(i);
        values.insert(pn.clone(), na::DVector::from_vec(vec![x[0], x[1], x[2]]));
        for (o, z) in t.obs.iter().enumerate() {
            let z = [z.u, z.v, z.d];
            let loss = Some(Box::new(HuberLoss::new(HUBER_K))
                as Box<dyn tiny_solver::loss_functions::Loss + Send>);
            if o == 0 {
                prob.add_residual_block(3, &[&pn], Box::new(Anchor { rig, z }), loss);
                continue;
            }
            let j = pose_name(t.first + o);
            let jacobians = (i == 0 && o == 1).then(|| counter.clone());
            if t.first == 0 {
                let factor = Seen {
                    rig,
                    z,
                    fixed_anchor: Some(to_na(&poses0[0])),
                    jacobians,
                };
                prob.add_residual_block(3, &[&j, &pn], Box::new(factor), loss);
            } else {
                let a = pose_name(t.first);
                let factor = Seen {
                    rig,
                    z,
                    fixed_anchor: None,
                    jacobians,
                };
                prob.add_residual_block(3, &[&j, &a, &pn], Box::new(factor), loss);
            }
        }
    }
    let build_s = start.elapsed().as_secs_f64();
    let options = OptimizerOptions {
        max_iteration: max_iterations,
        min_abs_error_decrease_threshold: 0.0,
        min_rel_error_decrease_threshold: 1e-6,
        ..OptimizerOptions::default()
    };
    let out = LevenbergMarquardtOptimizer::default().optimize(&prob, &values, Some(options))?;
    let mut poses = vec![poses0[0]];
    for k in 1..poses0.len() {
        let v = out.get(&pose_name(k))?;
        poses.push((
            nalgebra::Matrix3::from_fn(|i, j| v[3 * i + j]),
            nalgebra::Vector3::new(v[9], v[10], v[11]),
        ));
    }
    let points = (0..p.tracks.len())
        .map(|i| {
            out.get(&point_name(i))
                .map(|v| nalgebra::Vector3::new(v[0], v[1], v[2]))
        })
        .collect::<Option<Vec<_>>>()?;
    Some(Solved {
        poses,
        points,
        iterations: counter.load(Ordering::Relaxed),
        build_s,
    })
}
