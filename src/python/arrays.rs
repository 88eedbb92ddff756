//! numpy arrays in and out: images `H × W × 3` and grids `[nz, ny, nx]`, `float32`, in C order (the
//! library's layouts: `rgb[3 · (y · width + x) + c]`, `values[(z · ny + y) · nx + x]`).

use crate::film::{self, Image};
use crate::sdf::GridData;
use numpy::ndarray::{Array2, Array3};
use numpy::{AllowTypeChange, IntoPyArray, PyArray2, PyArray3, PyArrayLikeDyn};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// The image as a new `float32` array of shape `(height, width, 3)`.
pub(crate) fn image_to_py<'py>(py: Python<'py>, image: &Image) -> Bound<'py, PyArray3<f32>> {
    let shape = (image.height as usize, image.width as usize, 3);
    Array3::from_shape_vec(shape, image.rgb.clone())
        .expect("an image holds height · width · 3 values")
        .into_pyarray(py)
}

/// A grid's values as a new `float32` array of shape `(nz, ny, nx)`.
pub(crate) fn grid_to_py<'py>(py: Python<'py>, grid: &GridData) -> Bound<'py, PyArray3<f32>> {
    let [nx, ny, nz] = grid.dims;
    Array3::from_shape_vec((nz, ny, nx), grid.values.clone())
        .expect("a grid holds nx · ny · nz values")
        .into_pyarray(py)
}

/// Gradient entries (`f64`) as a new `float32` array of `shape` `[nz, ny, nx]`, as `grad` writes them.
pub(crate) fn gradient_to_py<'py>(
    py: Python<'py>,
    shape: [usize; 3],
    values: &[f64],
) -> Bound<'py, PyArray3<f32>> {
    let values = values.iter().map(|&g| g as f32).collect();
    Array3::from_shape_vec(shape, values)
        .expect("a block holds nz · ny · nx entries")
        .into_pyarray(py)
}

/// Any array-like as `float32` values in C order with their shape. `what` names the argument in
/// errors.
fn values(what: &str, array: &Bound<'_, PyAny>) -> PyResult<(Vec<usize>, Vec<f32>)> {
    let array: PyArrayLikeDyn<'_, f32, AllowTypeChange> = array.extract().map_err(|e| {
        PyValueError::new_err(format!("{what}: expected an array of numbers ({e})"))
    })?;
    let view = array.as_array();
    Ok((view.shape().to_vec(), view.iter().copied().collect()))
}

/// The first non-finite value, as the error naming `what` and its index.
fn require_finite(what: &str, shape: &[usize], values: &[f32]) -> PyResult<()> {
    let Some(i) = values.iter().position(|v| !v.is_finite()) else {
        return Ok(());
    };
    let mut index = vec![0; shape.len()];
    let mut rest = i;
    for (k, n) in shape.iter().enumerate().rev() {
        index[k] = rest % n;
        rest /= n;
    }
    Err(PyValueError::new_err(format!(
        "{what}: must be finite, got {} at index {index:?}",
        values[i]
    )))
}

/// An image argument (`H × W × 3`, finite, of the scene's size `(width, height)`).
pub(crate) fn image_from_py(
    what: &str,
    array: &Bound<'_, PyAny>,
    (width, height): (u32, u32),
) -> PyResult<Image> {
    let (shape, rgb) = values(what, array)?;
    let (w, h) = (width as usize, height as usize);
    if shape != [h, w, 3] {
        return Err(PyValueError::new_err(format!(
            "{what}: expected shape ({h}, {w}, 3) (height, width, RGB: the scene's image), got {}",
            tuple(&shape)
        )));
    }
    require_finite(what, &shape, &rgb)?;
    Ok(Image { width, height, rgb })
}

/// A grid argument: its shape `[nz, ny, nx]` and values (finite). A grid's own rules (at least 4
/// samples per axis) are the library's.
pub(crate) fn grid_from_py(
    what: &str,
    array: &Bound<'_, PyAny>,
) -> PyResult<([usize; 3], Vec<f32>)> {
    let (shape, values) = values(what, array)?;
    let Ok(shape) = <[usize; 3]>::try_from(shape.as_slice()) else {
        return Err(PyValueError::new_err(format!(
            "{what}: expected a 3-d array of shape (nz, ny, nx), got shape {}",
            tuple(&shape)
        )));
    };
    require_finite(what, &shape, &values)?;
    Ok((shape, values))
}

/// A shape as Python prints it: `(2, 3)`, `(4,)`.
fn tuple(shape: &[usize]) -> String {
    match shape {
        [one] => format!("({one},)"),
        _ => {
            let parts: Vec<String> = shape.iter().map(|n| n.to_string()).collect();
            format!("({})", parts.join(", "))
        }
    }
}

/// Every channel of an EXR file (as the command-line tool writes them: ``R``, ``G``, ``B``,
/// ``d.P.R``, ...) as a dict ``name -> float32 array (height, width)``, in the file's order. Lets a
/// script use the tool's outputs and targets.
#[pyfunction]
pub(crate) fn read_exr<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let (width, height, channels) = py
        .detach(|| film::read_exr(&path))
        .map_err(super::scene_error)?;
    let out = PyDict::new(py);
    for (name, plane) in channels {
        let plane = Array2::from_shape_vec((height as usize, width as usize), plane)
            .map_err(|e| PyValueError::new_err(format!("{}: {e}", path.display())))?;
        let array: Bound<'py, PyArray2<f32>> = plane.into_pyarray(py);
        out.set_item(name, array)?;
    }
    Ok(out)
}
