//! Range checks of settings, shared by every crate's configuration: one error type that
//! names the setting by its path in a run configuration (`orb.stereo.row_tolerance_px`),
//! its value and the range it must be in, and one function per kind of range.
//!
//! A setting outside its range is an error before the first frame, never a panic in the
//! middle of a run nor a run that succeeds on a meaningless value (a negative noise
//! sigma, a negative search tolerance).

use std::fmt::Display;

/// A setting outside its range.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{name} is {value}: it must be {rule}")]
pub struct InvalidSetting {
    /// The setting's path in a run configuration, e.g. `orb.stereo.row_tolerance_px`.
    pub name: String,
    /// Its value, as given.
    pub value: String,
    /// The range it must be in, in words.
    pub rule: String,
}

fn invalid(name: impl Display, value: impl Display, rule: &str) -> InvalidSetting {
    InvalidSetting {
        name: name.to_string(),
        value: value.to_string(),
        rule: rule.to_owned(),
    }
}

/// `value` is a finite number (any sign).
///
/// # Errors
/// [`InvalidSetting`] naming `name`.
pub fn finite(name: impl Display, value: f64) -> Result<(), InvalidSetting> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(invalid(name, value, "a finite number"))
    }
}

/// `value` is a finite number at least 0.
///
/// # Errors
/// [`InvalidSetting`] naming `name`.
pub fn at_least_zero(name: impl Display, value: f64) -> Result<(), InvalidSetting> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(invalid(name, value, "a finite number, 0 or more"))
    }
}

/// `value` is a finite number above 0.
///
/// # Errors
/// [`InvalidSetting`] naming `name`.
pub fn positive(name: impl Display, value: f64) -> Result<(), InvalidSetting> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(invalid(name, value, "a finite number above 0"))
    }
}

/// `value` is above 0, infinity included (an unlimited span), not NaN.
///
/// # Errors
/// [`InvalidSetting`] naming `name`.
pub fn positive_or_infinite(name: impl Display, value: f64) -> Result<(), InvalidSetting> {
    if value > 0.0 {
        Ok(())
    } else {
        Err(invalid(name, value, "a number above 0 (or unlimited)"))
    }
}

/// `value` is a ratio in `(0, 1]`.
///
/// # Errors
/// [`InvalidSetting`] naming `name`.
pub fn ratio(name: impl Display, value: f64) -> Result<(), InvalidSetting> {
    if value > 0.0 && value <= 1.0 {
        Ok(())
    } else {
        Err(invalid(name, value, "a ratio above 0 and at most 1"))
    }
}

/// `value` is a count of at least `min`.
///
/// # Errors
/// [`InvalidSetting`] naming `name`.
pub fn count_at_least(name: impl Display, value: usize, min: usize) -> Result<(), InvalidSetting> {
    if value >= min {
        Ok(())
    } else {
        Err(invalid(name, value, &format!("at least {min}")))
    }
}

/// `value` is at least `low` (another setting's value, named in the rule).
///
/// # Errors
/// [`InvalidSetting`] naming `name`.
pub fn not_below(
    name: impl Display,
    value: f64,
    low: f64,
    rule: &'static str,
) -> Result<(), InvalidSetting> {
    if value.is_finite() && value >= low {
        Ok(())
    } else {
        Err(invalid(name, value, rule))
    }
}

/// `value` is in `[low, high]` (both finite).
///
/// # Errors
/// [`InvalidSetting`] naming `name`.
pub fn within(name: impl Display, value: f64, low: f64, high: f64) -> Result<(), InvalidSetting> {
    if value >= low && value <= high {
        Ok(())
    } else {
        Err(invalid(
            name,
            value,
            &format!("a number from {low} to {high}"),
        ))
    }
}

/// `value` is a probability strictly between 0 and 1.
///
/// # Errors
/// [`InvalidSetting`] naming `name`.
pub fn open_unit(name: impl Display, value: f64) -> Result<(), InvalidSetting> {
    if value > 0.0 && value < 1.0 {
        Ok(())
    } else {
        Err(invalid(name, value, "a number above 0 and below 1"))
    }
}

