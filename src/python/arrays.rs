//! numpy arrays in and out: images `H × W × 3` and grids `[nz, ny, nx]`, `float32`, in C order (the
//! library's layouts: `rgb[3 · (y · width + x) + c]`, `values[(z · ny + y) · nx + x]`).

use crate::film::{self, Image};
use crate::sdf::GridData;
use numpy::ndarray::{Array2, Array3, ArrayD, IxDyn};
use numpy::{AllowTypeChange, IntoPyArray, PyArray2, PyArray3, PyArrayDyn, PyArrayLikeDyn};
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

/// Gradient entries (`f64`) as a new `float32` array of the block's `shape` (`[nz, ny, nx]` for a grid,
/// `[nz, ny, nx, 3]` for a colour texture), as `grad` writes them.
pub(crate) fn gradient_to_py<'py>(
    py: Python<'py>,
    shape: &[usize],
    values: &[f64],
) -> Bound<'py, PyArrayDyn<f32>> {
    let values = values.iter().map(|&g| g as f32).collect();
    ArrayD::from_shape_vec(IxDyn(shape), values)
        .expect("a block holds as many entries as its shape")
        .into_pyarray(py)
}

/// Any array-like as `float32` values in C order with their shape. `what` names the argument in
/// errors. A numpy array must hold floats: an integer or boolean array is refused, as a `.npy` grid
/// file of that dtype is, rather than converted silently.
fn values(what: &str, array: &Bound<'_, PyAny>) -> PyResult<(Vec<usize>, Vec<f32>)> {
    if let Ok(dtype) = array.getattr("dtype")
        && let Ok(kind) = dtype.getattr("kind").and_then(|k| k.extract::<String>())
        && kind != "f"
    {
        return Err(PyValueError::new_err(format!(
            "{what}: expected an array of floats (float32 or float64), got dtype {}",
            dtype.str().map_or("?".into(), |s| s.to_string())
        )));
    }
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

/// Writes an EXR file of float32 channels, as the command-line tool writes them, from ``channels``:
/// a dict ``name -> array``, each array ``(height, width)`` (one channel) or ``(height, width, 3)``
/// (three: ``"image"`` gives ``R``, ``G``, ``B``, and any other name ``N`` gives ``N.R``, ``N.G``,
/// ``N.B``), all of one image size. So ``write_exr(path, diff(scene, "ball.radius"))`` writes the
/// channels of ``implicit-psdr diff``, and ``read_exr`` reads them back. A missing folder is
/// created. Raises ``ValueError`` for arrays of other shapes or sizes, ``SceneError`` for a path
/// that cannot be written.
#[pyfunction]
pub(crate) fn write_exr(
    py: Python<'_>,
    path: PathBuf,
    channels: &Bound<'_, PyDict>,
) -> PyResult<()> {
    let mut out: film::Channels = Vec::new();
    let mut size: Option<(usize, usize)> = None;
    for (name, array) in channels.iter() {
        let name: String = name.extract()?;
        let what = format!("channels['{name}']");
        let (shape, values) = values(&what, &array)?;
        let (h, w, planes) = match shape.as_slice() {
            [h, w] => (*h, *w, vec![(name.clone(), values)]),
            [h, w, 3] => {
                let prefix = if name == "image" {
                    String::new()
                } else {
                    format!("{name}.")
                };
                let planes = (0..3)
                    .map(|c| {
                        let plane = values.iter().skip(c).step_by(3).copied().collect();
                        (format!("{prefix}{}", ["R", "G", "B"][c]), plane)
                    })
                    .collect();
                (*h, *w, planes)
            }
            _ => {
                return Err(PyValueError::new_err(format!(
                    "{what}: expected shape (height, width) or (height, width, 3), got {}",
                    tuple(&shape)
                )));
            }
        };
        if *size.get_or_insert((h, w)) != (h, w) || h == 0 || w == 0 {
            return Err(PyValueError::new_err(format!(
                "{what}: every channel must be of one non-empty size, got {}",
                tuple(&shape)
            )));
        }
        out.extend(planes);
    }
    let Some((h, w)) = size else {
        return Err(PyValueError::new_err("channels: give at least one channel"));
    };
    py.detach(|| {
        crate::io::create_parent(&path)?;
        film::write_exr(&path, w as u32, h as u32, &out)
    })
    .map_err(super::scene_error)
}
