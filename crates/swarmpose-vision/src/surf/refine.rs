//! Sub-pixel, sub-scale refinement of the detector maxima (Brown & Lowe, BMVC 2002, the
//! interpolation Bay et al. use).
//!
//! Around a maximum of the response `D` over (column, row, layer), `D` is approximated by
//! its second-order Taylor expansion and the maximum moved to the extremum of that
//! quadratic. Offsets are in grid samples (and layers), converted to pixels by the
//! octave's sampling step and to a filter size by the layer spacing of the octave.

use super::response::{Block, Detection, ResponseLayer, is_local_max};

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
/// the fit is repeated there, at most [`MAX_MOVES`] times, within `lower..=upper`.
///
/// Returns `None` only when a move lands on another local maximum (which is refined on
/// its own). When the fit does not settle (the offset still exceeds 0.5 after the last
/// move, a move would leave `lower..=upper`, or `H` is singular) the sample maximum is
/// kept with the offset of its own fit clamped to ±0.5: it is a strict maximum of its 26
/// neighbours, and whether the fit settles depends on small changes of the image
/// (keeping these adds about a point of repeatability on the KITTI test frame).
pub(super) fn refine(
    layers: &[ResponseLayer],
    start: Block,
    lower: Block,
    upper: Block,
    octave: usize,
) -> Option<Detection> {
    match settle(layers, start, lower, upper) {
        Fit::Settled(at, v, g, offset) => Some(detection(layers, at, v, g, offset, octave)),
        Fit::OtherMaximum => None,
        Fit::Unsettled => {
            let (v, g, hessian) = derivatives(layers, start.mid, start.col, start.row);
            let offset = hessian
                .try_inverse()
                .map(|inv| -(inv * g))
                .filter(|o| o.iter().all(|c| c.is_finite()))
                .map_or_else(nalgebra::Vector3::zeros, |o| o.map(|c| c.clamp(-0.5, 0.5)));
            Some(detection(layers, start, v, g, offset, octave))
        }
    }
}

/// The outcome of the iterated fit.
enum Fit {
    /// Sample, response, gradient and offset (all components within ±0.5).
    Settled(Block, f64, nalgebra::Vector3<f64>, nalgebra::Vector3<f64>),
    /// A move landed on another local maximum.
    OtherMaximum,
    /// No offset within ±0.5 was reached.
    Unsettled,
}

