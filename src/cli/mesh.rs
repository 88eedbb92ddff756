//! The `mesh` command: a shape's surface as a triangle mesh file.

use crate::cli::args::MeshArgs;
use crate::cli::load_scene;
use crate::{io, mesh};
use anyhow::{Context, Result, bail};
use std::path::PathBuf;

pub(crate) fn mesh(args: &MeshArgs) -> Result<()> {
    let name = &args.shape;
    let out = (args.out.clone()).unwrap_or_else(|| PathBuf::from(format!("{name}.ply")));
    let extension = out
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    if !extension.is_some_and(|e| io::MESH_EXTENSIONS.contains(&e.as_str())) {
        bail!("--out {}: must end in .ply or .obj", out.display());
    }
    let ext = out
        .extension()
        .unwrap_or_default()
        .to_string_lossy()
        .into_owned();
    io::check_output_path(&out, "--out", &ext)?;
    let scene = load_scene(&args.scene)?;
    let shape =
        (scene.shape_named(name)).with_context(|| format!("--shape: {}", args.scene.display()))?;
    let start = std::time::Instant::now();
    let mesh = mesh::extract_shape(shape, args.res as usize).context("--shape")?;
    io::write_mesh(&out, &mesh)?;
    outln!(
        "wrote {} ({} vertices, {} triangles, area {:.6}, volume {:.6}) in {:.2} s",
        out.display(),
        mesh.vertices.len(),
        mesh.faces.len(),
        mesh.area(),
        mesh.volume(),
        start.elapsed().as_secs_f64()
    )?;
    Ok(())
}
