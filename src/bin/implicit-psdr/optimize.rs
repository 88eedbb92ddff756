//! The `optimize` command: inverse rendering as an `OPT.json` describes it (see
//! docs/inverse-rendering.md), with its outputs in one folder.
//!
//! Everything is checked before anything is rendered (the file, the scenes, the views, the target
//! images, the parameters and grids) and before the output folder is touched. Targets rendered from a
//! scene are cached in `DIR/targets/`. While the run goes, only `progress.csv.partial` and
//! `snapshots.partial/` are written; a previous run's files are replaced at the end of a successful run
//! (every final file is written to a temporary name first, then all are renamed).

use crate::args::OptimizeArgs;
use crate::grad::{Writer, file_message, file_name, npy_writer, write_all_or_nothing};
use crate::progress_bar;
use anyhow::{Context, Result, bail};
use implicit_psdr::film::{self, Image, colormap};
use implicit_psdr::integrator::{self, RenderOptions};
use implicit_psdr::optimize::config::{OptimizeConfig, Target};
use implicit_psdr::optimize::{Iteration, Optimization, View, metrics};
use implicit_psdr::scene::{Scene, patch};
use std::io::{IsTerminal, Write as _};
use std::path::{Component, Path, PathBuf};

/// Targets rendered from a scene use seeds `seed + TARGET_SEED + k` (view `k`), apart from the seeds of
/// the iterations.
const TARGET_SEED: u64 = 0x7A46_E700_0000;
/// The current images of `views.png` use seeds `seed + PREVIEW_SEED + k` (the same at every snapshot).
const PREVIEW_SEED: u64 = 0x5EE0_0000_0000;
/// The cache key of rendered targets, beside them.
const TARGET_KEY: &str = "targets.json";
/// Size of `loss.png`'s loss panel (an IoU panel below it adds half the height).
const PLOT_SIZE: (u32, u32) = (640, 400);

