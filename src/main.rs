//! The `implicit-psdr` command-line tool: parses arguments and calls the library.
//!
//! Every failure prints one line `error: ...` on stderr and exits with code 2 (as clap does for usage
//! errors). Everything is validated before rendering, and outputs are written to a temporary file and
//! renamed, so a failed run leaves no partial output.

use anyhow::{Result, bail};
use clap::{Parser, Subcommand};
use implicit_psdr::film::{Image, colormap};
use implicit_psdr::integrator::derivative::{
    DiffOptions, Normalization, default_boundary_spp, render_derivatives,
    render_derivatives_with_boundary,
};
use implicit_psdr::integrator::{self, RenderOptions, fd};
use implicit_psdr::{compare, film, scene, sdf};
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
    /// List every differentiable parameter of a scene with its value, one `name value` per line.
    Params {
        /// The scene file.
        scene: PathBuf,
    },
    /// Render the image and its derivatives with respect to scene parameters (forward mode) to an EXR
    /// (`R`, `G`, `B`, and `d.P.R`, `d.P.G`, `d.P.B` per parameter P) and a PNG (the image beside one
    /// colour-mapped panel per derivative).
    Diff {
        /// The scene file.
        scene: PathBuf,
        /// A parameter to differentiate with respect to (repeat for several; see `params`).
        #[arg(long = "param", value_name = "P", required = true)]
        params: Vec<String>,
        /// Samples per pixel (default: the scene's `spp`).
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
        spp: Option<u32>,
        /// Seed of the deterministic sampler.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Also write each term of the derivative (`d_interior.P.R|G|B`, `d_primary.P.R|G|B`,
        /// `d_secondary.P.R|G|B`; they sum to `d.P`).
        #[arg(long)]
        terms: bool,
        /// Boundary samples per pixel for the secondary (shadow) term; 0 skips it [default: spp/8,
        /// rounded up].
        #[arg(long)]
        spp_secondary: Option<u32>,
        /// Silhouette-curve samples per pixel for the primary (silhouette) term; 0 skips it [default:
        /// spp/32, rounded up].
        #[arg(long)]
        spp_primary: Option<u32>,
        /// Pixel normalisation: `differentiable` (F / W, both differentiated: lower error) or `fixed`
        /// (the filter-weight sum is a constant).
        #[arg(long, value_enum, default_value_t = NormalizationArg::Differentiable)]
        normalization: NormalizationArg,
        /// Output EXR file.
        #[arg(long, default_value = "diff.exr")]
        out: PathBuf,
        /// Output PNG file.
        #[arg(long, default_value = "diff.png")]
        png: PathBuf,
    },
    /// Central finite differences of the image with respect to one parameter, with common random numbers
    /// (the same samples at P + h and P − h), to an EXR (`R`, `G`, `B` at P, and `d.P.R|G|B`) and a PNG.
    Fd {
        /// The scene file.
        scene: PathBuf,
        /// The parameter (see `params`).
        #[arg(long = "param", value_name = "P")]
        param: String,
        /// Step (default: 0.01 · max(|P|, 1)).
        #[arg(long, value_parser = positive_f32)]
        h: Option<f32>,
        /// Samples per pixel (default: the scene's `spp`).
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
        spp: Option<u32>,
        /// Seed of the deterministic sampler.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Output EXR file.
        #[arg(long, default_value = "fd.exr")]
        out: PathBuf,
        /// Output PNG file.
        #[arg(long, default_value = "fd.png")]
        png: PathBuf,
    },
    /// Compare the derivative channels of two EXR files (B is the reference): relative L2 error, raw and
    /// after a 5x5 box blur, sums, sums of absolute values and correlation.
    Compare {
        /// The EXR file to check.
        a: PathBuf,
        /// The reference EXR file.
        b: PathBuf,
        /// Compare only the channels whose names start with PREFIX (default: every channel starting
        /// with `d`).
        #[arg(long, value_name = "PREFIX")]
        channel: Option<String>,
    },
}

