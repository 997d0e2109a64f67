//! The detectors of the front end: the one list of their names.

use std::fmt;
use std::str::FromStr;

/// A detector and descriptor of the front end.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
pub enum Detector {
    /// FAST corners with upright BRIEF descriptors ([`super::Frontend::orb`]): fast.
    #[default]
    Orb,
    /// Upright SURF, as in the paper ([`super::Frontend::surf`]): slower.
    Surf,
}

impl Detector {
    /// Every detector, in the order of the documentation.
    pub const ALL: [Detector; 2] = [Detector::Orb, Detector::Surf];

    /// The name used on the command line and in Python (`orb`, `surf`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Detector::Orb => "orb",
            Detector::Surf => "surf",
        }
    }

    /// One line describing the detector.
    #[must_use]
    pub fn description(self) -> &'static str {
        match self {
            Detector::Orb => "FAST corners with upright BRIEF descriptors (fast, real-time)",
            Detector::Surf => "upright SURF, as in the paper (slower)",
        }
    }
}

impl fmt::Display for Detector {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// An unknown detector name.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown detector '{0}': use one of orb, surf")]
pub struct UnknownDetector(pub String);

impl FromStr for Detector {
    type Err = UnknownDetector;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Detector::ALL
            .into_iter()
            .find(|d| d.name() == s)
            .ok_or_else(|| UnknownDetector(s.to_owned()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for d in Detector::ALL {
            assert_eq!(d.name().parse::<Detector>(), Ok(d));
        }
        assert!("sift".parse::<Detector>().is_err());
    }
}