/// `value` is a count from `min` to `max`.
///
/// # Errors
/// [`InvalidSetting`] naming `name`.
pub fn count_within(
    name: impl Display,
    value: usize,
    min: usize,
    max: usize,
) -> Result<(), InvalidSetting> {
    if (min..=max).contains(&value) {
        Ok(())
    } else {
        Err(invalid(name, value, &format!("from {min} to {max}")))
    }
}

/// The path of a setting in a run configuration (`estimator.pso.inertia`): its name below
/// its parent's path, written out only when a message needs it, so that a check that
/// passes allocates nothing (the estimators check their settings at every call).
#[derive(Debug, Clone, Copy)]
pub struct Path<'a> {
    parent: Option<&'a Path<'a>>,
    name: &'a str,
}

impl<'a> Path<'a> {
    /// The top of the paths: `prefix` (`estimator`), or nothing when it is empty (a
    /// configuration given on its own).
    #[must_use]
    pub fn root(prefix: &'a str) -> Self {
        Self {
            parent: None,
            name: prefix,
        }
    }

    /// The path of setting `name` below this one.
    #[must_use]
    pub fn child(&'a self, name: &'a str) -> Self {
        Self {
            parent: Some(self),
            name,
        }
    }

    fn is_empty(&self) -> bool {
        self.name.is_empty() && self.parent.is_none_or(Path::is_empty)
    }
}

impl Display for Path<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.parent {
            Some(p) if !p.is_empty() => write!(f, "{p}.{}", self.name),
            _ => f.write_str(self.name),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_range_takes_its_values_and_names_the_others() {
        assert!(finite("a", -3.0).is_ok());
        assert!(finite("a", f64::NAN).is_err());
        assert!(at_least_zero("a", 0.0).is_ok());
        assert!(at_least_zero("a", -0.5).is_err());
        assert!(at_least_zero("a", f64::INFINITY).is_err());
        assert!(positive("a", 1e-9).is_ok());
        assert!(positive("a", 0.0).is_err());
        assert!(positive_or_infinite("a", f64::INFINITY).is_ok());
        assert!(positive_or_infinite("a", f64::NAN).is_err());
        assert!(positive_or_infinite("a", -1.0).is_err());
        assert!(ratio("a", 1.0).is_ok());
        assert!(ratio("a", 0.0).is_err());
        assert!(ratio("a", 1.5).is_err());
        assert!(count_at_least("a", 1, 1).is_ok());
        assert!(count_at_least("a", 1, 2).is_err());
        let e = count_at_least("selfcal.stripes", 0, 2).expect_err("out of range");
        assert_eq!(e.to_string(), "selfcal.stripes is 0: it must be at least 2");
        assert!(not_below("a", 2.0, 2.0, "r").is_ok());
        assert!(not_below("a", 1.0, 2.0, "r").is_err());
        let e = at_least_zero("orb.stereo.row_tolerance_px", -1.0).expect_err("out of range");
        assert_eq!(
            e.to_string(),
            "orb.stereo.row_tolerance_px is -1: it must be a finite number, 0 or more"
        );
    }

    #[test]
    fn paths_are_written_below_their_parents() {
        let (top, alone) = (Path::root("estimator"), Path::root(""));
        let (pso, bare) = (top.child("pso"), alone.child("pso"));
        assert_eq!(pso.child("inertia").to_string(), "estimator.pso.inertia");
        assert_eq!(bare.child("inertia").to_string(), "pso.inertia");
        assert_eq!(
            alone.child("sigma_multiplier").to_string(),
            "sigma_multiplier"
        );
        assert_eq!(top.to_string(), "estimator");
        let e = within(top.child("ambiguity_ratio"), 2.0, 0.0, 1.0).expect_err("out of range");
        assert_eq!(
            e.to_string(),
            "estimator.ambiguity_ratio is 2: it must be a number from 0 to 1"
        );
    }
}
