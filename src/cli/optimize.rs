//! The `optimize` command: inverse rendering as an `OPT.json` describes it (see
//! docs/inverse-rendering.md), with its outputs in one folder. The run is the library's
//! ([`crate::optimize::run`]); this shows progress and prints.

use crate::cli::args::OptimizeArgs;
use crate::cli::progress_bar;
use crate::cli::records::Records;
use crate::integrator::Progress;
use crate::optimize::config::OptimizeConfig;
use crate::optimize::{self, Observer, Outcome, Status};
use anyhow::Result;
use std::path::Path;

pub(crate) fn optimize(args: &OptimizeArgs) -> Result<()> {
    let cfg = OptimizeConfig::load(&args.config)?;
    for line in cfg.reach_warnings() {
        eprintln!("warning: {line}");
    }
    let out = &args.out;
    let mut bars = Bars {
        bar: None,
        records: None,
        iterations: 0,
    };
    let outcome = optimize::run(&cfg, Some(out), &mut bars).map_err(|e| match e {
        // The library names the folder; the command names its flag too.
        crate::Error::File { ref path, .. } if *path == out.display().to_string() => {
            anyhow::anyhow!("--out {e}")
        }
        e => e.into(),
    })?;

    let settings = &cfg.settings;
    let mut what = Vec::new();
    if !settings.params.is_empty() {
        what.push(count(settings.params.len(), "parameter"));
    }
    // optimize.grids names value blocks of three kinds; the summary names each kind.
    let kinds: Vec<_> = (settings.grids.iter())
        .filter_map(|node| cfg.scene.block_kind(node))
        .collect();
    for (kind, noun) in [
        (crate::scene::BlockKind::Grid, "grid"),
        (crate::scene::BlockKind::Volume, "volume texture"),
        (crate::scene::BlockKind::Envmap, "environment map"),
    ] {
        let n = kinds.iter().filter(|&&k| k == kind).count();
        if n > 0 {
            what.push(count(n, noun));
        }
    }
    let loss_name = format!("{:?}", settings.loss).to_lowercase();
    let (rows, seconds) = (&outcome.rows, outcome.seconds);
    outln!(
        "optimized {} over {} ({}, {} spp): {loss_name} loss {:.4e} -> {:.4e} in {seconds:.1} s; \
         wrote {} in {}",
        what.join(" and "),
        count(settings.iterations as usize, "iteration"),
        count(cfg.views.len(), "view"),
        settings.spp,
        rows.first().map_or(f64::NAN, |r| r.loss),
        rows.last().map_or(f64::NAN, |r| r.loss),
        outcome.written.join(", "),
        out.display()
    )?;
    summary(&cfg, &outcome, out)
}

