//! The problem ported to `apex-solver` 1.5.0: its `Problem` with one residual block per
//! stereo measurement and its `HuberLoss` (k = 2.5), its Levenberg-Marquardt with the
//! points marked for elimination and the explicit sparse Schur complement (exact
//! Cholesky of the reduced system), the closest of its solvers to swarmpose's.
//!
//! The crate takes analytic Jacobians, so the factors call swarmpose's own stereo model
//! (`StereoModel::in_reference`, `in_current`: the same whitened residual and Jacobians
//! as the window). Poses are the crate's `SE3` with its right perturbation; stored as the
//! camera in the world `T_wk`, `T_wk ∘ Exp(τ)` is `T_kw ← Exp(−τ) T_kw`, the window's
//! left perturbation in camera `k` up to the sign and second-order terms, so the
//! Jacobian in `τ` is minus the window's in `ξ`. Points are `(x, y, ρ)` in their first
//! keyframe (`Rn`); keyframe 0 is not a variable (held fixed).

use std::time::Instant;

use apex_solver::core::loss_functions::{HuberLoss, LossFunction};
use apex_solver::core::problem::Problem as ApexProblem;
use apex_solver::linalg::ExplicitSchurVariant;
use apex_solver::manifold::ManifoldType;
use apex_solver::{
    Factor, JacobianMode, LevenbergMarquardt, LevenbergMarquardtConfig, LinearSolverType,
};
use faer::mat::MatMut;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use nalgebra033 as na33;
use swarmpose_odometry::refine::model::{Matrix3x6, StereoModel, StereoObservation};

use crate::problem::{self, HUBER_K, KEYFRAMES, PoseCw, Problem, pose_error, robust_cost};

/// `T_kw` of the crate's `SE3` parameters `[tx, ty, tz, qw, qx, qy, qz]` of `T_wk`.
fn pose_of(x: &[f64]) -> PoseCw {
    let q = UnitQuaternion::from_quaternion(Quaternion::new(x[3], x[4], x[5], x[6]));
    let wc = Isometry3::from_parts(Translation3::new(x[0], x[1], x[2]), q);
    problem::pose_cw(&wc)
}

/// Writes a 3xN block into the crate's column-major Jacobian at column `col`.
fn put<const N: usize>(
    jac: &mut MatMut<'_, f64>,
    col: usize,
    m: &nalgebra::SMatrix<f64, 3, N>,
    sign: f64,
) {
    for c in 0..N {
        for r in 0..3 {
            jac[(r, col + c)] = sign * m[(r, c)];
        }
    }
}

/// A measurement in its anchor keyframe: variables `[point]`.
struct Anchor {
    model: StereoModel,
    z: StereoObservation,
}

impl Factor for Anchor {
    fn linearize(
        &self,
        params: &[&[f64]],
        residual: &mut [f64],
        jacobian: Option<MatMut<'_, f64>>,
    ) {
        let p = Vector3::new(params[0][0], params[0][1], params[0][2]);
        let l = self.model.in_reference(&p, &self.z);
        residual.copy_from_slice(l.residual.as_slice());
        if let Some(mut j) = jacobian {
            put(&mut j, 0, &l.d_point, 1.0);
        }
    }

    fn residual_dim(&self) -> usize {
        3
    }

    fn jacobian_shape(&self) -> (usize, usize) {
        (3, 3)
    }
}

/// A measurement in keyframe `j` of a point anchored in keyframe `a`: variables
/// `[T_wj, T_wa, point]`, or `[T_wj, point]` with the fixed keyframe 0 as anchor.
struct Seen {
    model: StereoModel,
    z: StereoObservation,
    fixed_anchor: Option<PoseCw>,
}

impl Factor for Seen {
    fn linearize(
        &self,
        params: &[&[f64]],
        residual: &mut [f64],
        jacobian: Option<MatMut<'_, f64>>,
    ) {
        let (rj, tj) = pose_of(params[0]);
        let ((ra, ta), pp) = match &self.fixed_anchor {
            Some(a) => (*a, params[1]),
            None => (pose_of(params[1]), params[2]),
        };
        let p = Vector3::new(pp[0], pp[1], pp[2]);
        let rot = rj * ra.transpose();
        let trans = tj - rot * ta;
        let Some(l) = self.model.in_current(&rot, &trans, &p, &self.z) else {
            // Behind the camera: a large residual and no gradient (swarmpose's window
            // rejects such a step outright).
            residual.fill(1e3);
            if let Some(mut j) = jacobian {
                j.fill(0.0);
            }
            return;
        };
        residual.copy_from_slice(l.residual.as_slice());
        let Some(mut j) = jacobian else { return };
        put(&mut j, 0, &l.d_pose, -1.0);
        let mut col = 6;
        if self.fixed_anchor.is_none() {
            // ∂h/∂ξ_a = [−ρ R_ja, R_ja [(x, y, 1)]×] (the window's, solve.rs).
            let mut dh_da = Matrix3x6::zeros();
            dh_da.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-rot * p.z));
            dh_da
                .fixed_view_mut::<3, 3>(0, 3)
                .copy_from(&(rot * Vector3::new(p.x, p.y, 1.0).cross_matrix()));
            put(&mut j, col, &(l.d_h * dh_da), -1.0);
            col += 6;
        }
        put(&mut j, col, &l.d_point, 1.0);
    }

    fn residual_dim(&self) -> usize {
        3
    }

    fn jacobian_shape(&self) -> (usize, usize) {
        (3, if self.fixed_anchor.is_some() { 9 } else { 15 })
    }
}

