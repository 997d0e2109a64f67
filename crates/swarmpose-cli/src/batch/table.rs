//! The merged table of a batch: one row per item, sorted by name, numbers at fixed
//! precision, no times: the same bytes whatever the sharding.

use std::fmt::Write as _;

use super::item::{STATUS_OK, Summary};

/// A row of the table: an item's summary, or an item of the manifest without one.
#[derive(Debug, Clone, PartialEq)]
pub enum Row {
    /// Its summary.
    Done(Box<Summary>),
    /// No summary: not run yet (or killed while it ran).
    Missing(String),
}

impl Row {
    /// The item's name.
    #[must_use]
    pub fn name(&self) -> &str {
        match self {
            Self::Done(s) => &s.item,
            Self::Missing(n) => n,
        }
    }

    /// The item's status (`missing` without a summary).
    #[must_use]
    pub fn status(&self) -> &str {
        match self {
            Self::Done(s) => &s.status,
            Self::Missing(_) => "missing",
        }
    }
}

/// The columns: name, and the cell of a row.
type Column = (&'static str, fn(&Summary) -> String);

fn num(v: Option<f64>, decimals: usize) -> String {
    v.map_or_else(String::new, |v| format!("{v:.decimals$}"))
}

/// Every column after `item` and `status`, in order.
const COLUMNS: [Column; 15] = [
    ("exit_code", |s| s.exit_code.to_string()),
    ("frames", |s| s.frames.to_string()),
    ("tracked", |s| s.tracked.to_string()),
    ("constant_velocity", |s| s.constant_velocity.to_string()),
    ("lost", |s| s.lost.to_string()),
    ("path_m", |s| {
        num(s.metrics.as_ref().map(|m| m.path_length_m), 3)
    }),
    ("final_drift_m", |s| {
        num(s.metrics.as_ref().map(|m| m.final_drift_m), 4)
    }),
    ("final_drift_percent", |s| {
        num(s.metrics.as_ref().and_then(|m| m.final_drift_percent), 3)
    }),
    ("eq20_rms", |s| {
        num(s.metrics.as_ref().map(|m| m.eq20_rms), 6)
    }),
    ("ate_aligned_m", |s| {
        num(s.metrics.as_ref().map(|m| m.ate_aligned_m), 4)
    }),
    ("rpe_translation_m", |s| {
        num(s.metrics.as_ref().map(|m| m.rpe_translation_m), 4)
    }),
    ("rpe_rotation_deg", |s| {
        num(s.metrics.as_ref().map(|m| m.rpe_rotation_deg), 4)
    }),
    ("kitti_translation_percent", |s| {
        num(
            s.metrics.as_ref().and_then(|m| m.kitti_translation_percent),
            3,
        )
    }),
    ("kitti_rotation_deg_per_100m", |s| {
        num(
            s.metrics
                .as_ref()
                .and_then(|m| m.kitti_rotation_deg_per_100m),
            3,
        )
    }),
    ("config_hash", |s| s.config_hash.chars().take(19).collect()),
];

fn cells(row: &Row) -> Vec<String> {
    let mut c = vec![row.name().to_owned(), row.status().to_owned()];
    match row {
        Row::Done(s) => c.extend(COLUMNS.iter().map(|(_, f)| f(s))),
        Row::Missing(_) => c.extend(COLUMNS.iter().map(|_| String::new())),
    }
    c
}

fn header() -> Vec<&'static str> {
    let mut h = vec!["item", "status"];
    h.extend(COLUMNS.iter().map(|(n, _)| *n));
    h
}

/// The CSV table, rows sorted by name: a field is quoted only when it holds a comma, a
/// quote (written twice) or a line break.
///
/// # Errors
/// The `csv` crate's (none is expected: the text is built in memory).
pub fn csv(rows: &[Row]) -> Result<Vec<u8>, csv::Error> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(header())?;
    for r in rows {
        w.write_record(cells(r))?;
    }
    w.into_inner().map_err(|e| csv::Error::from(e.into_error()))
}

