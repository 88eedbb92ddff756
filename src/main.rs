//! The `implicit-psdr` command-line tool: parses arguments, calls the library and prints.
//!
//! Every failure prints one line `error: ...` on stderr and exits with code 2 (as clap does for usage
//! errors). Everything is validated before rendering, and outputs are written last (the PNG's failure
//! removes the EXR), so a failed run leaves no partial output.

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};
use implicit_psdr::film::{self, Image, colormap};
use implicit_psdr::integrator::{
    self, BoundaryBudget, DiffOptions, Normalization, Progress, RenderOptions, RenderStats, fd,
};
use implicit_psdr::{compare, scene, sdf};
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

/// The scene and how to sample it, shared by the rendering commands.
#[derive(Args, Debug)]
struct SceneArgs {
    /// The scene file (JSON, see README).
    scene: PathBuf,
    /// Samples per pixel (default: the scene's `spp`).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    spp: Option<u32>,
    /// Seed of the deterministic sampler.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Override a parameter listed by `params` (repeatable), e.g. `--set ball.radius=0.8`.
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = assignment)]
    set: Vec<(String, f32)>,
}

/// Output files of the rendering commands; the defaults are `<command>.exr` and `<command>.png`.
#[derive(Args, Debug)]
struct OutputArgs {
    /// Output EXR file (`.exr`) [default: <command>.exr, e.g. out.exr for render].
    #[arg(long)]
    out: Option<PathBuf>,
    /// Output PNG file (`.png`) [default: <command>.png, e.g. out.png for render].
    #[arg(long)]
    png: Option<PathBuf>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a scene to an EXR (linear float32 R, G, B) and a PNG (8-bit sRGB, clamped).
    Render {
        #[command(flatten)]
        scene: SceneArgs,
        #[command(flatten)]
        outputs: OutputArgs,
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
    /// List every differentiable parameter of a scene with its value, one `name value` per line
    /// (angles in degrees, so derivatives with respect to them are per degree).
    Params {
        /// The scene file.
        scene: PathBuf,
    },
    /// Render the image and its derivatives with respect to scene parameters (forward mode) to an EXR
    /// (`R`, `G`, `B`, and `d.P.R`, `d.P.G`, `d.P.B` per parameter P) and a PNG (the image beside one
    /// colour-mapped panel per derivative).
    Diff {
        #[command(flatten)]
        scene: SceneArgs,
        /// A parameter to differentiate with respect to (repeat for several; see `params`).
        #[arg(long = "param", value_name = "P", required = true)]
        params: Vec<String>,
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
        #[arg(long, default_value = "differentiable", value_parser = normalization)]
        normalization: Normalization,
        #[command(flatten)]
        outputs: OutputArgs,
    },
    /// Central finite differences of the image with respect to one parameter, with common random numbers
    /// (the same samples at P + h and P − h), to an EXR (`R`, `G`, `B` at P, and `d.P.R|G|B`) and a PNG.
    Fd {
        #[command(flatten)]
        scene: SceneArgs,
        /// The parameter (see `params`).
        #[arg(long = "param", value_name = "P")]
        param: String,
        /// Step, a finite number > 0 (default: 0.01 · max(|P|, 1)).
        #[arg(long, allow_negative_numbers = true, value_parser = positive_f32)]
        h: Option<f32>,
        #[command(flatten)]
        outputs: OutputArgs,
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

/// `NAME=VALUE` with a finite value.
fn assignment(text: &str) -> Result<(String, f32), String> {
    let (name, value) = text.split_once('=').ok_or("expected NAME=VALUE")?;
    match value.trim().parse::<f32>() {
        Ok(v) if v.is_finite() => Ok((name.trim().to_string(), v)),
        _ => Err(format!("{value:?} is not a finite number")),
    }
}

/// `fixed` or `differentiable`.
fn normalization(text: &str) -> Result<Normalization, String> {
    text.parse()
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
        // --help and --version: clap prints them to stdout and exits with 0.
        Err(e) if !e.use_stderr() => e.exit(),
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
    match std::panic::catch_unwind(|| run(cli)) {
        Ok(Ok(())) => ExitCode::SUCCESS,
        Ok(Err(e)) => {
            // `{:#}` joins the context chain on one line: "scene.json: shapes[0].sdf.radius: ...".
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
        Err(_) => ExitCode::from(2),
    }
}

/// clap's message without its usage block, on one line: "error: unexpected argument '--sp' found".
fn one_line_usage_error(e: &clap::Error) -> String {
    let text = e.render().to_string();
    let lines: Vec<&str> = text
        .lines()
        .take_while(|l| !l.starts_with("Usage:"))
        .map(str::trim)
        .filter(|l| !(l.is_empty() || l.starts_with("tip:") || l.starts_with("For more")))
        .collect();
    lines.join(" ")
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Render { scene, outputs } => render(&scene, &outputs),
        Command::Bake {
            scene,
            shape,
            res,
            out,
        } => bake(&scene, &shape, res as usize, &out),
        Command::Params { scene } => {
            for (name, value) in load_scene(&scene)?.parameters() {
                println!("{name} {value}");
            }
            Ok(())
        }
        Command::Diff {
            scene,
            params,
            terms,
            spp_secondary,
            spp_primary,
            normalization,
            outputs,
        } => {
            let boundary = BoundaryBudget {
                primary_spp: spp_primary,
                secondary_spp: spp_secondary,
            };
            diff(&scene, &params, terms, boundary, normalization, &outputs)
        }
        Command::Fd {
            scene,
            param,
            h,
            outputs,
        } => finite_difference(&scene, &param, h, &outputs),
        Command::Compare { a, b, channel } => {
            let rows = compare::compare_files(&a, &b, channel.as_deref())?;
            print!("{}", compare::format_table(&a, &b, &rows));
            Ok(())
        }
    }
}

/// Puts the scene file in front of a field error (file errors name their file already).
fn in_file(path: &Path) -> impl Fn(implicit_psdr::Error) -> anyhow::Error + '_ {
    move |e| match e {
        implicit_psdr::Error::Field { .. } => anyhow::anyhow!("{}: {e}", path.display()),
        e => e.into(),
    }
}

fn load_scene(path: &Path) -> Result<scene::Scene> {
    scene::load(path).map_err(in_file(path))
}

/// Loads the scene with the `--set` overrides applied, and the options to render it with.
fn prepare(args: &SceneArgs) -> Result<(scene::Scene, RenderOptions)> {
    let mut scene = load_scene(&args.scene)?;
    for (name, value) in &args.set {
        scene = (scene.with_parameter(name, *value))
            .map_err(in_file(&args.scene))
            .with_context(|| format!("--set {name}={value}"))?;
    }
    let options = RenderOptions {
        spp: args.spp.unwrap_or(scene.spp),
        seed: args.seed,
        progress: progress_bar(),
    };
    Ok((scene, options))
}

/// A progress bar on stderr when it is a terminal: one bar per stage of work.
fn progress_bar() -> Progress {
    if !std::io::stderr().is_terminal() {
        return Progress::default();
    }
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg:>10} {bar:40} {pos}/{len} {elapsed}/{eta}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    Progress::new(move |stage, done, total| {
        bar.set_message(stage.to_string());
        bar.set_length(total);
        bar.set_position(done);
        if done == total {
            bar.finish_and_clear();
        }
    })
}

/// The checked output files of a rendering command called `command` (defaults `<command>.exr|png`).
fn output_paths(outputs: &OutputArgs, command: &str) -> Result<(PathBuf, PathBuf)> {
    let out = (outputs.out.clone()).unwrap_or_else(|| format!("{command}.exr").into());
    let png = (outputs.png.clone()).unwrap_or_else(|| format!("{command}.png").into());
    film::check_output_path(&out, "--out", "exr")?;
    film::check_output_path(&png, "--png", "png")?;
    Ok((out, png))
}

/// Writes the EXR `channels` and the PNG `picture`, all or nothing.
fn write_outputs(
    paths: &(PathBuf, PathBuf),
    image: &Image,
    channels: &film::Channels,
    picture: &Image,
) -> Result<()> {
    let size = (image.width, image.height);
    Ok(film::write_exr_and_png(
        &paths.0, &paths.1, size, channels, picture,
    )?)
}

/// Prints what went wrong during a render, on stderr.
fn warn(stats: &RenderStats) {
    for line in stats.warnings() {
        eprintln!("warning: {line}");
    }
}

/// Writes a derivative command's EXR `channels` and its picture (the image beside one panel per
/// derivative); returns each panel's colour scale.
fn write_derivatives(
    paths: &(PathBuf, PathBuf),
    image: &Image,
    channels: &film::Channels,
    derivatives: &[Image],
) -> Result<Vec<f32>> {
    let panels: Vec<&Image> = derivatives.iter().collect();
    let (picture, scales) = colormap::derivative_picture(image, &panels);
    write_outputs(paths, image, channels, &picture)?;
    Ok(scales)
}

fn print_scales(params: &[String], scales: &[f32]) {
    for (param, scale) in params.iter().zip(scales) {
        println!(
            "d.{param}: PNG colour scale ±{scale:.4e} (blue −, white 0, red +; 99th percentile of \
             |mean of R, G, B|)"
        );
    }
}

fn render(args: &SceneArgs, outputs: &OutputArgs) -> Result<()> {
    let paths = output_paths(outputs, "out")?;
    let (scene, options) = prepare(args)?;
    let (image, stats) = integrator::render(&scene, &options);
    write_outputs(&paths, &image, &image.rgb_channels(""), &image)?;
    println!(
        "rendered {}x{} at {} spp in {:.2} s ({:.3} M samples/s); wrote {} and {}",
        image.width,
        image.height,
        options.spp,
        stats.seconds,
        stats.samples as f64 / stats.seconds.max(1e-9) * 1e-6,
        paths.0.display(),
        paths.1.display()
    );
    warn(&stats);
    Ok(())
}

fn bake(scene_path: &Path, name: &str, res: usize, out: &Path) -> Result<()> {
    film::check_output_path(out, "--out", "npy")?;
    let scene = load_scene(scene_path)?;
    let shape =
        (scene.shape_named(name)).with_context(|| format!("--shape: {}", scene_path.display()))?;
    // The grid samples the SDF in the shape's own coordinates (before its rigid translation).
    let baked = sdf::bake_padded(&shape.sdf, res, &format!("shape {name:?}")).context("--shape")?;
    sdf::write_npy(out, &baked.grid)?;
    let [nx, ny, nz] = baked.grid.dims;
    // A scene resolves `file` relative to itself: name the file as a scene beside it would.
    let file = out.file_name().unwrap_or(out.as_os_str()).to_string_lossy();
    println!(
        "wrote {} ({nx} x {ny} x {nz} samples, x y z); in a scene file in the same folder use it as\n  {}",
        out.display(),
        baked.scene_node(&file)
    );
    Ok(())
}

fn diff(
    args: &SceneArgs,
    params: &[String],
    terms: bool,
    boundary: BoundaryBudget,
    normalization: Normalization,
    outputs: &OutputArgs,
) -> Result<()> {
    let paths = output_paths(outputs, "diff")?;
    if let Some(p) =
        (params.iter().enumerate()).find_map(|(k, p)| params[..k].contains(p).then_some(p))
    {
        bail!("--param {p} given twice");
    }
    let (mut scene, render) = prepare(args)?;
    scene
        .select_parameters(params)
        .map_err(in_file(&args.scene))?;
    let options = DiffOptions {
        render,
        normalization,
        boundary,
    };
    let result = integrator::render_derivatives(&scene, params.len(), &options)
        .map_err(in_file(&args.scene))?;
    let image = &result.image;
    let channels = result.channels(params, terms);
    let scales = write_derivatives(&paths, image, &channels, &result.total())?;

    println!("note: {}", result.note(&scene.creased_shapes()));
    println!(
        "rendered {}x{} and {} derivative image{} at {} spp in {:.2} s; wrote {} and {}",
        image.width,
        image.height,
        params.len(),
        if params.len() == 1 { "" } else { "s" },
        options.render.spp,
        result.stats.seconds,
        paths.0.display(),
        paths.1.display()
    );
    print_scales(params, &scales);
    warn(&result.stats);
    Ok(())
}

fn finite_difference(
    args: &SceneArgs,
    param: &str,
    h: Option<f32>,
    outputs: &OutputArgs,
) -> Result<()> {
    let paths = output_paths(outputs, "fd")?;
    let (scene, options) = prepare(args)?;
    let value = fd::parameter_value(&scene, param).map_err(in_file(&args.scene))?;
    let h = h.unwrap_or_else(|| fd::default_step(value));
    let start = std::time::Instant::now();
    // Validates the step and both values before rendering anything.
    let derivative = fd::finite_difference(&scene, param, h, &options)
        .map_err(in_file(&args.scene))
        .with_context(|| {
            format!(
                "--h {h} takes {param} = {value} to {} and {}",
                value + h,
                value - h
            )
        })?;
    let (image, stats) = integrator::render(&scene, &options);
    let seconds = start.elapsed().as_secs_f64();

    let mut channels = image.rgb_channels("");
    channels.extend(derivative.rgb_channels(&format!("d.{param}.")));
    let scales = write_derivatives(&paths, &image, &channels, std::slice::from_ref(&derivative))?;
    println!(
        "central differences of {param} = {value} with h = {h} (common random numbers): rendered \
         {}x{} three times at {} spp in {seconds:.2} s; wrote {} and {}",
        image.width,
        image.height,
        options.spp,
        paths.0.display(),
        paths.1.display()
    );
    print_scales(&[param.to_string()], &scales);
    warn(&stats);
    Ok(())
}
