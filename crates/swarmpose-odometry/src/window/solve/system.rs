//! The window's reduced system: each track's measurements linearised at the keyframe
//! poses and its point eliminated by its Schur complement, into the dense system of the
//! free poses ([`build`]).
//!
//! The refinement factorises its system by Cholesky, which reads the lower triangle only
//! (nalgebra's `cholesky()` and its `solve_mut`): there the blocks above the diagonal
//! are not computed but mirrored from those below ([`Blocks::Lower`]), and every entry
//! the factorisation reads is the same number, bit for bit, as with all blocks
//! computed ([`Blocks::Full`], for the marginalisation, which uses the whole matrix).
//! The blocks on the diagonal are always computed whole: a block `bᵀ w b` summed in
//! floating point is not exactly symmetric.

use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, SMatrix, Vector3, Vector6};
use swarmpose_vision::simd::{Kernel, dispatch};

use super::{Eliminated, Scratch};
use crate::nls::pose::Pose;
use crate::nls::products::{add_product, sub_product};
use crate::nls::robust::huber;
use crate::nls::schur::{point_inverse, through_point};
use crate::refine::Prepared;
use crate::refine::evidence::Matrix6xK;
use crate::refine::model::{CALIBRATION_TERMS, Matrix3x6, StereoModel, StereoObservation};
use crate::window::residual::{linearize, relative_poses};
use crate::window::tracks::Tracks;

/// Adds `block` to the `H_pξ` of variable `v` among `hpx[start..]`, and `score` to its
/// entry of `hgx` (kept beside `hpx`).
#[inline(always)]
fn add_hpx(
    (hpx, hgx): (&mut Vec<(usize, Matrix3x6)>, &mut Vec<Vector6<f64>>),
    start: usize,
    v: usize,
    (block, score): (&Matrix3x6, &Vector6<f64>),
) {
    match hpx[start..].iter().position(|(i, _)| *i == v) {
        Some(k) => {
            hpx[start + k].1 += block;
            hgx[start + k] += score;
        }
        None => {
            hpx.push((v, *block));
            hgx.push(*score);
        }
    }
}

/// Which blocks of the reduced system [`build`] computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Blocks {
    /// Every block.
    Full,
    /// The blocks on and below the diagonal (pose variable of the row not before that
    /// of the column); those above are their mirror (issue 34). For a solver that reads
    /// the lower triangle only.
    Lower,
}

impl Blocks {
    /// Whether the block of row variable `v1` and column variable `v2` is computed.
    #[inline(always)]
    fn computes(self, v1: usize, v2: usize) -> bool {
        self == Self::Full || v2 <= v1
    }
}

impl Scratch {
    /// Empties the buffers for a reduced system of `m` pose variables.
    fn reset(&mut self, m: usize) {
        self.elim.clear();
        self.hpx.clear();
        self.hgx.clear();
        self.blocks.clear();
        self.blocks.resize(m * m, Matrix6::zeros());
        self.gradient.clear();
        self.gradient.resize(m, Vector6::zeros());
        self.chi2 = 0.0;
        self.cost = 0.0;
        self.pose_calibration.clear();
        self.pose_calibration.resize(m, Matrix6xK::zeros());
    }

    /// The reduced system's blocks of `m` pose variables written out densely into `s`
    /// and `g`; with [`Blocks::Lower`], the entries of the blocks above the diagonal are
    /// those below, mirrored.
    fn assemble(&mut self, m: usize, blocks: Blocks) {
        let size = 6 * m;
        if self.s.shape() != (size, size) {
            self.s = DMatrix::zeros(size, size);
        }
        if self.g.len() != size {
            self.g = DVector::zeros(size);
        }
        for c in 0..size {
            for r in 0..size {
                let (v1, v2) = (r / 6, c / 6);
                self.s[(r, c)] = if blocks.computes(v1, v2) {
                    self.blocks[v1 * m + v2][(r % 6, c % 6)]
                } else {
                    self.blocks[v2 * m + v1][(c % 6, r % 6)]
                };
            }
        }
        for r in 0..size {
            self.g[r] = self.gradient[r / 6][r % 6];
        }
    }
}

/// The reduced system at `poses` and `points`, over the poses after the first `fixed`
/// (held fixed: 1 in the refinement, 0 to marginalise the first), into `sc.s` and `sc.g`,
/// with the `blocks` computed; `None` if a point left a view or its block is singular.
/// Compiled for the CPU's best instruction set ([`dispatch`]): the same IEEE operations,
/// fewer instructions (issue 34).
pub(super) fn build(
    model: &StereoModel,
    k: f64,
    (poses, fixed, blocks): (&[Pose], usize, Blocks),
    tracks: &Tracks,
    points: &[Vector3<f64>],
    sc: &mut Scratch,
) -> Option<()> {
    dispatch(Build {
        model,
        k,
        poses: (poses, fixed, blocks),
        tracks,
        points,
        sc,
    })
}

/// A call of [`build`] for [`dispatch`].
struct Build<'a> {
    model: &'a StereoModel,
    k: f64,
    poses: (&'a [Pose], usize, Blocks),
    tracks: &'a Tracks,
    points: &'a [Vector3<f64>],
    sc: &'a mut Scratch,
}

