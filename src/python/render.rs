//! `render` and `diff`: the image, and derivative images in forward mode, as the `render` and `diff`
//! commands compute them.

use super::args;
use super::arrays::image_to_py;
use super::scene::PyScene;
use super::{run_detached, scene_error, warn};
use crate::film::Normalization;
use crate::integrator::{self, BoundaryBudget, DiffOptions, RenderOptions, VelocityField};
use crate::scene::{GridDirection, Scene};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::Arc;

/// The render options of a call: `spp` (default the scene's, as the command-line tool) and `seed`.
pub(crate) fn render_options(
    scene: &Scene,
    spp: Option<i64>,
    seed: i128,
) -> PyResult<RenderOptions> {
    Ok(RenderOptions {
        spp: args::count("spp", spp, 1)?.unwrap_or(scene.spp),
        seed: args::seed(seed)?,
        ..RenderOptions::default()
    })
}

/// The derivative options of `diff` and `grad`: those of [`render_options`], the boundary budgets
/// `(primary, secondary)` (`None`: the default), the pixel normalisation and the velocity field
/// (`"auto"`, `"normal"` or `"carried"`), as the tool's.
pub(crate) fn diff_options(
    scene: &Scene,
    (spp, seed): (Option<i64>, i128),
    (primary_spp, secondary_spp): (Option<f64>, Option<f64>),
    (normalization, velocity_field): (&str, &str),
) -> PyResult<DiffOptions> {
    let normalization: Normalization = normalization
        .parse()
        .map_err(|e: String| PyValueError::new_err(format!("normalization: {e}")))?;
    let velocity: VelocityField = velocity_field
        .parse()
        .map_err(|e: String| PyValueError::new_err(format!("velocity_field: {e}")))?;
    Ok(DiffOptions {
        render: render_options(scene, spp, seed)?,
        normalization,
        boundary: BoundaryBudget {
            primary_spp: args::rate("spp_primary", primary_spp)?,
            secondary_spp: args::rate("spp_secondary", secondary_spp)?,
        },
        velocity,
    })
}

/// Renders the scene: a float32 array ``(height, width, 3)`` of linear RGB radiance (row 0 the top
/// row), the image ``implicit-psdr render`` writes for the same ``spp`` (default: the scene's) and
/// ``seed`` (default 0). ``threads`` caps the threads of this call (default: all cores); the image
/// does not depend on it.
#[pyfunction]
#[pyo3(signature = (scene, *, spp = None, seed = 0, threads = None))]
pub(crate) fn render<'py>(
    py: Python<'py>,
    scene: &PyScene,
    spp: Option<i64>,
    seed: i128,
    threads: Option<i64>,
) -> PyResult<Bound<'py, PyAny>> {
    let scene = scene.scene.clone();
    let options = render_options(&scene, spp, seed)?;
    let threads = args::threads(threads)?;
    let (image, stats) = run_detached(py, threads, move || integrator::render(&scene, &options))?;
    warn(py, &stats)?;
    Ok(image_to_py(py, &image).into_any())
}

/// Derivative images in forward mode, as ``implicit-psdr diff`` computes them (same samples as
/// ``render`` with the same ``spp`` and ``seed``, its image the same in expectation under a constant
/// sky; the interior, primary and secondary terms).
///
/// ``params``: parameter names (see ``Scene.params()``); ``grid_directions``: ``{node: U}``, the
/// derivative along a perturbation ``U`` (shape ``(nz, ny, nx)``) of a grid's values. Returns a dict
/// of float32 arrays ``(height, width, 3)`` named as the EXR channels of ``diff`` without their
/// ``.R/.G/.B``: ``"image"``, ``"d.P"`` per parameter, ``"d.NODE.values"`` per direction, and with
/// ``terms=True`` ``"d_interior.P"``, ``"d_primary.P"``, ``"d_secondary.P"`` (they sum to ``d.P``;
/// a term with budget 0 is absent). ``spp_primary`` / ``spp_secondary`` are the boundary budgets
/// in samples per pixel, which may be fractional (default ``ceil(spp/32)``, ``ceil(spp/8)``), ``normalization`` ``"differentiable"`` or
/// ``"fixed"``, ``velocity_field`` ``"auto"``, ``"normal"`` or ``"carried"`` (as ``--velocity-field``).
#[pyfunction]
#[pyo3(signature = (scene, params = None, *, spp = None, seed = 0, terms = false,
                    grid_directions = None, spp_primary = None, spp_secondary = None,
                    normalization = "differentiable", velocity_field = "auto", threads = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn diff<'py>(
    py: Python<'py>,
    scene: &PyScene,
    params: Option<&Bound<'py, PyAny>>,
    spp: Option<i64>,
    seed: i128,
    terms: bool,
    grid_directions: Option<&Bound<'py, PyDict>>,
    spp_primary: Option<f64>,
    spp_secondary: Option<f64>,
    normalization: &str,
    velocity_field: &str,
    threads: Option<i64>,
) -> PyResult<Bound<'py, PyDict>> {
    let params = args::names("params", params)?;
    let threads = args::threads(threads)?;
    let scene = scene.scene.clone();
    let options = diff_options(
        &scene,
        (spp, seed),
        (spp_primary, spp_secondary),
        (normalization, velocity_field),
    )?;
    let mut directions = Vec::new();
    for (node, u) in grid_directions.into_iter().flat_map(|d| d.iter()) {
        let node: String = node.extract()?;
        let source = format!("grid_directions[{node:?}]");
        let (shape, values) = super::arrays::grid_from_py(&source, &u)?;
        directions.push(GridDirection {
            node,
            shape: shape.to_vec(),
            values: Arc::new(values),
            source,
        });
    }
    if params.is_empty() && directions.is_empty() {
        return Err(PyValueError::new_err(
            "diff: nothing to differentiate (give params or grid_directions)",
        ));
    }
    let selection = scene
        .select_with_grid_directions(&params, &directions)
        .map_err(scene_error)?;
    let names = selection.names().to_vec();
    let result = run_detached(py, threads, move || {
        integrator::render_derivatives(&scene, &selection, &options)
    })?
    .map_err(scene_error)?;
    warn(py, &result.stats)?;
    let out = PyDict::new(py);
    // The EXR's channels come in R, G, B triples: `R, G, B`, then `d.P.R, d.P.G, d.P.B`, ...
    let channels = result.channels(&names, terms);
    let image = &result.image;
    for triple in channels.chunks(3) {
        let name = triple[0].0.strip_suffix('R').unwrap_or(&triple[0].0);
        let name = name.strip_suffix('.').unwrap_or("image");
        let mut rgb = crate::film::Image::new(image.width, image.height);
        for (c, (_, plane)) in triple.iter().enumerate() {
            for (i, v) in plane.iter().enumerate() {
                rgb.rgb[3 * i + c] = *v;
            }
        }
        out.set_item(name, image_to_py(py, &rgb))?;
    }
    Ok(out)
}
