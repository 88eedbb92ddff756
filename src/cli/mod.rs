//! The `implicit-psdr` command-line tool: parses arguments, calls the library and prints. It lives
//! in the library so that the binary (`src/bin/implicit-psdr`) and the Python package's console
//! script run the same code: both call [`main`].
//!
//! Every failure prints one line `error: ...` on stderr and exits with code 2 (as clap does for usage
//! errors). Everything is validated before rendering, and outputs are written last (the PNG's failure
//! removes the EXR; `grad` writes its JSON and `.npy` files to temporary names and renames them only
//! when all are written), so a failed run leaves no partial output.

//!
//! What a command reports goes to stdout through `outln!`: a reader that stops reading
//! (`implicit-psdr params scene.json | head`) silences the rest of the report, and the command
//! finishes its work and exits with 0.

/// `println!` to stdout as a `Result` (see [`write_stdout`]).
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::cli::write_stdout(format_args!("{}\n", format_args!($($arg)*)))
    };
}

mod args;
mod bake;
mod diff;
mod fd;
mod grad;
mod mesh;
mod optimize;
mod params;
mod records;
mod render;
mod report;

use crate::film::{Image, figure};
use crate::integrator::{BoundaryBudget, DiffOptions, Progress, RenderOptions, RenderStats};
use crate::scene::settings;
use crate::{compare, io, scene};
use anyhow::{Context, Result};
use args::{Cli, Command, EstimatorArgs, OutputArgs, SceneArgs};
use clap::Parser;
use std::io::{IsTerminal, Write as _};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

/// Runs the command line `args` (the program's name first, as [`std::env::args_os`] gives it) and
/// returns the process's exit code: 0, or 2 after one line `error: ...` on stderr.
///
/// The `implicit-psdr` binary and the Python package's `implicit-psdr` command both call this, so the
/// tool is the same whichever way it was installed.
pub fn main<I, T>(args: I) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        // --help and --version: clap prints them to stdout, and they succeed.
        Err(e) if !e.use_stderr() => {
            let _ = e.print();
            return 0;
        }
        Err(e) => {
            eprintln!("{} (see --help)", one_line_usage_error(&e));
            return 2;
        }
    };
    // A panic is a bug, but the contract of the tool still holds: one line on stderr (the first panic
    // only: rayon workers may panic together), exit code 2, no output file (outputs are written last).
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(|info| {
        static ONCE: std::sync::Once = std::sync::Once::new();
        ONCE.call_once(|| {
            let message = info.to_string().replace('\n', " ");
            eprintln!("error: internal error (please report): {message}");
        });
    }));
    let code = match std::panic::catch_unwind(|| run(cli)) {
        Ok(Ok(())) => 0,
        Ok(Err(e)) => {
            // `{:#}` joins the context chain on one line: "scene.json: shapes[0].sdf.radius: ...".
            eprintln!("error: {e:#}");
            2
        }
        Err(_) => 2,
    };
    std::panic::set_hook(previous);
    code
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
        Command::Render { scene, outputs } => render::render(&scene, &outputs),
        Command::Bake(args) => bake::bake(&args),
        Command::Mesh(args) => mesh::mesh(&args),
        Command::Params { scene } => params::params(&scene),
        Command::Diff(args) => diff::diff(&args),
        Command::Grad(args) => grad::grad(&args),
        Command::Fd(args) => fd::finite_difference(&args),
        Command::Optimize(args) => optimize::optimize(&args),
        Command::Report(args) => report::report(&args),
        Command::Compare { a, b, channel } => {
            let rows = compare::compare_files(&a, &b, channel.as_deref())?;
            write_stdout(format_args!("{}", compare::format_table(&a, &b, &rows)))
        }
    }
}

