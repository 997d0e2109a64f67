//! Matching between frames guided by a predicted motion (issue 34): each feature of the
//! destination frame is moved to where the prediction puts it in the source frame's
//! images, and its partner searched within [`TemporalConfig::guided_radius_px`] of there
//! rather than within [`TemporalConfig::max_displacement_px`] of where it was. The
//! window is narrower, so far fewer descriptor distances are computed, and fewer
//! look-alikes compete in the ratio test.
//!
//! A wrong prediction (a sudden turn, a frame dropped) puts the partners outside the
//! windows: the guided search then finds fewer matches, and the pair is searched again
//! without the prediction. "Fewer" is relative twice over, so that the rule depends
//! neither on the image size, the detector's budget nor the scene: the share of the
//! features the pair could match (matches over the fewer of the two frames' triangulated
//! features) against the same share of the last pair matched
//! ([`TemporalConfig::guided_min_ratio`] times it). A share of the features alone does not
//! tell a wrong prediction: on the shared sequences the right ones give 0.2 (a frame of
//! KITTI at half its frame rate) to 0.9 (EuRoC), predictions a metre off on KITTI 0.07 to
//! 0.3 (the far points still match).

use nalgebra::Isometry3;
use swarmpose_core::PoseError;

use super::{FrameMatches, StereoFrame, frame_matches, frame_pairs, match_frames};
use crate::features::{Descriptor, Keypoint};
use crate::stereo::RectifiedStereo;
use crate::temporal::TemporalConfig;

/// A predicted motion between two frames, for [`match_frames_guided`].
#[derive(Debug, Clone, Copy)]
pub struct MotionGuide<'a> {
    /// The predicted pose of the source frame's camera in the destination frame's: `dst =
    /// R src + t`, as [`FrameMatches::correspondences`].
    pub motion: &'a Isometry3<f64>,
    /// The rectified camera the frames' points were triangulated with.
    pub rig: &'a RectifiedStereo,
    /// The share of the features the last pair matched: its matches over the fewer of its
    /// two frames' triangulated features ([`match_share`]).
    pub last_share: f32,
}

/// The share of the features a pair matched: `matches` over the fewer of the two frames'
/// triangulated features (0 when one has none).
#[must_use]
pub fn match_share<D>(dst: &StereoFrame<D>, src: &StereoFrame<D>, matches: usize) -> f32 {
    let possible = dst.len().min(src.len());
    if possible == 0 {
        0.0
    } else {
        matches as f32 / possible as f32
    }
}

/// How [`match_frames_guided`] searched.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Search {
    /// Without a prediction (none was given, or the configuration uses none).
    Unguided,
    /// Near the predicted positions.
    Guided,
    /// Near the predicted positions, which gave too few matches, then without the
    /// prediction: the matches are the unguided search's.
    FellBack,
}

/// A column and row far outside any image: a point the prediction puts behind the camera
/// has no candidate.
const NOWHERE_PX: f32 = -1.0e9;

/// Where `guide` puts the points of `frame` in the other frame's left and right images
/// (the right ones only `with_right`), as keypoints (the rest of each keypoint unchanged).
fn predicted<D>(
    frame: &StereoFrame<D>,
    guide: &MotionGuide<'_>,
    with_right: bool,
) -> [Vec<Keypoint>; 2] {
    let rig = guide.rig;
    let mut left = Vec::with_capacity(frame.len());
    let mut right = Vec::with_capacity(if with_right { frame.len() } else { 0 });
    for ((p, kl), kr) in frame
        .points
        .iter()
        .zip(&frame.left_keypoints)
        .zip(&frame.right_keypoints)
    {
        let q = guide.motion.inverse_transform_point(p);
        let ((ul, ur), v) = if q.z > 0.0 && q.z.is_finite() {
            // The left pixel, and the right one a disparity `fx b / z` to its left.
            let (u, v) = rig.project_left(&q);
            let disparity_px = rig.fx * rig.baseline_m / q.z;
            ((u as f32, (u - disparity_px) as f32), v as f32)
        } else {
            ((NOWHERE_PX, NOWHERE_PX), NOWHERE_PX)
        };
        left.push(Keypoint { x: ul, y: v, ..*kl });
        if with_right {
            right.push(Keypoint { x: ur, y: v, ..*kr });
        }
    }
    [left, right]
}

