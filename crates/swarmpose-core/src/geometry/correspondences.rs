//! Matched 3D point pairs.

use nalgebra::Point3;

use crate::error::PoseError;

/// The fewest correspondences any estimator accepts: after the paper (section 5), four
/// supporting features are needed for the SVD refinement to be safe from reflections.
pub const MIN_CORRESPONDENCES: usize = 4;

/// Matched 3D points, `src[i] <-> dst[i]`, in metres. The motion sought maps the source
/// frame into the destination frame: `dst = R src + t`.
///
/// Construction checks that both sets have the same length and that every coordinate is
/// finite, so estimators never see NaN.
#[derive(Debug, Clone, PartialEq)]
pub struct Correspondences {
    src: Vec<Point3<f64>>,
    dst: Vec<Point3<f64>>,
    noise_sigma_m: Option<Vec<f64>>,
}

impl Correspondences {
    /// Pairs `src[i]` with `dst[i]`.
    ///
    /// # Errors
    /// [`PoseError::LengthMismatch`] if the lengths differ, [`PoseError::NonFinite`] for a
    /// NaN or infinite coordinate.
    pub fn new(src: Vec<Point3<f64>>, dst: Vec<Point3<f64>>) -> Result<Self, PoseError> {
        if src.len() != dst.len() {
            return Err(PoseError::LengthMismatch {
                src: src.len(),
                dst: dst.len(),
            });
        }
        if let Some(index) = src.iter().zip(&dst).position(|(s, d)| {
            !(s.coords
                .iter()
                .chain(d.coords.iter())
                .all(|v| v.is_finite()))
        }) {
            return Err(PoseError::NonFinite { index });
        }
        Ok(Self {
            src,
            dst,
            noise_sigma_m: None,
        })
    }

    /// Attaches a noise level per correspondence: `sigma[i]` is the standard deviation, in
    /// metres per axis, of the residual `dst_i - (R src_i + t)` of a correct match (for
    /// stereo, it grows with the square of the depth). Estimators that support it scale
    /// their inlier test per point instead of using one threshold.
    ///
    /// # Errors
    /// [`PoseError::LengthMismatch`] for a wrong length, [`PoseError::InvalidConfig`] for a
    /// value that is not finite and positive.
    pub fn with_noise_sigma(mut self, sigma: Vec<f64>) -> Result<Self, PoseError> {
        if sigma.len() != self.src.len() {
            return Err(PoseError::LengthMismatch {
                src: self.src.len(),
                dst: sigma.len(),
            });
        }
        if let Some(i) = sigma.iter().position(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(PoseError::InvalidConfig(format!(
                "noise sigma of correspondence {i} must be finite and > 0, got {}",
                sigma[i]
            )));
        }
        self.noise_sigma_m = Some(sigma);
        Ok(self)
    }

    /// Per-correspondence noise σ_i (metres per axis), if attached.
    #[must_use]
    pub fn noise_sigma(&self) -> Option<&[f64]> {
        self.noise_sigma_m.as_deref()
    }

    /// The correspondences at `indices`, in that order (noise levels included).
    ///
    /// # Panics
    /// Never for indices below [`Correspondences::len`]; an index out of range panics.
    #[must_use]
    pub fn select(&self, indices: &[usize]) -> Self {
        Self {
            src: indices.iter().map(|&i| self.src[i]).collect(),
            dst: indices.iter().map(|&i| self.dst[i]).collect(),
            noise_sigma_m: self
                .noise_sigma_m
                .as_ref()
                .map(|s| indices.iter().map(|&i| s[i]).collect()),
        }
    }

    /// Builds from `(src, dst)` pairs.
    ///
    /// # Errors
    /// As [`Correspondences::new`].
    pub fn from_pairs<I>(pairs: I) -> Result<Self, PoseError>
    where
        I: IntoIterator<Item = (Point3<f64>, Point3<f64>)>,
    {
        let (src, dst) = pairs.into_iter().unzip();
        Self::new(src, dst)
    }

    /// Number of correspondences.
    #[must_use]
    pub fn len(&self) -> usize {
        self.src.len()
    }

    /// True when there are no correspondences.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.src.is_empty()
    }

    /// Source points (frame of the later camera in odometry), metres.
    #[must_use]
    pub fn src(&self) -> &[Point3<f64>] {
        &self.src
    }

    /// Destination points (frame of the earlier camera in odometry), metres.
    #[must_use]
    pub fn dst(&self) -> &[Point3<f64>] {
        &self.dst
    }

    /// Fails with [`PoseError::TooFewPoints`] below `needed` correspondences.
    ///
    /// # Errors
    /// When `self.len() < needed`.
    pub fn require(&self, needed: usize) -> Result<(), PoseError> {
        if self.len() < needed {
            Err(PoseError::TooFewPoints {
                got: self.len(),
                needed,
            })
        } else {
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_mismatch_and_nan() {
        let p = Point3::new(1.0, 2.0, 3.0);
        assert_eq!(
            Correspondences::new(vec![p, p], vec![p]),
            Err(PoseError::LengthMismatch { src: 2, dst: 1 })
        );
        let bad = Point3::new(1.0, f64::NAN, 3.0);
        assert_eq!(
            Correspondences::new(vec![p, p], vec![p, bad]),
            Err(PoseError::NonFinite { index: 1 })
        );
        let inf = Point3::new(f64::INFINITY, 0.0, 0.0);
        assert_eq!(
            Correspondences::new(vec![inf], vec![p]),
            Err(PoseError::NonFinite { index: 0 })
        );
    }

    #[test]
    fn noise_sigma_is_checked_and_selected() {
        let p = Point3::origin();
        let c = Correspondences::from_pairs(vec![(p, p); 3]).expect("valid");
        assert!(c.clone().with_noise_sigma(vec![0.1; 2]).is_err());
        assert!(c.clone().with_noise_sigma(vec![0.1, 0.0, 0.1]).is_err());
        assert!(
            c.clone()
                .with_noise_sigma(vec![0.1, f64::NAN, 0.1])
                .is_err()
        );
        let c = c.with_noise_sigma(vec![0.1, 0.2, 0.3]).expect("valid");
        assert_eq!(c.select(&[2, 0]).noise_sigma(), Some(&[0.3, 0.1][..]));
    }

    #[test]
    fn require_counts() {
        let p = Point3::origin();
        let c = Correspondences::from_pairs(vec![(p, p); 3]).expect("valid");
        assert_eq!(
            c.require(4),
            Err(PoseError::TooFewPoints { got: 3, needed: 4 })
        );
        assert!(c.require(3).is_ok());
    }
}
