//! swarmpose's poses and covariances as ROS 2 messages: the conventions, in one place.
//!
//! - **Frames.** swarmpose's poses are those of the left camera in the left camera frame
//!   of the first frame, optical axes (x right, y down, z forward, metres). ROS's `odom`
//!   frame has body axes (REP-103: x forward, y left, z up): `odom` here is the first
//!   camera's position with body axes, so a pose `T` (camera `k` in camera 0) becomes
//!   `A T` with `A` = [`odom_from_optical`] (`x_odom = z_cam`, `y_odom = -x_cam`,
//!   `z_odom = -y_cam`). The child frame is the camera's optical frame (the images'
//!   `frame_id` when read from a bag).
//! - **Pose covariance.** swarmpose measures each frame's motion from a reference frame,
//!   with the 6x6 covariance of `ξ = (ν, ω)` (metres, radians) in `T_true = T ∘ E(ξ)`,
//!   `E(ξ): P ↦ Exp(ω) P + ν`, in camera `k`'s axes. The message's pose covariance is that
//!   covariance with its axes turned into `odom`'s (`J C Jᵀ`, `J = diag(R, R)`, `R` the
//!   camera's orientation in `odom`), in ROS's order `(x, y, z, rot x, rot y, rot z)`,
//!   which is the order of `ξ`: the uncertainty of this frame's motion measurement, not
//!   of the accumulated pose (use the twist, or robot_localization's differential mode).
//!   The first frame: zero. A frame not tracked (held at constant velocity or lost):
//!   [`UNKNOWN_VARIANCE`] on the diagonal.
//! - **Twist**, in the child (camera) frame: the measured motion over the time since its
//!   reference frame, `v = Rᵀ t / Δt` (m/s), `w = log(R) / Δt` (rad/s), covariance
//!   `C / Δt²` (first order). Untracked frames: zero twist, [`UNKNOWN_VARIANCE`].

use nalgebra::{Isometry3, Matrix3, Matrix6, Rotation3, Translation3, UnitQuaternion};

use crate::msg::{
    Header, Odometry, Point, Pose, PoseWithCovariance, Quaternion, Time, Twist,
    TwistWithCovariance, Vector3,
};

/// The variance given to what is not known (a frame that was not tracked), m² and rad²:
/// large enough for any filter to ignore it.
pub const UNKNOWN_VARIANCE: f64 = 1e6;

/// The rotation from optical camera axes to ROS body axes.
#[must_use]
pub fn odom_from_optical() -> UnitQuaternion<f64> {
    let a = Matrix3::new(0.0, 0.0, 1.0, -1.0, 0.0, 0.0, 0.0, -1.0, 0.0);
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(a))
}

/// A pose of the camera (in the first camera's optical frame) in `odom`.
#[must_use]
pub fn pose_in_odom(pose: &Isometry3<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::identity(), odom_from_optical()) * pose
}

/// An isometry as a ROS pose.
#[must_use]
pub fn ros_pose(p: &Isometry3<f64>) -> Pose {
    let t = p.translation.vector;
    let q = p.rotation.quaternion();
    Pose {
        position: Point {
            x: t.x,
            y: t.y,
            z: t.z,
        },
        orientation: Quaternion {
            x: q.i,
            y: q.j,
            z: q.k,
            w: q.w,
        },
    }
}

/// Seconds from the header stamp `first_ns` to `ns` (nanoseconds): a stream's time as
/// the engine takes it, the same for a bag read offline and for the live node.
#[must_use]
pub fn seconds_since(first_ns: i64, ns: i64) -> f64 {
    (ns - first_ns) as f64 * 1e-9
}

/// A 6x6 matrix as ROS's row-major 36 numbers.
#[must_use]
pub fn row_major(m: &Matrix6<f64>) -> [f64; 36] {
    std::array::from_fn(|k| m[(k / 6, k % 6)])
}

fn unknown() -> [f64; 36] {
    row_major(&(Matrix6::identity() * UNKNOWN_VARIANCE))
}

/// A frame's motion measurement: the motion from its reference frame (`T_ref,k`: this
/// camera's pose in the reference camera), its covariance, and the time between them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measurement {
    /// `T_ref,k`, metres.
    pub motion: Isometry3<f64>,
    /// Covariance of `ξ` (see the module), when the motion was refined.
    pub covariance: Option<Matrix6<f64>>,
    /// Time from the reference frame to this one, seconds.
    pub dt_s: f64,
}

/// Names of the frames of the messages.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FrameNames {
    /// The fixed frame (`odom`).
    pub odom: String,
    /// The camera's optical frame.
    pub camera: String,
}