/// The rest of the summary: where each optimised parameter ended, the last metrics, the loss without
/// the noise of one iteration, and the fitted scene's file.
fn summary(cfg: &OptimizeConfig, outcome: &Outcome, out: &Path) -> Result<()> {
    for name in &cfg.settings.params {
        let (from, to) = (cfg.scene.parameter(name), outcome.scene.parameter(name));
        if let (Ok(from), Ok(to)) = (from, to) {
            outln!("  {name}: {from} -> {to}")?;
        }
    }
    for node in &cfg.settings.grids {
        let kind = cfg.scene.block_kind(node);
        let (what, mesh) = if cfg.scene.texture_range(node).is_some() {
            let what = match kind {
                Some(crate::scene::BlockKind::Envmap) => "every texel of the environment map",
                _ => "every texel of the volume texture",
            };
            (what, String::new())
        } else {
            let ply = out.join(format!("{node}.ply"));
            (
                "every value of the grid",
                format!("; its shape's mesh in {}", ply.display()),
            )
        };
        outln!(
            "  {node}: {what}, in {}{}",
            out.join(crate::optimize::run::block_file(&cfg.scene, node))
                .display(),
            mesh
        )?;
    }
    for r in &outcome.refinements {
        let why = match r.signal_ratio {
            Some(signal) => format!(
                "Adam's signal ratio {signal:.3}, {:.3} for noise alone",
                r.noise_ratio
            ),
            None => "no step before it".to_string(),
        };
        outln!(
            "  {} refined before iteration {}: its steps x{} (the lattice spacing's power {}; {why})",
            r.node,
            r.iteration,
            r.rate_scale,
            r.power
        )?;
    }
    let rows = &outcome.rows;
    if let Some(last) = rows.last()
        && !last.shapes.is_empty()
    {
        // The shape columns come in (IoU, Chamfer) pairs after the first four.
        let names = outcome.columns.iter().skip(4).step_by(2);
        let metrics: Vec<String> = (last.shapes.iter().zip(names))
            .map(|((iou, chamfer), column)| {
                let shape = column.strip_prefix("iou.").map(|n| format!(" ({n})"));
                format!(
                    "IoU {iou:.4}, Chamfer {chamfer:.4e}{}",
                    shape.unwrap_or_default()
                )
            })
            .collect();
        outln!(
            "  final metrics against the target scene: {}",
            metrics.join("; ")
        )?;
    }
    if let (Some(last), Some(reference)) = (rows.last(), &cfg.reference_mesh)
        && let Some(m) = &last.mesh
    {
        outln!(
            "  final metrics against the reference mesh {}: Chamfer {:.4e} (of its box diagonal), \
             normal consistency {:.4}, IoU {:.4}",
            reference.path.display(),
            m.chamfer,
            m.normal_consistency,
            m.iou
        )?;
    }
    let tail = &rows[rows.len() - rows.len().div_ceil(10)..];
    if tail.len() > 1 {
        let mean = tail.iter().map(|r| r.loss).sum::<f64>() / tail.len() as f64;
        outln!(
            "  mean loss of the last {} iterations {mean:.4e} (one iteration's loss is an estimate \
             at {} spp)",
            tail.len(),
            cfg.settings.spp
        )?;
    }
    let result = out.join("result.json");
    outln!(
        "  the fitted scene: {} (render it with `implicit-psdr render {}`)",
        result.display(),
        result.display()
    )
}

/// `n` and `word`, plural unless `n` is 1.
fn count(n: usize, word: &str) -> String {
    format!("{n} {word}{}", if n == 1 { "" } else { "s" })
}

/// The progress of a run on stderr. On a terminal, bars: one per target render, then one over the
/// iterations with the last loss (and IoU); elsewhere, one-line records of the iterations.
struct Bars {
    bar: Option<indicatif::ProgressBar>,
    records: Option<Records>,
    iterations: u32,
}

impl Observer for Bars {
    fn render_progress(&self) -> Progress {
        progress_bar()
    }

    fn status(&mut self, status: Status<'_>) {
        match status {
            Status::Start { iterations } => {
                self.iterations = iterations;
                self.records = Records::new();
                if self.records.is_some() {
                    return;
                }
                let bar = indicatif::ProgressBar::new(iterations as u64);
                bar.set_style(
                    indicatif::ProgressStyle::with_template(
                        "iteration {pos}/{len} {bar:40} {msg} {elapsed}/{eta}",
                    )
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
                );
                self.bar = Some(bar);
            }
            Status::Iteration { row, done } => {
                if let Some(bar) = &self.bar {
                    bar.set_position(done as u64);
                    let iou = row.iou().map_or(String::new(), |i| format!(" IoU {i:.3}"));
                    bar.set_message(format!("loss {:.4e}{iou}", row.loss));
                }
                let total = self.iterations;
                if let Some(records) = &mut self.records {
                    records.record(done as f64, total as f64, || {
                        let mut what = format!("iteration {done}/{total}: loss {:.4e}", row.loss);
                        if let Some(&(iou, chamfer)) = row.shapes.first() {
                            what += &format!(", IoU {iou:.4}, Chamfer {chamfer:.4e}");
                        }
                        what
                    });
                }
            }
            Status::Done => {
                if let Some(bar) = &self.bar {
                    bar.finish_and_clear();
                }
            }
        }
    }
}