pub(crate) fn optimize(args: &OptimizeArgs) -> Result<()> {
    let config_path = &args.config;
    let cfg = OptimizeConfig::load(config_path)?;
    let in_config = |e: implicit_psdr::Error| match e {
        implicit_psdr::Error::Field { .. } => anyhow::anyhow!("{}: {e}", config_path.display()),
        e => e.into(),
    };
    let out = &args.out;
    if out.exists() && !out.is_dir() {
        bail!("--out {}: is not a folder", out.display());
    }
    // The library's own checks, before anything is rendered or written.
    let (width, height) = (cfg.scene.camera.width, cfg.scene.camera.height);
    let blank = vec![Image::new(width, height); cfg.views.len()];
    let (scene, views, settings) = (&cfg.scene, &cfg.views, &cfg.settings);
    Optimization::new(scene.clone(), views.clone(), blank, settings.clone()).map_err(in_config)?;
    let grid_outputs: Vec<(String, PathBuf)> = (settings.grids.iter())
        .map(|node| (node.clone(), out.join(format!("{node}.npy"))))
        .collect();
    let finals: Vec<PathBuf> = ["views.png", "loss.png", "result.json", "progress.csv"]
        .iter()
        .map(|f| out.join(f))
        .chain(grid_outputs.iter().map(|(_, p)| p.clone()))
        .collect();
    check_outputs(&cfg, out, &finals)?;

    std::fs::create_dir_all(out)
        .with_context(|| format!("--out {}: cannot create", out.display()))?;
    let targets = match &cfg.target {
        Target::Images { images, .. } => images.clone(),
        Target::Scene { path, scene } => cached_targets(&cfg, path, scene, out)?,
    };
    let mut opt = Optimization::new(scene.clone(), views.clone(), targets, settings.clone())
        .map_err(in_config)?;

    // The run's files in progress.
    let partial = out.join("progress.csv.partial");
    let snapshots_partial = out.join("snapshots.partial");
    if snapshots_partial.is_dir() {
        std::fs::remove_dir_all(&snapshots_partial)
            .with_context(|| format!("{}: cannot remove", snapshots_partial.display()))?;
    }
    let file = std::fs::File::create(&partial)
        .with_context(|| format!("{}: cannot write", partial.display()))?;
    let mut csv = std::io::BufWriter::new(file);
    let csv_error = |e: std::io::Error| anyhow::anyhow!("{}: cannot write: {e}", partial.display());
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
    let mut header = "iteration,loss,seconds,gradient_norm".to_string();
    for name in &compared {
        if compared.len() == 1 {
            header += ",iou,chamfer";
        } else {
            header += &format!(",iou.{name},chamfer.{name}");
        }
    }
    header +=
        ",loss_pass_seconds,interior_seconds,primary_seconds,secondary_seconds,grid_edit_seconds";
    writeln!(csv, "{header}").map_err(csv_error)?;
    csv.flush().map_err(csv_error)?;

    let iterations = settings.iterations;
    let bar = IterationBar::new(iterations);
    let start = std::time::Instant::now();
    let mut losses = Vec::with_capacity(iterations as usize);
    let mut ious = Vec::with_capacity(iterations as usize);
    for _ in 0..iterations {
        let Iteration {
            index,
            loss,
            gradient_norm,
            stage_seconds: t,
            ..
        } = opt.step().map_err(in_config)?;
        let seconds = start.elapsed().as_secs_f64();
        let mut row = format!("{index},{loss},{seconds},{gradient_norm}");
        let mut iou = None;
        for name in &compared {
            let quality = match reference {
                Some(r) => metrics::shape_quality(&opt.scene, r, name).map_err(in_config)?,
                None => None,
            };
            let (i, c) = quality.unwrap_or((f64::NAN, f64::NAN));
            iou.get_or_insert(i);
            row += &format!(",{i},{c}");
        }
        row += &format!(
            ",{},{},{},{},{}",
            t.loss_pass, t.interior, t.primary, t.secondary, t.grid_edits
        );
        writeln!(csv, "{row}").map_err(csv_error)?;
        csv.flush().map_err(csv_error)?;
        losses.push(loss);
        ious.push(iou.unwrap_or(f64::NAN));
        bar.update(opt.done, loss, iou);
        if let Some(every) = cfg.snapshot_every
            && opt.done.is_multiple_of(every)
            && opt.done < iterations
        {
            std::fs::create_dir_all(&snapshots_partial)
                .with_context(|| format!("{}: cannot create", snapshots_partial.display()))?;
            let picture = views_picture(&opt, settings.spp, settings.seed).map_err(in_config)?;
            let path = snapshots_partial.join(format!("views_{:05}.png", opt.done));
            film::write_png(&path, picture.width, picture.height, &picture.rgb)?;
        }
    }
    bar.finish();
    drop(csv);
    let seconds = start.elapsed().as_secs_f64();

    // The final files, all or nothing.
    let picture = views_picture(&opt, settings.spp, settings.seed).map_err(in_config)?;
    let plot = loss_plot(&losses, &ious)?;
    let result = result_json(&cfg, &opt.scene, out, &grid_outputs)?;
    let mut files: Vec<(PathBuf, Writer)> = Vec::new();
    files.push((out.join("views.png"), png_writer(picture)));
    files.push((out.join("loss.png"), png_writer(plot)));
    for (node, path) in &grid_outputs {
        let grid = opt.scene.grid_values(node).map_err(in_config)?;
        files.push((path.clone(), npy_writer(grid)));
    }
    files.push((
        out.join("result.json"),
        Box::new(move |tmp| std::fs::write(tmp, result).map_err(|e| format!("cannot write: {e}"))),
    ));
    write_all_or_nothing(files)?;
    let progress = out.join("progress.csv");
    std::fs::rename(&partial, &progress)
        .with_context(|| format!("{}: cannot write", progress.display()))?;
    let mut written: Vec<String> = ["progress.csv", "loss.png", "views.png", "result.json"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    written.extend(grid_outputs.iter().map(|(_, p)| file_name(p)));
    if snapshots_partial.is_dir() {
        let snapshots = out.join("snapshots");
        if snapshots.is_dir() {
            std::fs::remove_dir_all(&snapshots)
                .with_context(|| format!("{}: cannot remove", snapshots.display()))?;
        }
        std::fs::rename(&snapshots_partial, &snapshots)
            .with_context(|| format!("{}: cannot write", snapshots.display()))?;
        written.push("snapshots/".into());
    }

    let mut what = Vec::new();
    if !settings.params.is_empty() {
        what.push(count(settings.params.len(), "parameter"));
    }
    if !settings.grids.is_empty() {
        what.push(count(settings.grids.len(), "grid"));
    }
    let loss_name = format!("{:?}", settings.loss).to_lowercase();
    println!(
        "optimized {} over {} ({}, {} spp): {loss_name} loss {:.4e} -> {:.4e} in {seconds:.1} s; \
         wrote {} in {}",
        what.join(" and "),
        count(iterations as usize, "iteration"),
        count(views.len(), "view"),
        settings.spp,
        losses.first().copied().unwrap_or(f64::NAN),
        losses.last().copied().unwrap_or(f64::NAN),
        written.join(", "),
        out.display()
    );
    Ok(())
}

/// `n` and `word`, plural unless `n` is 1.
fn count(n: usize, word: &str) -> String {
    format!("{n} {word}{}", if n == 1 { "" } else { "s" })
}

/// A progress bar over the iterations, with the last loss (and IoU), on stderr when it is a terminal.
struct IterationBar(Option<indicatif::ProgressBar>);

impl IterationBar {
    fn new(iterations: u32) -> Self {
        if !std::io::stderr().is_terminal() {
            return Self(None);
        }
        let bar = indicatif::ProgressBar::new(iterations as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "iteration {pos}/{len} {bar:40} {msg} {elapsed}/{eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        Self(Some(bar))
    }

    /// Shows iteration `done`'s loss and, when the target shape is known, its IoU.
    fn update(&self, done: u32, loss: f64, iou: Option<f64>) {
        if let Some(bar) = &self.0 {
            bar.set_position(done as u64);
            let iou = iou.map_or(String::new(), |i| format!(" IoU {i:.3}"));
            bar.set_message(format!("loss {loss:.4e}{iou}"));
        }
    }

    fn finish(&self) {
        if let Some(bar) = &self.0 {
            bar.finish_and_clear();
        }
    }
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
            bail!(
                "--out {}: {} would replace the input {}",
                out.display(),
                file_name(path),
                input.display()
            );
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

/// FNV-1a, 64 bits: a stable fingerprint of the target scene file for the cache key.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The target images rendered from `scene` (the file `path`) with the views, at `target_spp`: read
/// from `DIR/targets/view_K.exr` when `DIR/targets/targets.json` says they were rendered from the
/// same scene file, views, samples and seed (and they are readable and of the scene's size); else
/// rendered and cached there (the key written last, so an interrupted cache is never trusted).
fn cached_targets(
    cfg: &OptimizeConfig,
    path: &Path,
    scene: &Scene,
    out: &Path,
) -> Result<Vec<Image>> {
    let dir = out.join("targets");
    let key_path = dir.join(TARGET_KEY);
    let bytes = std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?;
    let seed = cfg.settings.seed.wrapping_add(TARGET_SEED);
    let (width, height) = (cfg.scene.camera.width, cfg.scene.camera.height);
    let views: Vec<String> = cfg.views.iter().map(|v| format!("{v:?}")).collect();
    let key = serde_json::to_string_pretty(&serde_json::json!({
        "scene_fnv1a64": format!("{:016x}", fnv1a(&bytes)),
        "views": views,
        "target_spp": cfg.target_spp,
        "seed": seed,
        "width": width,
        "height": height,
    }))?;
    let image_path = |k: usize| dir.join(format!("view_{k}.exr"));
    if std::fs::read_to_string(&key_path).is_ok_and(|k| k == key) {
        let cached: Option<Vec<Image>> = (0..cfg.views.len())
            .map(|k| {
                film::read_exr_rgb(&image_path(k))
                    .ok()
                    .filter(|i| (i.width, i.height) == (width, height))
            })
            .collect();
        if let Some(images) = cached {
            return Ok(images);
        }
    }
    let images = render_targets(scene, &cfg.views, cfg.target_spp, seed)?;
    std::fs::create_dir_all(&dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    if key_path.exists() {
        std::fs::remove_file(&key_path)
            .with_context(|| format!("{}: cannot remove", key_path.display()))?;
    }
    for (k, image) in images.iter().enumerate() {
        film::write_exr(&image_path(k), width, height, &image.rgb_channels(""))?;
    }
    let tmp = dir.join(format!(".{TARGET_KEY}.{}.tmp", std::process::id()));
    std::fs::write(&tmp, &key)
        .and_then(|_| std::fs::rename(&tmp, &key_path))
        .with_context(|| format!("{}: cannot write", key_path.display()))?;
    Ok(images)
}

/// [`implicit_psdr::optimize::render_targets`] with a progress bar: view `k` at seed `seed + k`.
fn render_targets(scene: &Scene, views: &[View], spp: u32, seed: u64) -> Result<Vec<Image>> {
    let mut images = Vec::with_capacity(views.len());
    for (k, view) in views.iter().enumerate() {
        let scene = view.apply(scene)?;
        let options = RenderOptions {
            spp,
            seed: seed.wrapping_add(k as u64),
            progress: progress_bar(),
        };
        images.push(integrator::render(&scene, &options).0);
    }
    Ok(images)
}

/// One row per view: its target beside its current image (at `spp`, seeds `seed + PREVIEW_SEED + k`),
/// rows [`colormap::PANEL_GAP`] pixels apart.
fn views_picture(opt: &Optimization, spp: u32, seed: u64) -> implicit_psdr::Result<Image> {
    let mut rows = Vec::with_capacity(opt.views.len());
    for (k, target) in opt.targets.iter().enumerate() {
        let seed = seed.wrapping_add(PREVIEW_SEED).wrapping_add(k as u64);
        let current = opt.render_view(k, spp, seed)?;
        rows.push(colormap::side_by_side(&[target.clone(), current]));
    }
    let gap = colormap::PANEL_GAP;
    let width = rows.iter().map(|r| r.width).max().unwrap_or(0);
    let height = rows.iter().map(|r| r.height).sum::<u32>() + gap * (rows.len() as u32 - 1);
    let mut picture = Image::new(width, height);
    picture.rgb.fill(colormap::GAP_COLOUR);
    let mut y0 = 0usize;
    for row in &rows {
        let n = 3 * row.width as usize;
        for y in 0..row.height as usize {
            let start = 3 * (y0 + y) * width as usize;
            picture.rgb[start..start + n].copy_from_slice(&row.rgb[y * n..(y + 1) * n]);
        }
        y0 += (row.height + gap) as usize;
    }
    Ok(picture)
}

/// A writer of a PNG of `image`.
fn png_writer(image: Image) -> Writer {
    Box::new(move |tmp| {
        film::write_png(tmp, image.width, image.height, &image.rgb).map_err(file_message)
    })
}

/// The loss against the iteration on a log scale, with light grey lines at the powers of ten and every
/// tenth of the iterations; below it, when `ious` holds finite values, the IoU on `[0, 1]` with grey lines
/// every 0.1 (no text: the numbers are in progress.csv). Non-finite and zero losses are left out.
fn loss_plot(losses: &[f64], ious: &[f64]) -> Result<Image> {
    use plotters::prelude::*;
    let (w, h) = PLOT_SIZE;
    let with_iou = ious.iter().any(|v| v.is_finite());
    let h = if with_iou { h + h / 2 } else { h };
    let mut buffer = vec![255u8; 3 * (w * h) as usize];
    let points: Vec<(f64, f64)> = (losses.iter().enumerate())
        .filter(|(_, l)| l.is_finite() && **l > 0.0)
        .map(|(i, l)| (i as f64, *l))
        .collect();
    let iou_points: Vec<(f64, f64)> = (ious.iter().enumerate())
        .filter(|(_, v)| v.is_finite())
        .map(|(i, v)| (i as f64, *v))
        .collect();
    let last = (losses.len().max(1) - 1).max(1) as f64;
    let grey = RGBColor(215, 215, 215);
    let mut draw = || -> Result<(), Box<dyn std::error::Error + '_>> {
        let root = BitMapBackend::with_buffer(&mut buffer, (w, h)).into_drawing_area();
        root.fill(&WHITE)?;
        let (top, bottom) = root.split_vertically(PLOT_SIZE.1);
        let frame = |lo: f64, hi: f64| [(0.0, lo), (last, lo), (last, hi), (0.0, hi), (0.0, lo)];
        if !points.is_empty() {
            let lo = points.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
            let hi = points.iter().map(|p| p.1).fold(0.0, f64::max);
            // At least a factor of 2 above and below, so a flat curve sits in the middle.
            let (lo, hi) = (lo.min(hi / 2.0), hi.max(lo * 2.0));
            let mut chart = ChartBuilder::on(&top)
                .margin(16)
                .build_cartesian_2d(0.0..last, (lo..hi).log_scale())?;
            let (e0, e1) = (lo.log10().ceil() as i32, hi.log10().floor() as i32);
            for e in e0..=e1 {
                let y = 10f64.powi(e);
                chart.draw_series(LineSeries::new([(0.0, y), (last, y)], grey))?;
            }
            for i in 0..=10 {
                let x = last * i as f64 / 10.0;
                chart.draw_series(LineSeries::new([(x, lo), (x, hi)], grey))?;
            }
            chart.draw_series(LineSeries::new(frame(lo, hi), BLACK))?;
            chart.draw_series(LineSeries::new(points.clone(), BLUE.stroke_width(2)))?;
        }
        if with_iou {
            let mut chart = ChartBuilder::on(&bottom)
                .margin(16)
                .build_cartesian_2d(0.0..last, 0.0..1.0)?;
            for i in 0..=10 {
                let (x, y) = (last * i as f64 / 10.0, i as f64 / 10.0);
                chart.draw_series(LineSeries::new([(x, 0.0), (x, 1.0)], grey))?;
                chart.draw_series(LineSeries::new([(0.0, y), (last, y)], grey))?;
            }
            chart.draw_series(LineSeries::new(frame(0.0, 1.0), BLACK))?;
            let green = RGBColor(0, 140, 60);
            chart.draw_series(LineSeries::new(iou_points.clone(), green.stroke_width(2)))?;
        }
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| anyhow::anyhow!("loss.png: cannot draw the plot: {e}"))?;
    let mut image = Image::new(w, h);
    for (v, b) in image.rgb.iter_mut().zip(&buffer) {
        *v = colormap::srgb_decode(*b as f32 / 255.0);
    }
    Ok(image)
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
        .map_err(|e| anyhow::anyhow!("result.json: {e}"))?;
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
