//! numpy arrays in and out: (N, 3) points and (N, 3, 3) covariances of float32 or
//! float64 in any memory order (read in place, no intermediate copy), 4x4 poses, and
//! images (8-bit gray, float32 depth).

use std::borrow::Cow;

use nalgebra::{Isometry3, Matrix3, Matrix4, Point3, Rotation3, Translation3, UnitQuaternion};
use numpy::ndarray::{Array1, Array2, Array3, ArrayView2, ArrayView3, ArrayViewD, Ix2, Ix3};
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArrayDyn, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use swarmpose_eval::trajectory::check_rotation;
use swarmpose_odometry::DepthView;
use swarmpose_vision::features::GrayView;

/// A float array borrowed from Python, read-only, in its own dtype.
enum Floats<'py> {
    F64(PyReadonlyArrayDyn<'py, f64>),
    F32(PyReadonlyArrayDyn<'py, f32>),
}

/// `obj` as a float32 or float64 array; anything that is not a numpy array (a list)
/// goes through `numpy.asarray(obj, float64)`.
fn floats<'py>(name: &str, obj: &Bound<'py, PyAny>) -> PyResult<Floats<'py>> {
    if let Ok(a) = obj.extract::<PyReadonlyArrayDyn<'py, f64>>() {
        return Ok(Floats::F64(a));
    }
    if let Ok(a) = obj.extract::<PyReadonlyArrayDyn<'py, f32>>() {
        return Ok(Floats::F32(a));
    }
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        return Err(PyTypeError::new_err(format!(
            "{name} has dtype {}: float32 or float64 expected",
            a.dtype()
        )));
    }
    let numpy = obj.py().import("numpy")?;
    let converted = numpy.call_method1("asarray", (obj, numpy.getattr("float64")?))?;
    Ok(Floats::F64(
        converted.extract::<PyReadonlyArrayDyn<'py, f64>>()?,
    ))
}

fn shape_text(shape: &[usize]) -> String {
    let parts: Vec<String> = shape.iter().map(usize::to_string).collect();
    if parts.len() == 1 {
        format!("({},)", parts[0])
    } else {
        format!("({})", parts.join(", "))
    }
}

fn points_of<T: Copy + Into<f64>>(v: &ArrayView2<'_, T>) -> Vec<Point3<f64>> {
    v.outer_iter()
        .map(|r| Point3::new(r[0].into(), r[1].into(), r[2].into()))
        .collect()
}

fn view2<'a, T>(name: &str, v: ArrayViewD<'a, T>) -> PyResult<ArrayView2<'a, T>> {
    let shape = v.shape().to_vec();
    match v.into_dimensionality::<Ix2>() {
        Ok(v) if v.ncols() == 3 => Ok(v),
        _ => Err(PyValueError::new_err(format!(
            "{name} has shape {}: (N, 3) expected",
            shape_text(&shape)
        ))),
    }
}

fn view3<'a, T>(name: &str, v: ArrayViewD<'a, T>, n: usize) -> PyResult<ArrayView3<'a, T>> {
    let shape = v.shape().to_vec();
    match v.into_dimensionality::<Ix3>() {
        Ok(v) if v.shape() == [n, 3, 3] => Ok(v),
        _ => Err(PyValueError::new_err(format!(
            "{name} has shape {}: ({n}, 3, 3) expected",
            shape_text(&shape)
        ))),
    }
}

/// The rows of an (N, 3) float array as points (metres).
pub(crate) fn points(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<Point3<f64>>> {
    Ok(match floats(name, obj)? {
        Floats::F64(a) => points_of(&view2(name, a.as_array())?),
        Floats::F32(a) => points_of(&view2(name, a.as_array())?),
    })
}

fn matrices_of<T: Copy + Into<f64>>(v: &ArrayView3<'_, T>) -> Vec<Matrix3<f64>> {
    v.outer_iter()
        .map(|m| Matrix3::from_fn(|r, c| m[[r, c]].into()))
        .collect()
}

/// The (n, 3, 3) float array `obj` as `n` matrices.
pub(crate) fn matrices(
    name: &str,
    obj: &Bound<'_, PyAny>,
    n: usize,
) -> PyResult<Vec<Matrix3<f64>>> {
    Ok(match floats(name, obj)? {
        Floats::F64(a) => matrices_of(&view3(name, a.as_array(), n)?),
        Floats::F32(a) => matrices_of(&view3(name, a.as_array(), n)?),
    })
}

/// The 4x4 matrices of an (N, 4, 4) array.
fn matrices4_of<T: Copy + Into<f64>>(
    name: &str,
    v: ArrayViewD<'_, T>,
) -> PyResult<Vec<Matrix4<f64>>> {
    let shape = v.shape().to_vec();
    match v.into_dimensionality::<Ix3>() {
        Ok(v) if v.shape()[1..] == [4, 4] => Ok(v
            .outer_iter()
            .map(|m| Matrix4::from_fn(|r, c| m[[r, c]].into()))
            .collect()),
        _ => Err(PyValueError::new_err(format!(
            "{name} has shape {}: (N, 4, 4) expected",
            shape_text(&shape)
        ))),
    }
}

/// A (N, 4, 4) float array of rigid transforms: the last row `0 0 0 1` and the 3x3 block
/// a rotation to within rounding ([`swarmpose_eval::trajectory::check_rotation`], as for
/// trajectory files), projected to the nearest proper one.
pub(crate) fn poses(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<Isometry3<f64>>> {
    let m = match floats(name, obj)? {
        Floats::F64(a) => matrices4_of(name, a.as_array())?,
        Floats::F32(a) => matrices4_of(name, a.as_array())?,
    };
    m.iter()
        .enumerate()
        .map(|(i, m)| {
            if !m.iter().all(|v| v.is_finite()) {
                return Err(PyValueError::new_err(format!(
                    "{name}[{i}] has a non-finite entry"
                )));
            }
            let last = [m[(3, 0)], m[(3, 1)], m[(3, 2)], m[(3, 3)]];
            // Within rounding: np.linalg.inv of a transform leaves 1e-17 there.
            let off = last
                .iter()
                .zip([0.0, 0.0, 0.0, 1.0])
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            if off > 1e-6 {
                return Err(PyValueError::new_err(format!(
                    "{name}[{i}] has the last row {last:?}: [0, 0, 0, 1] expected"
                )));
            }
            let r: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
            check_rotation(&r).map_err(|e| PyValueError::new_err(format!("{name}[{i}]: {e}")))?;
            let rotation = Rotation3::from_matrix_eps(&r, 1e-12, 100, Rotation3::identity());
            Ok(Isometry3::from_parts(
                Translation3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]),
                UnitQuaternion::from_rotation_matrix(&rotation),
            ))
        })
        .collect()
}

