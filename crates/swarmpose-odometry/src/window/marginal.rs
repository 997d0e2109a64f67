//! Marginalisation of the keyframe that leaves the window ([`WindowConfig::marginalise`]).
//!
//! Without it, the oldest keyframe's information is discarded when it leaves: the next
//! keyframe becomes the fixed one at its current estimate, and the measurements of the
//! keyframe that left no longer constrain anything. With it, the leaving keyframe's pose
//! and the points of the tracks that go with it ([`Marginalisation`]) are eliminated from
//! the window's system linearised at the current estimate (the Schur complement), which
//! leaves a Gaussian prior on the remaining keyframes' poses, kept with its linearisation
//! point and added to every later refinement (the sliding-window filter of OKVIS and DSO).
//!
//! **Gauge.** The leaving keyframe is a free variable while it is marginalised (no pose is
//! held fixed): the measurements only see relative poses, so the prior has the 6-DoF
//! null space of a rigid motion of all the poses, and it describes the relative poses of
//! the keyframes that remain, nothing absolute. The refinement then keeps its gauge as
//! without a prior, the oldest remaining keyframe held fixed at its estimate: the prior
//! is conditioned on it (its rows dropped; its deviation from the linearisation point,
//! zero since it is held where it was linearised, enters the others' gradient). The
//! alternative, a prior with a fixed gauge carried from the first keyframe, would make the
//! oldest keyframe's absolute pose an unknown again, which the engine never revises.
//!
//! **Calibration.** The self-calibration changes the disparity correction (and may change
//! the focal length) from frame to frame, and the measurements in the prior were
//! linearised with the terms of their time. The prior keeps its sensitivity to them,
//! `∂b/∂c = S_ξc` (the pose-calibration block of the eliminated system, as the
//! refinement's), and the terms it was linearised at: its gradient is taken as
//! `b + S_ξc (c − c_lin)` with the current terms `c`, and `S_ξc` joins the refinement's
//! for the calibration's part of the covariance.
//!
//! **Linearisation point.** The prior is a quadratic in the perturbation `δ` of each of
//! its poses from the pose it was linearised at, `T = E(δ) T_lin` (`E` as in
//! [`super::solve`]); its Jacobian is taken as the identity (the poses move little inside
//! a window), so its information never changes with the estimate. When it is
//! marginalised again (with the next keyframe that leaves), it is moved exactly to the
//! current estimate (`b ← b + H δ`, the same quadratic) and combined with the new
//! measurements linearised there. The window's measurements keep their Jacobians at the
//! current estimate (no first-estimate Jacobians: they would need the point and pose
//! estimates of the moment each was linearised).

use std::collections::HashSet;
use std::hash::BuildHasher;

use nalgebra::{DMatrix, DVector, Matrix6, SymmetricEigen};

use super::prior::{Prior, terms};
use super::solve::{self, Scratch};
use super::tracks::{Tracks, tracks_of};
use super::{Keyframe, WindowConfig};
use crate::nls::pose::Pose;
use crate::refine::evidence::Matrix6xK;
use crate::refine::model::{CALIBRATION_TERMS, StereoModel};

/// What happens to the oldest keyframe's information when it leaves the window.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
pub enum Marginalisation {
    /// Discarded (the default): the next keyframe becomes the fixed one at its estimate.
    #[default]
    Off,
    /// The keyframe's pose is marginalised with the tracks it sees that have ended (not
    /// measured in the newest frame), all their measurements in the window; its
    /// measurements of tracks that go on are dropped (as OKVIS does with landmarks still
    /// observed), so those tracks keep their points.
    Finished,
    /// The keyframe's pose is marginalised with every track it sees, all their
    /// measurements in the window (as DSO does with the points a frame hosts); a track
    /// that goes on begins a new point from the newest frame.
    All,
}

impl Marginalisation {
    /// Every mode, in the order of [`Marginalisation::NAMES`].
    pub const ALL: [Marginalisation; 3] = [Self::Off, Self::Finished, Self::All];
    /// The modes' names (`off`, `finished`, `all`), as the command line takes them.
    pub const NAMES: [&'static str; 3] = ["off", "finished", "all"];

    /// The mode's name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Off => Self::NAMES[0],
            Self::Finished => Self::NAMES[1],
            Self::All => Self::NAMES[2],
        }
    }
}

impl std::str::FromStr for Marginalisation {
    type Err = String;

    /// One of [`Marginalisation::NAMES`].
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| format!("{s:?}: expected one of {}", Self::NAMES.join(", ")))
    }
}

