//! The `fd` command: central finite differences of one parameter with common random numbers, as
//! EXR channels and a PNG, like `diff`'s.

use crate::cli::args::FdArgs;
use crate::cli::{in_file, output_paths, prepare, warn, write_derivatives};
use crate::integrator::fd;
use anyhow::Result;

pub(crate) fn finite_difference(args: &FdArgs) -> Result<()> {
    let paths = output_paths(&args.outputs, "fd")?;
    let (scene, options) = prepare(&args.scene)?;
    let (param, h) = (&args.param, args.h);
    // Validates the step and both values before rendering anything.
    let result = fd::render_with_difference(&scene, param, h, &options)
        .map_err(in_file(&args.scene.scene))?;
    let (image, params) = (&result.image, std::slice::from_ref(param));
    write_derivatives(
        &paths,
        image,
        &result.channels(param),
        params,
        &[result.derivative],
    )?;
    outln!(
        "central differences of {param} = {} with h = {} (common random numbers): rendered {}x{} \
         three times at {} spp in {:.2} s; wrote {} and {}",
        result.value,
        result.h,
        image.width,
        image.height,
        options.spp,
        result.stats.seconds,
        paths.0.display(),
        paths.1.display()
    )?;
    warn(&result.stats);
    Ok(())
}
