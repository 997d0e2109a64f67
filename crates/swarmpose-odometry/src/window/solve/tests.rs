//! Tests of the window's bundle adjustment.

use super::*;
use crate::refine::model::StereoObservation;
use crate::window::residual::linearize;
use nalgebra::Rotation3;

/// Central differences of the residual against both pose Jacobians.
#[test]
fn pose_jacobians_match_finite_differences() {
    let model = crate::refine::model::test_model(Default::default());
    let pose = |r: (f64, f64, f64), t: [f64; 3]| Pose {
        rot: *Rotation3::from_euler_angles(r.0, r.1, r.2).matrix(),
        trans: Vector3::from(t),
    };
    let poses = [
        pose((0.0, 0.0, 0.0), [0.0, 0.0, 0.0]),
        pose((0.01, -0.03, 0.02), [0.1, -0.05, -0.9]),
        pose((0.02, -0.07, 0.01), [0.3, -0.02, -1.8]),
    ];
    let p = Vector3::new(0.2, -0.1, 1.0 / 14.0);
    let z = StereoObservation {
        u: 740.0,
        v: 120.0,
        d: 27.0,
    };
    let (anchor, slot) = (1, 2);
    let mut rel = Vec::new();
    relative_poses(&poses, &mut rel);
    let j = linearize(&model, (&rel, 3), anchor, slot, &p, &z).expect("in view");
    let (dj, da) = j.poses.expect("two keyframes");
    let h = 1e-6;
    for (which, analytic) in [(slot, dj), (anchor, da)] {
        for k in 0..6 {
            let residual = |s: f64| {
                let mut xi = [0.0; 6];
                xi[k] = s * h;
                let mut moved = poses;
                moved[which] = poses[which].moved(
                    &Vector3::new(xi[0], xi[1], xi[2]),
                    &Vector3::new(xi[3], xi[4], xi[5]),
                );
                let mut rel = Vec::new();
                relative_poses(&moved, &mut rel);
                linearize(&model, (&rel, 3), anchor, slot, &p, &z)
                    .expect("in view")
                    .residual
            };
            let num = (residual(1.0) - residual(-1.0)) / (2.0 * h);
            assert!(
                (num - analytic.column(k)).norm() < 1e-4 * (1.0 + num.norm()),
                "keyframe {which}, column {k}: {num} vs {}",
                analytic.column(k)
            );
        }
    }
}
