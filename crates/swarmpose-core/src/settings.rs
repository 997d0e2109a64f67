//! Range checks of settings, shared by every crate's configuration: one error type that
//! names the setting by its path in a run configuration (`orb.stereo.row_tolerance_px`),
//! its value and the range it must be in, and one function per kind of range.
//!
//! A setting outside its range is an error before the first frame, never a panic in the
//! middle of a run nor a run that succeeds on a meaningless value (a negative noise
//! sigma, a negative search tolerance).

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

fn invalid(name: &str, value: impl std::fmt::Display, rule: &str) -> InvalidSetting {
    InvalidSetting {
        name: name.to_owned(),
        value: value.to_string(),
        rule: rule.to_owned(),
    }
}

/// `value` is a finite number (any sign).
///
/// # Errors
/// [`InvalidSetting`] naming `name`.
pub fn finite(name: &str, value: f64) -> Result<(), InvalidSetting> {
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
pub fn at_least_zero(name: &str, value: f64) -> Result<(), InvalidSetting> {
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
pub fn positive(name: &str, value: f64) -> Result<(), InvalidSetting> {
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
pub fn positive_or_infinite(name: &str, value: f64) -> Result<(), InvalidSetting> {
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
pub fn ratio(name: &str, value: f64) -> Result<(), InvalidSetting> {
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
pub fn count_at_least(name: &str, value: usize, min: usize) -> Result<(), InvalidSetting> {
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
    name: &str,
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
pub fn within(name: &str, value: f64, low: f64, high: f64) -> Result<(), InvalidSetting> {
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
pub fn open_unit(name: &str, value: f64) -> Result<(), InvalidSetting> {
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
    name: &str,
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

/// The path of setting `name` below `prefix` (`prefix.name`; `name` alone when `prefix`
/// is empty, as for a configuration given on its own).
#[must_use]
pub fn path(prefix: &str, name: &str) -> String {
    if prefix.is_empty() {
        name.to_owned()
    } else {
        format!("{prefix}.{name}")
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
}
