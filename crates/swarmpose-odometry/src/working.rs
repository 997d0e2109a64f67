//! The working resolution: stereo images are brought into a band of sizes before any
//! other work, halved (the mean of each 2x2 block) while they have more than
//! [`OdometryConfig::max_working_pixels`] pixels and doubled (bicubic) while they have
//! fewer than [`OdometryConfig::min_working_pixels`] (0 by default: not doubled); the
//! engine runs on the camera of the working images.
//!
//! The front end's windows, descriptors, detector radius, image borders and noise model
//! are in pixels, made for cameras of about half a megapixel to a megapixel. On other
//! sizes they see other corners and patches of another extent. kitti_vo_seq2 (1241x376)
//! resampled to twice its size drifted 1.203 % at full size against 0.960 % as recorded,
//! and 0.914 % halved back by the engine; resampled to half its size (620x188) it drifted
//! 1.986 % (aligned ATE 0.368 m), and 1.148 % (0.059 m) doubled back (RESULTS.md, "Other
//! image sizes"). A camera of many megapixels loses some sub-pixel precision by the
//! halving and gains a frame rate a robot can use. Doubling costs four times the pixels'
//! time and is not the default: it also made the self-calibration of a small synthetic rig
//! less accurate and a still real camera wander more ([`OdometryConfig::min_working_pixels`]).
//!
//! What the engine reports in pixels (the disparity correction and its evidence, in
//! [`crate::FrameResult`] and [`crate::Odometry::calibration`]) is in pixels of the
//! camera's images, as are a fixed correction and a pixel noise given in the
//! configuration: they are converted at the engine's boundary, and only
//! [`crate::Odometry::working_camera`] shows the working images. Poses and covariances are
//! metric and do not change. RGB-D frames are never resampled.

use swarmpose_vision::features::GrayView;
use swarmpose_vision::frontend::DisparityCorrection;
use swarmpose_vision::image::{double, halve};

use crate::config::{Calibration, OdometryConfig};
use crate::error::OdometryError;
use crate::intake::StereoCamera;
use crate::record::FrameResult;
use crate::selfcal::Decision;

/// Fewest pixels [`OdometryConfig::max_working_pixels`] may ask for (100x100; a halved
/// image then has at least a quarter of them): fewer leave too few pixels for features.
pub const MIN_WORKING_PIXELS: usize = 10_000;

/// Most pixels [`OdometryConfig::min_working_pixels`] may ask for (4096x4096; a doubled
/// image has fewer than four times as many): a larger bound had small images doubled
/// until the process was killed for want of memory.
pub const MAX_MIN_WORKING_PIXELS: usize = 1 << 24;

/// Checks a band of working sizes: `max_pixels` at least [`MIN_WORKING_PIXELS`], and
/// `min_pixels` at most a quarter of `max_pixels`, so that a doubled image never needs
/// halving, and at most [`MAX_MIN_WORKING_PIXELS`]. It does not depend on the camera: a configuration can be checked before
/// there is one.
///
/// # Errors
/// [`OdometryError::Camera`] naming the option (`max_working_pixels` or
/// `min_working_pixels`) that is out of range.
pub fn check_band(min_pixels: usize, max_pixels: usize) -> Result<(), OdometryError> {
    if max_pixels < MIN_WORKING_PIXELS {
        return Err(OdometryError::Camera {
            message: format!(
                "max_working_pixels {max_pixels}: at least {MIN_WORKING_PIXELS} are needed \
                 (smaller images have too few pixels for features)"
            ),
        });
    }
    if min_pixels > MAX_MIN_WORKING_PIXELS {
        return Err(OdometryError::Camera {
            message: format!(
                "min_working_pixels {min_pixels}: at most {MAX_MIN_WORKING_PIXELS} (images \
                 doubled to more pixels would not fit in memory)"
            ),
        });
    }
    if min_pixels > max_pixels / 4 {
        return Err(OdometryError::Camera {
            message: format!(
                "min_working_pixels {min_pixels}: at most a quarter of max_working_pixels \
                 {max_pixels} (a doubled image has four times the pixels)"
            ),
        });
    }
    Ok(())
}

