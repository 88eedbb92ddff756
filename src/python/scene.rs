//! The `Scene` class: a scene loaded from a file or a dict, its parameters and grids, and pickling
//! (so that Ray can ship it to other processes).

use super::arrays::{grid_from_py, grid_to_py};
use super::{scene_error, warn_lines};
use crate::scene::{self, ParameterEntry, Scene, patch};
use crate::sdf::{self, GridData};
use numpy::PyArray3;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::{Map, Number, Value};
use std::path::{Path, PathBuf};

/// A scene: what the command-line tool loads from a scene file (see docs/scene-format.md),
/// with its parameters and grids, changeable in place.
///
/// Build it with ``Scene.load(path)`` or ``Scene.from_dict(dict)``. ``params()`` lists every
/// differentiable parameter (``ball.radius``, ``light.center.x``, ...; angles in degrees) and each
/// grid node's values as one block (``blob.values``) with its shape. Scenes pickle (grids included),
/// so they can be sent to other processes.
#[pyclass(name = "Scene", module = "implicit_psdr")]
#[derive(Clone)]
pub(crate) struct PyScene {
    /// The scene as the library renders it.
    pub(crate) scene: Scene,
    /// The JSON document it was parsed from; pickling writes the current values and grids into it.
    doc: Value,
}

