//! The window's tracks seen at least twice, gathered from its keyframes' measurements into
//! buffers that are reused from frame to frame.

use nalgebra::{Matrix3, Vector3};

use super::Keyframe;
use super::residual::{Relative, linearize_point, relative_poses};
use crate::nls::pose::Pose;
use crate::nls::products::add_gram;
use crate::nls::robust::huber;
use crate::refine::Prepared;
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
    /// Every measurement of the window (keyframe slot, measurement), to group them by
    /// track.
    gathered: Vec<(usize, StereoObservation)>,
    /// For each of `gathered`, its track identity (high half) and its index there (low
    /// half): sorted, each track's measurements together in slot order.
    keys: Vec<u64>,
    /// Each track's key in the order of the list ([`list_key`]) and its index there.
    order: Vec<(ListKey, usize)>,
    /// The tracks in that order.
    sorted: Vec<Track>,
}

/// A track's place in the list: the keyframe of its first measurement, then where that
/// is in the image (1/64 pixel).
type ListKey = (usize, i64, i64);

/// The [`ListKey`] of the track whose first measurement is `(slot, z)`.
#[inline(always)]
fn list_key(&(slot, z): &(usize, StereoObservation)) -> ListKey {
    (slot, (z.u * 64.0) as i64, (z.v * 64.0) as i64)
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
            + self.gathered.capacity() * size_of::<(usize, StereoObservation)>()
            + self.keys.capacity() * size_of::<u64>()
            + self.order.capacity() * size_of::<(ListKey, usize)>()
            + self.sorted.capacity() * size_of::<Track>()
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
    // The model's constants once, its correction inlined (the same bits, issue 34).
    let model = &Prepared::new(model);
    gather(model, frames, keep, out);
    relative_poses(poses, rel);
    step_points(model, k, (rel, poses.len()), out);
}

/// [`tracks_of`]'s tracks seen at least twice, anchored in their first keyframe, in their
/// deterministic order (by the first measurement's keyframe, then its place in the image).
#[inline(always)]
fn gather(model: &Prepared, frames: &[Keyframe], keep: impl Fn(u32) -> bool, out: &mut Tracks) {
    let Tracks {
        list,
        measurements,
        gathered,
        keys,
        order,
        sorted,
    } = out;
    gathered.clear();
    keys.clear();
    // A window holds far fewer than 2³² measurements (each keyframe's are bounded by its
    // features): the index fits the key's low half.
    'frames: for (slot, f) in frames.iter().enumerate() {
        for (t, z) in f.observations.iter().filter(|(t, _)| keep(*t)) {
            let Ok(i) = u32::try_from(gathered.len()) else {
                break 'frames;
            };
            keys.push((u64::from(*t) << 32) | u64::from(i));
            gathered.push((slot, *z));
        }
    }
    // By track, then slot (a track is measured once per keyframe, and the measurements
    // were gathered in slot order): each track's measurements together, in slot order.
    // Sorting the 8-byte keys, not the 40-byte measurements: the same order (issue 34).
    keys.sort_unstable();
    list.clear();
    measurements.clear();
    let at = |key: &u64| gathered[(key & 0xffff_ffff) as usize];
    for group in keys.chunk_by(|a, b| a >> 32 == b >> 32) {
        if group.len() < 2 {
            continue;
        }
        let point = model.anchor(&at(&group[0]).1);
        if point.z > 0.0 && point.iter().all(|v| v.is_finite()) {
            let start = measurements.len();
            measurements.extend(group.iter().map(at));
            list.push(Track {
                start,
                end: measurements.len(),
                point,
            });
        }
    }
    // By the first measurement: its keyframe, then where it is in the image. The keys
    // computed once, not in every comparison (issue 34); when two are equal the order
    // of those tracks is the unstable sort's, which that sort of the list alone gives.
    order.clear();
    order.extend(
        list.iter()
            .enumerate()
            .map(|(i, t)| (list_key(&measurements[t.start]), i)),
    );
    order.sort_unstable();
    if order.windows(2).all(|w| w[0].0 != w[1].0) {
        sorted.clear();
        sorted.extend(order.iter().map(|&(_, i)| list[i].clone()));
        std::mem::swap(list, sorted);
    } else {
        list.sort_unstable_by_key(|t| list_key(&measurements[t.start]));
    }
}

