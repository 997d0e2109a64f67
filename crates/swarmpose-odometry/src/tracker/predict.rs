//! The constant-velocity prediction: the last tracked motion, scaled to another time
//! step (frames held while tracking fails, and the check for a second motion).

use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use swarmpose_vision::features::Descriptor;

use super::Tracker;

/// The last tracked motion and the time it spans.
#[derive(Debug, Clone, Copy)]
pub(super) struct Velocity {
    pub(super) motion: Isometry3<f64>,
    pub(super) dt_s: f64,
}

/// `m` scaled to `f` times its rotation angle and translation (constant velocity over
/// a different time step).
pub(super) fn scale_motion(m: &Isometry3<f64>, f: f64) -> Isometry3<f64> {
    if (f - 1.0).abs() < 1e-12 {
        return *m;
    }
    let r = UnitQuaternion::from_scaled_axis(m.rotation.scaled_axis() * f);
    Isometry3::from_parts(Translation3::from(m.translation.vector * f), r)
}

impl<D: Descriptor> Tracker<D> {
    /// The constant-velocity motion from the reference, taken at `ref_timestamp_s`, to a
    /// frame taken at `timestamp_s`: the last tracked motion scaled to that time span, if
    /// it is recent ([`crate::OdometryConfig::max_prediction_s`]).
    pub(super) fn prediction(
        &self,
        ref_timestamp_s: f64,
        timestamp_s: f64,
    ) -> Option<Isometry3<f64>> {
        let v = self.velocity?;
        let recent = self
            .last_tracked_s
            .is_some_and(|t| timestamp_s - t <= self.config.max_prediction_s);
        (recent && v.dt_s > 0.0)
            .then(|| scale_motion(&v.motion, (timestamp_s - ref_timestamp_s) / v.dt_s))
    }
}
