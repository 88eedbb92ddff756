//! Triangle meshes as files: binary PLY (little-endian; `x y z nx ny nz` as `float` per vertex, each
//! face a `uchar` count and three `int` indices) or Wavefront OBJ (`v`, `vn` and `f a//a b//b c//c`,
//! indices from 1), chosen by the extension. Both are read by MeshLab, Blender, Open3D and trimesh.

use super::files::{create_parent, write_atomically};
use crate::error::{Error, Result};
use crate::mesh::TriangleMesh;
use std::fmt::Write as _;
use std::path::Path;

/// The mesh formats [`write_mesh`] writes, by extension.
pub const MESH_EXTENSIONS: [&str; 2] = ["ply", "obj"];

/// Writes `mesh` to `path` as binary PLY (`.ply`) or OBJ (`.obj`), whole or not at all (its folder
/// created if missing). Errors: another
/// extension, a write failure (naming the file).
pub fn write_mesh(path: &Path, mesh: &TriangleMesh) -> Result<()> {
    let bytes = match extension(path).as_deref() {
        Some("obj") => obj_text(mesh).into_bytes(),
        Some("ply") => ply_bytes(mesh),
        _ => {
            return Err(Error::file(path, "a mesh file must end in .ply or .obj"));
        }
    };
    create_parent(path)?;
    write_atomically(path, |tmp| {
        std::fs::write(tmp, &bytes).map_err(|e| Error::file(path, format!("cannot write: {e}")))
    })
}

/// The lower-case extension of `path`.
fn extension(path: &Path) -> Option<String> {
    Some(path.extension()?.to_str()?.to_ascii_lowercase())
}

/// The bytes of `mesh` as a binary PLY file (what [`write_mesh`] writes to a `.ply`).
pub fn ply_bytes(mesh: &TriangleMesh) -> Vec<u8> {
    let header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment implicit-psdr\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.vertices.len(),
        mesh.faces.len()
    );
    let mut out = header.into_bytes();
    out.reserve(mesh.vertices.len() * 24 + mesh.faces.len() * 13);
    for (v, n) in mesh.vertices.iter().zip(&mesh.normals) {
        for x in v.to_array().into_iter().chain(n.to_array()) {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }
    for f in &mesh.faces {
        out.push(3);
        for i in f {
            out.extend_from_slice(&(*i as i32).to_le_bytes());
        }
    }
    out
}

fn obj_text(mesh: &TriangleMesh) -> String {
    let mut out = String::from("# implicit-psdr\n");
    for v in &mesh.vertices {
        let _ = writeln!(out, "v {} {} {}", v.x, v.y, v.z);
    }
    for n in &mesh.normals {
        let _ = writeln!(out, "vn {} {} {}", n.x, n.y, n.z);
    }
    for f in &mesh.faces {
        let [a, b, c] = f.map(|i| i + 1);
        let _ = writeln!(out, "f {a}//{a} {b}//{b} {c}//{c}");
    }
    out
}