/// `--normalization` values.
#[derive(Copy, Clone, Debug, clap::ValueEnum)]
enum NormalizationArg {
    /// Pixel = mean of its samples; the filter-weight sum is treated as a constant.
    Fixed,
    /// Pixel = F / W with both sums differentiated.
    Differentiable,
}

impl From<NormalizationArg> for Normalization {
    fn from(n: NormalizationArg) -> Self {
        match n {
            NormalizationArg::Fixed => Normalization::Fixed,
            NormalizationArg::Differentiable => Normalization::Differentiable,
        }
    }
}

/// A finite number > 0.
fn positive_f32(text: &str) -> Result<f32, String> {
    match text.parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("expected a finite number > 0, got {text:?}")),
    }
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
        Command::Params { scene } => params(&scene),
        Command::Diff {
            scene,
            params,
            spp,
            seed,
            terms,
            spp_secondary,
            spp_primary,
            normalization,
            out,
            png,
        } => diff(
            &scene,
            &params,
            spp,
            seed,
            terms,
            BoundaryBudget {
                primary: spp_primary,
                secondary: spp_secondary,
            },
            normalization.into(),
            &out,
            &png,
        ),
        Command::Fd {
            scene,
            param,
            h,
            spp,
            seed,
            out,
            png,
        } => finite_difference(&scene, &param, h, spp, seed, &out, &png),
        Command::Compare { a, b, channel } => compare_files(&a, &b, channel.as_deref()),
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

/// Checks both outputs of an EXR + PNG command before anything is rendered.
fn check_outputs(out: &Path, png: &Path) -> Result<()> {
    check_output(out, "--out")?;
    check_output(png, "--png")?;
    if out == png {
        bail!("--out and --png name the same file {}", out.display());
    }
    Ok(())
}

fn render_options(scene: &scene::Scene, spp: Option<u32>, seed: u64) -> RenderOptions {
    RenderOptions {
        spp: spp.unwrap_or(scene.spp),
        seed,
        progress: std::io::stderr().is_terminal(),
    }
}

/// The EXR channels `{prefix}R`, `{prefix}G`, `{prefix}B` of an image.
fn rgb_channels(prefix: &str, image: &Image) -> film::Channels {
    ["R", "G", "B"]
        .iter()
        .enumerate()
        .map(|(c, name)| (format!("{prefix}{name}"), image.channel(c)))
        .collect()
}

/// Writes the EXR (planes of `image`'s size), then the PNG `picture`; removes the EXR if the PNG fails,
/// so the outputs are all-or-nothing.
fn write_outputs(
    out: &Path,
    png: &Path,
    image: &Image,
    channels: &film::Channels,
    picture: &Image,
) -> Result<()> {
    film::write_exr(out, image.width, image.height, channels)?;
    if let Err(e) = film::write_png(png, picture.width, picture.height, &picture.rgb) {
        let _ = std::fs::remove_file(out);
        return Err(e.into());
    }
    Ok(())
}

fn render(scene_path: &Path, spp: Option<u32>, seed: u64, out: &Path, png: &Path) -> Result<()> {
    check_outputs(out, png)?;
    let scene = load_scene(scene_path)?;
    let options = render_options(&scene, spp, seed);
    let (image, stats) = integrator::render(&scene, &options);
    write_outputs(out, png, &image, &rgb_channels("", &image), &image)?;

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
    warn_exhausted(stats.exhausted_rays);
    Ok(())
}