/// How the images are resampled: halved `levels` times when positive, doubled `−levels`
/// times when negative.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct WorkingScale {
    /// Halvings (positive) or doublings (negative); 0 for the images as they are.
    pub levels: i32,
}

impl WorkingScale {
    /// Halvings while the camera's images have more than `max_pixels` pixels, doublings
    /// while they have fewer than `min_pixels` (a band [`check_band`] accepts).
    ///
    /// # Errors
    /// [`OdometryError::Camera`] for a band [`check_band`] refuses.
    pub fn for_camera(
        camera: &StereoCamera,
        (min_pixels, max_pixels): (usize, usize),
    ) -> Result<Self, OdometryError> {
        check_band(min_pixels, max_pixels)?;
        let (mut w, mut h) = (camera.width, camera.height);
        let mut levels = 0;
        while w.saturating_mul(h) > max_pixels {
            if w < 2 || h < 2 {
                // Halving would leave an empty image (and doubling it would never end).
                return Err(OdometryError::Camera {
                    message: format!(
                        "images of {}x{} cannot be halved to at most {max_pixels} pixels \
                         (max_working_pixels): a side would be empty",
                        camera.width, camera.height
                    ),
                });
            }
            (w, h) = (w / 2, h / 2);
            levels += 1;
        }
        while w.saturating_mul(h) < min_pixels {
            (w, h) = (w * 2, h * 2);
            levels -= 1;
        }
        Ok(Self { levels })
    }

    /// Pixels of the camera's images per pixel of the working image.
    pub fn factor(self) -> f64 {
        2f64.powi(self.levels)
    }

    /// The camera of the working images ([`StereoCamera::halved`] or
    /// [`StereoCamera::doubled`], `levels` times).
    pub fn camera(self, camera: &StereoCamera) -> StereoCamera {
        let mut c = *camera;
        for _ in 0..self.levels.max(0) {
            c = c.halved();
        }
        for _ in 0..(-self.levels).max(0) {
            c = c.doubled();
        }
        c
    }

    /// `c` (pixels of the working images) in pixels of the camera's images.
    pub fn correction_in_camera_pixels(self, c: DisparityCorrection) -> DisparityCorrection {
        if self.levels == 0 {
            return c;
        }
        let s = self.factor();
        DisparityCorrection::from_coefficients(c.coefficients().map(|a| a * s))
    }

    /// `d`'s pixel figures (corrections, rotations, their covariances) in pixels of the
    /// camera's images; its scores are unit-free.
    pub fn decision_in_camera_pixels(self, mut d: Decision) -> Decision {
        if self.levels == 0 {
            return d;
        }
        let s = self.factor();
        d.correction = self.correction_in_camera_pixels(d.correction);
        d.focal_px *= s;
        d.covariance *= s * s;
        d.rows.rotation_px = d.rows.rotation_px.map(|v| v * s);
        for row in &mut d.rows.rotation_covariance {
            for v in row {
                *v *= s * s;
            }
        }
        d
    }

    /// `r`'s pixel figures (its correction, focal length change and inlier pixels) in
    /// pixels of the camera's images.
    pub fn result_in_camera_pixels(self, mut r: FrameResult) -> FrameResult {
        if self.levels == 0 {
            return r;
        }
        r.correction = self.correction_in_camera_pixels(r.correction);
        let s = self.factor();
        r.focal_px *= s;
        // Pixel centres line up: (u + 0.5) scales by the factor (`StereoCamera::halved`).
        let px = |(u, v): (f32, f32)| {
            let s = s as f32;
            (s * (u + 0.5) - 0.5, s * (v + 0.5) - 0.5)
        };
        for i in &mut r.inliers {
            i.pixel = px(i.pixel);
            i.reference_pixel = px(i.reference_pixel);
        }
        r
    }

