//! The `grad` command (the loss of the image against a target and its reverse-mode gradient), and the
//! grid-value blocks that `params` lists and `diff --grid-direction` selects.

use crate::args::GradArgs;
use crate::{diff_options, in_file, prepare, warn};
use anyhow::{Context, Result, bail};
use implicit_psdr::film::{self, Image};
use implicit_psdr::integrator::diff::terms_note;
use implicit_psdr::integrator::{GradientLayout, loss_gradient};
use implicit_psdr::scene::{GridBlock, GridDirection, ParameterEntry, Scene};
use implicit_psdr::sdf::{self, GridData};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// What `params` prints: every parameter as `name value`, and each grid node's values once, as
/// `NODE.values [nz, ny, nx] (N values; ...)`, after the node's `level` (or at the end).
pub(crate) fn parameter_list(scene: &Scene) -> String {
    let mut out = String::new();
    for entry in scene.parameter_entries() {
        let _ = match entry {
            ParameterEntry::Value(name, value) => writeln!(out, "{name} {value}"),
            ParameterEntry::Grid(b) => {
                let node = &b.node;
                writeln!(
                    out,
                    "{} [{}, {}, {}] ({} values; select with --grid {node} or --grid-direction \
                     {node}=U.npy)",
                    b.name,
                    b.shape[0],
                    b.shape[1],
                    b.shape[2],
                    b.len()
                )
            }
        };
    }
    out
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
        let u = sdf::read_npy(file)?;
        let [nx, ny, nz] = u.dims;
        read.push(GridDirection {
            node: node.clone(),
            shape: [nz, ny, nx],
            values: Arc::new(u.values),
            source: file.display().to_string(),
        });
    }
    scene.select_grid_directions(first_slot, "--grid-direction", &read)
}

/// Reads the target image (channels `R`, `G`, `B`, finite) and checks its size against the scene's.
fn read_target(path: &Path, (width, height): (u32, u32)) -> Result<Image> {
    let image = film::read_exr_rgb(path)?;
    let (w, h) = (image.width, image.height);
    if (w, h) != (width, height) {
        bail!(
            "{}: the target is {w}x{h}, the scene's image {width}x{height}",
            path.display()
        );
    }
    Ok(image)
}

/// Where `grad --out out` writes the gradient of `block`: `<stem of out>.<node>.values.npy` beside it.
fn grid_output(out: &Path, block: &GridBlock) -> PathBuf {
    let stem = out.file_stem().unwrap_or_default().to_string_lossy();
    out.with_file_name(format!("{stem}.{}.npy", block.name))
}

/// The file name of `path` (as grad.json refers to the files beside it).
pub(crate) fn file_name(path: &Path) -> String {
    let name = path.file_name().unwrap_or(path.as_os_str());
    name.to_string_lossy().into_owned()
}

/// `items` joined as "a", "a and b", "a, b and c".
fn join_and(items: &[String]) -> String {
    match items {
        [] => String::new(),
        [one] => one.clone(),
        [rest @ .., last] => format!("{} and {last}", rest.join(", ")),
    }
}

/// `n` and `word`, plural unless `n` is 1.
fn count(n: usize, word: &str) -> String {
    format!("{n} {word}{}", if n == 1 { "" } else { "s" })
}

/// The JSON number of `value`; an error naming `what` if it is not finite (JSON has no NaN).
fn json_number(value: f64, what: &str) -> Result<String> {
    if !value.is_finite() {
        bail!("the {what} is {value}: not written");
    }
    Ok(serde_json::to_string(&value)?)
}

/// The text of grad.json: `loss`, `spp`, `seed`, then `params` and `grids` in the order given.
fn gradient_json(
    loss: f64,
    spp: u32,
    seed: u64,
    params: &[(String, f64)],
    grids: &[(String, String)],
) -> Result<String> {
    let quote = |s: &str| serde_json::to_string(s).expect("a string serialises");
    let mut text = format!(
        "{{\n  \"loss\": {},\n  \"spp\": {spp},\n  \"seed\": {seed},\n  \"params\": {{",
        json_number(loss, "loss")?
    );
    for (i, (name, g)) in params.iter().enumerate() {
        let value = json_number(*g, &format!("gradient of {name}"))?;
        let comma = if i == 0 { "" } else { "," };
        let _ = write!(text, "{comma}\n    {}: {value}", quote(name));
    }
    text += if params.is_empty() {
        "},\n"
    } else {
        "\n  },\n"
    };
    text += "  \"grids\": {";
    for (i, (node, file)) in grids.iter().enumerate() {
        let comma = if i == 0 { "" } else { "," };
        let _ = write!(text, "{comma}\n    {}: {}", quote(node), quote(file));
    }
    text += if grids.is_empty() {
        "}\n}\n"
    } else {
        "\n  }\n}\n"
    };
    Ok(text)
}

/// A fresh temporary name beside `path` (hidden, ending in `.tmp`).
fn temporary(path: &Path) -> PathBuf {
    static COUNTER: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let unique = COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let pid = std::process::id();
    path.with_file_name(format!(".{}.{pid}.{unique}.tmp", file_name(path)))
}

/// Writes a file to the path given, or says why not (one line, without the path).
pub(crate) type Writer = Box<dyn FnOnce(&Path) -> Result<(), String>>;

