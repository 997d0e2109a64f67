//! Frame intake: the camera the engine is built for, the frames it takes, and the checks
//! that turn bad input into a clear error before any work is done.

use swarmpose_vision::features::GrayView;
use swarmpose_vision::stereo::RectifiedStereo;

use crate::error::OdometryError;

/// A rectified stereo camera and the size of its images.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StereoCamera {
    /// The rectified stereo model (pixels; baseline metres).
    pub rig: RectifiedStereo,
    /// Image width, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
}

impl StereoCamera {
    /// Checks that the numbers describe a camera: finite positive focal lengths and
    /// baseline, a finite principal point, a non-empty image, and a plausible camera for
    /// that image ([`RectifiedStereo::implausibility`]: focal lengths, pixel aspect,
    /// principal point; the baseline may be in any unit of length).
    ///
    /// # Errors
    /// [`OdometryError::Camera`] naming the value.
    pub fn validate(&self) -> Result<(), OdometryError> {
        let r = &self.rig;
        let bad = |what: &str, value: f64| OdometryError::Camera {
            message: format!("{what} is {value}: it must be a finite positive number"),
        };
        for (what, v) in [
            ("fx", r.fx),
            ("fy", r.fy),
            ("the baseline (metres)", r.baseline_m),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(what, v));
            }
        }
        for (what, v) in [("cx", r.cx), ("cy", r.cy)] {
            if !v.is_finite() {
                return Err(OdometryError::Camera {
                    message: format!("{what} is {v}: it must be finite"),
                });
            }
        }
        if self.width == 0 || self.height == 0 {
            return Err(OdometryError::Camera {
                message: format!(
                    "image size {}x{}: it must not be empty",
                    self.width, self.height
                ),
            });
        }
        match r.implausibility(self.width, self.height) {
            Some(message) => Err(OdometryError::Camera { message }),
            None => Ok(()),
        }
    }

    /// The camera of its images halved (2x2 means, [`swarmpose_vision::image::halve`]):
    /// `f / 2`, `(c − 0.5) / 2` (pixel centres at integers), an odd last column or row
    /// dropped; the baseline (metres) unchanged.
    #[must_use]
    pub fn halved(&self) -> Self {
        let mut c = *self;
        c.rig.fx /= 2.0;
        c.rig.fy /= 2.0;
        c.rig.cx = (c.rig.cx - 0.5) / 2.0;
        c.rig.cy = (c.rig.cy - 0.5) / 2.0;
        c.width /= 2;
        c.height /= 2;
        c
    }

    /// The camera of its images doubled ([`swarmpose_vision::image::double`]): `2 f`,
    /// `2 c + 0.5`; the baseline (metres) unchanged.
    #[must_use]
    pub fn doubled(&self) -> Self {
        let mut c = *self;
        c.rig.fx *= 2.0;
        c.rig.fy *= 2.0;
        c.rig.cx = 2.0 * c.rig.cx + 0.5;
        c.rig.cy = 2.0 * c.rig.cy + 0.5;
        c.width *= 2;
        c.height *= 2;
        c
    }
}

/// A stereo frame from any source: the rectified left and right images (8-bit gray,
/// the camera's size) and the time it was taken.
#[derive(Debug, Clone, Copy)]
pub struct StereoInput<'a> {
    /// Left image.
    pub left: GrayView<'a>,
    /// Right image.
    pub right: GrayView<'a>,
    /// Timestamp, seconds (any origin; strictly increasing along the stream).
    pub timestamp_s: f64,
}

/// A depth image, metres per pixel, row-major (0 or NaN: no depth).
#[derive(Debug, Clone, Copy)]
pub struct DepthView<'a> {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// Depths, metres: pixel `(x, y)` is `data[y * width + x]`.
    pub data: &'a [f32],
}

/// An RGB-D frame: the gray image, its registered depth, and the time it was taken.
#[derive(Debug, Clone, Copy)]
pub struct RgbdInput<'a> {
    /// Gray image.
    pub gray: GrayView<'a>,
    /// Depth registered to the gray image, metres.
    pub depth: DepthView<'a>,
    /// Timestamp, seconds (strictly increasing along the stream).
    pub timestamp_s: f64,
}

/// Checks one image against the camera.
pub(crate) fn check_image(
    camera: &StereoCamera,
    which: &'static str,
    width: usize,
    height: usize,
    len: usize,
) -> Result<(), OdometryError> {
    if width == 0 || height == 0 {
        return Err(OdometryError::Frame {
            message: format!("the {which} image is empty ({width}x{height})"),
        });
    }
    if len != width * height {
        return Err(OdometryError::Frame {
            message: format!(
                "the {which} image says {width}x{height} but holds {len} values, not {}",
                width * height
            ),
        });
    }
    if (width, height) != (camera.width, camera.height) {
        return Err(OdometryError::Frame {
            message: format!(
                "the {which} image is {width}x{height}, but the camera's images are {}x{}",
                camera.width, camera.height
            ),
        });
    }
    Ok(())
}

/// Checks a timestamp against the previous one.
pub(crate) fn check_timestamp(t: f64, previous: Option<f64>) -> Result<(), OdometryError> {
    if !t.is_finite() {
        return Err(OdometryError::Frame {
            message: format!("timestamp {t} is not a finite number of seconds"),
        });
    }
    if let Some(p) = previous
        && t <= p
    {
        return Err(OdometryError::Frame {
            message: format!(
                "timestamp {t} s does not come after the previous frame's {p} s: \
                 timestamps must increase"
            ),
        });
    }
    Ok(())
}

/// Checks a stereo frame.
pub(crate) fn check_stereo(
    camera: &StereoCamera,
    f: &StereoInput<'_>,
    previous: Option<f64>,
) -> Result<(), OdometryError> {
    check_image(
        camera,
        "left",
        f.left.width,
        f.left.height,
        f.left.data.len(),
    )?;
    check_image(
        camera,
        "right",
        f.right.width,
        f.right.height,
        f.right.data.len(),
    )?;
    check_timestamp(f.timestamp_s, previous)
}

/// Checks an RGB-D frame.
pub(crate) fn check_rgbd(
    camera: &StereoCamera,
    f: &RgbdInput<'_>,
    previous: Option<f64>,
) -> Result<(), OdometryError> {
    check_image(
        camera,
        "gray",
        f.gray.width,
        f.gray.height,
        f.gray.data.len(),
    )?;
    check_image(
        camera,
        "depth",
        f.depth.width,
        f.depth.height,
        f.depth.data.len(),
    )?;
    check_timestamp(f.timestamp_s, previous)
}
