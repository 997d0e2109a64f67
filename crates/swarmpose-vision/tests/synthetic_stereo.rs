//! Rendered stereo pairs of textured planes (the crate's own renderer): triangulated
//! depths at 10 m are within 1 % of the truth, and the front end plus the robust
//! estimator recover a known camera motion.

use nalgebra::{Isometry3, Point3, Vector3};
use swarmpose_core::{Estimator, PsoEstimator, PsoEstimatorConfig};
use swarmpose_vision::frontend::{CHI2_3_99, Frontend, refine_stereo};
use swarmpose_vision::image::GrayImage;
use swarmpose_vision::render::{TexturedPlane, depth_at, render};
use swarmpose_vision::stereo::RectifiedStereo;

const RIG: RectifiedStereo = RectifiedStereo {
    fx: 500.0,
    fy: 500.0,
    cx: 199.5,
    cy: 119.5,
    baseline_m: 0.53,
};
const SIZE: (usize, usize) = (400, 240);

/// Left and right images of a rig whose left camera is at `pose` (world frame).
fn stereo(pose: &Isometry3<f64>, planes: &[TexturedPlane]) -> (GrayImage, GrayImage) {
    let right = pose * Isometry3::translation(RIG.baseline_m, 0.0, 0.0);
    (
        render(&RIG, pose, SIZE.0, SIZE.1, planes, 3),
        render(&RIG, &right, SIZE.0, SIZE.1, planes, 3),
    )
}

#[test]
fn depths_at_ten_metres_are_within_one_percent() {
    let planes = [TexturedPlane::fronto_parallel(10.0, 0.05, 1)];
    let pose = Isometry3::identity();
    let (left, right) = stereo(&pose, &planes);
    let frame = Frontend::orb(RIG).stereo_frame(left.view(), right.view());
    assert!(frame.len() >= 100, "only {} stereo points", frame.len());
    let mut rel: Vec<f64> = frame
        .points
        .iter()
        .zip(&frame.left_keypoints)
        .map(|(p, k)| {
            let truth = depth_at(&RIG, &pose, &planes, f64::from(k.x), f64::from(k.y))
                .expect("the wall fills the view");
            (p.z - truth).abs() / truth
        })
        .collect();
    rel.sort_by(f64::total_cmp);
    let within = rel.iter().filter(|&&r| r < 0.01).count();
    eprintln!(
        "{} points; relative depth error median {:.4}, 95th percentile {:.4}; {within} within 1 %",
        rel.len(),
        rel[rel.len() / 2],
        rel[rel.len() * 95 / 100]
    );
    assert!(
        within * 100 >= rel.len() * 95,
        "{within} of {} within 1 %",
        rel.len()
    );
    assert!(rel[rel.len() / 2] < 0.003);
}

#[test]
fn front_end_recovers_a_known_motion() {
    // A wall at 12 m, a floor 1.5 m below the camera and a side wall 3 m to the left.
    let planes = [
        TexturedPlane::fronto_parallel(12.0, 0.15, 1),
        TexturedPlane {
            origin: Point3::new(0.0, 1.5, 0.0),
            u: Vector3::x(),
            v: Vector3::z(),
            cell_m: 0.1,
            seed: 2,
        },
        TexturedPlane {
            origin: Point3::new(-3.0, 0.0, 0.0),
            u: Vector3::z(),
            v: Vector3::y(),
            cell_m: 0.1,
            seed: 3,
        },
    ];
    let pose_i = Isometry3::identity();
    let pose_j = Isometry3::new(Vector3::new(0.1, -0.02, 0.5), Vector3::new(0.0, 0.03, 0.0));
    let frontend = Frontend::orb(RIG);
    let (li, ri) = stereo(&pose_i, &planes);
    let (lj, rj) = stereo(&pose_j, &planes);
    let fi = frontend.stereo_frame(li.view(), ri.view());
    let fj = frontend.stereo_frame(lj.view(), rj.view());
    let m = frontend.match_frames(&fi, &fj).expect("matches");
    assert!(
        m.correspondences.len() >= 100,
        "{}",
        m.correspondences.len()
    );
    let est = PsoEstimator::new(PsoEstimatorConfig::default())
        .estimate_seeded(&m.correspondences, 1)
        .expect("estimate");
    let (pose, _) = refine_stereo(
        &m.correspondences,
        &m.src_covariances,
        &m.dst_covariances,
        &est.transform,
        CHI2_3_99,
        10,
    )
    .expect("refine");
    let truth = pose_i.inverse() * pose_j;
    let d = truth.inverse() * pose;
    let (deg, cm) = (
        d.rotation.angle().to_degrees(),
        d.translation.vector.norm() * 100.0,
    );
    eprintln!(
        "{} correspondences; error {deg:.3} deg, {cm:.2} cm; t {:?} (truth {:?}); PSO alone t {:?}",
        m.correspondences.len(),
        pose.translation.vector.as_slice(),
        truth.translation.vector.as_slice(),
        est.transform.translation.vector.as_slice(),
    );
    assert!(deg < 0.1 && cm < 1.0, "{deg} deg {cm} cm");

    // The circular check keeps a subset, and a cleaner one: fewer matches far from the
    // true motion.
    let mut circular = frontend.clone();
    circular.temporal.circular_check = true;
    let mc = circular.match_frames(&fi, &fj).expect("matches");
    let bad = |m: &swarmpose_vision::frontend::FrameMatches| {
        let c = &m.correspondences;
        let n = c
            .src()
            .iter()
            .zip(c.dst())
            .filter(|(s, d)| (*d - truth * *s).norm() > 0.3)
            .count();
        n as f64 / c.len().max(1) as f64
    };
    eprintln!(
        "circular check: {} of {} kept; wrong fraction {:.3} -> {:.3}",
        mc.correspondences.len(),
        m.correspondences.len(),
        bad(&m),
        bad(&mc)
    );
    assert!(mc.correspondences.len() >= 50 && mc.correspondences.len() <= m.correspondences.len());
    assert!(bad(&mc) <= bad(&m));
}