fn huber() -> Option<Box<dyn LossFunction + Send + Sync>> {
    HuberLoss::new(HUBER_K)
        .ok()
        .map(|h| Box::new(h) as Box<dyn LossFunction + Send + Sync>)
}

/// What a solve gave.
struct Solved {
    poses: Vec<PoseCw>,
    points: Vec<Vector3<f64>>,
    iterations: usize,
    status: String,
    /// Seconds spent building the problem.
    build_s: f64,
}

/// Builds and solves the problem, at most `max_iterations` iterations, stopping when the
/// cost decreases by less than 1e-6 of itself (the window's rule; the crate's other
/// tolerances at their defaults).
fn solve(p: &Problem, max_iterations: usize) -> Result<Solved, String> {
    let start = Instant::now();
    let mut prob = ApexProblem::new(JacobianMode::Sparse);
    let to_param = |pose: &Isometry3<f64>| {
        let q = pose.rotation.quaternion();
        let t = pose.translation.vector;
        na33::DVector::from_vec(vec![t.x, t.y, t.z, q.w, q.i, q.j, q.k])
    };
    let fixed = problem::pose_cw(&p.initial[0]);
    let poses: Vec<_> = p
        .initial
        .iter()
        .skip(1)
        .map(|pose| prob.add_variable(ManifoldType::SE3, to_param(pose)))
        .collect();
    let points0 = p.initial_points();
    let mut points = Vec::with_capacity(points0.len());
    for (t, x) in p.tracks.iter().zip(&points0) {
        let key = prob.add_variable(
            ManifoldType::RN,
            na33::DVector::from_vec(vec![x.x, x.y, x.z]),
        );
        prob.mark_for_elimination(key);
        points.push(key);
        for (o, z) in t.obs.iter().enumerate() {
            let model = p.model;
            let z = *z;
            if o == 0 {
                prob.add_residual_block(&[key], Box::new(Anchor { model, z }), huber());
                continue;
            }
            let j = poses[t.first + o - 1];
            if t.first == 0 {
                let f = Seen {
                    model,
                    z,
                    fixed_anchor: Some(fixed),
                };
                prob.add_residual_block(&[j, key], Box::new(f), huber());
            } else {
                let f = Seen {
                    model,
                    z,
                    fixed_anchor: None,
                };
                prob.add_residual_block(&[j, poses[t.first - 1], key], Box::new(f), huber());
            }
        }
    }
    let build_s = start.elapsed().as_secs_f64();
    let config = LevenbergMarquardtConfig::new()
        .with_linear_solver_type(LinearSolverType::ExplicitSparseSchur)
        .with_schur_variant(ExplicitSchurVariant::Sparse)
        .with_max_iterations(max_iterations)
        .with_cost_tolerance(1e-6);
    let out = LevenbergMarquardt::with_config(config)
        .optimize(&mut prob)
        .map_err(|e| format!("apex-solver: {e}"))?;
    let mut solved_poses = vec![fixed];
    for key in &poses {
        let v = out.parameters.get(*key).ok_or("apex-solver lost a pose")?;
        solved_poses.push(pose_of(v.as_param_slice()));
    }
    let solved_points = points
        .iter()
        .map(|key| {
            out.parameters.get(*key).map(|v| {
                let s = v.as_param_slice();
                Vector3::new(s[0], s[1], s[2])
            })
        })
        .collect::<Option<Vec<_>>>()
        .ok_or("apex-solver lost a point")?;
    Ok(Solved {
        poses: solved_poses,
        points: solved_points,
        iterations: out.iterations,
        status: out.status.to_string(),
        build_s,
    })
}

/// apex-solver's figures on `threads` rayon threads. `limit` is passed on as the crate's
/// `max_iterations`, which runs one iteration more than it says (`limit` 0 runs one).
pub fn run(
    p: &Problem,
    limit: usize,
    reps: usize,
    threads: usize,
    label: &str,
) -> Result<crate::Row, String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| e.to_string())?;
    let run = || pool.install(|| solve(p, limit));
    let solved = run()?;
    let mut times_s = Vec::with_capacity(reps);
    let mut build_s = Vec::with_capacity(reps);
    for _ in 0..reps {
        let t = Instant::now();
        let s = run()?;
        times_s.push(t.elapsed().as_secs_f64());
        build_s.push(s.build_s);
    }
    let newest = problem::pose_wc(&solved.poses[KEYFRAMES - 1]);
    Ok(crate::Row {
        name: format!("apex-solver 1.5.0, explicit sparse Schur, {label}, {threads} thread(s)"),
        times_s,
        iterations: solved.iterations,
        cost: Some(robust_cost(p, &solved.poses, &solved.points)),
        error: pose_error(&p.truth[KEYFRAMES - 1], &newest),
        newest,
        note: format!(
            "problem construction + optimize (construction median {:.3} s); max_iterations {limit}; status: {}",
            crate::median_p90(&build_s).0,
            solved.status
        ),
    })
}
