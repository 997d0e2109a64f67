//! Sub-pixel, sub-scale refinement of the detector maxima (Brown & Lowe, BMVC 2002, the
//! interpolation Bay et al. use).
//!
//! Around a maximum of the response `D` over (column, row, layer), `D` is approximated by
//! its second-order Taylor expansion and the maximum moved to the extremum of that
//! quadratic. Offsets are in grid samples (and layers), converted to pixels by the
//! octave's sampling step and to a filter size by the layer spacing of the octave.

use super::hessian::{Detection, ResponseLayer, is_local_max};

/// Gradient `g` and Hessian `H` of the response over (column, row, layer) at
/// `(col, row)` of layer `mid`, by central differences, with the response `D` itself:
///
/// ```text
/// g = (∂D/∂c, ∂D/∂r, ∂D/∂l),   H_ij = ∂²D/∂i∂j,
/// ∂D/∂c ≈ (D(c+1) − D(c−1)) / 2,   ∂²D/∂c² ≈ D(c+1) + D(c−1) − 2D,
/// ∂²D/∂c∂r ≈ (D(c+1, r+1) − D(c−1, r+1) − D(c+1, r−1) + D(c−1, r−1)) / 4, …
/// ```
fn derivatives(
    layers: &[ResponseLayer],
    mid: usize,
    col: usize,
    row: usize,
) -> (f64, nalgebra::Vector3<f64>, nalgebra::Matrix3<f64>) {
    let (below, centre, above) = (&layers[mid - 1], &layers[mid], &layers[mid + 1]);
    let c = |l: &ResponseLayer, dc: isize, dr: isize| -> f64 {
        f64::from(l.at(col.wrapping_add_signed(dc), row.wrapping_add_signed(dr)))
    };
    let v = c(centre, 0, 0);
    let g = nalgebra::Vector3::new(
        (c(centre, 1, 0) - c(centre, -1, 0)) / 2.0,
        (c(centre, 0, 1) - c(centre, 0, -1)) / 2.0,
        (c(above, 0, 0) - c(below, 0, 0)) / 2.0,
    );
    let dxx = c(centre, 1, 0) + c(centre, -1, 0) - 2.0 * v;
    let dyy = c(centre, 0, 1) + c(centre, 0, -1) - 2.0 * v;
    let dss = c(above, 0, 0) + c(below, 0, 0) - 2.0 * v;
    let dxy = (c(centre, 1, 1) - c(centre, -1, 1) - c(centre, 1, -1) + c(centre, -1, -1)) / 4.0;
    let dxs = (c(above, 1, 0) - c(above, -1, 0) - c(below, 1, 0) + c(below, -1, 0)) / 4.0;
    let dys = (c(above, 0, 1) - c(above, 0, -1) - c(below, 0, 1) + c(below, 0, -1)) / 4.0;
    let hessian = nalgebra::Matrix3::new(dxx, dxy, dxs, dxy, dyy, dys, dxs, dys, dss);
    (v, g, hessian)
}

/// The centre of a 3×3×3 block: layer `mid` of the octave, grid `(col, row)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Block {
    /// Layer within the octave.
    pub mid: usize,
    /// Grid column.
    pub col: usize,
    /// Grid row.
    pub row: usize,
}

/// How many times the fit may move to a neighbouring sample.
const MAX_MOVES: usize = 2;

