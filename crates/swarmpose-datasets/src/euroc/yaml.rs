//! Just enough of the EuRoC `sensor.yaml` format: numeric arrays after a key, possibly
//! spanning lines (`intrinsics: [..]`, `T_BS: ... data: [..]`).

use std::path::Path;

use nalgebra::{Isometry3, Matrix3, Translation3};
use swarmpose_vision::rectify::RadTanCamera;

use crate::error::DatasetError;
use crate::text::{KeyLines, numbers, parse_error, read_text, strip_bom};

/// The numbers of the `[...]` array following `key:` (searched from byte `from`), with
/// the 1-based line where the key is.
fn array_after(
    text: &str,
    key: &str,
    from: usize,
    path: &Path,
) -> Result<(Vec<f64>, usize), DatasetError> {
    let missing = || parse_error(path, 0, format!("no '{key}' array"));
    let needle = format!("{key}:");
    let at = text[from..]
        .match_indices(&needle)
        .map(|(i, _)| from + i)
        .find(|&i| i == 0 || text[..i].ends_with(char::is_whitespace))
        .ok_or_else(missing)?;
    let line = text[..at].matches('\n').count() + 1;
    let open = text[at..].find('[').ok_or_else(missing)? + at;
    let close = text[open..]
        .find(']')
        .ok_or_else(|| parse_error(path, line, format!("'{key}' array is not closed")))?
        + open;
    // Drop comments inside the brackets.
    let inner: String = text[open + 1..close]
        .lines()
        .map(|l| l.split('#').next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join(" ");
    Ok((numbers(&inner, path, line)?, line))
}

/// A camera of a EuRoC `sensor.yaml`: its radial-tangential model and `T_BS`, the pose
/// of the camera (sensor) in the body frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorYaml {
    /// Intrinsics and distortion; `width`, `height` from `resolution`.
    pub camera: RadTanCamera,
    /// `X_body = T_BS X_camera`, metres.
    pub body_from_camera: Isometry3<f64>,
}

/// Reads a camera `sensor.yaml`.
///
/// # Errors
/// [`DatasetError::Parse`] naming the file (and line) of a missing or malformed entry.
pub fn read_sensor_yaml(path: &Path) -> Result<SensorYaml, DatasetError> {
    let text = read_text(path, "EuRoC camera sensor.yaml")?;
    parse_sensor_yaml(&text, path)
}

/// [`read_sensor_yaml`] of text already read; messages name `path`.
///
/// # Errors
/// As [`read_sensor_yaml`].
pub fn parse_sensor_yaml(text: &str, path: &Path) -> Result<SensorYaml, DatasetError> {
    let text = strip_bom(text);
    // A key given twice would be read from its first place silently.
    let mut keys = KeyLines::default();
    for (k, line) in text.lines().enumerate() {
        let key = line.split('#').next().unwrap_or("").trim_start();
        if let Some((name, _)) = key.split_once(':')
            && matches!(
                name.trim(),
                "intrinsics" | "distortion_coefficients" | "resolution" | "T_BS"
            )
        {
            keys.first(name.trim(), k + 1, path)?;
        }
    }
    let check = |v: &[f64], n: usize, key: &str, line: usize| {
        if v.len() == n {
            Ok(())
        } else {
            Err(parse_error(
                path,
                line,
                format!("'{key}' needs {n} numbers, found {}", v.len()),
            ))
        }
    };
    let (k, lk) = array_after(text, "intrinsics", 0, path)?;
    check(&k, 4, "intrinsics", lk)?;
    let (d, ld) = array_after(text, "distortion_coefficients", 0, path)?;
    check(&d, 4, "distortion_coefficients", ld)?;
    let (res, lr) = array_after(text, "resolution", 0, path)?;
    check(&res, 2, "resolution", lr)?;
    let tbs_at = text
        .find("T_BS:")
        .ok_or_else(|| parse_error(path, 0, "no 'T_BS' transform"))?;
    let (t, lt) = array_after(text, "data", tbs_at, path)?;
    check(&t, 16, "T_BS data", lt)?;
    if !(k[0] > 0.0 && k[1] > 0.0 && res[0] >= 1.0 && res[1] >= 1.0) {
        return Err(parse_error(
            path,
            lk,
            "focal lengths and resolution must be positive",
        ));
    }
    let r = Matrix3::new(t[0], t[1], t[2], t[4], t[5], t[6], t[8], t[9], t[10]);
    let det = r.determinant();
    let off = (r * r.transpose() - Matrix3::identity()).norm();
    if det < 0.0 {
        return Err(parse_error(
            path,
            lt,
            format!("the T_BS rotation has determinant {det:.3} (a reflection): a rotation has +1"),
        ));
    }
    if off.is_nan() || off > 1e-2 {
        return Err(parse_error(
            path,
            lt,
            format!(
                "the T_BS 3x3 part is not a rotation (|R Rᵀ - I| = {off:.3e}, at most 1e-2 accepted)"
            ),
        ));
    }
    let rot = crate::nearest_rotation(&r);
    Ok(SensorYaml {
        camera: RadTanCamera {
            fx: k[0],
            fy: k[1],
            cx: k[2],
            cy: k[3],
            k1: d[0],
            k2: d[1],
            p1: d[2],
            p2: d[3],
            width: res[0] as usize,
            height: res[1] as usize,
        },
        body_from_camera: Isometry3::from_parts(Translation3::new(t[3], t[7], t[11]), rot),
    })
}
