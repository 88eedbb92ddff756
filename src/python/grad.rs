//! `grad`: a loss and its gradient in reverse mode, as the `grad` command computes them, or the
//! gradient of any pixel adjoint (a loss of the caller's own).

use super::args;
use super::arrays::{gradient_to_py, image_from_py};
use super::render::diff_options;
use super::scene::PyScene;
use super::{run_detached, scene_error, warn};
use crate::film::Image;
use crate::integrator::{self, GradientLayout, Loss};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// What the gradient is of: a loss against a target image, or a pixel adjoint.
enum Against {
    Target(Image),
    Adjoint(Image),
}

/// The gradient of a loss of the image with respect to parameters and grid values (reverse mode,
/// the complete derivative: interior, primary and secondary terms).
///
/// Either ``target`` (an image ``(height, width, 3)``): the ``loss`` (``"l2"``, the mean of
/// ``(I - T)^2`` over pixels and channels, or ``"l1"``) of the image of ``seed`` against it, and its
/// gradient estimated with the samples of ``seed + 1``, exactly as ``implicit-psdr grad``. Or
/// ``adjoint`` (an image ``dL/dI`` of your own loss): the gradient ``sum(adjoint * dI/dP)`` with the
/// samples of ``seed`` (those of ``diff`` with the same ``seed``), and the loss is ``None``.
///
/// ``params``: parameter names; ``grids``: grid nodes (``NODE`` or ``NODE.values``) whose every
/// value gets a gradient. Returns ``(loss, {name: float, node: float32 array (nz, ny, nx)})``.
/// ``spp`` (default: the scene's), ``seed`` (default 0), the boundary budgets and
/// ``normalization`` and ``velocity_field`` are those of ``diff``; ``threads`` caps this call's threads.
#[pyfunction]
#[pyo3(signature = (scene, target = None, loss = "l2", adjoint = None, params = None,
                    grids = None, *, spp = None, seed = 0, spp_primary = None,
                    spp_secondary = None, normalization = "differentiable", velocity_field = "auto",
                    threads = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn grad<'py>(
    py: Python<'py>,
    scene: &PyScene,
    target: Option<&Bound<'py, PyAny>>,
    loss: &str,
    adjoint: Option<&Bound<'py, PyAny>>,
    params: Option<&Bound<'py, PyAny>>,
    grids: Option<&Bound<'py, PyAny>>,
    spp: Option<i64>,
    seed: i128,
    spp_primary: Option<f64>,
    spp_secondary: Option<f64>,
    normalization: &str,
    velocity_field: &str,
    threads: Option<i64>,
) -> PyResult<(Option<f64>, Bound<'py, PyDict>)> {
    let (params, grids) = (args::names("params", params)?, args::names("grids", grids)?);
    let threads = args::threads(threads)?;
    let scene = scene.scene.clone();
    let size = (scene.camera.width, scene.camera.height);
    let loss: Loss = loss
        .parse()
        .map_err(|e: String| PyValueError::new_err(format!("loss: {e}")))?;
    let against = match (target, adjoint) {
        (Some(t), None) => Against::Target(image_from_py("target", t, size)?),
        (None, Some(a)) => Against::Adjoint(image_from_py("adjoint", a, size)?),
        _ => {
            return Err(PyValueError::new_err(
                "grad: give exactly one of target (a loss against it) and adjoint (dL/dI)",
            ));
        }
    };
    if params.is_empty() && grids.is_empty() {
        return Err(PyValueError::new_err(
            "grad: nothing to differentiate (give params or grids)",
        ));
    }
    let options = diff_options(
        &scene,
        (spp, seed),
        (spp_primary, spp_secondary),
        (normalization, velocity_field),
    )?;
    let grids: Vec<String> = grids.iter().map(|g| scene.grid_node(g)).collect();
    let layout = GradientLayout::select(&scene, &params, &grids).map_err(scene_error)?;
    let chosen = layout.clone();
    let (loss, gradient) = run_detached(py, threads, move || match against {
        Against::Target(target) => {
            integrator::loss_gradient(&scene, &chosen, &target, loss, &options)
                .map(|g| (Some(g.loss), g.gradient))
        }
        Against::Adjoint(adjoint) => {
            integrator::render_gradient(&scene, &chosen, &adjoint, &options).map(|g| (None, g))
        }
    })?
    .map_err(scene_error)?;
    warn(py, &gradient.stats)?;
    let total = gradient.total();
    let out = PyDict::new(py);
    for (name, g) in layout.params.iter().zip(&total) {
        out.set_item(name, *g)?;
    }
    for (block, first) in &layout.grids {
        let values = &total[*first..first + block.len()];
        out.set_item(&block.node, gradient_to_py(py, &block.shape, values))?;
    }
    Ok((loss, out))
}
