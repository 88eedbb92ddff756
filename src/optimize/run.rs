//! A whole optimisation as an `OPT.json` describes it (see docs/inverse-rendering.md), with its outputs in
//! one folder: the library behind the `optimize` command and `implicit_psdr.optimize`.
//!
//! Everything is checked before anything is rendered (the file, the scenes, the views, the target
//! images, the parameters and grids) and before the output folder is touched. Targets rendered from a
//! scene are cached in `DIR/targets/` ([`super::targets`]). While the run goes, only
//! `progress.csv.partial` and `snapshots.partial/` are written; a previous run's files are replaced at
//! the end of a successful run (every final file is written to a temporary name first, then all are
//! renamed). Without a folder nothing is written: the run returns its rows and its scene.

use super::config::{OptimizeConfig, Target};
use super::pictures::{loss_plot, views_picture};
use super::progress::{Row, columns};
use super::targets::{cached_targets, render_targets_with, target_seed};
use super::{Iteration, Optimization, metrics, optimized_shapes};
use crate::error::{Error, Result};
use crate::film::Image;
use crate::integrator::Progress;
use crate::io::{self, Writer, file_message, file_name};
use crate::mesh::metrics::Measured;
use crate::scene::BlockKind;
use crate::scene::{Scene, patch};
use std::io::Write as _;
use std::path::{Component, Path, PathBuf};

/// Where a run stands, for a progress display.
#[derive(Clone, Copy, Debug)]
pub enum Status<'a> {
    /// The iterations start (the targets are ready).
    Start {
        /// Iterations to run.
        iterations: u32,
    },
    /// An iteration finished.
    Iteration {
        /// Its row of `progress.csv`.
        row: &'a Row,
        /// Iterations done so far.
        done: u32,
    },
    /// The iterations are done; the final files are written next.
    Done,
}

/// What a run tells its caller as it goes. Both methods do nothing by default.
pub trait Observer {
    /// Where the run stands.
    fn status(&mut self, _status: Status<'_>) {}

    /// The progress of one render of a target image (called once per view).
    fn render_progress(&self) -> Progress {
        Progress::default()
    }
}

/// An observer that shows nothing.
impl Observer for () {}

/// A finished run.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The columns of `progress.csv` ([`super::progress::columns`]).
    pub columns: Vec<String>,
    /// One row per iteration.
    pub rows: Vec<Row>,
    /// Wall time of the iterations, seconds.
    pub seconds: f64,
    /// The files and folders written in the output folder, in the order the `optimize` command
    /// lists them (`progress.csv`, `loss.png`, `views.png`, `result.json`, each grid's `NODE.npy`
    /// and `NODE.ply`, `snapshots/`); empty without a folder.
    pub written: Vec<String>,
    /// The scene at the optimised values.
    pub scene: Scene,
    /// The grids' refinements (`upsample_at`) and the step-size power each took.
    pub refinements: Vec<super::Refinement>,
}