/// [`tracks_of`]'s one Gauss-Newton step of each track's point on its own measurements
/// (`rel`: the relative poses of the `n` keyframes), dropping the points it leaves behind
/// a camera or not finite.
#[inline(always)]
fn step_points(model: &Prepared, k: f64, (rel, n): (&[Relative], usize), out: &mut Tracks) {
    let Tracks {
        list, measurements, ..
    } = out;
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
                // nalgebra's `h += d_pointᵀ d_point w` bit for bit, without its generic
                // product ([`add_gram`]).
                add_gram(&mut h, &d_point, w);
                g += d_point.transpose() * residual * w;
            }
        }
        if let Some(inv) = h.try_inverse() {
            t.point -= inv * g;
        }
    }
    list.retain(|t| t.point.z >= 0.0 && t.point.iter().all(|v| v.is_finite()));
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Isometry3, Vector3};
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// [`tracks_of`] as it was before issue 34's round five: the 40-byte measurements
    /// sorted by `(track, slot)`, and nalgebra's products in the point's step.
    fn tracks_of_before(
        model: &StereoModel,
        k: f64,
        frames: &[Keyframe],
        poses: &[Pose],
        keep: impl Fn(u32) -> bool,
    ) -> (Vec<Track>, Vec<(usize, StereoObservation)>) {
        let mut gathered = Vec::new();
        for (slot, f) in frames.iter().enumerate() {
            for (t, z) in f.observations.iter().filter(|(t, _)| keep(*t)) {
                gathered.push((*t, slot, *z));
            }
        }
        gathered.sort_unstable_by_key(|&(t, slot, _)| (t, slot));
        let (mut list, mut measurements) = (Vec::new(), Vec::new());
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
        list.sort_unstable_by_key(|t: &Track| {
            let (s, z) = measurements[t.start];
            (s, (z.u * 64.0) as i64, (z.v * 64.0) as i64)
        });
        let (mut rel, n) = (Vec::new(), poses.len());
        relative_poses(poses, &mut rel);
        for t in list.iter_mut() {
            let obs = &measurements[t.start..t.end];
            let anchor = obs[0].0;
            let mut h = Matrix3::zeros();
            let mut g = Vector3::zeros();
            for (slot, z) in obs {
                // The model's own methods, as before [`Prepared`].
                let l = if *slot == anchor {
                    Some(model.in_reference(&t.point, z))
                } else {
                    let (rot, trans) = &rel[slot * n + anchor];
                    model.in_current(rot, trans, &t.point, z)
                };
                if let Some((residual, d_point)) = l.map(|l| (l.residual, l.d_point)) {
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
        (list, measurements)
    }

    /// The tracks and their points are those of the former sort and products bit for bit
    /// (`{:?}` prints every bit of a number but a NaN's sign and payload), on seeded
    /// windows of 2 to 8 keyframes whose measurements come in a shuffled order of track
    /// identities (among them the largest), now and then NaN or a zero of either sign,
    /// with and without a filter on the identities; the buffers reused from window to
    /// window.
    /// `n` keyframes measuring a random three quarters of the tracks `ids` each, in a
    /// shuffled order, with zeros of both signs, NaN disparities, integer columns and
    /// tracks first measured in the same place (tied keys).
    fn random_frames(rng: &mut ChaCha8Rng, n: usize, ids: &[u32]) -> Vec<Keyframe> {
        (0..n)
            .map(|k| {
                let mut observations: Vec<(u32, StereoObservation)> = ids
                    .iter()
                    .filter_map(|&t| {
                        if rng.random_range(0..4) == 0 {
                            return None;
                        }
                        let mut z = StereoObservation {
                            u: rng.random_range(0.0..1240.0),
                            v: rng.random_range(0.0..370.0),
                            d: rng.random_range(1.0..60.0),
                        };
                        match rng.random_range(0..40) {
                            // Another track's first measurement in the same place:
                            // tied keys in the list's order.
                            0 if rng.random_range(0..4) == 0 => (z.u, z.v) = (512.0, 100.0),
                            0 => z.d = f64::NAN,
                            1 => z.u = 0.0,
                            2 => z.v = -0.0,
                            3 => z.u = z.u.round(),
                            _ => {}
                        }
                        Some((t, z))
                    })
                    .collect();
                // Shuffled: the sort, not the order of the measurements, groups them.
                for i in (1..observations.len()).rev() {
                    observations.swap(i, rng.random_range(0..=i));
                }
                Keyframe {
                    index: k,
                    pose_cw: Isometry3::new(
                        Vector3::new(0.0, 0.0, -0.5 * k as f64),
                        Vector3::new(0.0, 0.01 * k as f64, 0.0),
                    ),
                    observations,
                    keyframe: true,
                }
            })
            .collect()
    }

    #[test]
    fn the_tracks_are_the_former_sorts_bit_for_bit() {
        use swarmpose_vision::frontend::DisparityCorrection;
        let model = crate::refine::model::test_model(DisparityCorrection::from_coefficients([
            0.7, 1.9, -0.4, 0.3, 0.8,
        ]));
        let mut rng = ChaCha8Rng::seed_from_u64(3437);
        let (mut rel, mut out) = (Vec::new(), Tracks::default());
        let (mut tracks, mut tied) = (0, 0);
        for trial in 0..200 {
            let n = rng.random_range(2..9);
            let ids: Vec<u32> = (0..120)
                .map(|i| match i {
                    0 => u32::MAX,
                    1 => 0,
                    _ => rng.random_range(0..u32::MAX),
                })
                .collect();
            let frames = random_frames(&mut rng, n, &ids);
            let poses: Vec<Pose> = frames.iter().map(|f| Pose::of(&f.pose_cw)).collect();
            let odd = trial % 3 == 0;
            let keep = |t: u32| !odd || t % 2 == 1;
            tracks_of(&model, 2.5, &frames, &poses, keep, &mut rel, &mut out);
            let (list, measurements) = tracks_of_before(&model, 2.5, &frames, &poses, keep);
            let got: Vec<_> = out.iter().map(|(t, obs)| (t.point, obs.to_vec())).collect();
            let want: Vec<_> = list
                .iter()
                .map(|t| (t.point, measurements[t.start..t.end].to_vec()))
                .collect();
            assert_eq!(format!("{got:?}"), format!("{want:?}"), "trial {trial}");
            tracks += got.len();
            let first =
                |(_, obs): &(Vector3<f64>, Vec<(usize, StereoObservation)>)| list_key(&obs[0]);
            tied += got
                .windows(2)
                .filter(|w| first(&w[0]) == first(&w[1]))
                .count();
        }
        assert!(
            tracks > 10_000 && tied >= 10,
            "{tracks} tracks, {tied} tied"
        );
    }
}
