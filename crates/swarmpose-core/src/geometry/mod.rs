//! Geometry: correspondences, rigid transforms (eq. 1-2), rotation errors (eq. 20), the
//! map from a particle's 3-vector to a unit quaternion, and degeneracy tests.
//!
//! A rigid transform is an [`nalgebra::Isometry3`]: `p' = R p + t` with `R` stored as a
//! unit quaternion, so it is always a proper rotation.

mod correspondences;
mod covariance;
mod degeneracy;
mod pose;
mod rotation_map;

pub use correspondences::{Correspondences, CovariancePair, MIN_CORRESPONDENCES};
pub use covariance::check_covariance;
pub use degeneracy::{MAX_COORDINATE, check_spread, spread};
pub use pose::{
    chain, frobenius_rotation_error, quaternion_wxyz, rodrigues_rotate, rotation_angle_between,
};
pub use rotation_map::{particle_from_rotation, rotation_from_particle, wrap_rotation_vector};