/// The iterated fit of [`refine`].
fn settle(layers: &[ResponseLayer], start: Block, lower: Block, upper: Block) -> Fit {
    let mut at = start;
    for moves in 0..=MAX_MOVES {
        let (v, g, hessian) = derivatives(layers, at.mid, at.col, at.row);
        let Some(inverse) = hessian.try_inverse() else {
            return Fit::Unsettled;
        };
        let offset = -(inverse * g);
        if offset.iter().any(|o| !o.is_finite()) {
            return Fit::Unsettled;
        }
        if offset.iter().all(|o| o.abs() <= 0.5) {
            return Fit::Settled(at, v, g, offset);
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
        let moved = (|| {
            Some(Block {
                mid: shift(offset.z, at.mid, lower.mid, upper.mid)?,
                col: shift(offset.x, at.col, lower.col, upper.col)?,
                row: shift(offset.y, at.row, lower.row, upper.row)?,
            })
        })();
        let Some(moved) = moved else {
            return Fit::Unsettled;
        };
        at = moved;
        let (below, centre, above) = (&layers[at.mid - 1], &layers[at.mid], &layers[at.mid + 1]);
        let value = centre.at(at.col, at.row);
        if is_local_max(value, below, centre, above, at.col, at.row) {
            return Fit::OtherMaximum;
        }
    }
    Fit::Unsettled
}

/// The detection at sample `at` moved by `offset` (columns, rows, layers).
fn detection(
    layers: &[ResponseLayer],
    at: Block,
    v: f64,
    g: nalgebra::Vector3<f64>,
    offset: nalgebra::Vector3<f64>,
    octave: usize,
) -> Detection {
    let centre = &layers[at.mid];
    let step = centre.step as f64;
    let filter_step = (layers[at.mid + 1].filter - centre.filter) as f64;
    let filter = centre.filter as f64 + offset.z * filter_step;
    Detection {
        x: ((at.col as f64 + offset.x) * step) as f32,
        y: ((at.row as f64 + offset.y) * step) as f32,
        scale: (1.2 * filter / 9.0) as f32,
        response: (v + 0.5 * g.dot(&offset)) as f32,
        laplacian_positive: centre.laplacian_positive[at.row * centre.cols + at.col],
        octave: octave as u8,
    }
}

/// Sub-pixel position of a maximum `(col, row)` of the finest layer `layer` (which has
/// no layer below it): a 2D quadratic fit over (column, row) as in [`refine`], the offset
/// clamped to ±0.5 samples, at the layer's own filter size.
pub(super) fn refine_finest(layer: &ResponseLayer, col: usize, row: usize) -> Detection {
    let d = |dc: isize, dr: isize| -> f64 {
        f64::from(layer.at(col.wrapping_add_signed(dc), row.wrapping_add_signed(dr)))
    };
    let v = d(0, 0);
    let g = nalgebra::Vector2::new((d(1, 0) - d(-1, 0)) / 2.0, (d(0, 1) - d(0, -1)) / 2.0);
    let dxy = (d(1, 1) - d(-1, 1) - d(1, -1) + d(-1, -1)) / 4.0;
    let hessian = nalgebra::Matrix2::new(
        d(1, 0) + d(-1, 0) - 2.0 * v,
        dxy,
        dxy,
        d(0, 1) + d(0, -1) - 2.0 * v,
    );
    let offset = hessian
        .try_inverse()
        .map(|inv| -(inv * g))
        .filter(|o| o.iter().all(|c| c.is_finite()))
        .map_or_else(nalgebra::Vector2::zeros, |o| o.map(|c| c.clamp(-0.5, 0.5)));
    let step = layer.step as f64;
    Detection {
        x: ((col as f64 + offset.x) * step) as f32,
        y: ((row as f64 + offset.y) * step) as f32,
        scale: (1.2 * layer.filter as f64 / 9.0) as f32,
        response: (v + 0.5 * g.dot(&offset)) as f32,
        laplacian_positive: layer.laplacian_positive[row * layer.cols + col],
        octave: 0,
    }
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

    #[test]
    fn unsettled_fit_keeps_the_sample_with_a_clamped_offset() {
        // The peak lies 0.8 columns right of column 7, the last column a move may reach:
        // the fit cannot settle, and the maximum is kept half a sample to the right.
        let layers = layers(|c, r, l| {
            let (dc, dr, dl) = (c - 7.8, r - 4.0, l - 1.0);
            1.0 - 0.01 * dc * dc - 0.1 * dr * dr - 0.2 * dl * dl
        });
        let start = Block {
            mid: 1,
            col: 7,
            row: 4,
        };
        let Some(d) = refine(&layers, start, LOWER, UPPER, 0) else {
            panic!("rejected");
        };
        assert!(
            (d.x - 2.0 * 7.5).abs() < 1e-3 && (d.y - 2.0 * 4.0).abs() < 1e-3,
            "{d:?}"
        );
        assert!((d.scale - 1.2 * 15.0 / 9.0).abs() < 1e-3, "{d:?}");
    }

    #[test]
    fn finest_layer_maximum_is_refined_in_the_plane() {
        let layers = layers(|c, r, _| 1.0 - 0.05 * (c - 3.3).powi(2) - 0.05 * (r - 5.2).powi(2));
        let d = refine_finest(&layers[0], 3, 5);
        assert!(
            (d.x - 2.0 * 3.3).abs() < 1e-3 && (d.y - 2.0 * 5.2).abs() < 1e-3,
            "{d:?}"
        );
        assert!((d.scale - 1.2).abs() < 1e-6 && d.octave == 0);
    }
}