/// Fits a 3D quadratic to the 3×3×3 block around the maximum `start` and moves to its
/// extremum (Brown & Lowe 2002, the interpolation SURF uses):
///
/// ```text
/// D(x + δ) ≈ D + gᵀδ + ½ δᵀHδ,   δ* = −H⁻¹ g,   D(δ*) = D + ½ gᵀδ*,
/// ```
///
/// with `g` and `H` from [`derivatives`] over (column, row, layer). When a component of
/// `δ*` exceeds 0.5 the extremum is closer to the neighbouring sample in that direction:
/// the fit is repeated there, at most [`MAX_MOVES`] times, within `lower..=upper`. Returns
/// `None` when `H` is singular, when the offset still exceeds 0.5 after the last move
/// (rejected), or when a move lands on another local maximum (which is refined on its
/// own).
pub(super) fn refine(
    layers: &[ResponseLayer],
    start: Block,
    lower: Block,
    upper: Block,
    octave: usize,
) -> Option<Detection> {
    let mut at = start;
    for moves in 0..=MAX_MOVES {
        let (v, g, hessian) = derivatives(layers, at.mid, at.col, at.row);
        let offset = -(hessian.try_inverse()? * g);
        if offset.iter().any(|o| !o.is_finite()) {
            return None;
        }
        if offset.iter().all(|o| o.abs() <= 0.5) {
            let centre = &layers[at.mid];
            let step = centre.step as f64;
            let filter_step = (layers[at.mid + 1].filter - centre.filter) as f64;
            let filter = centre.filter as f64 + offset.z * filter_step;
            return Some(Detection {
                x: ((at.col as f64 + offset.x) * step) as f32,
                y: ((at.row as f64 + offset.y) * step) as f32,
                scale: (1.2 * filter / 9.0) as f32,
                response: (v + 0.5 * g.dot(&offset)) as f32,
                laplacian_positive: centre.laplacian_positive[at.row * centre.cols + at.col],
                octave: octave as u8,
            });
        }
        if moves == MAX_MOVES {
            break;
        }
        let shift = |o: f64, i: usize, lo: usize, hi: usize| -> Option<usize> {
            if o > 0.5 {
                (i < hi).then_some(i + 1)
            } else if o < -0.5 {
                (i > lo).then(|| i - 1)
            } else {
                Some(i)
            }
        };
        at = Block {
            mid: shift(offset.z, at.mid, lower.mid, upper.mid)?,
            col: shift(offset.x, at.col, lower.col, upper.col)?,
            row: shift(offset.y, at.row, lower.row, upper.row)?,
        };
        let (below, centre, above) = (&layers[at.mid - 1], &layers[at.mid], &layers[at.mid + 1]);
        let value = centre.at(at.col, at.row);
        if is_local_max(value, below, centre, above, at.col, at.row) {
            return None;
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three 9 × 9 layers (filters 9, 15, 21, step 2) sampling `f(c, r, l)`.
    fn layers(f: impl Fn(f64, f64, f64) -> f64) -> Vec<ResponseLayer> {
        (0..3)
            .map(|l| ResponseLayer {
                filter: 9 + 6 * l,
                step: 2,
                cols: 9,
                rows: 9,
                det: (0..81)
                    .map(|i| f((i % 9) as f64, (i / 9) as f64, l as f64) as f32)
                    .collect(),
                laplacian_positive: vec![true; 81],
            })
            .collect()
    }

    const LOWER: Block = Block {
        mid: 1,
        col: 1,
        row: 1,
    };
    const UPPER: Block = Block {
        mid: 1,
        col: 7,
        row: 7,
    };

    #[test]
    fn quadratic_peak_is_recovered_exactly() {
        let (c0, r0, l0) = (4.3, 3.8, 1.2);
        let layers = layers(|c, r, l| {
            1.0 - 0.01 * (c - c0).powi(2) - 0.02 * (r - r0).powi(2) - 0.05 * (l - l0).powi(2)
        });
        let start = Block {
            mid: 1,
            col: 4,
            row: 4,
        };
        let Some(d) = refine(&layers, start, LOWER, UPPER, 1) else {
            panic!("rejected");
        };
        // Pixels = samples × step; filter = 15 + 0.2 × 6.
        assert!(
            (d.x - 2.0 * 4.3).abs() < 1e-3 && (d.y - 2.0 * 3.8).abs() < 1e-3,
            "{d:?}"
        );
        assert!((d.scale - 1.2 * 16.2 / 9.0).abs() < 1e-3, "{d:?}");
        assert!((d.response - 1.0).abs() < 1e-4);
        assert_eq!(d.octave, 1);
    }

    #[test]
    fn far_extremum_moves_once_then_fits() {
        // A tilted ridge: the sample at column 4 is the largest of its 3×3×3 block, but
        // the coupled quadratic peaks 0.6 columns away (plus the row offset it implies).
        let layers = layers(|c, r, l| {
            let (dc, dr, dl) = (c - 4.6, r - 4.2, l - 1.0);
            1.0 - 0.1 * dc * dc - 0.1 * dr * dr + 0.15 * dc * dr - 0.2 * dl * dl
        });
        let start = Block {
            mid: 1,
            col: 4,
            row: 4,
        };
        let Some(d) = refine(&layers, start, LOWER, UPPER, 0) else {
            panic!("rejected");
        };
        assert!(
            (d.x - 2.0 * 4.6).abs() < 1e-3 && (d.y - 2.0 * 4.2).abs() < 1e-3,
            "{d:?}"
        );
    }
}
