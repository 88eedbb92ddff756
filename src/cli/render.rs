//! The `render` command: the image as an EXR and a PNG.

use crate::cli::args::{OutputArgs, SceneArgs};
use crate::cli::{output_paths, prepare, warn};
use crate::integrator;
use crate::io;
use anyhow::Result;

pub(crate) fn render(args: &SceneArgs, outputs: &OutputArgs) -> Result<()> {
    let (out, png) = output_paths(outputs, "out")?;
    let (scene, options) = prepare(args)?;
    let (image, stats) = integrator::render(&scene, &options);
    let size = (image.width, image.height);
    io::write_exr_and_png(&out, &png, size, &image.rgb_channels(""), &image)?;
    outln!(
        "rendered {}x{} at {} spp in {:.2} s ({:.3} M samples/s); wrote {} and {}",
        image.width,
        image.height,
        options.spp,
        stats.seconds,
        stats.samples as f64 / stats.seconds.max(1e-9) * 1e-6,
        out.display(),
        png.display()
    )?;
    warn(&stats);
    Ok(())
}
