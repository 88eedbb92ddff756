//! The `fd` command: central finite differences of parameters with common random numbers, as EXR
//! channels and a PNG, like `diff`'s.

use crate::cli::args::FdArgs;
use crate::cli::{in_file, output_paths, prepare, warn, write_derivatives};
use crate::integrator::fd;
use anyhow::Result;

pub(crate) fn finite_difference(args: &FdArgs) -> Result<()> {
    let paths = output_paths(&args.outputs, "fd")?;
    let (scene, options) = prepare(&args.scene)?;
    // Validates the step and both values of every parameter before rendering anything.
    let result = fd::render_with_differences(&scene, &args.params, args.h, &options)
        .map_err(in_file(&args.scene.scene))?;
    let image = &result.image;
    let derivatives: Vec<_> = (result.differences.iter())
        .map(|d| d.derivative.clone())
        .collect();
    write_derivatives(
        &paths,
        image,
        &result.channels(),
        &args.params,
        &derivatives,
    )?;
    let steps: Vec<String> = (result.differences.iter())
        .map(|d| format!("{} = {} with h = {}", d.name, d.value, d.h))
        .collect();
    outln!(
        "central differences of {} (common random numbers): rendered {}x{} {} times at {} spp in \
         {:.2} s; wrote {} and {}",
        steps.join(", "),
        image.width,
        image.height,
        match 1 + 2 * steps.len() {
            3 => "three".to_string(),
            n => n.to_string(),
        },
        options.spp,
        result.stats.seconds,
        paths.0.display(),
        paths.1.display()
    )?;
    warn(&result.stats);
    Ok(())
}