/// A writer's message for a library error: a file error's own message (the caller names the file).
pub(crate) fn file_message(e: implicit_psdr::Error) -> String {
    match e {
        implicit_psdr::Error::File { message, .. } => message,
        e => e.to_string(),
    }
}

/// The [`Writer`] of a grid as a float32 `.npy`.
pub(crate) fn npy_writer(grid: impl std::borrow::Borrow<GridData> + 'static) -> Writer {
    Box::new(move |tmp| sdf::write_npy(tmp, grid.borrow()).map_err(file_message))
}

/// Writes every file of `files` (`(path, writer)`) to a temporary name, then renames them all; on any
/// failure removes what it wrote, so either every file is written or none.
pub(crate) fn write_all_or_nothing(files: Vec<(PathBuf, Writer)>) -> Result<()> {
    let mut temporaries = Vec::new();
    let mut renamed = Vec::new();
    let mut result = Ok(());
    for (path, write) in files {
        let tmp = temporary(&path);
        temporaries.push((tmp.clone(), path.clone()));
        result = write(&tmp).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()));
        if result.is_err() {
            break;
        }
    }
    if result.is_ok() {
        for (tmp, path) in &temporaries {
            result = (std::fs::rename(tmp, path))
                .with_context(|| format!("{}: cannot write", path.display()));
            if result.is_err() {
                break;
            }
            renamed.push(path.clone());
        }
    }
    if result.is_err() {
        for (tmp, _) in &temporaries {
            let _ = std::fs::remove_file(tmp);
        }
        for path in &renamed {
            let _ = std::fs::remove_file(path);
        }
    }
    result
}

pub(crate) fn grad(args: &GradArgs) -> Result<()> {
    let out = &args.out;
    film::check_output_path(out, "--out", "json")?;
    let scene_path = &args.scene.scene;
    if let (Ok(a), Ok(b)) = (out.canonicalize(), scene_path.canonicalize())
        && a == b
    {
        bail!("--out {}: is the scene file", out.display());
    }
    let (mut scene, render) = prepare(&args.scene)?;
    let file = in_file(scene_path);
    let target = read_target(&args.target, (scene.camera.width, scene.camera.height))?;
    let grids: Vec<String> = args.grids.iter().map(|g| scene.grid_node(g)).collect();
    let layout = GradientLayout::select(&mut scene, &args.params, &grids).map_err(&file)?;
    let grid_paths: Vec<PathBuf> = (layout.grids.iter())
        .map(|(block, _)| grid_output(out, block))
        .collect();
    for path in &grid_paths {
        if path.is_dir() {
            bail!(
                "{}: is a folder (grad writes the gradient of a grid there)",
                path.display()
            );
        }
    }
    scene.velocity = args.estimator.velocity_field;
    let options = diff_options(render, &args.estimator);
    let result = loss_gradient(&scene, &layout, &target, args.loss, &options).map_err(&file)?;
    let gradient = result.gradient.total();
    let (primary, secondary) = options.boundary.totals(&scene, options.render.spp);
    let note = terms_note(
        ("the gradient holds", "the gradient"),
        primary > 0,
        secondary > 0,
        &scene.unsampled_creases(),
    );
    println!("note: {note}");

    let params: Vec<(String, f64)> = (layout.params.iter().cloned())
        .zip(gradient.iter().copied())
        .collect();
    let grid_files: Vec<(String, String)> = (layout.grids.iter().zip(&grid_paths))
        .map(|((block, _), path)| (block.node.clone(), file_name(path)))
        .collect();
    let (spp, seed) = (options.render.spp, options.render.seed);
    let json = gradient_json(result.loss, spp, seed, &params, &grid_files)?;
    let mut files: Vec<(PathBuf, Writer)> = Vec::new();
    for ((block, first), path) in layout.grids.iter().zip(&grid_paths) {
        let values = gradient[*first..first + block.len()]
            .iter()
            .map(|&g| g as f32)
            .collect();
        let [nz, ny, nx] = block.shape;
        let what = format!("the gradient of {}", block.name);
        let grid = GridData::new([nx, ny, nz], values, &what)?;
        files.push((path.clone(), npy_writer(grid)));
    }
    files.push((
        out.clone(),
        Box::new(move |tmp| std::fs::write(tmp, json).map_err(|e| format!("cannot write: {e}"))),
    ));
    write_all_or_nothing(files)?;

    let mut wrt = Vec::new();
    if !params.is_empty() {
        wrt.push(count(params.len(), "parameter"));
    }
    if !layout.grids.is_empty() {
        let values: usize = layout.grids.iter().map(|(b, _)| b.len()).sum();
        wrt.push(format!(
            "{values} values of {}",
            count(layout.grids.len(), "grid")
        ));
    }
    let written: Vec<String> = std::iter::once(out)
        .chain(&grid_paths)
        .map(|p| p.display().to_string())
        .collect();
    let loss_name = format!("{:?}", args.loss).to_lowercase();
    println!(
        "{loss_name} loss {} against {} (seed {seed}); gradient with respect to {} (seed {}) at \
         {spp} spp in {:.2} s; wrote {}",
        result.loss,
        args.target.display(),
        join_and(&wrt),
        implicit_psdr::integrator::gradient::adjoint_seed(seed),
        result.gradient.stats.seconds,
        join_and(&written)
    );
    warn(&result.gradient.stats);
    Ok(())
}
