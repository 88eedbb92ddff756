//! Triangle meshes from files, by extension: Wavefront OBJ (`tobj`), PLY in ASCII or binary (`ply-rs-bw`;
//! a `vertex` element with `x y z` and a `face` element with a `vertex_indices` or `vertex_index`
//! list), STL in ASCII or binary (`stl_io`, which also merges the repeated corners of its triangles)
//! and OFF (read here: `OFF`, `COFF`, `NOFF` or `CNOFF` headers, `#` comments, extra per-vertex and
//! per-face fields ignored). Polygons with more than three corners are split into fans of triangles.
//!
//! Everything is checked: a file that cannot be read or parsed, that holds no triangle, a coordinate
//! that is not finite or an index past the vertex list is an [`Error::File`] naming the file and what is
//! wrong, in one line.

use crate::error::{Error, Result};
use crate::mesh::TriangleMesh;
use glam::Vec3;
use std::path::Path;

/// The mesh formats [`read_mesh`] reads, by extension.
pub const MESH_READ_EXTENSIONS: [&str; 4] = ["obj", "ply", "stl", "off"];

/// Reads the triangle mesh in `path` (`.obj`, `.ply`, `.stl` or `.off`, any case): its vertices, its
/// triangles (polygons split into fans) and per-vertex normals from the triangles (area-weighted, zero
/// at a vertex no triangle uses). Errors: an unknown extension, a file that cannot be read or parsed,
/// no triangle, a coordinate that is not finite, an index out of range (each one line naming the file).
pub fn read_mesh(path: &Path) -> Result<TriangleMesh> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let (vertices, polygons) = match ext.as_deref() {
        Some("obj") => read_obj(path)?,
        Some("ply") => read_ply(path)?,
        Some("stl") => read_stl(path)?,
        Some("off") => read_off(path)?,
        _ => {
            return Err(Error::file(
                path,
                format!(
                    "unknown mesh format (the extension must be one of .{})",
                    MESH_READ_EXTENSIONS.join(", .")
                ),
            ));
        }
    };
    from_polygons(path, vertices, &polygons)
}

/// A mesh from raw vertices and polygons (vertex indices), checked: finite coordinates, indices in
/// range, at least one triangle. `what` names the source in errors.
pub fn from_polygons(
    what: &Path,
    vertices: Vec<Vec3>,
    polygons: &[Vec<i64>],
) -> Result<TriangleMesh> {
    if let Some(k) = vertices.iter().position(|v| !v.is_finite()) {
        return Err(Error::file(
            what,
            format!(
                "vertex {k} has a coordinate that is not finite: {:?}",
                vertices[k].to_array()
            ),
        ));
    }
    let n = vertices.len() as i64;
    let mut faces = Vec::with_capacity(polygons.len());
    for (f, poly) in polygons.iter().enumerate() {
        if let Some(&i) = poly.iter().find(|&&i| i < 0 || i >= n) {
            return Err(Error::file(
                what,
                format!("face {f} uses vertex {i}, out of range (the file has {n} vertices)"),
            ));
        }
        for k in 2..poly.len() {
            faces.push([poly[0] as u32, poly[k - 1] as u32, poly[k] as u32]);
        }
    }
    if faces.is_empty() {
        return Err(Error::file(what, "the mesh has no faces (no triangle)"));
    }
    let mut mesh = TriangleMesh {
        normals: Vec::new(),
        vertices,
        faces,
    };
    mesh.normals = mesh.vertex_normals();
    Ok(mesh)
}

type Raw = (Vec<Vec3>, Vec<Vec<i64>>);

/// A parser's message on one line: its first line, blanks collapsed.
fn one_line(e: &dyn std::fmt::Display) -> String {
    let text = e.to_string();
    let first = text.lines().next().unwrap_or("");
    first.split_whitespace().collect::<Vec<_>>().join(" ")
}

