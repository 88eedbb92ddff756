//! Meshes for Python: a shape's surface as numpy arrays, the mesh the `mesh` command writes.

use super::scene::PyScene;
use super::scene_error;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// Vertices `(n, 3)` and faces `(m, 3)` as numpy arrays.
type MeshArrays<'py> = (Bound<'py, PyArray2<f32>>, Bound<'py, PyArray2<i32>>);

/// The surface of shape ``shape`` (a grid's at its level) as a closed triangle mesh in scene
/// coordinates, extracted by dual contouring on a lattice of ``res`` points (4 to 1024) along the
/// longest side of its bounds, as the ``mesh`` command does: ``(vertices, faces)``, float32
/// ``(n, 3)`` and int32 ``(m, 3)`` (counter-clockwise seen from outside).
#[pyfunction]
#[pyo3(signature = (scene, shape, res = crate::mesh::DEFAULT_RESOLUTION))]
pub(crate) fn extract_mesh<'py>(
    py: Python<'py>,
    scene: &PyScene,
    shape: &str,
    res: usize,
) -> PyResult<MeshArrays<'py>> {
    if !(4..=1024).contains(&res) {
        return Err(PyValueError::new_err(format!(
            "res must be in 4..=1024, got {res}"
        )));
    }
    let shape = scene.scene.shape_named(shape).map_err(scene_error)?;
    let mesh = py
        .detach(|| crate::mesh::extract_shape(shape, res))
        .map_err(scene_error)?;
    let vertices: Vec<f32> = mesh.vertices.iter().flat_map(|v| v.to_array()).collect();
    let faces: Vec<i32> = (mesh.faces.iter())
        .flat_map(|f| f.map(|i| i as i32))
        .collect();
    let vertices = Array2::from_shape_vec((mesh.vertices.len(), 3), vertices)
        .expect("three coordinates per vertex");
    let faces =
        Array2::from_shape_vec((mesh.faces.len(), 3), faces).expect("three indices per face");
    Ok((vertices.into_pyarray(py), faces.into_pyarray(py)))
}
