//! The settings of the two front ends, with their defaults: what [`Frontend::orb`] and
//! [`Frontend::surf`] build, and what a run configuration records.

use super::Frontend;
use crate::bucketing::BucketConfig;
use crate::orb::{OrbConfig, OrbExtractor};
use crate::stereo::{RectifiedStereo, StereoConfig};
use crate::surf::{Surf, SurfConfig};
use crate::temporal::TemporalConfig;

/// Settings of the binary front end ([`Frontend::orb_with`]).
///
/// The defaults were chosen on KITTI and are the one configuration for every camera:
/// upright BRIEF (a car-mounted camera does not roll, and steering the pattern costs
/// distinctiveness), FAST threshold 12 with 20 features per 48-pixel cell on the left,
/// every FAST-10 corner on the right (so every left feature can find its partner), and a
/// frame-to-frame search within 150 pixels. The search near where the engine's prediction
/// puts each feature ([`TemporalConfig::guided_radius_px`]) is not the default: at 15-40
/// pixels it is a third as costly and lowers the aligned ATE of most variants of
/// kitti_vo_seq2, but raises Karlsruhe's (docs/history.md, issue 34).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
pub struct OrbFrontendConfig {
    /// The left image's detector and descriptor.
    pub left: OrbConfig,
    /// The right image's detector and descriptor.
    pub right: OrbConfig,
    /// Stereo matching along rows.
    pub stereo: StereoConfig,
    /// Matching between frames.
    pub temporal: TemporalConfig,
}

impl Default for OrbFrontendConfig {
    fn default() -> Self {
        let left = OrbConfig {
            fast_threshold: 12,
            bucketing: Some(BucketConfig {
                cell_width: 48,
                cell_height: 48,
                per_cell: 20,
            }),
            max_features: 4000,
            oriented: false,
        };
        let right = OrbConfig {
            fast_threshold: 10,
            bucketing: None,
            max_features: usize::MAX,
            ..left
        };
        Self {
            left,
            right,
            stereo: StereoConfig::default(),
            temporal: TemporalConfig {
                max_displacement_px: Some(150.0),
                ..TemporalConfig::default()
            },
        }
    }
}

/// Settings of the SURF front end ([`Frontend::surf_with`]).
///
/// The defaults: upright SURF configured for odometry ([`SurfConfig::odometry`]:
/// threshold 0.0004, finest-layer maxima, no octave smoothing), the Euclidean distance
/// limits and stricter ratio of unit-length descriptors, and bucketing. With the default
/// [`SurfConfig`] (threshold 0.0008, tuned for repeatability under rotation and scale)
/// the bucketed left images keep a third fewer features and 8 of the 50 kitti_vo_seq2
/// pairs fall back to constant velocity; see the SURF module documentation.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
pub struct SurfFrontendConfig {
    /// The detector and descriptor of both images.
    pub surf: SurfConfig,
    /// Stereo matching along rows.
    pub stereo: StereoConfig,
    /// Matching between frames.
    pub temporal: TemporalConfig,
    /// Bucketing of each image's features (`None` keeps them all).
    pub bucketing: Option<BucketConfig>,
}

impl Default for SurfFrontendConfig {
    fn default() -> Self {
        Self {
            surf: SurfConfig::odometry(),
            stereo: FLOAT_STEREO,
            temporal: FLOAT_TEMPORAL,
            bucketing: Some(BucketConfig::default()),
        }
    }
}

/// Stereo matching of unit-length real-valued descriptors.
const FLOAT_STEREO: StereoConfig = StereoConfig {
    max_distance: 0.35,
    ratio: 0.85,
    ..StereoConfig::DEFAULT
};

/// Matching between frames of unit-length real-valued descriptors.
const FLOAT_TEMPORAL: TemporalConfig = TemporalConfig {
    max_distance: 0.4,
    ratio: 0.85,
    ..TemporalConfig::DEFAULT
};

impl Frontend<OrbExtractor> {
    /// The fast binary front end with its default settings ([`OrbFrontendConfig`]).
    #[must_use]
    pub fn orb(rig: RectifiedStereo) -> Self {
        Self::orb_with(rig, &OrbFrontendConfig::default())
    }

    /// The fast binary front end with the settings `config`.
    #[must_use]
    pub fn orb_with(rig: RectifiedStereo, config: &OrbFrontendConfig) -> Self {
        Self {
            extractor: OrbExtractor::new(config.left),
            right_extractor: Some(OrbExtractor::new(config.right)),
            rig,
            stereo: config.stereo,
            temporal: config.temporal,
            bucketing: None,
        }
    }
}

impl Frontend<Surf> {
    /// The SURF front end with its default settings ([`SurfFrontendConfig`]).
    #[must_use]
    pub fn surf(rig: RectifiedStereo) -> Self {
        Self::surf_with(rig, &SurfFrontendConfig::default())
    }

    /// The SURF front end with the settings `config`.
    #[must_use]
    pub fn surf_with(rig: RectifiedStereo, config: &SurfFrontendConfig) -> Self {
        Self {
            extractor: Surf::new(config.surf),
            right_extractor: None,
            rig,
            stereo: config.stereo,
            temporal: config.temporal,
            bucketing: config.bucketing,
        }
    }
}

impl<E> Frontend<E> {
    /// A front end for a real-valued descriptor (SURF): Euclidean distance limits
    /// suited to unit-length descriptors, a stricter ratio, and bucketing.
    #[must_use]
    pub fn float_descriptor(extractor: E, rig: RectifiedStereo) -> Self {
        Self {
            extractor,
            right_extractor: None,
            rig,
            stereo: FLOAT_STEREO,
            temporal: FLOAT_TEMPORAL,
            bucketing: Some(BucketConfig::default()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_right_detector_takes_every_fast10_corner() {
        let c = OrbFrontendConfig::default();
        assert_eq!(c.right.fast_threshold, 10);
        assert_eq!(c.right.bucketing, None);
        assert_eq!(c.right.oriented, c.left.oriented);
        assert_eq!(c.left.bucketing.map(|b| b.per_cell), Some(20));
    }
}