#[pymethods]
impl PyScene {
    /// Loads a scene file (JSON); relative grid ``file`` names resolve against its folder. Raises
    /// ``SceneError`` naming the file and the field. Warns (``RuntimeWarning``) about a shape outside
    /// the camera's view and a rectangle light that lights nothing the camera sees, as the tool does.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let loaded = py.detach(|| {
            let scene = scene::load(&path).map_err(|e| in_file(&path, e))?;
            // The file parsed as a scene, so it is JSON.
            let text = std::fs::read_to_string(&path).map_err(|e| crate::Error::file(&path, e))?;
            let doc = serde_json::from_str(&text).map_err(|e| crate::Error::file(&path, e))?;
            Ok::<_, crate::Error>(Self { scene, doc })
        });
        let loaded = loaded.map_err(scene_error)?;
        warn_lines(py, loaded.scene.reach_warnings())?;
        Ok(loaded)
    }

    /// A scene from a dict of the scene file's structure (as ``json.load`` returns it). Relative
    /// grid ``file`` names resolve against ``base_dir`` (default: the current folder). Raises
    /// ``SceneError`` naming the field (a NaN, say, or an unknown key).
    #[staticmethod]
    #[pyo3(signature = (scene, base_dir = None))]
    fn from_dict(scene: &Bound<'_, PyAny>, base_dir: Option<PathBuf>) -> PyResult<Self> {
        let doc = to_json(scene, "scene").map_err(scene_error)?;
        let base_dir = base_dir.unwrap_or_else(|| PathBuf::from("."));
        let parsed = Self::parse(doc, &base_dir).map_err(scene_error)?;
        warn_lines(scene.py(), parsed.scene.reach_warnings())?;
        Ok(parsed)
    }

    /// Every parameter, in the order of the ``params`` command: ``name -> value`` (a float), and
    /// each grid node's values as ``"NODE.values" -> (nz, ny, nx)`` after the node's ``level``.
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        for entry in self.scene.parameter_entries() {
            match entry {
                ParameterEntry::Value(name, value) => out.set_item(name, value)?,
                ParameterEntry::Grid(block) => {
                    out.set_item(block.name, PyTuple::new(py, block.shape)?)?
                }
            }
        }
        Ok(out)
    }

    /// Sets parameter ``name`` (as ``params()`` lists it) to ``value``; the value must be in the
    /// parameter's range, as in the scene file. Raises ``SceneError`` (unknown name, with near
    /// matches; a value out of range or not finite); the scene is unchanged then.
    fn set(&mut self, name: &str, value: f64) -> PyResult<()> {
        let value = value as f32;
        self.scene = (self.scene.with_parameter(name, value)).map_err(scene_error)?;
        Ok(())
    }

    /// Replaces the values of grid ``node`` (``NODE`` or ``NODE.values``) by ``values``, an array of
    /// shape ``(nz, ny, nx)`` (any size of at least 4 per axis; the grid keeps its box). Raises
    /// ``ValueError`` for an array that is not 3-d or not finite, ``SceneError`` for an unknown node.
    fn set_grid(&mut self, node: &str, values: &Bound<'_, PyAny>) -> PyResult<()> {
        let node = self.scene.grid_node(node);
        let what = format!("{node}.values");
        // An unknown node is reported before the array's faults.
        self.scene.grid_values(&node).map_err(scene_error)?;
        let ([nz, ny, nx], values) = grid_from_py(&what, values)?;
        let data = GridData::new([nx, ny, nz], values, &what).map_err(scene_error)?;
        self.scene.set_grid(&node, data).map_err(scene_error)
    }

    /// The values of grid ``node`` (``NODE`` or ``NODE.values``): a new float32 array of shape
    /// ``(nz, ny, nx)``.
    fn grid<'py>(&self, py: Python<'py>, node: &str) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let node = self.scene.grid_node(node);
        let data = self.scene.grid_values(&node).map_err(scene_error)?;
        Ok(grid_to_py(py, &data))
    }

    /// The scene as a dict of the scene file's structure (what ``json.load`` of its file gives), with
    /// every parameter's current value written where the file keeps it. Grid nodes keep their
    /// ``file``, which holds the values the scene was loaded with: ``save`` writes changed grids too.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let doc = patch::patched_scene_json(&self.doc, &self.scene, &[]).map_err(scene_error)?;
        let json = py.import("json")?;
        json.call_method1("loads", (doc.to_string(),))
    }

    /// Writes the scene to the scene file ``path`` (``.json``; a missing folder is created), with
    /// every parameter's current value and every grid's current values: grid node ``NODE`` goes to
    /// ``<stem>.NODE.npy`` beside it (``<stem>`` the file's name without ``.json``), and the file
    /// names it so. ``Scene.load(path)`` gives this scene back; ``implicit-psdr render path``
    /// renders it. Raises ``SceneError`` for a path that cannot be written (nothing is written then).
    fn save(&self, path: PathBuf) -> PyResult<()> {
        crate::io::check_output_path(&path, "path", "json").map_err(scene_error)?;
        let stem = (path.file_stem()).map_or("scene".into(), |s| s.to_string_lossy().into_owned());
        let blocks = self.scene.grid_blocks();
        let files: Vec<(String, String)> = (blocks.iter())
            .map(|b| (b.node.clone(), format!("{stem}.{}.npy", b.node)))
            .collect();
        let doc = patch::patched_scene_json(&self.doc, &self.scene, &files).map_err(scene_error)?;
        let folder = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let mut writes: Vec<(PathBuf, crate::io::Writer)> = Vec::new();
        for (block, (_, file)) in blocks.iter().zip(&files) {
            let data = self.scene.grid_values(&block.node).map_err(scene_error)?;
            writes.push((
                folder.join(file),
                Box::new(move |tmp| sdf::write_npy(tmp, &data).map_err(crate::io::file_message)),
            ));
        }
        writes.push((path, crate::io::bytes_writer(patch::scene_text(&doc))));
        crate::io::write_all_or_nothing(writes).map_err(scene_error)
    }

    /// An independent copy (changing one does not change the other).
    fn copy(&self) -> Self {
        self.clone()
    }

    fn __copy__(&self) -> Self {
        self.clone()
    }

    fn __deepcopy__(&self, _memo: &Bound<'_, PyAny>) -> Self {
        self.clone()
    }

    /// Image width in pixels.
    #[getter]
    fn width(&self) -> u32 {
        self.scene.camera.width
    }

    /// Image height in pixels.
    #[getter]
    fn height(&self) -> u32 {
        self.scene.camera.height
    }

    /// The scene's samples per pixel: the default ``spp`` of ``render``, ``diff`` and ``grad``.
    #[getter]
    fn spp(&self) -> u32 {
        self.scene.spp
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene({}x{}, {} spp, {} shapes, {} emitters)",
            self.scene.camera.width,
            self.scene.camera.height,
            self.scene.spp,
            self.scene.shapes.len(),
            self.scene.emitters.len()
        )
    }

    /// Pickling: the document with the current parameter values, and every grid's values.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let blocks = self.scene.grid_blocks();
        let files: Vec<(String, String)> = (blocks.iter().enumerate())
            .map(|(k, b)| (b.node.clone(), format!("grid{k}.npy")))
            .collect();
        let doc = patch::patched_scene_json(&self.doc, &self.scene, &files).map_err(scene_error)?;
        let grids = PyDict::new(py);
        for (block, (_, file)) in blocks.iter().zip(&files) {
            let data = self.scene.grid_values(&block.node).map_err(scene_error)?;
            grids.set_item(file, grid_to_py(py, &data))?;
        }
        let constructor = py
            .import("implicit_psdr._native")?
            .getattr("_scene_from_state")?;
        let args = (doc.to_string(), grids);
        PyTuple::new(py, [constructor, args.into_pyobject(py)?.into_any()])
    }
}

impl PyScene {
    /// Parses a scene document exactly as a scene file's text.
    fn parse(doc: Value, base_dir: &Path) -> crate::Result<Self> {
        let scene = scene::parse(&doc.to_string(), base_dir)?;
        Ok(Self { scene, doc })
    }
}