/// Runs the optimisation `cfg`, writing its files in the folder `out` (created if missing) or nowhere
/// (`None`), and telling `observer` where it stands.
///
/// Errors are one line. An error of `cfg`'s own fields names the file `cfg.path`; one about the output
/// folder is an [`Error::File`] naming `out` itself (`out: is not a folder`, `out: result.json would
/// replace the input ...`, `out: cannot create: ...`), so that a front end can name its flag.
pub fn run(
    cfg: &OptimizeConfig,
    out: Option<&Path>,
    observer: &mut dyn Observer,
) -> Result<Outcome> {
    let in_config = |e: Error| match e {
        Error::Field { .. } => Error::file(&cfg.path, e),
        e => e,
    };
    if let Some(out) = out
        && out.exists()
        && !out.is_dir()
    {
        return Err(Error::file(out, "is not a folder"));
    }
    // The library's own checks, before anything is rendered or written.
    let (width, height) = (cfg.scene.camera.width, cfg.scene.camera.height);
    let blank = vec![Image::new(width, height); cfg.views.len()];
    let (scene, views, settings) = (&cfg.scene, &cfg.views, &cfg.settings);
    Optimization::new(scene.clone(), views.clone(), blank, settings.clone()).map_err(in_config)?;
    let grid_outputs: Vec<(String, PathBuf)> = match out {
        Some(out) => (settings.grids.iter())
            .map(|node| (node.clone(), out.join(block_file(scene, node))))
            .collect(),
        None => Vec::new(),
    };
    if let Some(out) = out {
        let finals: Vec<PathBuf> = ["views.png", "loss.png", "result.json", "progress.csv"]
            .iter()
            .map(|f| out.join(f))
            .chain(grid_outputs.iter().map(|(_, p)| p.clone()))
            .chain(
                (grid_outputs.iter())
                    .filter(|(node, _)| has_mesh(scene, node))
                    .map(|(_, p)| p.with_extension("ply")),
            )
            .collect();
        check_outputs(cfg, out, &finals)?;
        std::fs::create_dir_all(out)
            .map_err(|e| Error::file(out, format!("cannot create: {e}")))?;
    }
    let progress = || observer.render_progress();
    let targets = match (&cfg.target, out) {
        (Target::Images { images, .. }, _) => images.clone(),
        (Target::Scene { path, scene }, Some(out)) => {
            cached_targets(cfg, path, scene, out, &progress)?
        }
        (Target::Scene { scene, .. }, None) => {
            let (spp, seed) = (cfg.target_spp, target_seed(cfg));
            render_targets_with(scene, &cfg.views, spp, seed, &progress)?
        }
    };
    let mut opt = Optimization::new(scene.clone(), views.clone(), targets, settings.clone())
        .map_err(in_config)?;

    // The run's files in progress.
    let partial = out.map(|out| out.join("progress.csv.partial"));
    let snapshots_partial = out.map(|out| out.join("snapshots.partial"));
    if let Some(dir) = &snapshots_partial
        && dir.is_dir()
    {
        std::fs::remove_dir_all(dir)
            .map_err(|e| Error::file(dir, format!("cannot remove: {e}")))?;
    }
    let mut csv = match &partial {
        Some(path) => {
            let file = std::fs::File::create(path)
                .map_err(|e| Error::file(path, format!("cannot write: {e}")))?;
            Some((std::io::BufWriter::new(file), path))
        }
        None => None,
    };
    let mut write_line = |line: &str| -> Result<()> {
        if let Some((csv, path)) = &mut csv {
            let csv_error = |e: std::io::Error| Error::file(&**path, format!("cannot write: {e}"));
            writeln!(csv, "{line}").map_err(csv_error)?;
            csv.flush().map_err(csv_error)?;
        }
        Ok(())
    };
    // Shape quality columns: the optimised grids' shapes that the target scene also holds.
    let reference = match &cfg.target {
        Target::Scene { scene, .. } => Some(scene),
        Target::Images { .. } => None,
    };
    let compared: Vec<String> = reference.map_or_else(Vec::new, |r| {
        (opt.grid_shapes().into_iter())
            .filter(|name| r.shape_named(name).is_ok())
            .collect()
    });
    // The reference mesh, prepared once, and the shapes measured against it.
    let mesh_shapes = optimized_shapes(&opt.scene, &settings.params, &settings.grids);
    let reference_mesh = match &cfg.reference_mesh {
        Some(r) => Some(Measured::new(&r.mesh).map_err(|e| {
            in_config(Error::field(
                "reference_mesh",
                format!("{}: {e}", r.path.display()),
            ))
        })?),
        None => None,
    };
    let columns = columns(&compared, reference_mesh.is_some());
    write_line(&columns.join(","))?;

    let iterations = settings.iterations;
    observer.status(Status::Start { iterations });
    let start = std::time::Instant::now();
    // Time spent measuring the shapes and writing snapshots, left out of the rows' `seconds` so that
    // they count optimisation alone (what a race against another optimiser compares).
    let mut measuring = std::time::Duration::ZERO;
    let mut rows = Vec::with_capacity(iterations as usize);
    for _ in 0..iterations {
        let Iteration {
            index,
            loss,
            gradient_norm,
            stage_seconds,
            ..
        } = opt.step().map_err(in_config)?;
        let stepped = std::time::Instant::now();
        let seconds = (stepped - start - measuring).as_secs_f64();
        // The shapes are measured at the run's result: the moving average of the values.
        let measured = if compared.is_empty() && reference_mesh.is_none() {
            None
        } else {
            Some(opt.averaged_scene().map_err(in_config)?)
        };
        let mut shapes = Vec::with_capacity(compared.len());
        for name in &compared {
            let quality = match (reference, &measured) {
                (Some(r), Some(m)) => metrics::shape_quality(m, r, name).map_err(in_config)?,
                _ => None,
            };
            shapes.push(quality.unwrap_or((f64::NAN, f64::NAN)));
        }
        let mesh = (reference_mesh.as_ref().zip(measured.as_ref()))
            .map(|(reference, m)| metrics::mesh_quality(m, &mesh_shapes, reference));
        let row = Row {
            iteration: index,
            loss,
            seconds,
            gradient_norm,
            shapes,
            mesh,
            stage_seconds,
        };
        write_line(&row.csv())?;
        observer.status(Status::Iteration {
            row: &row,
            done: opt.done,
        });
        rows.push(row);
        if let Some(dir) = &snapshots_partial
            && let Some(every) = cfg.snapshot_every
            && opt.done.is_multiple_of(every)
            && opt.done < iterations
        {
            std::fs::create_dir_all(dir)
                .map_err(|e| Error::file(dir, format!("cannot create: {e}")))?;
            // Snapshots show the averaged values, as the result will.
            let averaged = opt.averaged_scene().map_err(in_config)?;
            let current = std::mem::replace(&mut opt.scene, averaged);
            let picture = views_picture(&opt, settings.spp, settings.seed).map_err(in_config);
            let path = dir.join(format!("views_{:05}.png", opt.done));
            let mut meshes = Vec::new();
            for (node, _) in grid_outputs.iter().filter(|(n, _)| has_mesh(&opt.scene, n)) {
                meshes.push((node, node_mesh(&opt, node).map_err(in_config)));
            }
            opt.scene = current;
            let picture = picture?;
            io::write_png(&path, picture.width, picture.height, &picture.rgb)?;
            for (node, mesh) in meshes {
                io::write_mesh(&dir.join(format!("{node}_{:05}.ply", opt.done)), &mesh?)?;
            }
        }
        measuring += stepped.elapsed();
    }
    observer.status(Status::Done);
    drop(csv);
    // The result: the moving average of the values (the last values without one).
    opt.scene = opt.averaged_scene().map_err(in_config)?;
    let seconds = start.elapsed().as_secs_f64();

    let mut written = Vec::new();
    if let (Some(out), Some(partial), Some(snapshots_partial)) = (out, partial, snapshots_partial) {
        written = write_finals(cfg, &opt, out, &grid_outputs, &rows)?;
        let progress = out.join("progress.csv");
        std::fs::rename(&partial, &progress)
            .map_err(|e| Error::file(&progress, format!("cannot write: {e}")))?;
        if snapshots_partial.is_dir() {
            let snapshots = out.join("snapshots");
            if snapshots.is_dir() {
                std::fs::remove_dir_all(&snapshots)
                    .map_err(|e| Error::file(&snapshots, format!("cannot remove: {e}")))?;
            }
            std::fs::rename(&snapshots_partial, &snapshots)
                .map_err(|e| Error::file(&snapshots, format!("cannot write: {e}")))?;
            written.push("snapshots/".into());
        }
    }
    Ok(Outcome {
        columns,
        rows,
        seconds,
        written,
        refinements: opt.refinements().to_vec(),
        scene: opt.scene,
    })
}