/// Writes a command's report to stdout. Once the reader has gone away (a closed pipe), the rest of
/// the report is dropped and the command goes on with its work: what it writes to files does not
/// depend on who reads its report. Any other failure to write is an error.
fn write_stdout(text: std::fmt::Arguments<'_>) -> Result<()> {
    static CLOSED: AtomicBool = AtomicBool::new(false);
    if CLOSED.load(Ordering::Relaxed) {
        return Ok(());
    }
    let mut stdout = std::io::stdout().lock();
    match stdout.write_fmt(text).and_then(|()| stdout.flush()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {
            CLOSED.store(true, Ordering::Relaxed);
            Ok(())
        }
        result => result.context("stdout"),
    }
}

/// The command-line option behind each argument of the library that its errors name.
const OPTIONS: &[(&str, &str)] = &[
    ("params", "--param"),
    ("grids", "--grid"),
    ("grid_directions", "--grid-direction"),
    ("target", "--target"),
    ("budget", "--budget"),
    ("estimators", "--estimators"),
];

/// A library error in the command line's words: the option in place of the library argument it
/// sets, and where to find the parameter names.
pub(crate) fn flagged(e: crate::Error) -> crate::Error {
    let crate::Error::Field { field, message } = e else {
        return e;
    };
    match OPTIONS.iter().find(|(argument, _)| *argument == field) {
        Some((argument, option)) => {
            let hint = *argument == "params" && message.starts_with("no parameter");
            let message = match hint {
                true => format!("{message} (run `implicit-psdr params SCENE.json` to list them)"),
                false => message,
            };
            crate::Error::field(*option, message)
        }
        None => crate::Error::Field { field, message },
    }
}

/// Puts the scene file in front of a field error (file errors name their file already), in the
/// command line's words ([`flagged`]).
fn in_file(path: &Path) -> impl Fn(crate::Error) -> anyhow::Error + '_ {
    move |e| match flagged(e) {
        e @ crate::Error::Field { .. } => anyhow::anyhow!("{}: {e}", path.display()),
        e => e.into(),
    }
}

pub(crate) fn load_scene(path: &Path) -> Result<scene::Scene> {
    scene::load(path).map_err(in_file(path))
}

/// Loads the scene with the `--set` overrides applied (settings before parameters), and the options
/// to render it with.
fn prepare(args: &SceneArgs) -> Result<(scene::Scene, RenderOptions)> {
    let (settings, parameters): (Vec<_>, Vec<_>) =
        (args.set.iter().cloned()).partition(|(name, _)| settings::is_setting(name));
    let mut scene = match settings.as_slice() {
        [] => load_scene(&args.scene)?,
        _ => settings::load_with_settings(&args.scene, &settings)
            .map_err(in_file(&args.scene))
            .with_context(|| {
                let set: Vec<String> = (settings.iter()).map(|(n, v)| format!("{n}={v}")).collect();
                format!("--set {}", set.join(" --set "))
            })?,
    };
    for (name, value) in &parameters {
        // Checked to be a finite number when the arguments were parsed.
        let number: f32 = value.parse()?;
        scene = (scene.with_parameter(name, number))
            .map_err(in_file(&args.scene))
            .with_context(|| format!("--set {name}={value}"))?;
    }
    for line in scene.reach_warnings() {
        eprintln!("warning: {line}");
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
        velocity: args.velocity_field,
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
    io::check_output_path(&out, "--out", "exr")?;
    io::check_output_path(&png, "--png", "png")?;
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
    channels: &io::Channels,
    params: &[String],
    derivatives: &[Image],
) -> Result<()> {
    let panels: Vec<&Image> = derivatives.iter().collect();
    let (picture, scales) = figure::derivative_figure(image, params, &panels)?;
    let size = (image.width, image.height);
    io::write_exr_and_png(&paths.0, &paths.1, size, channels, &picture)?;
    for (param, scale) in params.iter().zip(scales) {
        outln!(
            "d.{param}: PNG colour scale ±{scale:.4e} (blue −, white 0, red +; 99th percentile of \
             |mean of R, G, B|)"
        )?;
    }
    Ok(())
}