impl Default for FrameNames {
    fn default() -> Self {
        Self {
            odom: "odom".to_owned(),
            camera: "camera_optical".to_owned(),
        }
    }
}

/// The `nav_msgs/Odometry` of a frame at `stamp_ns` whose camera pose (first camera's
/// optical frame) is `pose`: `first` for the first frame, `measured` when the frame was
/// tracked.
#[must_use]
pub fn odometry(
    stamp_ns: i64,
    pose: &Isometry3<f64>,
    first: bool,
    measured: Option<&Measurement>,
    names: &FrameNames,
) -> Odometry {
    let in_odom = pose_in_odom(pose);
    let r = in_odom.rotation.to_rotation_matrix();
    let mut j = Matrix6::zeros();
    j.fixed_view_mut::<3, 3>(0, 0).copy_from(r.matrix());
    j.fixed_view_mut::<3, 3>(3, 3).copy_from(r.matrix());
    let pose_cov = match (first, measured.and_then(|m| m.covariance)) {
        (true, _) => [0.0; 36],
        (false, Some(c)) => row_major(&(j * c * j.transpose())),
        (false, None) => unknown(),
    };
    let twist = match measured {
        Some(m) if m.dt_s > 0.0 && m.dt_s.is_finite() => {
            let v = m.motion.rotation.inverse() * m.motion.translation.vector / m.dt_s;
            let w = m.motion.rotation.scaled_axis() / m.dt_s;
            TwistWithCovariance {
                twist: Twist {
                    linear: Vector3 {
                        x: v.x,
                        y: v.y,
                        z: v.z,
                    },
                    angular: Vector3 {
                        x: w.x,
                        y: w.y,
                        z: w.z,
                    },
                },
                covariance: m
                    .covariance
                    .map_or_else(unknown, |c| row_major(&(c / (m.dt_s * m.dt_s)))),
            }
        }
        _ if first => TwistWithCovariance::default(),
        _ => TwistWithCovariance {
            twist: Twist::default(),
            covariance: unknown(),
        },
    };
    Odometry {
        header: Header {
            stamp: Time::from_nanos(stamp_ns),
            frame_id: names.odom.clone(),
        },
        child_frame_id: names.camera.clone(),
        pose: PoseWithCovariance {
            pose: ros_pose(&in_odom),
            covariance: pose_cov,
        },
        twist,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3 as V3;

    #[test]
    fn forward_in_the_camera_is_forward_in_odom() {
        let forward = Isometry3::translation(0.0, 0.0, 2.0);
        let p = pose_in_odom(&forward);
        assert!((p.translation.vector - V3::new(2.0, 0.0, 0.0)).norm() < 1e-12);
        let down = pose_in_odom(&Isometry3::translation(0.0, 1.0, 0.0));
        assert!((down.translation.vector - V3::new(0.0, 0.0, -1.0)).norm() < 1e-12);
        // The optical axis of the first camera points along odom x.
        let z = pose_in_odom(&Isometry3::identity()).rotation * V3::z();
        assert!((z - V3::x()).norm() < 1e-12);
    }

    #[test]
    fn covariance_turns_with_the_axes_and_stays_symmetric() {
        let c = Matrix6::from_fn(|i, j| if i == j { (i + 1) as f64 * 1e-4 } else { 0.0 });
        let m = Measurement {
            motion: Isometry3::translation(0.0, 0.0, 1.0),
            covariance: Some(c),
            dt_s: 0.1,
        };
        let o = odometry(
            5,
            &Isometry3::identity(),
            false,
            Some(&m),
            &FrameNames::default(),
        );
        let p = Matrix6::from_row_slice(&o.pose.covariance);
        assert!((p - p.transpose()).norm() == 0.0);
        // Camera z (variance 3e-4) is odom x.
        assert!((p[(0, 0)] - 3e-4).abs() < 1e-18 && (p[(1, 1)] - 1e-4).abs() < 1e-18);
        assert!((o.twist.twist.linear.z - 10.0).abs() < 1e-12);
        assert!((o.twist.covariance[0] - 1e-4 / 0.01).abs() < 1e-15);
        assert!(p.symmetric_eigen().eigenvalues.min() >= 0.0);
        let lost = odometry(
            5,
            &Isometry3::identity(),
            false,
            None,
            &FrameNames::default(),
        );
        assert_eq!(lost.pose.covariance[0], UNKNOWN_VARIANCE);
        let first = odometry(
            0,
            &Isometry3::identity(),
            true,
            None,
            &FrameNames::default(),
        );
        assert_eq!(first.pose.covariance, [0.0; 36]);
    }
}
