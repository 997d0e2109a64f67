//! Serde helpers for settings whose value may be infinite (JSON has no infinity):
//! such a number is written as the string `"inf"` and read from it.

use serde::{Deserialize, Deserializer, Serializer};

/// Writes a finite number as a number and +∞ as `"inf"`.
pub(crate) fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
    if *v == f64::INFINITY {
        s.serialize_str("inf")
    } else {
        s.serialize_f64(*v)
    }
}

/// Reads a number, or `"inf"` for +∞.
pub(crate) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum NumberOrInf {
        Number(f64),
        Text(String),
    }
    match NumberOrInf::deserialize(d)? {
        NumberOrInf::Number(v) => Ok(v),
        NumberOrInf::Text(t) if t == "inf" => Ok(f64::INFINITY),
        NumberOrInf::Text(t) => Err(serde::de::Error::custom(format!(
            "{t:?}: expected a number or \"inf\""
        ))),
    }
}
