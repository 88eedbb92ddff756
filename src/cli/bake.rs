//! The `bake` command: a shape's SDF, or a triangle mesh's signed distance, sampled on a grid, as a
//! `.npy` file and the scene node that uses it.

use crate::cli::args::BakeArgs;
use crate::cli::load_scene;
use crate::sdf::Baked;
use crate::{io, mesh, sdf};
use anyhow::{Context, Result};

pub(crate) fn bake(args: &BakeArgs) -> Result<()> {
    let out = &args.out;
    io::check_output_path(out, "--out", "npy")?;
    let baked = match (&args.mesh, &args.scene, &args.shape) {
        (Some(file), _, _) => bake_mesh_file(file, args)?,
        (None, Some(scene), Some(name)) => {
            let scene = load_scene(scene)?;
            let shape = (scene.shape_named(name))
                .with_context(|| format!("--shape: {}", args.scene_name()))?;
            // The grid samples the SDF in the shape's own coordinates (before its rigid translation).
            let what = format!("shape {name:?}");
            sdf::bake_padded_by(&shape.sdf, args.res as usize, args.padding, &what)
                .context("--shape")?
        }
        _ => unreachable!("clap requires SCENE with --shape, or --mesh"),
    };
    io::write_npy(out, &baked.grid)?;
    let [nx, ny, nz] = baked.grid.dims;
    // A scene resolves `file` relative to itself: name the file as a scene beside it would.
    let file = out.file_name().unwrap_or(out.as_os_str()).to_string_lossy();
    outln!(
        "wrote {} ({nx} x {ny} x {nz} samples, x y z); in a scene file in the same folder use it as\n  {}",
        out.display(),
        baked.scene_node(&file)
    )?;
    Ok(())
}

/// The mesh in `file`, read and baked; every error names the file.
fn bake_mesh_file(file: &std::path::Path, args: &BakeArgs) -> Result<Baked> {
    let mesh = io::read_mesh(file).context("--mesh")?;
    let baked = mesh::bake_mesh(&mesh, args.res as usize, args.padding)
        .with_context(|| format!("--mesh {}", file.display()))?;
    Ok(baked)
}

impl BakeArgs {
    fn scene_name(&self) -> String {
        (self.scene.as_ref()).map_or(String::new(), |p| p.display().to_string())
    }
}