/// [`super::match_frames`], guided by the predicted motion `guide` when there is one and
/// the configuration has a [`TemporalConfig::guided_radius_px`]; the matches and how they
/// were searched.
///
/// # Errors
/// As [`super::Frontend::match_frames`].
pub fn match_frames_guided<D: Descriptor>(
    dst: &StereoFrame<D>,
    src: &StereoFrame<D>,
    config: &TemporalConfig,
    guide: Option<MotionGuide<'_>>,
) -> Result<(FrameMatches, Search), PoseError> {
    let Some((guide, radius_px)) = guide.zip(config.guided_radius_px) else {
        return Ok((match_frames(dst, src, config)?, Search::Unguided));
    };
    let guided = TemporalConfig {
        max_displacement_px: Some(radius_px),
        ..*config
    };
    let [left, right] = predicted(dst, &guide, config.circular_check);
    let pairs = frame_pairs((&left, &right), dst, src, &guided);
    if match_share(dst, src, pairs.len()) < config.guided_min_ratio * guide.last_share {
        return Ok((match_frames(dst, src, config)?, Search::FellBack));
    }
    Ok((frame_matches(dst, src, &pairs)?, Search::Guided))
}

#[cfg(test)]
mod tests {
    use nalgebra::{Matrix3, Point3, Translation3, UnitQuaternion, Vector3};

    use super::*;
    use crate::features::BinaryDescriptor;

    const RIG: RectifiedStereo = RectifiedStereo {
        fx: 700.0,
        fy: 700.0,
        cx: 600.0,
        cy: 180.0,
        baseline_m: 0.5,
    };

    /// The frame of a camera seeing `points` (in its own frame), keeping those inside a
    /// 1200x360 image; each feature carries the index of its point.
    fn frame(points: &[Point3<f64>], descs: &[BinaryDescriptor]) -> StereoFrame<BinaryDescriptor> {
        let mut f = StereoFrame::default();
        for (k, (p, d)) in points.iter().zip(descs).enumerate() {
            let (u, v) = RIG.project_left(p);
            if p.z < 1.0 || !(0.0..1200.0).contains(&u) || !(0.0..360.0).contains(&v) {
                continue;
            }
            let disparity = RIG.fx * RIG.baseline_m / p.z;
            let kp = |x: f64| Keypoint {
                x: x as f32,
                y: v as f32,
                scale: 15.0,
                angle: 0.0,
                response: k as f32,
                octave: 0,
            };
            f.left_keypoints.push(kp(u));
            f.right_keypoints.push(kp(u - disparity));
            f.left_descriptors.push(*d);
            f.right_descriptors.push(*d);
            f.points.push(*p);
            f.disparities_px.push(disparity as f32);
            f.row_offsets_px.push(f32::NAN);
            f.sigmas_m.push(0.1);
            f.covariances.push(Matrix3::identity() * 0.01);
        }
        f
    }

    /// A scene of 600 points with random descriptors seen from two cameras, the source
    /// 1.2 m ahead of the destination and turned by `yaw` radians; and that motion.
    fn pair(
        yaw: f64,
    ) -> (
        StereoFrame<BinaryDescriptor>,
        StereoFrame<BinaryDescriptor>,
        Isometry3<f64>,
    ) {
        let mut g = crate::test_noise::Lcg(34);
        let mut unit = || f64::from(g.next_u32() >> 8) / f64::from(1u32 << 24);
        let points: Vec<Point3<f64>> = (0..600)
            .map(|_| {
                let z = 5.0 + 55.0 * unit();
                Point3::new((unit() - 0.5) * z * 1.6, (unit() - 0.5) * z * 0.5, z)
            })
            .collect();
        let mut g = crate::test_noise::Lcg(35);
        let descs: Vec<BinaryDescriptor> = (0..600)
            .map(|_| BinaryDescriptor(std::array::from_fn(|_| (g.next_u32() >> 24) as u8)))
            .collect();
        let motion = Isometry3::from_parts(
            Translation3::new(0.1, 0.0, 1.2),
            UnitQuaternion::from_axis_angle(&Vector3::y_axis(), yaw),
        );
        let moved: Vec<Point3<f64>> = points
            .iter()
            .map(|p| motion.inverse_transform_point(p))
            .collect();
        (frame(&points, &descs), frame(&moved, &descs), motion)
    }