/// Mean of the values present, and how many there were.
fn mean(values: impl Iterator<Item = Option<f64>>) -> (Option<f64>, usize) {
    let v: Vec<f64> = values.flatten().collect();
    let m = (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
    (m, v.len())
}

/// The aggregate lines: counts by status and the mean figures over the items that have
/// them.
#[must_use]
pub fn aggregates(rows: &[Row]) -> Vec<String> {
    let mut statuses: Vec<(&str, usize)> = Vec::new();
    for r in rows {
        match statuses.iter_mut().find(|(s, _)| *s == r.status()) {
            Some((_, n)) => *n += 1,
            None => statuses.push((r.status(), 1)),
        }
    }
    statuses.sort_unstable();
    let counts: Vec<String> = statuses.iter().map(|(s, n)| format!("{n} {s}")).collect();
    let mut lines = vec![format!("items: {} ({})", rows.len(), counts.join(", "))];
    let metrics: Vec<_> = rows
        .iter()
        .filter_map(|r| match r {
            Row::Done(s) if s.status == STATUS_OK => s.metrics.as_ref(),
            _ => None,
        })
        .collect();
    let figures = [
        (
            "mean final drift",
            "%",
            3,
            mean(metrics.iter().map(|m| m.final_drift_percent)),
        ),
        (
            "mean ATE (aligned)",
            "m",
            4,
            mean(metrics.iter().map(|m| Some(m.ate_aligned_m))),
        ),
        (
            "mean KITTI segment translation error",
            "%",
            3,
            mean(metrics.iter().map(|m| m.kitti_translation_percent)),
        ),
        (
            "mean KITTI segment rotation error",
            "deg/100 m",
            3,
            mean(metrics.iter().map(|m| m.kitti_rotation_deg_per_100m)),
        ),
    ];
    for (what, unit, decimals, (m, n)) in figures {
        let value = m.map_or_else(|| "n/a".to_owned(), |m| format!("{m:.decimals$} {unit}"));
        lines.push(format!("{what}: {value} (over {n} ok item(s))"));
    }
    lines
}

/// The Markdown table and the aggregates.
#[must_use]
pub fn markdown(rows: &[Row]) -> String {
    let h = header();
    let mut out = format!("| {} |\n|", h.join(" | "));
    for _ in &h {
        out.push_str("---|");
    }
    out.push('\n');
    for r in rows {
        let _ = writeln!(out, "| {} |", cells(r).join(" | "));
    }
    out.push('\n');
    for line in aggregates(rows) {
        let _ = writeln!(out, "- {line}");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A name with a comma or a quote (a manifest does not allow one today, a merged table
    /// from elsewhere may) comes back whole from any CSV reader; plain names are not quoted.
    #[test]
    fn item_names_round_trip_through_the_csv_table() {
        let names = ["plain-name", "a,b", "say \"hi\"", "both, \"x\""];
        let rows: Vec<Row> = names
            .iter()
            .map(|n| Row::Missing((*n).to_owned()))
            .collect();
        let table = csv(&rows).expect("a table");
        let text = String::from_utf8(table.clone()).expect("UTF-8");
        assert!(text.contains("\nplain-name,missing,"), "{text}");
        let mut reader = ::csv::Reader::from_reader(table.as_slice());
        let header = reader.headers().expect("a header").clone();
        assert_eq!(header.len(), 2 + COLUMNS.len());
        let back: Vec<(String, String)> = reader
            .records()
            .map(|r| {
                let r = r.expect("a record");
                assert_eq!(r.len(), header.len());
                (r[0].to_owned(), r[1].to_owned())
            })
            .collect();
        let expected: Vec<(String, String)> = names
            .iter()
            .map(|n| ((*n).to_owned(), "missing".to_owned()))
            .collect();
        assert_eq!(back, expected);
    }
}