/// Rebuilds a pickled scene: the document with its grids (`file name -> values`), written to a
/// temporary folder for the parser and removed again.
#[pyfunction]
#[pyo3(name = "_scene_from_state")]
pub(crate) fn scene_from_state(doc: &str, grids: &Bound<'_, PyDict>) -> PyResult<PyScene> {
    let doc: Value = serde_json::from_str(doc)
        .map_err(|e| PyValueError::new_err(format!("a pickled scene: {e}")))?;
    let dir = temporary_folder().map_err(scene_error)?;
    let result = (|| {
        for (file, values) in grids.iter() {
            let file: String = file.extract()?;
            let ([nz, ny, nx], values) = grid_from_py(&file, &values)?;
            let data = GridData::new([nx, ny, nz], values, &file).map_err(scene_error)?;
            sdf::write_npy(&dir.join(&file), &data).map_err(scene_error)?;
        }
        PyScene::parse(doc, &dir).map_err(scene_error)
    })();
    let _ = std::fs::remove_dir_all(&dir);
    result
}

/// A new, empty folder in the system's temporary folder.
fn temporary_folder() -> crate::Result<PathBuf> {
    static COUNTER: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let base = std::env::temp_dir();
    loop {
        let unique = COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir = base.join(format!(".implicit-psdr.{}.{unique}", std::process::id()));
        match std::fs::create_dir(&dir) {
            Ok(()) => return Ok(dir),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(crate::Error::file(&dir, e)),
        }
    }
}

/// Puts the scene file in front of a field error, as the command-line tool does (file errors name
/// their file already).
fn in_file(path: &Path, e: crate::Error) -> crate::Error {
    match e {
        crate::Error::Field { .. } => crate::Error::file(path, e),
        e => e,
    }
}

/// A Python dict of a JSON file's structure (a scene, an `OPT.json`) as JSON, or an error naming its
/// field (`shapes[0].sdf.radius`; the dict itself is `root`): dicts with string keys, lists and
/// tuples, strings, booleans, integers, finite floats and `None`.
pub(crate) fn to_json(value: &Bound<'_, PyAny>, root: &str) -> crate::Result<Value> {
    json_at(value, "", root)
}

/// [`to_json`] of the value at field `path` (`""`: the root, named `root`).
fn json_at(value: &Bound<'_, PyAny>, path: &str, root: &str) -> crate::Result<Value> {
    let field = || if path.is_empty() { root } else { path };
    let wrong = |what: String| crate::Error::field(field(), what);
    // bool is a subclass of int in Python: test it first.
    if value.is_instance_of::<PyBool>() {
        return Ok(Value::Bool(value.extract().expect("a bool")));
    }
    if value.is_instance_of::<PyInt>() {
        if let Ok(i) = value.extract::<i64>() {
            return Ok(Value::from(i));
        }
        return Err(wrong(format!("the integer {value} is too large")));
    }
    if value.is_instance_of::<PyFloat>() {
        let x: f64 = value.extract().expect("a float");
        return (Number::from_f64(x).map(Value::Number))
            .ok_or_else(|| wrong(format!("must be a finite number, got {x}")));
    }
    if let Ok(s) = value.cast::<PyString>() {
        return Ok(Value::String(s.to_string()));
    }
    if value.is_none() {
        return Ok(Value::Null);
    }
    if let Ok(dict) = value.cast::<PyDict>() {
        let mut map = Map::new();
        for (k, v) in dict.iter() {
            let Ok(key) = k.cast::<PyString>() else {
                return Err(wrong(format!("keys must be strings, got {k}")));
            };
            let key = key.to_string();
            let inner = if path.is_empty() {
                key.clone()
            } else {
                format!("{path}.{key}")
            };
            map.insert(key, json_at(&v, &inner, root)?);
        }
        return Ok(Value::Object(map));
    }
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        let items: Vec<Bound<'_, PyAny>> = value
            .try_iter()
            .and_then(|i| i.collect())
            .map_err(|e| wrong(e.to_string()))?;
        let items = (items.iter().enumerate())
            .map(|(i, v)| json_at(v, &format!("{}[{i}]", field()), root))
            .collect::<crate::Result<_>>()?;
        return Ok(Value::Array(items));
    }
    // numpy arrays (a vector given as `np.array([0, 1, 0])`): their lists.
    if value.hasattr("tolist").unwrap_or(false)
        && value.hasattr("shape").unwrap_or(false)
        && let Ok(list) = value.call_method0("tolist")
        && !list.is(value)
    {
        return json_at(&list, path, root);
    }
    // numpy scalars and other numbers: their float value.
    if let Ok(x) = value.extract::<f64>() {
        return (Number::from_f64(x).map(Value::Number))
            .ok_or_else(|| wrong(format!("must be a finite number, got {x}")));
    }
    let kind = value
        .get_type()
        .name()
        .map_or("?".into(), |n| n.to_string());
    Err(wrong(format!(
        "cannot be converted to JSON (a {kind}; expected a dict, list, str, number, bool or None)"
    )))
}
