//! Meshes for Python: a shape's surface as numpy arrays, the mesh the `mesh` command writes.

use super::scene::PyScene;
use super::scene_error;
use numpy::ndarray::Array2;
use numpy::{AllowTypeChange, IntoPyArray, PyArray2, PyArray3, PyArrayLikeDyn};
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

/// The signed distance of the triangle mesh ``(vertices, faces)`` (float ``(n, 3)``, int ``(m, 3)``)
/// sampled on a ``res`` × ``res`` × ``res`` lattice, as ``implicit-psdr bake --mesh`` computes it
/// (exact distance to the triangles, negative where the generalised winding number is at least
/// 1/2): first and last samples on the faces of ``bbox`` (``(min, max)``, each three numbers), by
/// default the mesh's bounds padded by 10% of their longest edge and grown to a cube around their
/// centre. Returns ``(values, bbox_min, bbox_max)``: float32 ``(res, res, res)`` indexed
/// ``[z, y, x]`` as ``bake``'s grids, and the box as two float32 arrays. Raises ``ValueError`` for
/// a bad mesh (no faces, a coordinate that is not finite, an index out of range) or box.
#[pyfunction]
#[pyo3(signature = (vertices, faces, res = 64, bbox = None))]
pub(crate) fn mesh_to_grid<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
    res: usize,
    bbox: Option<([f32; 3], [f32; 3])>,
) -> PyResult<GridArrays<'py>> {
    if !(2..=1024).contains(&res) {
        return Err(PyValueError::new_err(format!(
            "res must be in 2..=1024, got {res}"
        )));
    }
    let v: PyArrayLikeDyn<'_, f32, AllowTypeChange> = vertices.extract().map_err(|e| {
        PyValueError::new_err(format!(
            "vertices: expected an (n, 3) array of numbers ({e})"
        ))
    })?;
    let f: PyArrayLikeDyn<'_, i64, AllowTypeChange> = faces.extract().map_err(|e| {
        PyValueError::new_err(format!("faces: expected an (m, 3) array of integers ({e})"))
    })?;
    let (v, f) = (v.as_array(), f.as_array());
    if v.ndim() != 2 || v.shape()[1] != 3 {
        return Err(PyValueError::new_err(format!(
            "vertices: expected shape (n, 3), got {:?}",
            v.shape()
        )));
    }
    if f.ndim() != 2 || f.shape()[1] != 3 {
        return Err(PyValueError::new_err(format!(
            "faces: expected shape (m, 3), got {:?}",
            f.shape()
        )));
    }
    let points: Vec<f32> = v.iter().copied().collect();
    let indices: Vec<i64> = f.iter().copied().collect();
    let vertices: Vec<glam::Vec3> = points.chunks_exact(3).map(glam::Vec3::from_slice).collect();
    let polygons: Vec<Vec<i64>> = indices.chunks_exact(3).map(|c| c.to_vec()).collect();
    let mesh =
        crate::io::mesh_read::from_polygons(std::path::Path::new("mesh"), vertices, &polygons)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let grid = py
        .detach(move || -> crate::Result<_> {
            let sdf = crate::mesh::MeshSdf::new(&mesh)?;
            let (lo, hi) = match bbox {
                Some((lo, hi)) => (glam::Vec3::from(lo), glam::Vec3::from(hi)),
                None => {
                    let b = crate::mesh::signed_distance::padded_box(
                        sdf.bounds,
                        crate::sdf::BAKE_PADDING,
                    )?;
                    let half = glam::Vec3::splat(b.extent().max_element() / 2.0);
                    (b.center() - half, b.center() + half)
                }
            };
            if !(lo.is_finite() && hi.is_finite() && lo.cmplt(hi).all()) {
                return Err(crate::Error::field(
                    "bbox",
                    format!("expected min < max on every axis, got {lo} and {hi}"),
                ));
            }
            Ok((sdf.sample_dims(lo, hi, [res; 3]), lo, hi))
        })
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let (grid, lo, hi) = grid;
    let values = super::arrays::grid_to_py(py, &grid);
    let corner =
        |p: glam::Vec3| numpy::ndarray::Array1::from(p.to_array().to_vec()).into_pyarray(py);
    Ok((values, corner(lo), corner(hi)))
}

/// Values `(res, res, res)` and the box's corners.
type GridArrays<'py> = (
    Bound<'py, PyArray3<f32>>,
    Bound<'py, numpy::PyArray1<f32>>,
    Bound<'py, numpy::PyArray1<f32>>,
);