/// A 4x4 homogeneous transform.
pub(crate) fn transform<'py>(py: Python<'py>, t: &Isometry3<f64>) -> Bound<'py, PyArray2<f64>> {
    matrix(py, &t.to_homogeneous())
}

/// Any nalgebra matrix as a 2-D array, row-major.
pub(crate) fn matrix<'py, const R: usize, const C: usize>(
    py: Python<'py>,
    m: &nalgebra::SMatrix<f64, R, C>,
) -> Bound<'py, PyArray2<f64>> {
    Array2::from_shape_fn((R, C), |(r, c)| m[(r, c)]).into_pyarray(py)
}

/// A 1-D float array.
pub(crate) fn vector<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, v)
}

/// Indices as a 1-D int64 array.
pub(crate) fn indices<'py>(py: Python<'py>, v: &[usize]) -> Bound<'py, PyArray1<i64>> {
    Array1::from_iter(v.iter().map(|&i| i64::try_from(i).unwrap_or(i64::MAX))).into_pyarray(py)
}

/// Poses as an (N, 4, 4) array.
pub(crate) fn transforms<'py>(
    py: Python<'py>,
    poses: &[Isometry3<f64>],
) -> Bound<'py, PyArray3<f64>> {
    let h: Vec<Matrix4<f64>> = poses.iter().map(Isometry3::to_homogeneous).collect();
    Array3::from_shape_fn((poses.len(), 4, 4), |(i, r, c)| h[i][(r, c)]).into_pyarray(py)
}

/// An (H, W) image array of `data`, row-major (8-bit gray, or float32 depth).
pub(crate) fn image_array<'py, T: numpy::Element + Clone>(
    py: Python<'py>,
    width: usize,
    height: usize,
    data: &[T],
) -> PyResult<Bound<'py, PyArray2<T>>> {
    let a = Array2::from_shape_vec((height, width), data.to_vec())
        .map_err(|e| PyValueError::new_err(format!("image of {width}x{height}: {e}")))?;
    Ok(a.into_pyarray(py))
}

/// An image borrowed from Python: shape (H, W) of one dtype (uint8 gray, float32
/// depth).
pub(crate) struct ImageArray<'py, T: numpy::Element> {
    array: numpy::PyReadonlyArray2<'py, T>,
}

impl<'py, T: numpy::Element + Copy> ImageArray<'py, T> {
    /// Borrows `obj` as an image; `dtype` names `T` in messages.
    pub(crate) fn new(name: &str, obj: &Bound<'py, PyAny>, dtype: &str) -> PyResult<Self> {
        if let Ok(array) = obj.extract::<numpy::PyReadonlyArray2<'py, T>>() {
            return Ok(Self { array });
        }
        match obj.cast::<PyUntypedArray>() {
            Ok(a) => Err(PyValueError::new_err(format!(
                "{name} image has shape {} and dtype {}: a (height, width) {dtype} array expected",
                shape_text(a.shape()),
                a.dtype()
            ))),
            Err(_) => Err(PyTypeError::new_err(format!(
                "{name} image is a {}: a (height, width) {dtype} numpy array expected",
                obj.get_type().name()?
            ))),
        }
    }

    /// The size and pixels, row-major: borrowed when the array is C-contiguous, else
    /// copied.
    pub(crate) fn pixels(&self) -> Pixels<'_, T> {
        let s = self.array.shape();
        // `as_slice` also accepts Fortran order, whose memory is column-major.
        let data = match self.array.as_slice() {
            Ok(s) if self.array.is_c_contiguous() => Cow::Borrowed(s),
            _ => Cow::Owned(self.array.as_array().iter().copied().collect()),
        };
        Pixels {
            width: s[1],
            height: s[0],
            data,
        }
    }
}

/// An image's pixels, row-major, with its size (pixels): what the engine's views borrow.
pub(crate) struct Pixels<'a, T: Clone> {
    width: usize,
    height: usize,
    data: Cow<'a, [T]>,
}

impl Pixels<'_, u8> {
    /// A gray image view of the pixels.
    pub(crate) fn gray(&self) -> GrayView<'_> {
        GrayView {
            width: self.width,
            height: self.height,
            data: &self.data,
        }
    }
}

impl Pixels<'_, f32> {
    /// A depth view of the pixels (metres).
    pub(crate) fn depth(&self) -> DepthView<'_> {
        DepthView {
            width: self.width,
            height: self.height,
            data: &self.data,
        }
    }
}
