//! The window's tracks seen at least twice, gathered from its keyframes' measurements into
//! buffers that are reused from frame to frame.

use nalgebra::{Matrix3, Vector3};

use super::Keyframe;
use super::residual::{Relative, linearize_point, relative_poses};
use crate::nls::pose::Pose;
use crate::nls::robust::huber;
use crate::refine::model::{StereoModel, StereoObservation};

/// A track seen at least twice in the window: its measurements
/// ([`Tracks::obs`]), the first in its anchor keyframe, and its point.
#[derive(Debug, Clone)]
pub(super) struct Track {
    /// Its measurements are `Tracks::measurements[start..end]`.
    start: usize,
    end: usize,
    pub(super) point: Vector3<f64>,
}

/// The tracks of a window ([`tracks_of`]) and their measurements; the buffers are kept
/// for the next frame.
#[derive(Debug, Clone, Default)]
pub(super) struct Tracks {
    /// The tracks, in a deterministic order.
    pub(super) list: Vec<Track>,
    /// The measurements of all tracks (keyframe slot, measurement), each track's together
    /// in slot order.
    measurements: Vec<(usize, StereoObservation)>,
    /// Every measurement of the window with its track identity, to group them.
    gathered: Vec<(u32, usize, StereoObservation)>,
}

impl Tracks {
    /// The measurements of `t` (keyframe slot, measurement), the first in its anchor.
    pub(super) fn obs(&self, t: &Track) -> &[(usize, StereoObservation)] {
        &self.measurements[t.start..t.end]
    }

    /// Each track with its measurements.
    pub(super) fn iter(&self) -> impl Iterator<Item = (&Track, &[(usize, StereoObservation)])> {
        self.list.iter().map(|t| (t, self.obs(t)))
    }

    /// Number of tracks.
    pub(super) fn len(&self) -> usize {
        self.list.len()
    }

    /// True when there is none.
    pub(super) fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// Measurements of all tracks.
    pub(super) fn observations(&self) -> usize {
        self.list.iter().map(|t| t.end - t.start).sum()
    }

    /// Heap bytes held.
    pub(super) fn heap_bytes(&self) -> usize {
        self.list.capacity() * size_of::<Track>()
            + self.measurements.capacity() * size_of::<(usize, StereoObservation)>()
            + self.gathered.capacity() * size_of::<(u32, usize, StereoObservation)>()
    }
}

/// The tracks seen at least twice in `frames` (posed at `poses`) whose identity passes
/// `keep`, each with its point anchored in its first keyframe and fitted to the poses by
/// one Gauss-Newton step on its own measurements (more changed no result in the
/// ablations of RESULTS.md, and cost as much as a Levenberg-Marquardt iteration each), in
/// a deterministic order, into `out`. Leaves `rel` at the relative poses of `poses`.
#[inline(always)]
pub(super) fn tracks_of(
    model: &StereoModel,
    k: f64,
    frames: &[Keyframe],
    poses: &[Pose],
    keep: impl Fn(u32) -> bool,
    rel: &mut Vec<Relative>,
    out: &mut Tracks,
) {
    let Tracks {
        list,
        measurements,
        gathered,
    } = out;
    gathered.clear();
    for (slot, f) in frames.iter().enumerate() {
        for (t, z) in f.observations.iter().filter(|(t, _)| keep(*t)) {
            gathered.push((*t, slot, *z));
        }
    }
    // By track, then slot (a track is measured once per keyframe): each track's
    // measurements together, in slot order.
    gathered.sort_unstable_by_key(|&(t, slot, _)| (t, slot));
    list.clear();
    measurements.clear();
    for group in gathered.chunk_by(|a, b| a.0 == b.0) {
        if group.len() < 2 {
            continue;
        }
        let point = model.anchor(&group[0].2);
        if point.z > 0.0 && point.iter().all(|v| v.is_finite()) {
            let start = measurements.len();
            measurements.extend(group.iter().map(|&(_, slot, z)| (slot, z)));
            list.push(Track {
                start,
                end: measurements.len(),
                point,
            });
        }
    }
    // By the first measurement: its keyframe, then where it is in the image.
    list.sort_unstable_by_key(|t| {
        let (s, z) = measurements[t.start];
        (s, (z.u * 64.0) as i64, (z.v * 64.0) as i64)
    });
    let n = poses.len();
    relative_poses(poses, rel);
    for t in list.iter_mut() {
        let obs = &measurements[t.start..t.end];
        let anchor = obs[0].0;
        let mut h = Matrix3::zeros();
        let mut g = Vector3::zeros();
        for (slot, z) in obs {
            if let Some((residual, d_point)) =
                linearize_point(model, (rel, n), anchor, *slot, &t.point, z)
            {
                let (w, _) = huber(residual.norm_squared(), k);
                h += d_point.transpose() * d_point * w;
                g += d_point.transpose() * residual * w;
            }
        }
        if let Some(inv) = h.try_inverse() {
            t.point -= inv * g;
        }
    }
    list.retain(|t| t.point.z >= 0.0 && t.point.iter().all(|v| v.is_finite()));
}