/// The pseudo-inverse of a symmetric positive semi-definite 6x6 block (eigenvalues below
/// `1e-9` of the largest taken as zero: a pose its measurements do not constrain in some
/// direction has no cross-information in it either).
fn pseudo_inverse(m: &Matrix6<f64>) -> Matrix6<f64> {
    let e = SymmetricEigen::new((m + m.transpose()) * 0.5);
    let top = e.eigenvalues.max();
    if !(top.is_finite() && top > 0.0) {
        return Matrix6::zeros();
    }
    let inv = e
        .eigenvalues
        .map(|l| if l > 1e-9 * top { 1.0 / l } else { 0.0 });
    e.eigenvectors * Matrix6::from_diagonal(&inv) * e.eigenvectors.transpose()
}

/// The tracks that go with `leaving` (the keyframe that leaves) under `mode`: those whose
/// track has ended (not in `live`, the newest frame's), or all it sees.
pub(super) fn leaving_tracks<S: BuildHasher>(
    leaving: &Keyframe,
    live: &HashSet<u32, S>,
    mode: Marginalisation,
) -> HashSet<u32> {
    leaving
        .observations
        .iter()
        .map(|(t, _)| *t)
        .filter(|t| mode == Marginalisation::All || !live.contains(t))
        .collect()
}

/// Marginalises the oldest keyframe `frames[0]` (about to leave the window) with the
/// tracks `mode` sends with it (`live`: the tracks the newest frame measures), on top of
/// the `prior` of earlier ones: returns the prior on `frames[1..]`, and removes the
/// marginalised tracks' measurements from `frames[1..]` (they are in the prior now).
/// `None` (nothing removed) when there is nothing to marginalise into or the system is
/// singular: the keyframe's information is then discarded as without marginalisation.
pub(crate) fn marginalise<S: BuildHasher>(
    model: &StereoModel,
    config: &WindowConfig,
    frames: &mut [Keyframe],
    prior: Option<Prior>,
    live: &HashSet<u32, S>,
    mode: Marginalisation,
) -> Option<Prior> {
    let n = frames.len();
    if n < 2 || mode == Marginalisation::Off {
        return None;
    }
    let leaving = leaving_tracks(&frames[0], live, mode);
    let poses: Vec<Pose> = frames.iter().map(|f| Pose::of(&f.pose_cw)).collect();
    let mut sc = Scratch::default();
    let k = config.huber_k;
    let mut tracks = Tracks::default();
    tracks_of(
        model,
        k,
        frames,
        &poses,
        |t| leaving.contains(&t),
        &mut sc.rel,
        &mut tracks,
    );
    let (mut s, mut g) = if tracks.is_empty() {
        (DMatrix::zeros(6 * n, 6 * n), DVector::zeros(6 * n))
    } else {
        solve::linearised_system(model, k, &poses, &tracks, &mut sc)?
    };
    sc.pose_calibration.resize(n, Matrix6xK::zeros());
    let c = terms(model);
    if let Some(p) = &prior
        && let Some(slots) = p.on(frames)
    {
        p.add_to(
            (&slots, &poses, 0),
            &c,
            (&mut s, &mut g),
            &mut sc.pose_calibration,
        );
    }
    let cal = DMatrix::from_fn(6 * n, CALIBRATION_TERMS, |r, col| {
        sc.pose_calibration[r / 6][(r % 6, col)]
    });
    let s00: Matrix6<f64> = s.fixed_view::<6, 6>(0, 0).into_owned();
    let inv = pseudo_inverse(&s00);
    let r = 6 * (n - 1);
    let sr0 = s.view((6, 0), (r, 6)).into_owned();
    let t = &sr0 * inv;
    let mut information = s.view((6, 6), (r, r)).into_owned() - &t * sr0.transpose();
    information = (&information + information.transpose()) * 0.5;
    let gradient = g.rows(6, r).into_owned() - &t * g.fixed_rows::<6>(0);
    let calibration = cal.rows(6, r).into_owned() - &t * cal.rows(0, 6);
    if !(information.iter().all(|v| v.is_finite())
        && gradient.iter().all(|v| v.is_finite())
        && calibration.iter().all(|v| v.is_finite()))
    {
        return None;
    }
    for f in frames.iter_mut().skip(1) {
        f.observations.retain(|(t, _)| !leaving.contains(t));
    }
    Some(Prior {
        frames: frames[1..].iter().map(|f| f.index).collect(),
        linearised: poses[1..].to_vec(),
        information,
        gradient,
        calibration,
        at: c,
    })
}

#[cfg(test)]
#[path = "marginal_tests.rs"]
mod tests;
