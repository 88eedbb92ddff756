//! `optimize`: a whole inverse-rendering run as an `OPT.json` describes it, as the `optimize`
//! command runs it.

use super::scene::to_json;
use super::{run_detached, scene_error};
use crate::optimize::config::OptimizeConfig;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::{Path, PathBuf};

/// What a dict config is called in errors (a file config is named by its path).
const CONFIG_NAME: &str = "config";

/// Runs the optimisation that ``config`` describes and returns its progress: one dict per
/// iteration with the columns of the ``optimize`` command's ``progress.csv`` (``iteration``, an
/// int; ``loss``, ``seconds``, ``gradient_norm``, ``iou`` and ``chamfer`` when the target scene
/// holds an optimised grid's shape, ``mesh_chamfer``, ``mesh_normal_consistency`` and ``mesh_iou``
/// with ``reference_mesh``, and the ``*_seconds`` of each stage; floats).
///
/// ``config``: the path of an ``OPT.json``, or a dict of its structure (as ``json.load`` returns
/// it), whose file names (``scene``, ``target``) resolve against ``base_dir`` (default: the current
/// folder). With ``out`` (a folder, created if missing) the run writes the command's files there:
/// ``progress.csv``, ``loss.png``, ``views.png``, ``result.json`` (the optimised scene, for
/// ``Scene.load``), each optimised grid's ``NODE.npy`` and ``NODE.ply``, ``snapshots/`` and the cache of rendered
/// targets; without it nothing is written. The numbers are those of the command for the same
/// config, bit for bit (apart from the times). ``threads`` caps this call's threads. Raises
/// ``SceneError`` naming the file (or ``config``) and the field.
#[pyfunction]
#[pyo3(signature = (config, out = None, *, base_dir = None, threads = None))]
pub(crate) fn optimize<'py>(
    py: Python<'py>,
    config: &Bound<'py, PyAny>,
    out: Option<PathBuf>,
    base_dir: Option<PathBuf>,
    threads: Option<i64>,
) -> PyResult<Bound<'py, PyList>> {
    let threads = super::args::threads(threads)?;
    // A dict is read here, with the GIL; a file (and the scenes either names) in the run.
    let doc = match config.cast::<PyDict>() {
        Ok(dict) => Ok(to_json(dict.as_any(), CONFIG_NAME).map_err(|e| scene_error(in_config(e)))?),
        Err(_) => Err(config.extract::<PathBuf>()?),
    };
    let base_dir = base_dir.unwrap_or_else(|| PathBuf::from("."));
    let (cfg, warnings) = run_detached(py, threads, move || {
        let cfg = match &doc {
            Ok(doc) => OptimizeConfig::from_value(doc, &base_dir, Path::new(CONFIG_NAME))?,
            Err(path) => OptimizeConfig::load(path)?,
        };
        let warnings = cfg.reach_warnings();
        Ok((cfg, warnings))
    })?
    .map_err(scene_error)?;
    super::warn_lines(py, warnings)?;
    let outcome = run_detached(py, threads, move || {
        crate::optimize::run(&cfg, out.as_deref(), &mut ())
    })?
    .map_err(scene_error)?;
    let rows = PyList::empty(py);
    for row in &outcome.rows {
        let dict = PyDict::new(py);
        let values = row.values();
        for (k, (column, value)) in outcome.columns.iter().zip(values).enumerate() {
            if k == 0 {
                dict.set_item(column, row.iteration)?;
            } else {
                dict.set_item(column, value)?;
            }
        }
        rows.append(dict)?;
    }
    Ok(rows)
}

/// A field error of a dict config named as the config's own errors are (`config: iterations: ...`).
fn in_config(e: crate::Error) -> crate::Error {
    match e {
        crate::Error::Field { .. } => crate::Error::file(CONFIG_NAME, e),
        e => e,
    }
}
