//! Is a point set spread enough to fix a rotation?

use nalgebra::{Matrix3, Point3};

use crate::error::{DegeneracyKind, PoseError};

/// Relative spread below which a direction counts as flat: a second principal extent
/// under `1e-6` of the first (1 µm over 1 m) is collinear.
const RELATIVE_FLAT: f64 = 1e-6;
/// Absolute spread (metres) below which a set counts as coincident, relative to the
/// magnitude of its coordinates.
const ABSOLUTE_COINCIDENT: f64 = 1e-9;
/// The largest coordinate magnitude a point set may have: the scatter matrix squares
/// differences of coordinates, which overflow beyond about 1e154.
pub const MAX_COORDINATE: f64 = 1e150;

/// Principal extents of a point set: the square roots of the eigenvalues of its
/// mean-centred scatter matrix divided by the point count, in metres, sorted descending.
///
/// Returns zeros for an empty set.
#[must_use]
pub fn spread<'a, I>(points: I) -> [f64; 3]
where
    I: IntoIterator<Item = &'a Point3<f64>>,
    I::IntoIter: Clone,
{
    let it = points.into_iter();
    let mut n = 0usize;
    let mut sum = nalgebra::Vector3::zeros();
    for p in it.clone() {
        sum += p.coords;
        n += 1;
    }
    if n == 0 {
        return [0.0; 3];
    }
    let mean = sum / n as f64;
    let mut scatter = Matrix3::zeros();
    for p in it {
        let d = p.coords - mean;
        scatter += d * d.transpose();
    }
    scatter /= n as f64;
    // Capped iterations (the uncapped decomposition can spin on pathological input); a
    // failure to converge reports no spread, so the set is refused rather than trusted.
    let Some(eig) = scatter
        .try_symmetric_eigen(f64::EPSILON, crate::arun::MAX_DECOMPOSITION_ITERATIONS)
        .map(|e| e.eigenvalues)
    else {
        return [0.0; 3];
    };
    let mut ev = [
        eig[0].max(0.0).sqrt(),
        eig[1].max(0.0).sqrt(),
        eig[2].max(0.0).sqrt(),
    ];
    ev.sort_by(|a, b| b.total_cmp(a));
    ev
}

/// Fails if the set is coincident or collinear; `set` names it in the error.
///
/// Coplanar sets pass: a plane fixes a rotation (Arun's reflection guard handles it).
///
/// # Errors
/// [`PoseError::Degenerate`] with [`DegeneracyKind::Coincident`] or
/// [`DegeneracyKind::Collinear`]; [`PoseError::TooLarge`] for a coordinate beyond
/// [`MAX_COORDINATE`] (its spread cannot be computed: it is not "coincident").
pub fn check_spread<'a, I>(points: I, set: &'static str) -> Result<(), PoseError>
where
    I: IntoIterator<Item = &'a Point3<f64>>,
    I::IntoIter: Clone,
{
    let it = points.into_iter();
    let scale = it.clone().map(|p| p.coords.amax()).fold(0.0_f64, f64::max);
    if scale > MAX_COORDINATE {
        return Err(PoseError::TooLarge {
            set,
            magnitude: scale,
            max: MAX_COORDINATE,
        });
    }
    let scale = scale.max(1.0);
    let [s1, s2, _] = spread(it);
    if s1 <= ABSOLUTE_COINCIDENT * scale {
        return Err(PoseError::Degenerate {
            set,
            kind: DegeneracyKind::Coincident,
        });
    }
    if s2 <= RELATIVE_FLAT * s1 {
        return Err(PoseError::Degenerate {
            set,
            kind: DegeneracyKind::Collinear,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classifies_sets() {
        let same = vec![Point3::new(1.0, 2.0, 3.0); 5];
        assert!(matches!(
            check_spread(&same, "source"),
            Err(PoseError::Degenerate {
                kind: DegeneracyKind::Coincident,
                ..
            })
        ));
        let line: Vec<_> = (0..6)
            .map(|i| Point3::new(1.0 + i as f64, 2.0 + 2.0 * i as f64, -3.0 * i as f64))
            .collect();
        assert!(matches!(
            check_spread(&line, "source"),
            Err(PoseError::Degenerate {
                kind: DegeneracyKind::Collinear,
                ..
            })
        ));
        let plane: Vec<_> = (0..6)
            .map(|i| Point3::new((i % 3) as f64, (i / 3) as f64, 4.0))
            .collect();
        assert!(check_spread(&plane, "source").is_ok());
        let s = spread(&plane);
        assert!(s[2] < 1e-12 && s[1] > 0.1);
        // Points 1e300 apart are not "coincident": their spread overflows.
        let huge: Vec<_> = (0..6)
            .map(|i| Point3::new(1e300 * (i % 3) as f64, 1e300 * (i / 3) as f64, 1.0))
            .collect();
        let e = check_spread(&huge, "source").expect_err("too large");
        assert!(matches!(e, PoseError::TooLarge { .. }), "{e:?}");
        assert!(e.to_string().contains("too large"), "{e}");
    }
}
