//! A frame's inliers ([`FrameResult::inliers`]) as ROS 2 messages, for `odometry.mcap`'s
//! `--mcap-images` and the live node alike:
//!
//! - `sensor_msgs/CompressedImage` (`format` `png`): the frame's left image (the
//!   rectified image the engine took) with a green line from where each inlier was in
//!   the frame it was matched to and a marker where it is now
//!   ([`swarmpose_vision::draw::draw_tracks`]);
//! - `sensor_msgs/PointCloud2`: the inliers' points in the camera's optical frame (x
//!   right, y down, z forward; the odometry's child frame), metres, an unordered cloud
//!   (`height` 1) of fields `x`, `y`, `z` FLOAT32, little-endian, 12 bytes a point.
//!
//! A frame that was not tracked has no inliers: its image is drawn without them and its
//! cloud is empty.

use image::ImageEncoder;
use swarmpose_odometry::FrameResult;
use swarmpose_vision::draw::draw_tracks;
use swarmpose_vision::features::GrayView;

use crate::msg::{CompressedImage, Header, PointCloud2, PointField};

/// Bytes of one point of the cloud (`x`, `y`, `z` FLOAT32).
pub const POINT_STEP: u32 = 12;

/// The inliers' points of `r` as a `PointCloud2` with `header` (its `frame_id` the
/// camera's optical frame).
#[must_use]
pub fn inlier_cloud(r: &FrameResult, header: Header) -> PointCloud2 {
    let fields = ["x", "y", "z"]
        .iter()
        .zip(0u32..)
        .map(|(name, k)| PointField {
            name: (*name).to_owned(),
            offset: 4 * k,
            datatype: PointField::FLOAT32,
            count: 1,
        })
        .collect();
    let mut data = Vec::with_capacity(r.inliers.len() * POINT_STEP as usize);
    for i in &r.inliers {
        for c in i.point_m {
            data.extend_from_slice(&c.to_le_bytes());
        }
    }
    let n = u32::try_from(r.inliers.len()).unwrap_or(u32::MAX);
    PointCloud2 {
        header,
        height: 1,
        width: n,
        fields,
        is_bigendian: false,
        point_step: POINT_STEP,
        row_step: n.saturating_mul(POINT_STEP),
        data,
        is_dense: true,
    }
}

/// `left` (the frame's left image as the engine took it) with the inliers of `r` drawn,
/// as a PNG `CompressedImage` with `header`.
///
/// # Errors
/// The PNG encoder's message.
pub fn inlier_image(
    r: &FrameResult,
    left: GrayView<'_>,
    header: Header,
) -> Result<CompressedImage, String> {
    let pixels: Vec<(f32, f32)> = r.inliers.iter().map(|i| i.pixel).collect();
    let reference: Vec<(f32, f32)> = r.inliers.iter().map(|i| i.reference_pixel).collect();
    let canvas = draw_tracks(left, &pixels, &reference);
    let (w, h) = (
        u32::try_from(canvas.width).map_err(|e| e.to_string())?,
        u32::try_from(canvas.height).map_err(|e| e.to_string())?,
    );
    let mut data = Vec::new();
    image::codecs::png::PngEncoder::new(&mut data)
        .write_image(&canvas.rgb, w, h, image::ExtendedColorType::Rgb8)
        .map_err(|e| format!("cannot encode the inlier image as PNG: {e}"))?;
    Ok(CompressedImage {
        header,
        format: "png".to_owned(),
        data,
    })
}
