//! A new frame's measurements, each of one track: the tracks its inlier links continue,
//! measured where the patch of the frame where each began appears (with images), and the
//! tracks that begin in it.

use swarmpose_vision::temporal::template::AlignLimits;

use super::calibration::corrected;
use super::{Images, Link, Window};
use crate::refine::model::{StereoModel, StereoObservation};

/// Iterations of a template's (affine) alignment.
const ALIGN_ITERATIONS: usize = 10;
/// Largest move of a template's alignment from the pair's measurement, pixels (as the
/// pair's).
const ALIGN_MAX_MOVE_PX: f32 = 2.0;
/// Smallest normalised cross-correlation of an aligned template with the image: below,
/// the patch has changed too much since the track began (scale, occlusion) and the track
/// ends. Set before any run; with a translation-only alignment 0.7 and 0.9 gave the
/// same figures on the real sequences (within 0.01 points of drift) and suite means of
/// 0.068 % and 0.056 % (0.060 % at 0.8; docs/window.md).
const ALIGN_MIN_NCC: f32 = 0.8;

/// The pixel position of a measurement.
fn at(z: &StereoObservation) -> (f32, f32) {
    (z.u as f32, z.v as f32)
}

impl Window {
    /// The track of each link's current feature and its measurement in the current
    /// frame, into `observations` (one per track); with a `correcting` model, its
    /// disparity corrected by the model's correction, the one in use for this frame
    /// ([`super::calibration`]). The current frame's track of each feature becomes the
    /// newest, and the tracks that did not go on lose their templates.
    pub(super) fn link_tracks(
        &mut self,
        correcting: Option<&StereoModel>,
        links: &[Link],
        images: Option<Images<'_>>,
        observations: &mut Vec<(u32, StereoObservation)>,
    ) {
        let mut tracks = std::mem::take(&mut self.next_tracks);
        tracks.clear();
        tracks.reserve(links.len());
        let mut used = std::mem::take(&mut self.used);
        used.clear();
        used.reserve(links.len());
        for l in links {
            if tracks.contains_key(&l.current_feature) {
                continue;
            }
            let (track, z) = match (self.newest_tracks.get(&l.reference_feature), images) {
                (Some(&t), None) => (t, l.current_keypoint),
                (Some(&t), Some(im)) => self.continue_track(t, l, im),
                (None, _) => self.begin_track(correcting, l, images),
            };
            if used.insert(track) {
                tracks.insert(l.current_feature, track);
                let z = match correcting {
                    Some(m) => corrected(m, &m.correction, &z),
                    None => z,
                };
                observations.push((track, z));
            }
        }
        // The map of the frame before is kept for the next frame's.
        self.next_tracks = std::mem::replace(&mut self.newest_tracks, tracks);
        // `used` holds the tracks of the newest frame: the live ones.
        self.templates.retain(|t| used.contains(&t));
        self.used = used;
    }

    /// The track `t` continued by the link `l`: measured where the patch of the frame
    /// where it began appears in the current image ([`PatchTemplate::align_affine`](swarmpose_vision::temporal::template::PatchTemplate::align_affine));
    /// when it is not found again the track ends, and the feature begins a new one at
    /// its detected keypoint.
    fn continue_track(&mut self, t: u32, l: &Link, im: Images<'_>) -> (u32, StereoObservation) {
        let found = self.templates.get_mut(t).and_then(|tpl| {
            let limits = AlignLimits {
                iterations: ALIGN_ITERATIONS,
                max_move_px: ALIGN_MAX_MOVE_PX,
                min_ncc: Some(ALIGN_MIN_NCC),
            };
            tpl.align_affine(im.current, at(&l.current), limits)
        });
        match found {
            Some((u, v)) => (
                t,
                StereoObservation {
                    u: f64::from(u),
                    v: f64::from(v),
                    d: l.current.d,
                },
            ),
            None => {
                let t = self.new_track();
                // A patch that is no template leaves the track without one.
                let _ = self
                    .templates
                    .sample(t, im.current, at(&l.current_keypoint));
                (t, l.current_keypoint)
            }
        }
    }

    /// A new track begun by the link `l`: its measurement in the reference frame (the
    /// window's newest; with a `correcting` model, corrected by its correction, the one in
    /// use when the pair was measured) and, with images, the reference's patch as its
    /// template, the pair's measurement then being its first in the current frame (the
    /// detected keypoint otherwise).
    fn begin_track(
        &mut self,
        correcting: Option<&StereoModel>,
        l: &Link,
        images: Option<Images<'_>>,
    ) -> (u32, StereoObservation) {
        let t = self.new_track();
        let z = match correcting {
            Some(m) => corrected(m, &m.correction, &l.reference),
            None => l.reference,
        };
        if let Some(r) = self.frames.back_mut() {
            r.observations.push((t, z));
        }
        if images.is_some_and(|im| self.templates.sample(t, im.reference, at(&l.reference))) {
            (t, l.current)
        } else {
            (t, l.current_keypoint)
        }
    }
}
