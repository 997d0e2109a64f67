//! The JSON report printed by `swarmpose register`, as read back by `swarmpose
//! correspondences --inliers`: its inlier indices, after checking that the report was
//! made from the same correspondences (row count and [`points_checksum`]).

use swarmpose_core::Correspondences;

/// Why a register report cannot be used for a set of correspondences.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{input}: {message}")]
pub struct ReportError {
    /// The report's name (a file path).
    pub input: String,
    /// What is wrong, and what would be accepted.
    pub message: String,
}

/// A checksum of the coordinates of `data` (FNV-1a, 64 bits, over the bit patterns of
/// the six coordinates of every row, in order), as 16 hexadecimal digits. The CSV
/// writer writes every value so that it reads back bit for bit, so the checksum of the
/// correspondences written and of those read back from the file are equal.
#[must_use]
pub fn points_checksum(data: &Correspondences) -> String {
    const OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
    const PRIME: u64 = 0x0000_0100_0000_01b3;
    let mut h = OFFSET;
    for (s, d) in data.src().iter().zip(data.dst()) {
        for v in [s.x, s.y, s.z, d.x, d.y, d.z] {
            for b in v.to_bits().to_le_bytes() {
                h ^= u64::from(b);
                h = h.wrapping_mul(PRIME);
            }
        }
    }
    format!("{h:016x}")
}

/// The inlier flags of a register report (`text`, named `input` in messages) for
/// correspondences of `rows` rows whose [`points_checksum`] is `checksum`.
///
/// # Errors
/// [`ReportError`] when the text is not a JSON object, lacks `inliers`,
/// `n_correspondences` or `points_checksum`, when the row count or the checksum differs
/// (the report is of other correspondences), or when an inlier index is not below `rows`.
pub fn parse_inliers(
    text: &str,
    input: &str,
    rows: usize,
    checksum: &str,
) -> Result<Vec<bool>, ReportError> {
    let fail = |message: String| ReportError {
        input: input.to_owned(),
        message,
    };
    let value: serde_json::Value = serde_json::from_str(text.trim_start_matches('\u{feff}'))
        .map_err(|e| fail(format!("not a register JSON report: {e}")))?;
    let n = value
        .get("n_correspondences")
        .and_then(serde_json::Value::as_u64)
        .ok_or_else(|| fail("no \"n_correspondences\" count: not a register report".into()))?;
    if usize::try_from(n).ok() != Some(rows) {
        return Err(fail(format!(
            "the report is of {n} correspondences, the CSV has {rows}: it was made from \
             another CSV"
        )));
    }
    let sum = value
        .get("points_checksum")
        .and_then(serde_json::Value::as_str)
        .ok_or_else(|| {
            fail(
                "no \"points_checksum\": run `swarmpose register` on the CSV again to make \
                 a report that can be checked"
                    .into(),
            )
        })?;
    if sum != checksum {
        return Err(fail(format!(
            "points_checksum {sum} differs from the CSV's {checksum}: the report was made \
             from another CSV"
        )));
    }
    let list = value
        .get("inliers")
        .and_then(serde_json::Value::as_array)
        .ok_or_else(|| fail("no \"inliers\" array".into()))?;
    let mut flags = vec![false; rows];
    for v in list {
        let i = v
            .as_u64()
            .and_then(|i| usize::try_from(i).ok())
            .filter(|&i| i < rows)
            .ok_or_else(|| {
                fail(format!(
                    "inlier {v} is not a row index below {rows} (0-based)"
                ))
            })?;
        flags[i] = true;
    }
    Ok(flags)
}

#[cfg(test)]
mod tests {
    use nalgebra::Point3;

    use super::*;

    fn data(x: f64) -> Correspondences {
        let p: Vec<Point3<f64>> = (0..3).map(|i| Point3::new(f64::from(i), x, 1.0)).collect();
        Correspondences::new(p.clone(), p).expect("valid")
    }

    #[test]
    fn a_report_of_the_same_points_gives_its_inliers() {
        let sum = points_checksum(&data(0.5));
        let text =
            format!(r#"{{"n_correspondences":3,"points_checksum":"{sum}","inliers":[0,2]}}"#);
        assert_eq!(
            parse_inliers(&text, "r.json", 3, &sum).expect("ok"),
            vec![true, false, true]
        );
    }

    #[test]
    fn a_report_of_other_points_is_refused() {
        let sum = points_checksum(&data(0.5));
        let other = points_checksum(&data(0.25));
        assert_ne!(sum, other);
        let text =
            format!(r#"{{"n_correspondences":3,"points_checksum":"{other}","inliers":[0]}}"#);
        let e = parse_inliers(&text, "r.json", 3, &sum).expect_err("other CSV");
        assert!(e.to_string().starts_with("r.json: points_checksum"), "{e}");
        let e = parse_inliers(&text, "r.json", 4, &sum).expect_err("other count");
        assert!(e.message.contains("the CSV has 4"), "{e}");
        let text = format!(r#"{{"n_correspondences":3,"points_checksum":"{sum}","inliers":[3]}}"#);
        let e = parse_inliers(&text, "r.json", 3, &sum).expect_err("index");
        assert!(e.message.contains("below 3"), "{e}");
        for bad in ["", "[]", "{}", r#"{"n_correspondences":3}"#] {
            assert!(parse_inliers(bad, "r.json", 3, &sum).is_err(), "{bad}");
        }
    }
}