    fn config() -> TemporalConfig {
        TemporalConfig {
            max_displacement_px: Some(150.0),
            guided_radius_px: Some(20.0),
            ..TemporalConfig::default()
        }
    }

    /// The point index of each match's two features: equal for a right match.
    fn right_matches(
        dst: &StereoFrame<BinaryDescriptor>,
        src: &StereoFrame<BinaryDescriptor>,
        m: &FrameMatches,
    ) -> usize {
        m.dst_index
            .iter()
            .zip(&m.src_index)
            .filter(|&(&i, &j)| dst.left_keypoints[i].response == src.left_keypoints[j].response)
            .count()
    }

    #[test]
    fn a_right_prediction_guides_the_search() {
        // A turn of 0.25 rad moves every feature by about 175 px, beyond the unguided
        // search's 150.
        let (dst, src, motion) = pair(0.25);
        let unguided = match_frames(&dst, &src, &config()).expect("matches");
        let guide = MotionGuide {
            motion: &motion,
            rig: &RIG,
            last_share: match_share(&dst, &src, unguided.src_index.len()),
        };
        let (guided, search) =
            match_frames_guided(&dst, &src, &config(), Some(guide)).expect("matches");
        assert_eq!(search, Search::Guided);
        let n = guided.src_index.len();
        assert!(n >= 300, "{n} guided matches");
        assert_eq!(right_matches(&dst, &src, &guided), n);
        assert!(
            n > 2 * unguided.src_index.len(),
            "{n} vs {}",
            unguided.src_index.len()
        );
        // Confirmed by the right images, predicted there too: the same matches.
        let circular = TemporalConfig {
            circular_check: true,
            ..config()
        };
        let (confirmed, search) =
            match_frames_guided(&dst, &src, &circular, Some(guide)).expect("matches");
        assert_eq!(search, Search::Guided);
        assert_eq!(confirmed.src_index, guided.src_index);
    }

    #[test]
    fn a_wrong_prediction_falls_back_to_the_unguided_search() {
        let (dst, src, _) = pair(0.05);
        let wrong = Isometry3::from_parts(
            Translation3::new(0.0, 0.0, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -0.3),
        );
        let unguided = match_frames(&dst, &src, &config()).expect("matches");
        let guide = MotionGuide {
            motion: &wrong,
            rig: &RIG,
            last_share: match_share(&dst, &src, unguided.src_index.len()),
        };
        let (m, search) = match_frames_guided(&dst, &src, &config(), Some(guide)).expect("matches");
        assert_eq!(search, Search::FellBack);
        assert_eq!(
            (m.src_index, m.dst_index),
            (unguided.src_index, unguided.dst_index)
        );
    }

    #[test]
    fn without_a_prediction_or_a_radius_the_search_is_unguided() {
        let (dst, src, motion) = pair(0.05);
        let unguided = match_frames(&dst, &src, &config()).expect("matches");
        let guide = MotionGuide {
            motion: &motion,
            rig: &RIG,
            last_share: 0.5,
        };
        let no_radius = TemporalConfig {
            guided_radius_px: None,
            ..config()
        };
        for (c, g) in [(config(), None), (no_radius, Some(guide))] {
            let (m, search) = match_frames_guided(&dst, &src, &c, g).expect("matches");
            assert_eq!(search, Search::Unguided);
            assert_eq!(m.src_index, unguided.src_index);
        }
    }
}