/// Writes `views.png`, `loss.png`, each optimised grid's `NODE.npy` and `NODE.ply` (the mesh of its
/// shape) and `result.json` in `out`, all or
/// nothing; returns the names of the final files in the order the command lists them (`progress.csv`
/// first: it is renamed into place next).
fn write_finals(
    cfg: &OptimizeConfig,
    opt: &Optimization,
    out: &Path,
    grid_outputs: &[(String, PathBuf)],
    rows: &[Row],
) -> Result<Vec<String>> {
    let in_config = |e: Error| match e {
        Error::Field { .. } => Error::file(&cfg.path, e),
        e => e,
    };
    let settings = &cfg.settings;
    let losses: Vec<f64> = rows.iter().map(|r| r.loss).collect();
    let ious: Vec<f64> = rows.iter().map(|r| r.iou().unwrap_or(f64::NAN)).collect();
    let picture = views_picture(opt, settings.spp, settings.seed).map_err(in_config)?;
    let plot = loss_plot(&losses, &ious)?;
    let result = result_json(cfg, &opt.scene, out, grid_outputs)?;
    let mut files: Vec<(PathBuf, Writer)> = Vec::new();
    files.push((out.join("views.png"), png_writer(picture)));
    files.push((out.join("loss.png"), png_writer(plot)));
    let blocks = opt.scene.blocks();
    for (node, path) in grid_outputs {
        let writer: Writer = match blocks.iter().find(|b| b.node == *node) {
            Some(b) if b.kind == BlockKind::Envmap => {
                let (shape, values) = (
                    b.shape.clone(),
                    opt.scene.block_values(node).map_err(in_config)?,
                );
                Box::new(move |tmp| write_envmap(tmp, &shape, &values).map_err(file_message))
            }
            Some(b) if b.kind != BlockKind::Grid => {
                let (shape, values) = (
                    b.shape.clone(),
                    opt.scene.block_values(node).map_err(in_config)?,
                );
                Box::new(move |tmp| io::write_npy_array(tmp, &shape, &values).map_err(file_message))
            }
            _ => {
                let grid = opt.scene.grid_values(node).map_err(in_config)?;
                Box::new(move |tmp| io::write_npy(tmp, &grid).map_err(file_message))
            }
        };
        files.push((path.clone(), writer));
        if has_mesh(&opt.scene, node) {
            let mesh = node_mesh(opt, node).map_err(in_config)?;
            let ply = io::bytes_writer(io::ply_bytes(&mesh));
            files.push((path.with_extension("ply"), ply));
        }
    }
    files.push((out.join("result.json"), io::bytes_writer(result)));
    io::write_all_or_nothing(files)?;
    let mut written: Vec<String> = ["progress.csv", "loss.png", "views.png", "result.json"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    for (node, p) in grid_outputs {
        written.push(file_name(p));
        if has_mesh(&opt.scene, node) {
            written.push(file_name(&p.with_extension("ply")));
        }
    }
    Ok(written)
}

/// The output file of optimised block `node`: `NODE.exr` for an environment map (the format its
/// `file` reads), `NODE.npy` otherwise.
pub(crate) fn block_file(scene: &Scene, node: &str) -> String {
    let envmap = scene.block_kind(node) == Some(BlockKind::Envmap);
    format!("{node}.{}", if envmap { "exr" } else { "npy" })
}

/// Writes an environment map's values (shape `[H, W, 3]`) as an RGB EXR.
fn write_envmap(path: &Path, shape: &[usize], values: &[f32]) -> Result<()> {
    let (h, w) = (shape[0], shape[1]);
    let channels: Vec<(String, Vec<f32>)> = (["R", "G", "B"].iter().enumerate())
        .map(|(c, n)| {
            (
                n.to_string(),
                values.iter().skip(c).step_by(3).copied().collect(),
            )
        })
        .collect();
    io::write_exr(path, w as u32, h as u32, &channels)
}

/// Whether the optimised block `node` is a grid, whose shape's mesh the run writes (a volume
/// texture has none).
fn has_mesh(scene: &Scene, node: &str) -> bool {
    scene.texture_range(node).is_none()
}

/// The surface of the shape holding grid `node`, as the `mesh` command extracts it (scene
/// coordinates, [`crate::mesh::DEFAULT_RESOLUTION`]).
fn node_mesh(opt: &Optimization, node: &str) -> Result<crate::mesh::TriangleMesh> {
    let blocks = opt.scene.grid_blocks();
    let block = (blocks.iter().find(|b| b.node == node))
        .ok_or_else(|| Error::field("optimize.grids", format!("no grid {node:?}")))?;
    let shape = opt.scene.shape_named(&block.shape_name)?;
    crate::mesh::extract_shape(shape, crate::mesh::DEFAULT_RESOLUTION)
}

/// A writer of a PNG of `image`.
fn png_writer(image: Image) -> Writer {
    Box::new(move |tmp| {
        io::write_png(tmp, image.width, image.height, &image.rgb).map_err(file_message)
    })
}

/// Refuses an output folder where a final output would replace one of the run's inputs (the OPT file,
/// the scenes, the target images, the scene's grid files).
fn check_outputs(cfg: &OptimizeConfig, out: &Path, finals: &[PathBuf]) -> Result<()> {
    let mut inputs = vec![cfg.path.clone(), cfg.scene_path.clone()];
    match &cfg.target {
        Target::Scene { path, .. } => inputs.push(path.clone()),
        Target::Images { paths, .. } => inputs.extend(paths.iter().cloned()),
    }
    let scene_dir = parent(&cfg.scene_path);
    for (_, file) in patch::grid_files(&cfg.scene_json)? {
        inputs.push(scene_dir.join(file));
    }
    let inputs: Vec<PathBuf> = inputs
        .iter()
        .filter_map(|p| p.canonicalize().ok())
        .collect();
    for path in finals {
        if let Ok(p) = path.canonicalize()
            && let Some(input) = inputs.iter().find(|i| **i == p)
        {
            return Err(Error::file(
                out,
                format!(
                    "{} would replace the input {}",
                    file_name(path),
                    input.display()
                ),
            ));
        }
    }
    Ok(())
}

/// The folder of `path` (`.` for a bare file name).
fn parent(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// The text of result.json: the starting scene's document with the optimised values, each optimised
/// grid's `file` pointing at its `NODE.npy` and every other grid's at its original file as seen from
/// `out` (relative if the two share a root, else absolute).
fn result_json(
    cfg: &OptimizeConfig,
    scene: &Scene,
    out: &Path,
    grid_outputs: &[(String, PathBuf)],
) -> Result<String> {
    let scene_dir = parent(&cfg.scene_path);
    let mut files: Vec<(String, String)> = Vec::new();
    for (node, file) in patch::grid_files(&cfg.scene_json)? {
        let new = match grid_outputs.iter().find(|(n, _)| *n == node) {
            Some((_, path)) => file_name(path),
            None => relative_to(out, &scene_dir.join(&file))
                .to_string_lossy()
                .into_owned(),
        };
        files.push((node, new));
    }
    let doc = patch::patched_scene_json(&cfg.scene_json, scene, &files)
        .map_err(|e| Error::file("result.json", e))?;
    Ok(patch::scene_text(&doc))
}

/// `path` as seen from the folder `dir`: relative when both resolve (`../scenes/blob.npy`), else
/// `path` made absolute.
fn relative_to(dir: &Path, path: &Path) -> PathBuf {
    let (Ok(dir), Ok(path)) = (dir.canonicalize(), path.canonicalize()) else {
        return std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    };
    let a: Vec<Component> = dir.components().collect();
    let b: Vec<Component> = path.components().collect();
    let common = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
    // Sharing only the root: the absolute path says more than a climb to it.
    if common <= 1 {
        return path;
    }
    let mut out = PathBuf::new();
    for _ in common..a.len() {
        out.push("..");
    }
    for c in &b[common..] {
        out.push(c);
    }
    out
}
