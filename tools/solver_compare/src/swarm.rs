//! The problem driven through swarmpose's public window API, `Window::add`, one keyframe
//! at a time, as the engine does.
//!
//! The engine refines the window with every frame it adds; here the last `add` alone is
//! to solve the whole ten-keyframe problem from the initial poses, like the crates. The
//! public API has no way to add keyframes without refining, so the window is given one
//! extra frame `X` before keyframe 0 that holds a poison track: anchored in `X` (which
//! looks backwards) and measured in keyframe 0, where its point is behind the camera.
//! Every refinement while `X` is in the window stops at that measurement and leaves the
//! poses as given; the last `add` pushes `X` out (the window holds ten keyframes), and
//! its refinement starts from exactly the initial poses. Nothing of `X` is left in that
//! refinement: the poison track has one measurement left, and tracks seen once are not
//! refined. The tool checks the window's counts of tracks and measurements against the
//! problem's.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use swarmpose_odometry::refine::evidence::MatrixK;
use swarmpose_odometry::refine::model::StereoObservation;
use swarmpose_odometry::window::{Link, Window, WindowConfig, WindowMotion, WindowReport};

use crate::problem::{HUBER_K, KEYFRAMES, Problem};

/// Feature index of the poison track.
const POISON: usize = usize::MAX - 1;

/// A window holding the poison frame and keyframes `0..KEYFRAMES - 1`, ready for the last
/// keyframe's `add`, with the links and poses of that call.
#[derive(Clone)]
pub struct Prepared {
    window: Window,
    last_links: Vec<Link>,
}

/// The frame index of keyframe `k` (the poison frame is 0).
fn frame(k: usize) -> usize {
    k + 1
}

/// The inlier links from keyframe `k - 1` to keyframe `k`: every track seen in both.
/// A track's feature index is its index in the problem, in every keyframe.
fn links(p: &Problem, k: usize) -> Vec<Link> {
    p.tracks
        .iter()
        .enumerate()
        .filter(|(_, t)| t.first < k && k < t.first + t.obs.len())
        .map(|(i, t)| {
            let (reference, current) = (t.obs[k - 1 - t.first], t.obs[k - t.first]);
            Link {
                reference_feature: i,
                current_feature: i,
                reference,
                current,
                current_keypoint: current,
            }
        })
        .collect()
}

/// The window fed up to keyframe `KEYFRAMES - 2` without any refinement.
pub fn prepare(p: &Problem, max_iterations: usize) -> Result<Prepared, String> {
    let model = &p.model;
    let cov = MatrixK::zeros();
    let mut window = Window::new(WindowConfig {
        keyframes: KEYFRAMES,
        max_iterations,
        huber_k: HUBER_K,
        ..WindowConfig::default()
    });
    // X: keyframe 0's camera turned to look backwards.
    let x_pose = p.initial[0]
        * Isometry3::from_parts(
            Translation3::identity(),
            UnitQuaternion::from_scaled_axis(Vector3::y() * std::f64::consts::PI),
        );
    let poison = |u: f64| StereoObservation {
        u,
        v: 180.0,
        d: 20.0,
    };
    let link = Link {
        reference_feature: POISON,
        current_feature: POISON,
        reference: poison(600.0),
        current: poison(100.0),
        current_keypoint: poison(100.0),
    };
    let first = window.add(
        (model, &cov),
        (0, &x_pose),
        (frame(0), &p.initial[0]),
        &[link],
        None,
    );
    if first.is_some() || window.len() != 2 {
        return Err("the poison frame did not start the window".into());
    }
    for k in 1..KEYFRAMES - 1 {
        let out = window.add(
            (model, &cov),
            (frame(k - 1), &p.initial[k - 1]),
            (frame(k), &p.initial[k]),
            &links(p, k),
            None,
        );
        // With no iteration there is nothing to stop: the refinement returns the poses
        // as given.
        if out.is_some() && max_iterations > 0 {
            return Err(format!(
                "keyframe {k} was refined while X was in the window"
            ));
        }
        if window.len() != k + 2 {
            return Err(format!("keyframe {k} did not stay in the window"));
        }
    }
    Ok(Prepared {
        window,
        last_links: links(p, KEYFRAMES - 1),
    })
}

/// What the last `add` gave.
pub struct Solved {
    /// The newest keyframe, the camera in the world.
    pub pose: Isometry3<f64>,
    pub report: WindowReport,
    pub motion: WindowMotion,
}

/// The last keyframe's `add` on a copy of `prep` (the window's refinement of all ten).
pub fn solve(p: &Problem, prep: &mut Prepared) -> Result<Solved, String> {
    let k = KEYFRAMES - 1;
    let (pose, report, motion) = prep
        .window
        .add(
            (&p.model, &MatrixK::zeros()),
            (frame(k - 1), &p.initial[k - 1]),
            (frame(k), &p.initial[k]),
            &prep.last_links,
            None,
        )
        .ok_or("the window's refinement failed")?;
    if report.keyframes != KEYFRAMES || prep.window.len() != KEYFRAMES {
        return Err(format!(
            "the window holds {} keyframes, not {KEYFRAMES}",
            report.keyframes
        ));
    }
    Ok(Solved {
        pose,
        report,
        motion,
    })
}
