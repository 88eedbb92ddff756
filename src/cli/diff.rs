//! The `diff` command: the image and its derivatives in forward mode (named parameters and grid
//! directions), as EXR channels and a PNG of colour-mapped panels.

use crate::cli::args::DiffArgs;
use crate::cli::{diff_options, in_file, output_paths, prepare, warn, write_derivatives};
use crate::integrator;
use crate::io;
use crate::scene::GridDirection;
use anyhow::Result;
use std::path::PathBuf;
use std::sync::Arc;

pub(crate) fn diff(args: &DiffArgs) -> Result<()> {
    let paths = output_paths(&args.outputs, "diff")?;
    let (scene, render) = prepare(&args.scene)?;
    let file = in_file(&args.scene.scene);
    let directions = read_directions(&args.grid_directions).map_err(&file)?;
    let selection =
        (scene.select_with_grid_directions(&args.params, &directions)).map_err(&file)?;
    let names = selection.names();
    let options = diff_options(render, &args.estimator);
    let count = names.len();
    let result = integrator::render_derivatives(&scene, &selection, &options).map_err(&file)?;
    let image = &result.image;
    outln!("note: {}", result.note(&scene.unsampled_creases()))?;
    let channels = result.channels(names, args.terms);
    write_derivatives(&paths, image, &channels, names, &result.total())?;
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

/// The forward-mode directions `(node, U.npy)` of `diff --grid-direction`, read. Errors: an
/// unreadable U or one with a value that is not finite (a U of another shape than its block is
/// reported when selected, naming its file).
fn read_directions(directions: &[(String, PathBuf)]) -> Result<Vec<GridDirection>, crate::Error> {
    let mut read = Vec::new();
    for (node, file) in directions {
        let u = io::read_npy_array(file)?;
        if let Some(i) = u.values.iter().position(|v| !v.is_finite()) {
            return Err(crate::Error::file(
                file,
                format!("value {i} is not finite ({})", u.values[i]),
            ));
        }
        read.push(GridDirection {
            node: node.clone(),
            shape: u.shape,
            values: Arc::new(u.values),
            source: file.display().to_string(),
        });
    }
    Ok(read)
}
