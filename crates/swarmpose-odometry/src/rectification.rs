//! Is the rig rectified? Stereo matching pairs features along the same row (within
//! [`StereoConfig::row_tolerance_px`](swarmpose_vision::stereo::StereoConfig)). A right
//! camera knocked a few pixels up or down (pitched, shifted) leaves almost no match within
//! that tolerance, and the run tracked on a handful of points with its frames "lost" for no
//! stated reason. When a frame's stereo matches collapse, they are searched again with rows
//! up to [`WIDE_ROW_TOLERANCE_PX`] apart: many more matches, whose rows are off by a
//! consistent amount, mean the images are not rectified, and the frame is refused saying so.

use swarmpose_vision::features::{FeatureExtractor, Features, GrayView};
use swarmpose_vision::frontend::Frontend;

use crate::error::OdometryError;

/// Rows searched for the matches of a rig that is not rectified, pixels.
pub const WIDE_ROW_TOLERANCE_PX: f32 = 8.0;
/// The rig is taken as not rectified when the wide search finds at least this many times
/// the matches of the normal one, at least [`MIN_WIDE_MATCHES`], and their median row
/// offset is beyond the normal tolerance.
const WIDE_RATIO: usize = 4;
/// See [`WIDE_RATIO`].
const MIN_WIDE_MATCHES: usize = 50;

/// Checks a frame with `matches` stereo matches (few for its features) for rows that are
/// off: the same test as for images given the wrong way round, with rows instead.
///
/// # Errors
/// [`OdometryError::Frame`] naming both counts and the median row offset.
pub(crate) fn check_rows<E: FeatureExtractor>(
    frontend: &Frontend<E>,
    left: &Features<E::Descriptor>,
    right: &Features<E::Descriptor>,
    left_img: GrayView<'_>,
    right_img: GrayView<'_>,
    matches: usize,
) -> Result<(), OdometryError> {
    let (wide, median) =
        frontend.wide_row_matches(left, right, left_img, right_img, WIDE_ROW_TOLERANCE_PX);
    let Some(median) = median else {
        return Ok(());
    };
    let tolerance = frontend.stereo.row_tolerance_px;
    if wide >= MIN_WIDE_MATCHES && wide >= WIDE_RATIO * matches && median.abs() > tolerance {
        return Err(OdometryError::Frame {
            message: format!(
                "the stereo images are not rectified: {matches} stereo matches within \
                 {tolerance} px of their row, {wide} within {WIDE_ROW_TOLERANCE_PX} px, \
                 whose right rows are {median:+.1} px off the left ones (a right camera \
                 pitched or shifted vertically): rectify the images or fix the calibration"
            ),
        });
    }
    Ok(())
}
