//! The `bake` command: a shape's SDF sampled on a grid, as a `.npy` file and the scene node that
//! uses it.

use crate::cli::args::BakeArgs;
use crate::cli::load_scene;
use crate::{io, sdf};
use anyhow::{Context, Result};

pub(crate) fn bake(args: &BakeArgs) -> Result<()> {
    let (out, name) = (&args.out, &args.shape);
    io::check_output_path(out, "--out", "npy")?;
    let scene = load_scene(&args.scene)?;
    let shape =
        (scene.shape_named(name)).with_context(|| format!("--shape: {}", args.scene.display()))?;
    // The grid samples the SDF in the shape's own coordinates (before its rigid translation).
    let baked = sdf::bake_padded(&shape.sdf, args.res as usize, &format!("shape {name:?}"))
        .context("--shape")?;
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
