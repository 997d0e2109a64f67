//! The causes of a disparity error that self-calibration may correct, as a set.

/// A set of causes of a disparity error, each a term of the correction (bit flags).
///
/// In a configuration file it is its [`CorrectionModel::name`] (`"principal-point+yaw"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(into = "String", try_from = "String")
)]
pub struct CorrectionModel(pub u8);

impl CorrectionModel {
    /// No correction.
    pub const NONE: Self = Self(0);
    /// A horizontal principal point of the right camera: a constant offset (rigidity).
    pub const PRINCIPAL_POINT: Self = Self(1);
    /// A yaw of the right camera: `−f ψ (1 + x²)` (rows).
    pub const YAW: Self = Self(1 << 1);
    /// A roll of the right camera: `f θ y` (rows).
    pub const ROLL: Self = Self(1 << 2);
    /// A pitch of the right camera: `f φ x y` (rows).
    pub const PITCH: Self = Self(1 << 3);
    /// A focal length of the right camera: `f ε x` (rigidity).
    pub const FOCAL: Self = Self(1 << 4);
    /// The focal length of the rectified rig, both cameras (rigidity, when the camera
    /// turns: see [`crate::refine::model::FOCAL_TERM`]).
    pub const FOCAL_LENGTH: Self = Self(1 << 5);
    /// A disparity error growing as `x²` towards the image's left and right edges, fitted
    /// by rigidity alone: what rigidity chooses in place of the rows' yaw when its own
    /// `x²` term explains the scene better (a yaw would also add `−f ψ` to every
    /// disparity and bend the rows as `x y`; residual lens distortion of the
    /// rectification is one cause that does neither). Considered whenever
    /// [`CorrectionModel::YAW`] is a candidate.
    pub const QUADRATIC: Self = Self(1 << 6);
    /// The causes the default configuration may choose: principal point, yaw (with its
    /// alternative [`CorrectionModel::QUADRATIC`]) and the right camera's focal length (a
    /// constant, a constant plus a quadratic term, and a term linear in `x`).
    pub const DEFAULT_CANDIDATES: Self =
        Self(Self::PRINCIPAL_POINT.0 | Self::YAW.0 | Self::FOCAL.0);
    /// Every cause.
    pub const ALL: Self = Self(0b111_1111);
    /// A correction given by the user, not chosen by evidence.
    pub const GIVEN: Self = Self(1 << 7);
    /// The causes, in order, with their names.
    pub const CAUSES: [(Self, &'static str); 7] = [
        (Self::PRINCIPAL_POINT, "principal-point"),
        (Self::YAW, "yaw"),
        (Self::QUADRATIC, "quadratic"),
        (Self::ROLL, "roll"),
        (Self::PITCH, "pitch"),
        (Self::FOCAL, "focal"),
        (Self::FOCAL_LENGTH, "focal-length"),
    ];

    /// True when every cause of `other` is in `self`.
    #[must_use]
    pub fn has(self, other: Self) -> bool {
        self.0 & other.0 == other.0 && other.0 != 0
    }

    /// The union.
    #[must_use]
    pub fn with(self, other: Self) -> Self {
        Self(self.0 | other.0)
    }

    /// `none`, or the causes joined by `+` (`principal-point+yaw`).
    #[must_use]
    pub fn name(self) -> String {
        if self.0 == 0 {
            return "none".into();
        }
        if self == Self::GIVEN {
            return "given".into();
        }
        Self::CAUSES
            .iter()
            .filter(|(c, _)| self.has(*c))
            .map(|(_, n)| *n)
            .collect::<Vec<_>>()
            .join("+")
    }

    /// The model named by [`CorrectionModel::name`].
    ///
    /// # Errors
    /// The unknown cause.
    pub fn parse(text: &str) -> Result<Self, String> {
        if text == "none" {
            return Ok(Self::NONE);
        }
        text.split('+').try_fold(Self::NONE, |m, part| {
            Self::CAUSES
                .iter()
                .find(|(_, n)| *n == part)
                .map(|(c, _)| m.with(*c))
                .ok_or_else(|| {
                    let names: Vec<&str> = Self::CAUSES.iter().map(|(_, n)| *n).collect();
                    format!(
                        "unknown cause '{part}': use none or causes joined by '+' among {}",
                        names.join(", ")
                    )
                })
        })
    }
}

impl From<CorrectionModel> for String {
    fn from(m: CorrectionModel) -> String {
        m.name()
    }
}

impl TryFrom<String> for CorrectionModel {
    type Error = String;

    fn try_from(text: String) -> Result<Self, String> {
        Self::parse(&text)
    }
}

impl std::fmt::Display for CorrectionModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.name())
    }
}
