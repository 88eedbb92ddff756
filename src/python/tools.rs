//! `fd` and `bake`: central finite differences and a shape baked into a grid, as the `fd` and
//! `bake` commands compute them.

use super::args;
use super::arrays::{grid_to_py, image_to_py};
use super::render::render_options;
use super::scene::PyScene;
use super::{SceneError, run_detached, scene_error, warn};
use crate::integrator::fd::render_with_differences;
use crate::sdf;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

/// Central finite differences ``(I(P + h) - I(P - h)) / 2h`` of the image with respect to each of
/// ``params`` (a name or a list), as ``implicit-psdr fd`` computes them: both renders of a pair with
/// the image's samples (``spp``, default the scene's, and ``seed``), step ``h`` (default
/// ``0.01 * max(|P|, 1)`` per parameter). Returns a dict named as ``diff``'s: ``"image"`` and
/// ``"d.P"`` per parameter, float32 arrays ``(height, width, 3)``. Raises ``SceneError`` for an
/// unknown name or a step that takes a parameter out of its range, before rendering anything.
#[pyfunction]
#[pyo3(signature = (scene, params, *, h = None, spp = None, seed = 0, threads = None))]
pub(crate) fn fd<'py>(
    py: Python<'py>,
    scene: &PyScene,
    params: &Bound<'py, PyAny>,
    h: Option<f64>,
    spp: Option<i64>,
    seed: i128,
    threads: Option<i64>,
) -> PyResult<Bound<'py, PyDict>> {
    let params = args::names("params", Some(params))?;
    if params.is_empty() {
        return Err(PyValueError::new_err("params: give at least one parameter"));
    }
    let h = match h {
        Some(h) if !(h.is_finite() && h > 0.0) => {
            return Err(PyValueError::new_err(format!(
                "h: must be a finite number > 0, got {h}"
            )));
        }
        h => h.map(|h| h as f32),
    };
    let threads = args::threads(threads)?;
    let scene = scene.scene.clone();
    let options = render_options(&scene, spp, seed)?;
    let result = run_detached(py, threads, move || {
        render_with_differences(&scene, &params, h, &options)
    })?
    .map_err(scene_error)?;
    warn(py, &result.stats)?;
    let out = PyDict::new(py);
    out.set_item("image", image_to_py(py, &result.image))?;
    for d in &result.differences {
        out.set_item(format!("d.{}", d.name), image_to_py(py, &d.derivative))?;
    }
    Ok(out)
}

/// Shape ``shape``'s SDF sampled over its bounds (padded by 10% of their largest extent) with
/// ``res`` samples (4 to 512) along the longest edge, as ``implicit-psdr bake`` does. Returns
/// ``(values, node)``: a float32 array ``(nz, ny, nx)`` and the scene's ``grid`` node as a dict
/// (``type``, ``bbox_min``, ``bbox_max``; add its ``file`` once the values are saved, e.g. with
/// ``numpy.save``) in the shape's own coordinates, before its ``translate``.
#[pyfunction]
#[pyo3(signature = (scene, shape, res))]
pub(crate) fn bake<'py>(
    py: Python<'py>,
    scene: &PyScene,
    shape: &str,
    res: i64,
) -> PyResult<Bound<'py, PyTuple>> {
    let res = match args::count("res", Some(res), 4)? {
        Some(n) if n <= 512 => n as usize,
        _ => {
            return Err(PyValueError::new_err(format!(
                "res: must be <= 512, got {res}"
            )));
        }
    };
    let found = scene
        .scene
        .shape_named(shape)
        .map_err(|e| SceneError::new_err(format!("shape: {e}")))?;
    let sdf = found.sdf.clone();
    let what = format!("shape {shape:?}");
    let baked = run_detached(py, None, move || sdf::bake_padded(&sdf, res, &what))?
        .map_err(|e| SceneError::new_err(format!("shape: {e}")))?;
    let node = PyDict::new(py);
    node.set_item("type", "grid")?;
    node.set_item("bbox_min", decimal(baked.bbox_min))?;
    node.set_item("bbox_max", decimal(baked.bbox_max))?;
    PyTuple::new(
        py,
        [grid_to_py(py, &baked.grid).into_any(), node.into_any()],
    )
}

/// A point's coordinates as the shortest decimals that read back as the same `f32` (what the `bake`
/// command prints), not the `f32`'s exact binary value widened to a float.
fn decimal(p: glam::Vec3) -> Vec<f64> {
    (p.to_array().iter())
        .map(|x| {
            x.to_string()
                .parse()
                .expect("a finite f32 prints as a number")
        })
        .collect()
}
