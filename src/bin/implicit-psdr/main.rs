//! The `implicit-psdr` command-line tool: parses arguments, calls the library and prints.
//!
//! Every failure prints one line `error: ...` on stderr and exits with code 2 (as clap does for usage
//! errors). Everything is validated before rendering, and outputs are written last (the PNG's failure
//! removes the EXR; `grad` writes its JSON and `.npy` files to temporary names and renames them only
//! when all are written), so a failed run leaves no partial output.

mod args;
mod grad;
mod optimize;
mod report;

use anyhow::{Context, Result};
use args::{BakeArgs, Cli, Command, DiffArgs, EstimatorArgs, FdArgs, OutputArgs, SceneArgs};
use clap::Parser;
use implicit_psdr::film::{self, Image, colormap};
use implicit_psdr::integrator::{
    self, BoundaryBudget, DiffOptions, Progress, RenderOptions, RenderStats, fd,
};
use implicit_psdr::{compare, scene, sdf};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
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
        Command::Bake(args) => bake(&args),
        Command::Params { scene } => {
            print!("{}", grad::parameter_list(&load_scene(&scene)?));
            Ok(())
        }
        Command::Diff(args) => diff(&args),
        Command::Grad(args) => grad::grad(&args),
        Command::Fd(args) => finite_difference(&args),
        Command::Optimize(args) => optimize::optimize(&args),
        Command::Report(args) => report::report(&args),
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

pub(crate) fn load_scene(path: &Path) -> Result<scene::Scene> {
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

/// The derivative options of `diff` and `grad`: the image's samples and the estimator's settings.
fn diff_options(render: RenderOptions, args: &EstimatorArgs) -> DiffOptions {
    DiffOptions {
        render,
        normalization: args.normalization,
        boundary: BoundaryBudget {
            primary_spp: args.spp_primary,
            secondary_spp: args.spp_secondary,
        },
    }
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

/// Prints what went wrong during a render, on stderr.
fn warn(stats: &RenderStats) {
    for line in stats.warnings() {
        eprintln!("warning: {line}");
    }
}

/// Writes a derivative command's EXR `channels` and its picture (the image beside one panel per
/// derivative of `params`), all or nothing; prints each panel's colour scale.
fn write_derivatives(
    paths: &(PathBuf, PathBuf),
    image: &Image,
    channels: &film::Channels,
    params: &[String],
    derivatives: &[Image],
) -> Result<()> {
    let panels: Vec<&Image> = derivatives.iter().collect();
    let (picture, scales) = colormap::derivative_picture(image, &panels);
    let size = (image.width, image.height);
    film::write_exr_and_png(&paths.0, &paths.1, size, channels, &picture)?;
    for (param, scale) in params.iter().zip(scales) {
        println!(
            "d.{param}: PNG colour scale ±{scale:.4e} (blue −, white 0, red +; 99th percentile of \
             |mean of R, G, B|)"
        );
    }
    Ok(())
}

fn render(args: &SceneArgs, outputs: &OutputArgs) -> Result<()> {
    let (out, png) = output_paths(outputs, "out")?;
    let (scene, options) = prepare(args)?;
    let (image, stats) = integrator::render(&scene, &options);
    let size = (image.width, image.height);
    film::write_exr_and_png(&out, &png, size, &image.rgb_channels(""), &image)?;
    println!(
        "rendered {}x{} at {} spp in {:.2} s ({:.3} M samples/s); wrote {} and {}",
        image.width,
        image.height,
        options.spp,
        stats.seconds,
        stats.samples as f64 / stats.seconds.max(1e-9) * 1e-6,
        out.display(),
        png.display()
    );
    warn(&stats);
    Ok(())
}

fn bake(args: &BakeArgs) -> Result<()> {
    let (out, name) = (&args.out, &args.shape);
    film::check_output_path(out, "--out", "npy")?;
    let scene = load_scene(&args.scene)?;
    let shape =
        (scene.shape_named(name)).with_context(|| format!("--shape: {}", args.scene.display()))?;
    // The grid samples the SDF in the shape's own coordinates (before its rigid translation).
    let baked = sdf::bake_padded(&shape.sdf, args.res as usize, &format!("shape {name:?}"))
        .context("--shape")?;
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

fn diff(args: &DiffArgs) -> Result<()> {
    let paths = output_paths(&args.outputs, "diff")?;
    let (mut scene, render) = prepare(&args.scene)?;
    let file = in_file(&args.scene.scene);
    scene.select_parameters(&args.params).map_err(&file)?;
    // Grid directions take the slots after the named parameters, and their blocks' names.
    let mut names = args.params.clone();
    names.extend(
        grad::select_directions(&mut scene, names.len(), &args.grid_directions).map_err(&file)?,
    );
    scene.velocity = args.estimator.velocity_field;
    let options = diff_options(render, &args.estimator);
    let count = names.len();
    let result = integrator::render_derivatives(&scene, count, &options).map_err(&file)?;
    let image = &result.image;
    println!("note: {}", result.note(&scene.unsampled_creases()));
    let channels = result.channels(&names, args.terms);
    write_derivatives(&paths, image, &channels, &names, &result.total())?;
    println!(
        "rendered {}x{} and {count} derivative image{} at {} spp in {:.2} s; wrote {} and {}",
        image.width,
        image.height,
        if count == 1 { "" } else { "s" },
        options.render.spp,
        result.stats.seconds,
        paths.0.display(),
        paths.1.display()
    );
    warn(&result.stats);
    Ok(())
}

fn finite_difference(args: &FdArgs) -> Result<()> {
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
    println!(
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
    );
    warn(&result.stats);
    Ok(())
}
