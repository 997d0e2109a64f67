//! Typed errors of the core.

use thiserror::Error;

/// Why a point set cannot determine a rigid motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DegeneracyKind {
    /// All points coincide (no spread at all).
    Coincident,
    /// All points lie on one line, so a rotation about that line is unobservable.
    Collinear,
    /// The cross-covariance of source and destination has rank below 2.
    RankDeficient,
}

impl std::fmt::Display for DegeneracyKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            DegeneracyKind::Coincident => "all points coincide",
            DegeneracyKind::Collinear => "all points are collinear",
            DegeneracyKind::RankDeficient => "the cross-covariance has rank below 2",
        })
    }
}

/// Everything that can go wrong when estimating a pose.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PoseError {
    /// Source and destination sets differ in length.
    #[error("source has {src} points but destination has {dst}")]
    LengthMismatch {
        /// Number of source points.
        src: usize,
        /// Number of destination points.
        dst: usize,
    },
    /// Too few correspondences for the method.
    #[error("too few correspondences: {got}, at least {needed} are needed")]
    TooFewPoints {
        /// How many were given.
        got: usize,
        /// How many the method needs.
        needed: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("correspondence {index} has a non-finite coordinate")]
    NonFinite {
        /// 0-based index of the correspondence.
        index: usize,
    },
    /// The points cannot determine a rotation.
    #[error("degenerate {set} point set: {kind}")]
    Degenerate {
        /// Which set: "source", "destination" or "inlier".
        set: &'static str,
        /// What is degenerate about it.
        kind: DegeneracyKind,
    },
    /// Fewer supporting features than the refinement needs.
    #[error("insufficient support: {support} supporting features, at least {needed} needed")]
    InsufficientSupport {
        /// How many correspondences supported the best hypothesis.
        support: usize,
        /// The minimum (4, after the paper).
        needed: usize,
    },
    /// A coordinate so large that its square overflows (the spread of the set could not
    /// be computed).
    #[error(
        "the {set} coordinates are too large: {magnitude:e} in magnitude, at most {max:e} \
         can be computed with (change the unit)"
    )]
    TooLarge {
        /// Which set: "source", "destination" or "inlier".
        set: &'static str,
        /// The largest coordinate's magnitude.
        magnitude: f64,
        /// The largest magnitude accepted ([`crate::geometry::MAX_COORDINATE`]).
        max: f64,
    },
    /// A configuration value is out of its valid range.
    #[error("invalid configuration: {0}")]
    InvalidConfig(String),
}

impl From<crate::settings::InvalidSetting> for PoseError {
    fn from(e: crate::settings::InvalidSetting) -> Self {
        Self::InvalidConfig(e.to_string())
    }
}
