//! The `implicit-psdr` command-line tool: parses arguments and calls the library.
//!
//! Every failure prints one line `error: ...` on stderr and exits with code 2 (as clap does for usage
//! errors). Everything is validated before rendering, and outputs are written to a temporary file and
//! renamed, so a failed run leaves no partial output.

use anyhow::{Result, bail};
use clap::{Parser, Subcommand};
use implicit_psdr::integrator::{self, RenderOptions};
use implicit_psdr::{film, scene, sdf};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Physically based rendering of implicit surfaces.
#[derive(Parser, Debug)]
#[command(version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a scene to an EXR (linear float32 R, G, B) and a PNG (8-bit sRGB, clamped).
    Render {
        /// The scene file (JSON, see README).
        scene: PathBuf,
        /// Samples per pixel (default: the scene's `spp`).
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
        spp: Option<u32>,
        /// Seed of the deterministic sampler.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Output EXR file.
        #[arg(long, default_value = "out.exr")]
        out: PathBuf,
        /// Output PNG file.
        #[arg(long, default_value = "out.png")]
        png: PathBuf,
    },
    /// Sample one shape's SDF over its bounds (padded) into a grid and write it as a float32 .npy of
    /// shape [nz, ny, nx].
    Bake {
        /// The scene file holding the shape.
        scene: PathBuf,
        /// Name of the shape to bake.
        #[arg(long)]
        shape: String,
        /// Samples along the longest edge of the box (4 to 512); the other axes get near-cubic cells.
        #[arg(long, value_parser = clap::value_parser!(u32).range(4..=512))]
        res: u32,
        /// Output .npy file.
        #[arg(long)]
        out: PathBuf,
    },
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => {
            // --help and --version: clap prints them to stdout and exits with 0.
            e.exit()
        }
        Err(e) => {
            eprintln!("{} (see --help)", one_line_usage_error(&e));
            return ExitCode::from(2);
        }
    };
    // A panic is a bug, but the contract of the tool still holds: one line on stderr (the first panic
    // only: rayon workers may panic together), exit code 2, no output file (outputs are written last).
    std::panic::set_hook(Box::new(|info| {
        static ONCE: std::sync::Once = std::sync::Once::new();
        ONCE.call_once(|| {
            let message = info.to_string().replace('\n', " ");
            eprintln!("error: internal error (please report): {message}");
        });
    }));
    let Ok(result) = std::panic::catch_unwind(|| run(cli)) else {
        return ExitCode::from(2);
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // `{:#}` joins the context chain on one line: "scene.json: shapes[0].sdf.radius: ...".
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Render {
            scene,
            spp,
            seed,
            out,
            png,
        } => render(&scene, spp, seed, &out, &png),
        Command::Bake {
            scene,
            shape,
            res,
            out,
        } => bake(&scene, &shape, res as usize, &out),
    }
}

/// clap's message without its usage block, on one line: "error: unexpected argument '--sp' found".
fn one_line_usage_error(e: &clap::Error) -> String {
    let text = e.render().to_string();
    let message: Vec<&str> = text
        .lines()
        .take_while(|l| !l.starts_with("Usage:"))
        .map(str::trim)
        .filter(|l| {
            !(l.is_empty() || l.starts_with("tip:") || l.starts_with("For more information"))
        })
        .collect();
    message.join(" ")
}

/// Loads a scene; field errors get the scene file in front (file errors name their file already).
fn load_scene(path: &Path) -> Result<scene::Scene> {
    scene::load(path).map_err(|e| match e {
        implicit_psdr::Error::Field { .. } => anyhow::anyhow!("{}: {e}", path.display()),
        e => e.into(),
    })
}

/// Fails unless `path`'s folder exists, so that a long render cannot end in an unwritable output.
fn check_output(path: &Path, what: &str) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        bail!(
            "{what} {}: folder {} does not exist",
            path.display(),
            dir.display()
        );
    }
    if path.is_dir() {
        bail!("{what} {}: is a folder", path.display());
    }
    Ok(())
}

fn render(scene_path: &Path, spp: Option<u32>, seed: u64, out: &Path, png: &Path) -> Result<()> {
    check_output(out, "--out")?;
    check_output(png, "--png")?;
    if out == png {
        bail!("--out and --png name the same file {}", out.display());
    }
    let scene = load_scene(scene_path)?;
    let options = RenderOptions {
        spp: spp.unwrap_or(scene.spp),
        seed,
        progress: std::io::stderr().is_terminal(),
    };
    let (image, stats) = integrator::render(&scene, &options);

    let channels: Vec<(String, Vec<f32>)> = ["R", "G", "B"]
        .iter()
        .enumerate()
        .map(|(c, name)| (name.to_string(), image.channel(c)))
        .collect();
    film::write_exr(out, image.width, image.height, &channels)?;
    if let Err(e) = film::write_png(png, image.width, image.height, &image.rgb) {
        // Keep the outputs all-or-nothing.
        let _ = std::fs::remove_file(out);
        return Err(e.into());
    }

    let rate = stats.samples as f64 / stats.seconds.max(1e-9);
    println!(
        "rendered {}x{} at {} spp in {:.2} s ({:.3} M samples/s); wrote {} and {}",
        image.width,
        image.height,
        options.spp,
        stats.seconds,
        rate * 1e-6,
        out.display(),
        png.display()
    );
    if stats.exhausted_rays > 0 {
        eprintln!(
            "warning: {} rays ran out of sphere-tracing steps and were treated as misses",
            stats.exhausted_rays
        );
    }
    Ok(())
}

/// Relative padding of the baked box: the B-spline needs samples beyond the surface on every side.
const BAKE_PADDING: f32 = 0.1;

fn bake(scene_path: &Path, name: &str, res: usize, out: &Path) -> Result<()> {
    check_output(out, "--out")?;
    let scene = load_scene(scene_path)?;
    let Some(shape) = scene.shapes.iter().find(|s| s.name == name) else {
        let names: Vec<&str> = scene.shapes.iter().map(|s| s.name.as_str()).collect();
        bail!(
            "--shape: no shape named {name:?} in {} (shapes: {})",
            scene_path.display(),
            names.join(", ")
        );
    };
    // The grid samples the SDF in the shape's own coordinates (before its rigid translation).
    let local = shape.sdf.bounds();
    if !local.is_finite() || local.is_empty() {
        bail!(
            "--shape: shape {name:?} is unbounded (e.g. a plane), it cannot be baked into a grid"
        );
    }
    // Padding keeps a few cells between the surface and the box, where the B-spline reconstruction
    // is accurate; sdf::bake puts `res` samples along the longest edge and near-cubic cells elsewhere.
    let padded = local.expanded(BAKE_PADDING * local.extent().max_element());
    let (bbox_min, bbox_max) = (padded.min, padded.max);
    let grid = sdf::bake(&shape.sdf, bbox_min, bbox_max, res);
    sdf::write_npy(out, &grid)?;
    let [nx, ny, nz] = grid.dims;
    println!(
        "wrote {} ({nx} x {ny} x {nz} samples, x y z); use it as\n  {{\"type\": \"grid\", \"file\": \"{}\", \"bbox_min\": [{}, {}, {}], \"bbox_max\": [{}, {}, {}]}}",
        out.display(),
        out.display(),
        bbox_min.x,
        bbox_min.y,
        bbox_min.z,
        bbox_max.x,
        bbox_max.y,
        bbox_max.z
    );
    Ok(())
}
