//! The one parallel driver every estimator runs on: work items (rows of camera samples, chunks of
//! boundary samples) in parallel, each writing into its own film tile and counting what happened, then
//! tiles and counts merged in item order, so the result is the same whatever the number of threads.

use super::options::Progress;
use crate::film::Film;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// Counters of a render: what happened, for the caller to report.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Camera samples taken.
    pub samples: u64,
    /// Rays whose sphere tracing ran out of steps (treated as misses).
    pub exhausted_rays: u64,
    /// Samples whose radiance was not finite (NaN or infinite); they count as black.
    pub invalid_samples: u64,
    /// Derivative passes only: samples with a finite radiance but a non-finite derivative (a bug; their
    /// derivative counts as zero).
    pub invalid_derivatives: u64,
    /// The first invalid sample or derivative in work order, with its pixel and sample index.
    pub first_invalid: Option<String>,
    /// Wall-clock seconds.
    pub seconds: f64,
}

impl RenderStats {
    /// Adds the counts of `other` (a later work item or pass); the first invalid sample stays the
    /// earliest. `samples` and `seconds` are the caller's.
    pub fn absorb(&mut self, other: RenderStats) {
        self.exhausted_rays += other.exhausted_rays;
        self.invalid_samples += other.invalid_samples;
        self.invalid_derivatives += other.invalid_derivatives;
        if self.first_invalid.is_none() {
            self.first_invalid = other.first_invalid;
        }
    }

    /// What a user should hear about, one line each (none for a clean render): rays that ran out of
    /// sphere-tracing steps, non-finite samples and derivatives with the first of them.
    pub fn warnings(&self) -> Vec<String> {
        let mut lines = Vec::new();
        if self.exhausted_rays > 0 {
            lines.push(format!(
                "{} rays ran out of sphere-tracing steps and were treated as misses",
                self.exhausted_rays
            ));
        }
        if let Some(first) = &self.first_invalid {
            lines.push(format!(
                "{} non-finite samples (counted as black) and {} non-finite derivatives (counted \
                 as 0); the first: {first}",
                self.invalid_samples, self.invalid_derivatives
            ));
        }
        lines
    }

    /// Counts an invalid sample (`derivative`: a non-finite derivative of a finite sample), keeping
    /// `describe()`'s message if it is the first.
    pub fn invalid(&mut self, derivative: bool, describe: impl FnOnce() -> String) {
        if derivative {
            self.invalid_derivatives += 1;
        } else {
            self.invalid_samples += 1;
        }
        if self.first_invalid.is_none() {
            self.first_invalid = Some(describe());
        }
    }
}

/// Runs `work(item, tile, stats)` for items `0..items` in parallel and merges the tiles into `film` in
/// item order (in waves of [`Film::wave`] items); returns the merged counts. `stage` names the work for
/// `progress`.
pub fn run<F: Film>(
    film: &mut F,
    items: usize,
    stage: &str,
    progress: &Progress,
    work: impl Fn(usize, &mut F::Tile, &mut RenderStats) + Sync,
) -> RenderStats {
    let done = AtomicU64::new(0);
    let wave = film.wave().max(1);
    let mut stats = RenderStats::default();
    let mut start = 0;
    while start < items {
        let end = items.min(start.saturating_add(wave));
        let shared: &F = film;
        let tiles: Vec<(F::Tile, RenderStats)> = (start..end)
            .into_par_iter()
            .map(|item| {
                let mut tile = shared.tile(item);
                let mut stats = RenderStats::default();
                shared.run_item(|| work(item, &mut tile, &mut stats));
                let finished = done.fetch_add(1, Ordering::Relaxed) + 1;
                progress.report(stage, finished, items as u64);
                (tile, stats)
            })
            .collect();
        for (item, (tile, s)) in (start..end).zip(tiles) {
            film.merge(item, tile);
            stats.absorb(s);
        }
        start = end;
    }
    stats
}
