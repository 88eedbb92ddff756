//! The `grad` command: the loss of the image against a target and its reverse-mode gradient, written
//! as grad.json and one `.npy` per grid.

use crate::cli::args::GradArgs;
use crate::cli::{diff_options, in_file, prepare, warn};
use crate::film::Image;
use crate::integrator::diff::terms_note;
use crate::integrator::{GradientLayout, loss_gradient};
use crate::io::{self, Writer, file_message, file_name};
use crate::scene::{BlockKind, GridBlock};
use anyhow::{Result, bail};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Reads the target image (channels `R`, `G`, `B`, finite) and checks its size against the scene's.
fn read_target(path: &Path, (width, height): (u32, u32)) -> Result<Image> {
    let image = io::read_exr_rgb(path)?;
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

pub(crate) fn grad(args: &GradArgs) -> Result<()> {
    let out = &args.out;
    io::check_output_path(out, "--out", "json")?;
    let scene_path = &args.scene.scene;
    if let (Ok(a), Ok(b)) = (out.canonicalize(), scene_path.canonicalize())
        && a == b
    {
        bail!("--out {}: is the scene file", out.display());
    }
    let (scene, render) = prepare(&args.scene)?;
    let file = in_file(scene_path);
    let target = read_target(&args.target, (scene.camera.width, scene.camera.height))?;
    let grids: Vec<String> = args.grids.iter().map(|g| scene.grid_node(g)).collect();
    let layout = GradientLayout::select(&scene, &args.params, &grids).map_err(&file)?;
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
    outln!("note: {note}")?;

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
        let values: Vec<f32> = gradient[*first..first + block.len()]
            .iter()
            .map(|&g| g as f32)
            .collect();
        let what = format!("the gradient of {}", block.name);
        if let Some(i) = values.iter().position(|v: &f32| !v.is_finite()) {
            bail!(
                "{what}: value {i} is not finite ({}): not written",
                values[i]
            );
        }
        let shape = block.shape.clone();
        let writer: Writer =
            Box::new(move |tmp| io::write_npy_array(tmp, &shape, &values).map_err(file_message));
        files.push((path.clone(), writer));
    }
    files.push((out.clone(), io::bytes_writer(json)));
    io::write_all_or_nothing(files)?;

    let mut wrt = Vec::new();
    if !params.is_empty() {
        wrt.push(count(params.len(), "parameter"));
    }
    if !layout.grids.is_empty() {
        let values: usize = layout.grids.iter().map(|(b, _)| b.len()).sum();
        let kinds = |kind: BlockKind| layout.grids.iter().filter(|(b, _)| b.kind == kind).count();
        let mut of = Vec::new();
        for kind in [BlockKind::Grid, BlockKind::Volume, BlockKind::Envmap] {
            if kinds(kind) > 0 {
                of.push(count(kinds(kind), kind.describe()));
            }
        }
        wrt.push(format!("{values} values of {}", join_and(&of)));
    }
    let written: Vec<String> = std::iter::once(out)
        .chain(&grid_paths)
        .map(|p| p.display().to_string())
        .collect();
    let loss_name = format!("{:?}", args.loss).to_lowercase();
    outln!(
        "{loss_name} loss {} against {} (seed {seed}); gradient with respect to {} (seed {}) at \
         {spp} spp in {:.2} s; wrote {}",
        result.loss,
        args.target.display(),
        join_and(&wrt),
        crate::integrator::gradient::adjoint_seed(seed),
        result.gradient.stats.seconds,
        join_and(&written)
    )?;
    warn(&result.gradient.stats);
    Ok(())
}