impl Kernel for Build<'_> {
    type Output = Option<()>;

    #[inline(always)]
    fn run(self) -> Option<()> {
        let Self {
            model,
            k,
            poses,
            tracks,
            points,
            sc,
        } = self;
        build_with(model, k, poses, tracks, points, sc)
    }
}

/// [`build`]'s body, compiled into each instruction set's copy.
#[inline(always)]
fn build_with(
    model: &StereoModel,
    k: f64,
    (poses, fixed, blocks): (&[Pose], usize, Blocks),
    tracks: &Tracks,
    points: &[Vector3<f64>],
    sc: &mut Scratch,
) -> Option<()> {
    let n = poses.len();
    let m = n.checked_sub(fixed)?;
    // The model's constants once per system, not per measurement (the same bits).
    let model = &Prepared::new(model);
    relative_poses(poses, &mut sc.rel);
    sc.reset(m);
    for ((_, obs), p) in tracks.iter().zip(points) {
        let point = add_track(model, k, (n, fixed, m, blocks), obs, p, sc)?;
        eliminate_point(point, (m, blocks), sc)?;
    }
    sc.assemble(m, blocks);
    Some(())
}

/// A track's point blocks, summed over its measurements: `H_pp`, the gradient `g_p` and
/// `H_pc` (by the calibration terms), and where its `H_pξ` blocks begin in
/// [`Scratch::hpx`].
struct PointSums {
    hpp: Matrix3<f64>,
    gp: Vector3<f64>,
    hpc: SMatrix<f64, 3, CALIBRATION_TERMS>,
    start: usize,
}

/// Adds the measurements `obs` of one track (the first in its anchor keyframe) at its
/// point `p` to the system of `m` pose variables (`n` keyframes, the first `fixed` held
/// fixed): their cost, the pose blocks, and the track's `H_pξ` blocks (into `sc.hpx`);
/// returns the point's own blocks, or `None` if the point left a view.
#[inline(always)]
fn add_track(
    model: &Prepared,
    k: f64,
    (n, fixed, m, blocks): (usize, usize, usize, Blocks),
    obs: &[(usize, StereoObservation)],
    p: &Vector3<f64>,
    sc: &mut Scratch,
) -> Option<PointSums> {
    // Variable of keyframe slot `i`: the first `fixed` slots have none.
    let var = |slot: usize| slot.checked_sub(fixed);
    let anchor = obs[0].0;
    let mut point = PointSums {
        hpp: Matrix3::zeros(),
        gp: Vector3::zeros(),
        hpc: SMatrix::<f64, 3, CALIBRATION_TERMS>::zeros(),
        start: sc.hpx.len(),
    };
    for (slot, z) in obs {
        let j = linearize(model, (&sc.rel, n), anchor, *slot, p, z)?;
        let r2 = j.residual.norm_squared();
        let (w, rho) = huber(r2, k);
        sc.chi2 += w * r2;
        sc.cost += rho;
        let dpw = j.d_point.transpose() * w;
        // nalgebra's products bit for bit, without temporaries ([`products`]).
        add_product(&mut point.hpp, &dpw, &j.d_point);
        add_product(&mut point.gp, &dpw, &j.residual);
        add_product(&mut point.hpc, &dpw, &j.d_correction);
        // By reference: the two 3x6 blocks are not copied out (issue 34).
        let Some((dj, da)) = &j.poses else {
            continue;
        };
        let pair = [(var(*slot), dj), (var(anchor), da)];
        for &(v1, b1) in &pair {
            let Some(v1) = v1 else { continue };
            let b1w = b1.transpose() * w;
            let score = b1w * j.residual;
            let hpx = (&mut sc.hpx, &mut sc.hgx);
            add_hpx(hpx, point.start, v1, (&(dpw * b1), &score));
            sc.gradient[v1] += score;
            add_product(&mut sc.pose_calibration[v1], &b1w, &j.d_correction);
            for &(v2, b2) in &pair {
                let Some(v2) = v2.filter(|&v2| blocks.computes(v1, v2)) else {
                    continue;
                };
                add_product(&mut sc.blocks[v1 * m + v2], &b1w, b2);
            }
        }
    }
    Some(point)
}

/// Eliminates the track's `point` (its Schur complement subtracted from the `blocks` of
/// the system of `m` pose variables) and keeps its blocks for back-substitution; `None`
/// when its block is singular.
#[inline(always)]
fn eliminate_point(point: PointSums, (m, blocks): (usize, Blocks), sc: &mut Scratch) -> Option<()> {
    let PointSums {
        hpp,
        gp,
        hpc,
        start,
    } = point;
    let hpp_inv = point_inverse(&hpp)?;
    let end = sc.hpx.len();
    for i1 in start..end {
        let (v1, b1) = sc.hpx[i1];
        let t1 = through_point(&b1, &hpp_inv);
        sub_product(&mut sc.gradient[v1], &t1, &gp);
        sub_product(&mut sc.pose_calibration[v1], &t1, &hpc);
        for i2 in start..end {
            let (v2, b2) = &sc.hpx[i2];
            if blocks.computes(v1, *v2) {
                sub_product(&mut sc.blocks[v1 * m + v2], &t1, b2);
            }
        }
    }
    sc.elim.push(Eliminated {
        hpp_inv,
        gp,
        start,
        end,
    });
    Some(())
}
