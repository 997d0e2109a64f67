//! Matched 3D point pairs.

use nalgebra::{Matrix3, Point3};

use super::covariance::{check_covariance, largest_eigenvalue};
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
    covariance_m2: Option<NoiseCovariance>,
}

/// The per-point covariances `(src_cov, dst_cov)`, m², as returned by
/// [`Correspondences::noise_covariance`].
pub type CovariancePair<'a> = (&'a [Matrix3<f64>], &'a [Matrix3<f64>]);

/// Per-point noise covariances of both sets, m² (see
/// [`Correspondences::with_noise_covariance`]).
#[derive(Debug, Clone, PartialEq)]
struct NoiseCovariance {
    src: Vec<Matrix3<f64>>,
    dst: Vec<Matrix3<f64>>,
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
            covariance_m2: None,
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

    /// Attaches the noise covariance of every point, m², each in its own frame:
    /// `src_cov[i]` of `src_i` (source frame), `dst_cov[i]` of `dst_i` (destination frame).
    /// The residual of a correct match then has covariance
    /// `Σ_i(R) = R src_cov[i] Rᵀ + dst_cov[i]`, and estimators that support it test and
    /// weigh correspondences by the Mahalanobis norm `rᵀ Σ_i⁻¹ r`. Stereo points are the
    /// typical case: their noise is elongated along the viewing ray.
    ///
    /// Also sets the isotropic noise level of [`Correspondences::noise_sigma`] to
    /// `σ_i = sqrt(λ_max(src_cov[i]) + λ_max(dst_cov[i]))`, the largest standard deviation
    /// the residual can have in any direction, whatever the rotation (replacing one set
    /// before).
    ///
    /// # Errors
    /// [`PoseError::LengthMismatch`] for a wrong length, [`PoseError::InvalidConfig`] for a
    /// matrix that is not finite, symmetric and positive definite.
    pub fn with_noise_covariance(
        mut self,
        src_cov: Vec<Matrix3<f64>>,
        dst_cov: Vec<Matrix3<f64>>,
    ) -> Result<Self, PoseError> {
        for cov in [&src_cov, &dst_cov] {
            if cov.len() != self.src.len() {
                return Err(PoseError::LengthMismatch {
                    src: self.src.len(),
                    dst: cov.len(),
                });
            }
        }
        for (set, cov) in [("source", &src_cov), ("destination", &dst_cov)] {
            for (i, c) in cov.iter().enumerate() {
                check_covariance(c).map_err(|why| {
                    PoseError::InvalidConfig(format!("noise covariance of {set} point {i} {why}"))
                })?;
            }
        }
        let sigma = src_cov
            .iter()
            .zip(&dst_cov)
            .map(|(s, d)| (largest_eigenvalue(s) + largest_eigenvalue(d)).sqrt())
            .collect();
        self.noise_sigma_m = Some(sigma);
        self.covariance_m2 = Some(NoiseCovariance {
            src: src_cov,
            dst: dst_cov,
        });
        Ok(self)
    }

    /// Attaches covariances that are positive definite by construction (a noise model
    /// fitted by an estimator), with each row's σ (the square root of the sum of the two
    /// largest eigenvalues, as [`Correspondences::with_noise_covariance`] derives it).
    /// Only lengths are checked: the per-matrix checks would cost more than the fit.
    pub(crate) fn with_trusted_noise_covariance(
        mut self,
        src_cov: Vec<Matrix3<f64>>,
        dst_cov: Vec<Matrix3<f64>>,
        sigma: Vec<f64>,
    ) -> Option<Self> {
        let n = self.src.len();
        if src_cov.len() != n || dst_cov.len() != n || sigma.len() != n {
            return None;
        }
        self.noise_sigma_m = Some(sigma);
        self.covariance_m2 = Some(NoiseCovariance {
            src: src_cov,
            dst: dst_cov,
        });
        Some(self)
    }

    /// The per-point noise covariances `(src_cov, dst_cov)`, m², if attached.
    #[must_use]
    pub fn noise_covariance(&self) -> Option<CovariancePair<'_>> {
        self.covariance_m2
            .as_ref()
            .map(|c| (c.src.as_slice(), c.dst.as_slice()))
    }

    /// Per-correspondence noise σ_i (metres per axis), if attached.
    #[must_use]
    pub fn noise_sigma(&self) -> Option<&[f64]> {
        self.noise_sigma_m.as_deref()
    }

    /// The correspondences at `indices`, in that order (noise levels and covariances
    /// included).
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
            covariance_m2: self.covariance_m2.as_ref().map(|c| NoiseCovariance {
                src: indices.iter().map(|&i| c.src[i]).collect(),
                dst: indices.iter().map(|&i| c.dst[i]).collect(),
            }),
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
    fn noise_covariance_is_checked_selected_and_bounds_sigma() {
        let p = Point3::origin();
        let c = Correspondences::from_pairs(vec![(p, p); 2]).expect("valid");
        let ray = Matrix3::from_diagonal(&nalgebra::Vector3::new(1e-4, 1e-4, 0.04));
        let iso = Matrix3::identity() * 1e-4;
        assert!(
            c.clone()
                .with_noise_covariance(vec![ray], vec![iso, iso])
                .is_err()
        );
        let mut asym = iso;
        asym[(0, 1)] = 1e-5;
        assert!(
            c.clone()
                .with_noise_covariance(vec![ray, asym], vec![iso, iso])
                .is_err()
        );
        let singular = Matrix3::from_diagonal(&nalgebra::Vector3::new(1e-4, 0.0, 1e-4));
        assert!(
            c.clone()
                .with_noise_covariance(vec![ray, singular], vec![iso, iso])
                .is_err()
        );
        let c = c
            .with_noise_covariance(vec![ray, iso], vec![iso, iso])
            .expect("valid");
        let sigma = c.noise_sigma().expect("derived");
        assert!(
            (sigma[0] - (0.04f64 + 1e-4).sqrt()).abs() < 1e-12,
            "{sigma:?}"
        );
        assert!((sigma[1] - 2e-4f64.sqrt()).abs() < 1e-12, "{sigma:?}");
        let picked = c.select(&[1]);
        assert_eq!(picked.noise_covariance(), Some((&[iso][..], &[iso][..])));
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
