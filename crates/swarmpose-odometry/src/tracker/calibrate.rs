//! The self-calibration's part of a tracked pair: the row offsets of its confirmed
//! matches, and its rigidity evidence, computed again under the correction that evidence
//! leads to until the two agree ([`crate::selfcal`]).

use swarmpose_vision::features::Descriptor;
use swarmpose_vision::frontend::{DisparityCorrection, FrameMatches, StereoFrame};

use super::Tracker;
use crate::estimate::{Observations, median_flow_px};
use crate::refine::{Refined, refine};
use crate::selfcal::{CorrectionModel, NoEvidence, SelfCalibration, scene};

/// A new correction that moves no disparity by more than this, pixels, does not call
/// for a second refinement of the pair.
const CORRECTION_TOLERANCE_PX: f64 = 0.05;

/// Smallest median image motion of a pair's inliers, pixels, for the pair to add rigidity
/// evidence to the self-calibration: below a pixel the front end's own sub-pixel errors
/// are as large as the motion and bend the pair like a disparity offset (on a rendered
/// path of 5 cm a frame, an exact rig, a -0.7 px offset was chosen and dropped from frame
/// to frame; RESULTS.md). Such a pair carries almost no information about the
/// calibration anyway; its time still fades the evidence. Set from that reasoning, not
/// tuned: every pair of the shared real sequences but the still EuRoC clip moves more.
const MIN_EVIDENCE_FLOW_PX: f64 = 1.0;

/// Most refinements of a pair again under the correction its own evidence leads to.
const FIXED_POINT_ITERATIONS: usize = 4;

/// A pair's refinement with the correction (and focal length change, pixels) it was
/// refined under, and that correction's model.
pub(super) type Best = (Refined, DisparityCorrection, f64, CorrectionModel);

impl<D: Descriptor> Tracker<D> {
    /// Largest change, pixels, of the correction and the focal length (`a` and `b`, each
    /// with its focal length change) over the image's columns.
    pub(super) fn correction_change(
        &self,
        (a, fa): (&DisparityCorrection, f64),
        (b, fb): (&DisparityCorrection, f64),
    ) -> f64 {
        let r = &self.camera.rig;
        let (w, h) = (self.camera.width as f64, self.camera.height as f64);
        let mut diff = b.coefficients();
        for (d, a) in diff.iter_mut().zip(a.coefficients()) {
            *d -= a;
        }
        let diff = DisparityCorrection::from_coefficients(diff);
        // At the corners and edge midpoints of the image.
        let xs = [-r.cx / r.fx, 0.0, (w - r.cx) / r.fx];
        let ys = [-r.cy / r.fy, 0.0, (h - r.cy) / r.fy];
        let disparity = xs
            .iter()
            .flat_map(|x| ys.iter().map(move |y| diff.at_normalised(*x, *y).abs()))
            .fold(0.0, f64::max);
        // A focal length change moves a pixel at normalised x by Δf x.
        let focal = xs.iter().map(|x| x.abs()).fold(0.0, f64::max) * (fb - fa).abs();
        disparity.max(focal)
    }

    /// True when the reference measurements of the pair's `inliers` lie on more than one
    /// plane in `(u, v, d)` ([`scene::more_than_one_plane`], against the disparity noise).
    fn scene_shows_depth(&self, obs: &Observations, inliers: &[usize]) -> bool {
        let points: Vec<(f64, f64, f64)> = inliers
            .iter()
            .filter_map(|&k| obs.reference.get(k))
            .map(|z| (z.u, z.v, z.d))
            .collect();
        scene::more_than_one_plane(
            &points,
            self.noise.disparity_px,
            self.config.selfcal.min_off_plane_sigmas,
        )
    }

    /// Adds the evidence of the pair `m` (the current frame `frame`, its measurements
    /// `obs`, `dt_s` seconds after its reference) to `selfcal` (the tracker's, taken out
    /// of it while the reference frame is borrowed), and returns the pair's refinement
    /// under the correction the evidence leads to (`best` when it does not move); `min`
    /// inliers at least.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn self_calibrate(
        &self,
        selfcal: &mut SelfCalibration,
        frame: &StereoFrame<D>,
        m: &FrameMatches,
        obs: &Observations,
        mut best: Best,
        dt_s: f64,
        min: usize,
    ) -> Best {
        // The row offsets of the current frame's confirmed matches.
        let rows = best.0.inliers.iter().map(|&k| {
            let j = m.src_index[obs.source[k]];
            let kp = &frame.left_keypoints[j];
            (
                f64::from(kp.x),
                f64::from(kp.y),
                f64::from(frame.disparities_px[j]),
                frame.row_offsets_px.get(j).copied().unwrap_or(f32::NAN),
            )
        });
        selfcal.add_rows(rows, &self.camera.rig, self.camera.width);
        // The pair's evidence depends on the correction it is computed under (its
        // inliers are gated and weighted under it), so it is computed again under
        // the correction it leads to, until the two agree (a fixed point per pair). A
        // pair that moved too little adds none (the rows may still move the decision).
        // A pair whose scene is one plane cannot tell a disparity offset from the scene's
        // scale ([`scene`]): it adds none either.
        let evidence = if median_flow_px(obs, &best.0.inliers) < MIN_EVIDENCE_FLOW_PX {
            Err(NoEvidence::TooLittleMotion)
        } else if !self.scene_shows_depth(obs, &best.0.inliers) {
            Err(NoEvidence::OnePlane)
        } else {
            Ok(())
        };
        let add = |cal: &mut SelfCalibration, best: &Best| match evidence {
            Ok(()) => {
                cal.add_pair(&best.0.reduced, &best.1, best.2, best.0.scale2, dt_s);
            }
            Err(why) => {
                cal.add_pair_without_evidence(dt_s, why);
            }
        };
        let before = selfcal.clone();
        let mut cal = before.clone();
        add(&mut cal, &best);
        for _ in 0..FIXED_POINT_ITERATIONS {
            let d = *cal.decision();
            let change = self.correction_change((&best.1, best.2), (&d.correction, d.focal_px));
            if change <= CORRECTION_TOLERANCE_PX {
                break;
            }
            let Ok(r) = refine(
                &self.model(d.correction, d.focal_px),
                &self.config.refinement,
                &obs.reference,
                &obs.current,
                Some(&obs.folds),
                &best.0.motion,
                min,
            ) else {
                break;
            };
            best = (r, d.correction, d.focal_px, d.model);
            cal = before.clone();
            add(&mut cal, &best);
        }
        *selfcal = cal;
        best
    }
}