fn read_obj(path: &Path) -> Result<Raw> {
    let file = std::fs::File::open(path).map_err(|e| Error::file(path, e))?;
    let options = tobj::LoadOptions {
        triangulate: false,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    // Materials are not needed: no `.mtl` file is opened.
    let (models, _) = tobj::load_obj_buf(&mut std::io::BufReader::new(file), &options, |_| {
        Err(tobj::LoadError::GenericFailure)
    })
    .map_err(|e| Error::file(path, format!("not a readable OBJ file: {}", one_line(&e))))?;
    let (mut vertices, mut polygons) = (Vec::new(), Vec::new());
    for model in &models {
        let m = &model.mesh;
        let base = vertices.len() as i64;
        vertices.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        let mut next = 0usize;
        let arities: Vec<usize> = if m.face_arities.is_empty() {
            vec![3; m.indices.len() / 3]
        } else {
            m.face_arities.iter().map(|&a| a as usize).collect()
        };
        for a in arities {
            let corners = m.indices.get(next..next + a).ok_or_else(|| {
                Error::file(
                    path,
                    "not a readable OBJ file: a face runs past its indices",
                )
            })?;
            polygons.push(corners.iter().map(|&i| i as i64 + base).collect());
            next += a;
        }
    }
    Ok((vertices, polygons))
}

fn read_ply(path: &Path) -> Result<Raw> {
    use ply_rs_bw::ply::Property;
    let file = std::fs::File::open(path).map_err(|e| Error::file(path, e))?;
    let parser = ply_rs_bw::parser::Parser::<ply_rs_bw::ply::DefaultElement>::new();
    let ply = parser
        .read_ply(&mut std::io::BufReader::new(file))
        .map_err(|e| Error::file(path, format!("not a readable PLY file: {}", one_line(&e))))?;
    let bad = |message: &str| Error::file(path, format!("not a usable PLY file: {message}"));
    let vertex = (ply.payload.get("vertex")).ok_or_else(|| bad("no `vertex` element"))?;
    let mut vertices = Vec::with_capacity(vertex.len());
    for (k, v) in vertex.iter().enumerate() {
        let coordinate = |name: &str| -> Result<f32> {
            let p = v
                .get(name)
                .ok_or_else(|| bad(&format!("vertex {k} has no property `{name}`")))?;
            p.to_f32_lossy()
                .ok_or_else(|| bad(&format!("vertex {k}: `{name}` is a list")))
        };
        vertices.push(Vec3::new(
            coordinate("x")?,
            coordinate("y")?,
            coordinate("z")?,
        ));
    }
    let faces = ply.payload.get("face").map_or(&[][..], |f| &f[..]);
    let mut polygons = Vec::with_capacity(faces.len());
    for (k, f) in faces.iter().enumerate() {
        let list = (f.get("vertex_indices").or_else(|| f.get("vertex_index")))
            .ok_or_else(|| bad(&format!("face {k} has no `vertex_indices` list")))?;
        let indices: Vec<i64> = match list {
            Property::ListChar(l) => l.iter().map(|&i| i as i64).collect(),
            Property::ListUChar(l) => l.iter().map(|&i| i as i64).collect(),
            Property::ListShort(l) => l.iter().map(|&i| i as i64).collect(),
            Property::ListUShort(l) => l.iter().map(|&i| i as i64).collect(),
            Property::ListInt(l) => l.iter().map(|&i| i as i64).collect(),
            Property::ListUInt(l) => l.iter().map(|&i| i as i64).collect(),
            _ => {
                return Err(bad(&format!(
                    "face {k}: `vertex_indices` is not a list of integers"
                )));
            }
        };
        polygons.push(indices);
    }
    Ok((vertices, polygons))
}

fn read_stl(path: &Path) -> Result<Raw> {
    let file = std::fs::File::open(path).map_err(|e| Error::file(path, e))?;
    let mesh = stl_io::read_stl(&mut std::io::BufReader::new(file))
        .map_err(|e| Error::file(path, format!("not a readable STL file: {}", one_line(&e))))?;
    let vertices = (mesh.vertices.iter())
        .map(|v| Vec3::from_array(v.0))
        .collect();
    let polygons = (mesh.faces.iter())
        .map(|f| f.vertices.iter().map(|&i| i as i64).collect())
        .collect();
    Ok((vertices, polygons))
}

/// OFF: a header line (`OFF`, possibly with the counts after it), `V F E`, then `V` lines `x y z ...`
/// and `F` lines `n i_1 ... i_n ...`; `#` starts a comment.
fn read_off(path: &Path) -> Result<Raw> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::file(path, e))?;
    let bad = |message: String| Error::file(path, format!("not a readable OFF file: {message}"));
    // Lines without comments and blank lines, with their line numbers.
    let mut lines = text.lines().enumerate().filter_map(|(n, l)| {
        let l = l.split('#').next().unwrap_or("").trim();
        (!l.is_empty()).then_some((n + 1, l))
    });
    let (_, header) = lines
        .next()
        .ok_or_else(|| bad("the file is empty".into()))?;
    let mut words = header.split_whitespace();
    let keyword = words.next().unwrap_or("");
    if !keyword.ends_with("OFF") || keyword.len() > 5 {
        return Err(bad(format!("the first line must be OFF, got {keyword:?}")));
    }
    let rest: Vec<&str> = words.collect();
    let (count_line, counts): (usize, Vec<&str>) = if rest.is_empty() {
        let (n, l) = lines
            .next()
            .ok_or_else(|| bad("no vertex and face counts".into()))?;
        (n, l.split_whitespace().collect())
    } else {
        (1, rest)
    };
    let count = |k: usize| -> Result<usize> {
        (counts.get(k).and_then(|c| c.parse::<usize>().ok()))
            .ok_or_else(|| bad(format!("line {count_line}: expected the counts `V F E`")))
    };
    let (nv, nf) = (count(0)?, count(1)?);
    let mut vertices = Vec::with_capacity(nv.min(1 << 24));
    for k in 0..nv {
        let (n, l) = lines
            .next()
            .ok_or_else(|| bad(format!("{nv} vertices announced, {k} found")))?;
        let xyz: Vec<f32> = (l.split_whitespace().take(3))
            .map(|w| w.parse::<f32>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|e| bad(format!("line {n}: {e}")))?;
        if xyz.len() < 3 {
            return Err(bad(format!("line {n}: expected x y z")));
        }
        vertices.push(Vec3::new(xyz[0], xyz[1], xyz[2]));
    }
    let mut polygons = Vec::with_capacity(nf.min(1 << 24));
    for k in 0..nf {
        let (n, l) = lines
            .next()
            .ok_or_else(|| bad(format!("{nf} faces announced, {k} found")))?;
        let mut words = l.split_whitespace();
        let arity: usize = (words.next().and_then(|w| w.parse().ok()))
            .ok_or_else(|| bad(format!("line {n}: expected a face `n i_1 ... i_n`")))?;
        let indices: Vec<i64> = (words.take(arity))
            .map(|w| w.parse::<i64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|e| bad(format!("line {n}: {e}")))?;
        if indices.len() < arity {
            return Err(bad(format!(
                "line {n}: a face of {arity} corners lists {}",
                indices.len()
            )));
        }
        polygons.push(indices);
    }
    Ok((vertices, polygons))
}
