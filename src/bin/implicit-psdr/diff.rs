//! The `diff` command: the image and its derivatives in forward mode (named parameters and grid
//! directions), as EXR channels and a PNG of colour-mapped panels.

use crate::args::DiffArgs;
use crate::{diff_options, in_file, output_paths, prepare, warn, write_derivatives};
use anyhow::Result;
use implicit_psdr::integrator;
use implicit_psdr::io;
use implicit_psdr::scene::{GridDirection, Scene};
use std::path::PathBuf;
use std::sync::Arc;

pub(crate) fn diff(args: &DiffArgs) -> Result<()> {
    let paths = output_paths(&args.outputs, "diff")?;
    let (mut scene, render) = prepare(&args.scene)?;
    let file = in_file(&args.scene.scene);
    scene.select_parameters(&args.params).map_err(&file)?;
    // Grid directions take the slots after the named parameters, and their blocks' names.
    let mut names = args.params.clone();
    names.extend(select_directions(&mut scene, names.len(), &args.grid_directions).map_err(&file)?);
    let options = diff_options(render, &args.estimator);
    let count = names.len();
    let result = integrator::render_derivatives(&scene, count, &options).map_err(&file)?;
    let image = &result.image;
    outln!("note: {}", result.note(&scene.unsampled_creases()))?;
    let channels = result.channels(&names, args.terms);
    write_derivatives(&paths, image, &channels, &names, &result.total())?;
    outln!(
        "rendered {}x{} and {count} derivative image{} at {} spp in {:.2} s; wrote {} and {}",
        image.width,
        image.height,
        if count == 1 { "" } else { "s" },
        options.render.spp,
        result.stats.seconds,
        paths.0.display(),
        paths.1.display()
    )?;
    warn(&result.stats);
    Ok(())
}

/// Selects the forward-mode directions `(node, U.npy)` of `diff --grid-direction`, in derivative slots
/// `first_slot`, `first_slot + 1`, ...; returns their blocks' names (`NODE.values`). Errors: an
/// unreadable U, and those of [`Scene::select_grid_directions`] (a U of another shape names its file).
pub(crate) fn select_directions(
    scene: &mut Scene,
    first_slot: usize,
    directions: &[(String, PathBuf)],
) -> Result<Vec<String>, implicit_psdr::Error> {
    let mut read = Vec::new();
    for (node, file) in directions {
        let u = io::read_npy(file)?;
        let [nx, ny, nz] = u.dims;
        read.push(GridDirection {
            node: node.clone(),
            shape: [nz, ny, nx],
            values: Arc::new(u.values),
            source: file.display().to_string(),
        });
    }
    scene.select_grid_directions(first_slot, &read)
}