fn warn_exhausted(rays: u64) {
    if rays > 0 {
        eprintln!(
            "warning: {rays} rays ran out of sphere-tracing steps and were treated as misses"
        );
    }
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

fn params(scene_path: &Path) -> Result<()> {
    let scene = load_scene(scene_path)?;
    let mut text = String::new();
    for (name, value) in scene.parameters() {
        text.push_str(&format!("{name} {value}\n"));
    }
    print!("{text}");
    Ok(())
}

/// Boundary samples per pixel of each boundary term (0 skips it; `None`: the default for the spp,
/// [`default_boundary_spp`]).
struct BoundaryBudget {
    primary: Option<u32>,
    secondary: Option<u32>,
}

/// Boundary samples per pixel of each boundary term, resolved (0 skips it).
struct BoundarySpp {
    primary: u32,
    secondary: u32,
}

/// The `note:` line of `diff`: which terms `d.P` holds, and which shapes have crease edges (`(name,
/// reason)`, [`Scene::creased_shapes`]), whose boundary terms are not sampled.
fn terms_note(
    interior_only_reason: Option<&str>,
    budget: &BoundarySpp,
    creased: &[(String, String)],
) -> String {
    if let Some(reason) = interior_only_reason {
        return format!(
            "note: derivatives hold the interior term only ({reason}); the silhouette and shadow \
             terms are missing, so d.P is wrong where edges move"
        );
    }
    let mut held = vec!["interior"];
    let mut missing = Vec::new();
    for (n, name) in [
        (budget.secondary, "secondary (shadow)"),
        (budget.primary, "primary (silhouette)"),
    ] {
        if n > 0 {
            held.push(name)
        } else {
            missing.push(name)
        }
    }
    let missing = if missing.is_empty() {
        String::new()
    } else {
        format!("; skipped: {} (budget 0)", missing.join(", "))
    };
    let held = match held.as_slice() {
        [one] => one.to_string(),
        [rest @ .., last] => format!("{} and {last}", rest.join(", ")),
        [] => String::new(),
    };
    let creases = if creased.is_empty() {
        String::new()
    } else {
        let list: Vec<String> = creased.iter().map(|(n, r)| format!("{n} ({r})")).collect();
        format!(
            "; crease edges are not sampled, so where they move or hide what moves d.P misses their \
             boundary terms: {}",
            list.join(", ")
        )
    };
    format!("note: derivatives hold the {held} terms{missing}{creases}")
}

/// The PNG of a derivative command: the image beside one colour-mapped panel per derivative. Returns it
/// with each panel's colour scale.
fn derivative_picture(image: &Image, derivatives: &[&Image]) -> (Image, Vec<f32>) {
    let mut panels = vec![image.clone()];
    let mut scales = Vec::new();
    for d in derivatives {
        let (panel, scale) = colormap::derivative_panel(d);
        panels.push(panel);
        scales.push(scale);
    }
    (colormap::side_by_side(&panels), scales)
}

fn print_scale(param: &str, scale: f32) {
    println!(
        "d.{param}: PNG colour scale ±{scale:.4e} (blue −, white 0, red +; 99th percentile of |mean of R, G, B|)"
    );
}

#[allow(clippy::too_many_arguments)]
fn diff(
    scene_path: &Path,
    params: &[String],
    spp: Option<u32>,
    seed: u64,
    terms: bool,
    budget: BoundaryBudget,
    normalization: Normalization,
    out: &Path,
    png: &Path,
) -> Result<()> {
    check_outputs(out, png)?;
    for (k, p) in params.iter().enumerate() {
        if params[..k].contains(p) {
            bail!("--param {p} given twice");
        }
    }
    let mut scene = load_scene(scene_path)?;
    scene.select_parameters(params)?;
    let options = DiffOptions {
        render: render_options(&scene, spp, seed),
        normalization,
    };
    let (primary, secondary) = default_boundary_spp(options.render.spp);
    let budget = BoundarySpp {
        primary: budget.primary.unwrap_or(primary),
        secondary: budget.secondary.unwrap_or(secondary),
    };
    // Both integrators have both boundary terms; without a budget for either the interior term stands
    // alone and the note says so.
    let interior_only = if budget.primary == 0 && budget.secondary == 0 {
        Some("--spp-primary and --spp-secondary are 0")
    } else {
        None
    };
    let result = if interior_only.is_none() {
        let pixels = scene.camera.width as u64 * scene.camera.height as u64;
        render_derivatives_with_boundary(
            &scene,
            params.len(),
            &options,
            budget.primary as u64 * pixels,
            budget.secondary as u64 * pixels,
        )?
    } else {
        render_derivatives(&scene, params.len(), &options)?
    };
    if result.interior.len() != params.len() {
        bail!(
            "internal error: {} derivative images for {} parameters",
            result.interior.len(),
            params.len()
        );
    }
    let image = &result.image;

    let mut channels = rgb_channels("", image);
    // The derivative is the sum of the terms computed so far (no primary boundary term yet).
    let total = result.total();
    for (p, d) in params.iter().zip(&total) {
        channels.extend(rgb_channels(&format!("d.{p}."), d));
    }
    if terms {
        for (p, d) in params.iter().zip(&result.interior) {
            channels.extend(rgb_channels(&format!("d_interior.{p}."), d));
        }
        for (p, d) in params.iter().zip(&result.primary) {
            channels.extend(rgb_channels(&format!("d_primary.{p}."), d));
        }
        for (p, d) in params.iter().zip(&result.secondary) {
            channels.extend(rgb_channels(&format!("d_secondary.{p}."), d));
        }
    }
    let derivatives: Vec<&Image> = total.iter().collect();
    let (picture, scales) = derivative_picture(image, &derivatives);
    write_outputs(out, png, image, &channels, &picture)?;

    println!(
        "{}",
        terms_note(interior_only, &budget, &scene.creased_shapes())
    );
    println!(
        "rendered {}x{} and {} derivative image{} at {} spp in {:.2} s; wrote {} and {}",
        image.width,
        image.height,
        params.len(),
        if params.len() == 1 { "" } else { "s" },
        options.render.spp,
        result.stats.seconds,
        out.display(),
        png.display()
    );
    for (p, scale) in params.iter().zip(scales) {
        print_scale(p, scale);
    }
    warn_exhausted(result.stats.exhausted_rays);
    Ok(())
}

fn finite_difference(
    scene_path: &Path,
    param: &str,
    h: Option<f32>,
    spp: Option<u32>,
    seed: u64,
    out: &Path,
    png: &Path,
) -> Result<()> {
    check_outputs(out, png)?;
    let scene = load_scene(scene_path)?;
    let value = fd::parameter_value(&scene, param)?;
    let h = h.unwrap_or_else(|| fd::default_step(value));
    let options = render_options(&scene, spp, seed);
    let start = std::time::Instant::now();
    // Validates the step and both values before rendering anything.
    let derivative = fd::finite_difference(&scene, param, h, &options)?;
    let (image, stats) = integrator::render(&scene, &options);
    let seconds = start.elapsed().as_secs_f64();

    let mut channels = rgb_channels("", &image);
    channels.extend(rgb_channels(&format!("d.{param}."), &derivative));
    let (picture, scales) = derivative_picture(&image, &[&derivative]);
    write_outputs(out, png, &image, &channels, &picture)?;

    println!(
        "central differences of {param} = {value} with h = {h} (common random numbers): rendered \
         {}x{} three times at {} spp in {seconds:.2} s; wrote {} and {}",
        image.width,
        image.height,
        options.spp,
        out.display(),
        png.display()
    );
    print_scale(param, scales[0]);
    warn_exhausted(stats.exhausted_rays);
    Ok(())
}

fn compare_files(a: &Path, b: &Path, prefix: Option<&str>) -> Result<()> {
    let rows = compare::compare_files(a, b, prefix)?;
    let width = rows
        .iter()
        .map(|r| r.name.len())
        .max()
        .unwrap_or(0)
        .max("channel".len());
    println!(
        "A = {}, B = {} (the reference): rel.err = |A - B| / |B| (L2), blurred after a 5x5 box blur",
        a.display(),
        b.display()
    );
    println!(
        "{:<width$}  {:>10}  {:>12}  {:>11}  {:>11}  {:>11}  {:>11}  {:>8}",
        "channel", "rel.err", "rel.err.blur", "sum A", "sum B", "sum |A|", "sum |B|", "corr"
    );
    for r in &rows {
        let correlation = r
            .correlation
            .map_or_else(|| "n/a".to_string(), |c| format!("{c:.5}"));
        println!(
            "{:<width$}  {:>10.3e}  {:>12.3e}  {:>11.4e}  {:>11.4e}  {:>11.4e}  {:>11.4e}  {:>8}",
            r.name,
            r.relative_l2,
            r.relative_l2_blurred,
            r.sum_a,
            r.sum_b,
            r.abs_sum_a,
            r.abs_sum_b,
            correlation
        );
    }
    Ok(())
}
