//! The working resolution: stereo images larger than
//! [`OdometryConfig::max_working_pixels`] are halved (the mean of each 2x2 block) until
//! they are not, before any other work, and the engine runs on the halved camera.
//!
//! The front end's windows, descriptors, detector radius and noise model are in pixels,
//! set for cameras of about half a megapixel to a megapixel. On images several times that
//! size they see other corners, less distinctive patches and the wrong noise: kitti_vo_seq2
//! resampled to twice its size (2482x752, no new information) drifted 1.203 % at full
//! size against 0.960 % as recorded; halved back inside the engine it gives the recorded
//! size's result again (RESULTS.md, "Other image sizes"), at the recorded size's speed.
//! A real camera of many megapixels loses some sub-pixel precision this way, and gains a
//! frame rate a robot can use; `usize::MAX` keeps every image at its full size.
//!
//! Everything the engine reports in pixels (the disparity correction and its evidence,
//! [`crate::Odometry::working_camera`]) is in pixels of the working image; a fixed
//! correction and a pixel noise given in the configuration are in pixels of the camera's
//! images and are converted. Poses and covariances are metric and do not change. RGB-D
//! frames are never halved.

use swarmpose_vision::features::GrayView;
use swarmpose_vision::frontend::DisparityCorrection;
use swarmpose_vision::image::halve;

use crate::config::{Calibration, OdometryConfig};
use crate::error::OdometryError;
use crate::intake::StereoCamera;

/// Fewest pixels [`OdometryConfig::max_working_pixels`] may ask for (100x100; a halved
/// image then has at least a quarter of them): fewer leave too few pixels for features.
pub const MIN_WORKING_PIXELS: usize = 10_000;

/// How many times the images are halved.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct WorkingScale {
    /// Halvings, 0 for the full size.
    pub levels: u32,
}

impl WorkingScale {
    /// Halvings until the camera's images have at most `max_pixels` pixels.
    ///
    /// # Errors
    /// [`OdometryError::Camera`] when `max_pixels` is below [`MIN_WORKING_PIXELS`].
    pub fn for_camera(camera: &StereoCamera, max_pixels: usize) -> Result<Self, OdometryError> {
        if max_pixels < MIN_WORKING_PIXELS {
            return Err(OdometryError::Camera {
                message: format!(
                    "max_working_pixels {max_pixels}: at least {MIN_WORKING_PIXELS} are needed \
                     (smaller images have too few pixels for features)"
                ),
            });
        }
        let (mut w, mut h) = (camera.width, camera.height);
        let mut levels = 0;
        while w.saturating_mul(h) > max_pixels {
            (w, h) = (w / 2, h / 2);
            levels += 1;
        }
        Ok(Self { levels })
    }

    /// Pixels of the camera's images per pixel of the working image.
    pub fn factor(self) -> f64 {
        f64::from(1u32 << self.levels.min(31))
    }

    /// The camera of the working images: each halving takes `f / 2` and `(c − 0.5) / 2`
    /// (pixel centres at integers) and drops an odd last column or row; the baseline
    /// does not change.
    pub fn camera(self, camera: &StereoCamera) -> StereoCamera {
        let mut c = *camera;
        for _ in 0..self.levels {
            c.rig.fx /= 2.0;
            c.rig.fy /= 2.0;
            c.rig.cx = (c.rig.cx - 0.5) / 2.0;
            c.rig.cy = (c.rig.cy - 0.5) / 2.0;
            c.width /= 2;
            c.height /= 2;
        }
        c
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

/// The buffers of one image's halvings, reused from frame to frame.
#[derive(Debug, Clone, Default)]
pub(crate) struct Halver {
    a: Vec<u8>,
    b: Vec<u8>,
}

impl Halver {
    /// `image` halved `levels` times (at least once).
    pub fn apply(&mut self, image: GrayView<'_>, levels: u32) -> GrayView<'_> {
        let (mut w, mut h) = halve(image, &mut self.a);
        for _ in 1..levels {
            let src = GrayView {
                width: w,
                height: h,
                data: &self.a,
            };
            (w, h) = halve(src, &mut self.b);
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
        self.a.capacity() + self.b.capacity()
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
    fn large_images_are_halved_until_they_fit() {
        let max = OdometryConfig::default().max_working_pixels;
        let levels = |w, h, max| {
            WorkingScale::for_camera(&camera(w, h), max)
                .expect("a working size")
                .levels
        };
        assert_eq!(levels(1241, 376, max), 0);
        assert_eq!(levels(1280, 1024, max), 0);
        assert_eq!(levels(2482, 752, max), 1);
        assert_eq!(levels(3840, 2160, max), 2);
        assert_eq!(levels(3840, 2160, usize::MAX), 0);
        assert_eq!(levels(64, 64, MIN_WORKING_PIXELS), 0);
        assert_eq!(levels(1000, 1000, MIN_WORKING_PIXELS), 4);
        let e = WorkingScale::for_camera(&camera(640, 480), 100).expect_err("too small");
        assert!(e.to_string().contains("max_working_pixels 100"), "{e}");
        // The halved camera sees a point where the halved image has it.
        let s = WorkingScale { levels: 1 };
        let full = camera(2482, 752);
        let half = s.camera(&full);
        assert_eq!((half.width, half.height), (1241, 376));
        let (x, z) = (0.8, 12.0);
        let u_full = full.rig.fx * x / z + full.rig.cx;
        let u_half = half.rig.fx * x / z + half.rig.cx;
        assert!((u_half - (u_full - 0.5) / 2.0).abs() < 1e-12);
        assert_eq!(half.rig.baseline_m, full.rig.baseline_m);
    }

    #[test]
    fn given_pixel_quantities_are_converted() {
        let s = WorkingScale { levels: 2 };
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
        let c = s.config(&config);
        let Calibration::Fixed(d) = c.calibration else {
            panic!("still fixed");
        };
        assert_eq!((d.offset_px, d.quadratic_px), (1.0, -2.0));
        let n = c.pixel_noise.expect("given");
        assert_eq!((n.position_px, n.disparity_px), (0.5, 0.25));
    }

    #[test]
    fn halving_twice_is_a_quarter() {
        let data: Vec<u8> = (0..16 * 8).map(|i| (i % 16 * 10) as u8).collect();
        let image = GrayView {
            width: 16,
            height: 8,
            data: &data,
        };
        let mut h = Halver::default();
        let q = h.apply(image, 2);
        assert_eq!((q.width, q.height), (4, 2));
        // Columns 4i..4i+3 of the ramp: means 15, 55, 95, 135.
        assert_eq!(q.data[..4], [15, 55, 95, 135]);
    }
}
