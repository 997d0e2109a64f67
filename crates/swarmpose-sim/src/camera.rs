//! The pinhole camera of eq. (17)-(19) and the visibility test of section 6.1.
//!
//! `x = K [I | 0] X`: a point `X` in a camera's frame (metres, `z` forward) projects to
//! pixel `(u, v) = (α_x X/Z + c_x, α_y Y/Z + c_y)`. It is *visible* when it is in front of
//! the camera (`Z > z_min`) and its pixel lies inside the image.

use nalgebra::Point3;

/// A pinhole camera: calibration `K` of eq. (19), image size and near limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pinhole {
    /// Focal length `α_x`, pixels.
    pub fx: f64,
    /// Focal length `α_y`, pixels.
    pub fy: f64,
    /// Image centre `c_x`, pixels.
    pub cx: f64,
    /// Image centre `c_y`, pixels.
    pub cy: f64,
    /// Image width, pixels (`0 <= u < width`).
    pub width: f64,
    /// Image height, pixels (`0 <= v < height`).
    pub height: f64,
    /// Least depth counted as "in front of the camera", metres.
    pub z_min: f64,
}

impl Default for Pinhole {
    /// The KITTI-like camera of `gen_scenarios.py`: `α = 718.856`, `c = (607.19, 185.22)`,
    /// 1241 x 376 pixels, `z_min = 0.1` m.
    fn default() -> Self {
        Self {
            fx: 718.856,
            fy: 718.856,
            cx: 607.19,
            cy: 185.22,
            width: 1241.0,
            height: 376.0,
            z_min: 0.1,
        }
    }
}

impl Pinhole {
    /// Pixel `(u, v)` of a point in this camera's frame, or `None` behind the near limit.
    #[must_use]
    pub fn project(&self, p: &Point3<f64>) -> Option<(f64, f64)> {
        (p.z > self.z_min).then(|| (self.fx * p.x / p.z + self.cx, self.fy * p.y / p.z + self.cy))
    }

    /// Whether the point (camera frame) is in front of the camera and inside the image.
    #[must_use]
    pub fn sees(&self, p: &Point3<f64>) -> bool {
        self.project(p)
            .is_some_and(|(u, v)| u >= 0.0 && u < self.width && v >= 0.0 && v < self.height)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_is_seen_and_behind_is_not() {
        let cam = Pinhole::default();
        assert!(cam.sees(&Point3::new(0.0, 0.0, 5.0)));
        assert!(!cam.sees(&Point3::new(0.0, 0.0, -5.0)));
        assert!(!cam.sees(&Point3::new(0.0, 0.0, 0.05)));
        // Far to the side: outside the 1241-pixel width.
        assert!(!cam.sees(&Point3::new(10.0, 0.0, 5.0)));
        let (u, v) = cam
            .project(&Point3::new(0.0, 0.0, 5.0))
            .unwrap_or((-1.0, -1.0));
        assert!((u - 607.19).abs() < 1e-12 && (v - 185.22).abs() < 1e-12);
    }
}
