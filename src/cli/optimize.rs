//! The `optimize` command: inverse rendering as an `OPT.json` describes it (see
//! docs/inverse-rendering.md), with its outputs in one folder. The run is the library's
//! ([`crate::optimize::run`]); this shows progress and prints.

use crate::cli::args::OptimizeArgs;
use crate::cli::progress_bar;
use crate::integrator::Progress;
use crate::optimize::config::OptimizeConfig;
use crate::optimize::{self, Observer, Status};
use anyhow::Result;
use std::io::IsTerminal;

pub(crate) fn optimize(args: &OptimizeArgs) -> Result<()> {
    let cfg = OptimizeConfig::load(&args.config)?;
    let out = &args.out;
    let mut bars = Bars(None);
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
    if !settings.grids.is_empty() {
        what.push(count(settings.grids.len(), "grid"));
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
    Ok(())
}

/// `n` and `word`, plural unless `n` is 1.
fn count(n: usize, word: &str) -> String {
    format!("{n} {word}{}", if n == 1 { "" } else { "s" })
}

/// The progress bars of a run on stderr when it is a terminal: one per target render, then one over
/// the iterations with the last loss (and IoU).
struct Bars(Option<indicatif::ProgressBar>);

impl Observer for Bars {
    fn render_progress(&self) -> Progress {
        progress_bar()
    }

    fn status(&mut self, status: Status<'_>) {
        match status {
            Status::Start { iterations } => {
                if !std::io::stderr().is_terminal() {
                    return;
                }
                let bar = indicatif::ProgressBar::new(iterations as u64);
                bar.set_style(
                    indicatif::ProgressStyle::with_template(
                        "iteration {pos}/{len} {bar:40} {msg} {elapsed}/{eta}",
                    )
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
                );
                self.0 = Some(bar);
            }
            Status::Iteration { row, done } => {
                if let Some(bar) = &self.0 {
                    bar.set_position(done as u64);
                    let iou = row.iou().map_or(String::new(), |i| format!(" IoU {i:.3}"));
                    bar.set_message(format!("loss {:.4e}{iou}", row.loss));
                }
            }
            Status::Done => {
                if let Some(bar) = &self.0 {
                    bar.finish_and_clear();
                }
            }
        }
    }
}