    /// The configuration with its pixel quantities (a fixed disparity correction, a given
    /// pixel noise) in pixels of the working image.
    pub fn config(self, config: &OdometryConfig) -> OdometryConfig {
        let s = self.factor();
        let mut c = config.clone();
        if let Calibration::Fixed(d) = c.calibration {
            c.calibration = Calibration::Fixed(DisparityCorrection::from_coefficients(
                d.coefficients().map(|a| a / s),
            ));
        }
        if let Some(n) = c.pixel_noise.as_mut() {
            n.position_px /= s;
            n.disparity_px /= s;
        }
        c
    }
}

/// The buffers of one image's resampling, reused from frame to frame.
#[derive(Debug, Clone, Default)]
pub(crate) struct Resampler {
    a: Vec<u8>,
    b: Vec<u8>,
    tmp: Vec<i32>,
}

impl Resampler {
    /// `image` halved `levels` times (positive) or doubled `−levels` times (negative);
    /// `levels` is not 0.
    pub fn apply(&mut self, image: GrayView<'_>, levels: i32) -> GrayView<'_> {
        let (mut w, mut h) = if levels > 0 {
            halve(image, &mut self.a)
        } else {
            double(image, &mut self.tmp, &mut self.a)
        };
        for _ in 1..levels.unsigned_abs() {
            let src = GrayView {
                width: w,
                height: h,
                data: &self.a,
            };
            (w, h) = if levels > 0 {
                halve(src, &mut self.b)
            } else {
                double(src, &mut self.tmp, &mut self.b)
            };
            std::mem::swap(&mut self.a, &mut self.b);
        }
        GrayView {
            width: w,
            height: h,
            data: &self.a,
        }
    }

    /// Heap bytes held.
    pub fn heap_bytes(&self) -> usize {
        self.a.capacity() + self.b.capacity() + self.tmp.capacity() * size_of::<i32>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use swarmpose_vision::stereo::RectifiedStereo;

    fn camera(width: usize, height: usize) -> StereoCamera {
        StereoCamera {
            rig: RectifiedStereo {
                fx: 1437.7,
                fy: 1437.7,
                cx: 1214.9,
                cy: 370.9,
                baseline_m: 0.537,
            },
            width,
            height,
        }
    }

    #[test]
    fn images_are_brought_into_the_working_band() {
        let d = OdometryConfig::default();
        let band = (d.min_working_pixels, d.max_working_pixels);
        let levels = |w, h, band| {
            WorkingScale::for_camera(&camera(w, h), band)
                .expect("a working size")
                .levels
        };
        assert_eq!(levels(1241, 376, band), 0);
        assert_eq!(levels(1344, 372, band), 0);
        assert_eq!(levels(1280, 1024, band), 0);
        assert_eq!(levels(2482, 752, band), 1);
        assert_eq!(levels(3840, 2160, band), 2);
        // By default small images stay as they are; with a lower bound they are doubled.
        assert_eq!(levels(620, 188, band), 0);
        let band = (250_000, d.max_working_pixels);
        assert_eq!(levels(620, 188, band), -1);
        assert_eq!(levels(480, 288, band), -1);
        assert_eq!(levels(640, 480, band), 0);
        assert_eq!(levels(752, 480, band), 0);
        assert_eq!(levels(320, 240, band), -1);
        assert_eq!(levels(160, 120, band), -2);
        // No resampling at all.
        assert_eq!(levels(3840, 2160, (0, usize::MAX)), 0);
        assert_eq!(levels(320, 240, (0, usize::MAX)), 0);
        assert_eq!(levels(64, 64, (0, MIN_WORKING_PIXELS)), 0);
        assert_eq!(levels(1000, 1000, (0, MIN_WORKING_PIXELS)), 4);
        let e = WorkingScale::for_camera(&camera(640, 480), (0, 100)).expect_err("too small");
        assert!(e.to_string().contains("max_working_pixels 100"), "{e}");
        let e =
            WorkingScale::for_camera(&camera(640, 480), (300_000, 1_000_000)).expect_err("no band");
        assert!(e.to_string().contains("min_working_pixels 300000"), "{e}");
        // The resampled camera sees a point where the resampled image has it.
        let full = camera(2482, 752);
        let (x, z) = (0.8, 12.0);
        let u = |c: &StereoCamera| c.rig.fx * x / z + c.rig.cx;
        let half = WorkingScale { levels: 1 }.camera(&full);
        assert_eq!((half.width, half.height), (1241, 376));
        assert!((u(&half) - (u(&full) - 0.5) / 2.0).abs() < 1e-12);
        let twice = WorkingScale { levels: -1 }.camera(&full);
        assert_eq!((twice.width, twice.height), (4964, 1504));
        assert!((u(&twice) - (2.0 * u(&full) + 0.5)).abs() < 1e-9);
        assert_eq!(half.rig.baseline_m, full.rig.baseline_m);
        assert_eq!(twice.rig.baseline_m, full.rig.baseline_m);
    }

    #[test]
    fn images_too_thin_to_halve_are_refused() {
        // A 1x20000 image halved once has no column: it was worked on as 0x10000, and
        // with a lower bound the doubling of the empty image never ended.
        for band in [(0, MIN_WORKING_PIXELS), (100, MIN_WORKING_PIXELS)] {
            let e = WorkingScale::for_camera(&camera(1, 20_000), band).expect_err("empty");
            assert!(
                e.to_string()
                    .contains("images of 1x20000 cannot be halved to at most 10000 pixels"),
                "{e}"
            );
        }
        let e = WorkingScale::for_camera(&camera(30_000, 3), (0, MIN_WORKING_PIXELS))
            .expect_err("empty");
        assert!(e.to_string().contains("30000x3"), "{e}");
        // A lower bound beyond any camera (the images were doubled until the process
        // was killed for want of memory).
        let e = WorkingScale::for_camera(&camera(1241, 376), (usize::MAX / 4, usize::MAX))
            .expect_err("too large");
        assert!(
            e.to_string().contains(&format!(
                "min_working_pixels {}: at most 16777216",
                usize::MAX / 4
            )),
            "{e}"
        );
        let at_most = (MAX_MIN_WORKING_PIXELS, usize::MAX);
        assert_eq!(
            WorkingScale::for_camera(&camera(1241, 376), at_most)
                .expect("at the bound")
                .levels,
            -3
        );
        // Thin images that can be halved still are.
        let levels = WorkingScale::for_camera(&camera(4, 20_000), (100, MIN_WORKING_PIXELS))
            .expect("a working size")
            .levels;
        assert_eq!(levels, 2);
    }

    #[test]
    fn given_pixel_quantities_are_converted() {
        let config = OdometryConfig {
            calibration: Calibration::Fixed(DisparityCorrection {
                offset_px: 4.0,
                quadratic_px: -8.0,
                ..DisparityCorrection::default()
            }),
            pixel_noise: Some(crate::refine::model::PixelNoise {
                position_px: 2.0,
                disparity_px: 1.0,
            }),
            ..OdometryConfig::default()
        };
        for (levels, scale) in [(2, 0.25), (-1, 2.0)] {
            let c = WorkingScale { levels }.config(&config);
            let Calibration::Fixed(d) = c.calibration else {
                panic!("still fixed");
            };
            assert_eq!((d.offset_px, d.quadratic_px), (4.0 * scale, -8.0 * scale));
            let n = c.pixel_noise.expect("given");
            assert_eq!((n.position_px, n.disparity_px), (2.0 * scale, scale));
        }
    }

    #[test]
    fn resampling_twice() {
        let data: Vec<u8> = (0..16 * 8).map(|i| (i % 16 * 10) as u8).collect();
        let image = GrayView {
            width: 16,
            height: 8,
            data: &data,
        };
        let mut r = Resampler::default();
        let q = r.apply(image, 2);
        assert_eq!((q.width, q.height), (4, 2));
        // Columns 4i..4i+3 of the ramp: means 15, 55, 95, 135.
        assert_eq!(q.data[..4], [15, 55, 95, 135]);
        let q = r.apply(image, -2);
        assert_eq!((q.width, q.height), (64, 32));
    }
}
