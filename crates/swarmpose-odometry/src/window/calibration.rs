//! How a change of the disparity correction enters the window: through new measurements
//! only ([`super::WindowConfig::correction_per_frame`]; not the default).
//!
//! The self-calibration decides again after every pair, and its correction moves from frame
//! to frame (its value as the evidence grows and fades, and its model when a term enters or
//! leaves). Solved under the newest correction, the window would re-triangulate every
//! keyframe's measurements under it: a change of the correction rescales the window's whole
//! path, and the pose given out, measured from the oldest keyframe (held fixed), moves by the
//! window's length times the change of scale: a robot reading the online pose sees its
//! velocity jump where nothing moved. On Karlsruhe the online steps differ from the smoothed
//! ones by up to 6.0 % that way at the frames where the correction's model changes, 0.6 %
//! with each measurement's own correction (docs/self-calibration.md).
//!
//! So each measurement keeps the correction in use for the frame where it was made (the
//! tracker's, after that frame's pair), entering the window with its disparity corrected by
//! it ([`corrected`]); the window solves with no correction of its own ([`solver_model`]).
//! The keyframes' measurements do not change when the correction does, so neither do their
//! relative poses, and a new correction enters the poses through the measurements of the
//! frames that follow. (Keeping the correction of the frame where each track began, tried
//! first, lags more: on Karlsruhe 1.6 % at model changes and a larger ATE.) The price is
//! that lag: solved under the newest correction, the window applies a better correction to
//! its last keyframes at once, and the drift is lower (docs/self-calibration.md). The
//! window's covariance still carries the correction's uncertainty: its Jacobian in the
//! correction's coefficients does not depend on their values. The focal length of the rig
//! (the opt-in `focal-length` cause) is not kept per frame: the window takes the newest.

use swarmpose_vision::frontend::DisparityCorrection;

use crate::refine::model::{StereoModel, StereoObservation};

/// The measurement `z` with its disparity corrected by `correction`: `d + δ(x_r, y)` at the
/// point `model` triangulates with it ([`StereoModel::anchor`]), the rest of `model` as it
/// is. Unchanged for no correction.
pub(super) fn corrected(
    model: &StereoModel,
    correction: &DisparityCorrection,
    z: &StereoObservation,
) -> StereoObservation {
    if *correction == DisparityCorrection::default() {
        return *z;
    }
    let with = StereoModel {
        correction: *correction,
        ..*model
    };
    let rho = with.anchor(z).z;
    StereoObservation {
        d: model.rig.fx * model.rig.baseline_m * rho,
        ..*z
    }
}

/// `model` without a disparity correction: the window's, on measurements corrected by their
/// tracks' own ([`corrected`]).
pub(super) fn solver_model(model: &StereoModel) -> StereoModel {
    StereoModel {
        correction: DisparityCorrection::default(),
        ..*model
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::refine::model::test_model;

    /// A corrected measurement, seen by a model without correction, is the point the
    /// correcting model triangulates; no correction leaves it as it is.
    #[test]
    fn a_corrected_measurement_triangulates_as_under_its_correction() {
        let c = DisparityCorrection {
            offset_px: 0.8,
            quadratic_px: -1.5,
            linear_x_px: 0.3,
            ..DisparityCorrection::default()
        };
        let model = test_model(DisparityCorrection::default());
        let z = StereoObservation {
            u: 900.0,
            v: 150.0,
            d: 12.5,
        };
        let under = StereoModel {
            correction: c,
            ..model
        }
        .anchor(&z);
        let zc = corrected(&model, &c, &z);
        let plain = solver_model(&model).anchor(&zc);
        assert!((plain - under).norm() < 1e-9, "{plain} against {under}");
        assert!(zc.d > z.d);
        assert_eq!(corrected(&model, &DisparityCorrection::default(), &z), z);
    }
}
