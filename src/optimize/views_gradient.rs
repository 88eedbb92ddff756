//! The loss and gradient of an iteration's views, several views at once.
//!
//! Each view's loss pass and adjoint pass are parallel within the view, but not perfectly: the passes
//! end in a few long rows, the adjoint pass merges its tiles in waves, the silhouette extraction
//! narrows to a few boxes at each level of its octree. Running the views in parallel too lets a thread
//! that runs out of one view's work take another's (rayon's work stealing across the nested loops):
//! on the race's 61³ iterations (two threads) about 13% less wall time than one view after the other.
//! The views' results are added in view order, so the loss and the gradient are the same bits
//! whatever the number of threads.

use super::{Optimization, StageSeconds};
use crate::error::Result;
use crate::integrator::loss_gradient;
use rayon::prelude::*;

/// Views whose passes may run at once: each holds its gradient (one value per entry) until the
/// group's results are added, which bounds the memory of iterations over many views.
const VIEWS_AT_ONCE: usize = 8;

/// The mean loss and gradient of an iteration's views, before its step.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewsGradient {
    /// The mean loss over the views.
    pub loss: f64,
    /// The mean gradient over the views, in the layout's entry order.
    pub gradient: Vec<f64>,
    /// Samples whose gradient was dropped as non-finite, summed over the views.
    pub invalid_samples: u64,
    /// The wall seconds of the views, shared among the loss passes and the three terms in proportion
    /// to the seconds each took in every view (views overlap, so their own seconds add up to more than
    /// the wall time); `grid_edits` is 0.
    pub stage_seconds: StageSeconds,
}

impl Optimization {
    /// The mean loss and gradient of `views` at iteration `index` (its seeds and image scale), the
    /// views in parallel (module docs). Errors: the first failing view's, in view order.
    pub fn views_gradient(&self, index: u32, views: &[usize]) -> Result<ViewsGradient> {
        let start = std::time::Instant::now();
        let image_loss = self.settings.loss.multiscale(self.settings.loss_scales);
        let divisor = self.divisor_at(index);
        let targets = match self.reduced_targets.iter().find(|(d, _)| *d == divisor) {
            Some((_, reduced)) => reduced,
            None => &self.targets,
        };
        let mut gradient = vec![0.0f64; self.layout.entries];
        let mut loss = 0.0;
        let mut invalid_samples = 0;
        // Each view's own seconds: loss pass, interior, primary, secondary.
        let mut own = [0.0f64; 4];
        for group in views.chunks(VIEWS_AT_ONCE) {
            let results: Vec<Result<_>> = group
                .par_iter()
                .map(|&v| {
                    let scene = self.views[v].apply_reduced(&self.scene, divisor)?;
                    let options = self.options(index, v);
                    let g = loss_gradient(&scene, &self.layout, &targets[v], image_loss, &options)?;
                    let [interior, primary, secondary] = g.gradient.term_seconds;
                    let seconds = [g.loss_seconds, interior, primary, secondary];
                    let invalid = g.gradient.stats.invalid_derivatives;
                    Ok((g.loss, g.gradient.total(), invalid, seconds))
                })
                .collect();
            for result in results {
                let (view_loss, view_gradient, invalid, seconds) = result?;
                loss += view_loss;
                invalid_samples += invalid;
                for (t, d) in gradient.iter_mut().zip(view_gradient) {
                    *t += d;
                }
                for (o, s) in own.iter_mut().zip(seconds) {
                    *o += s;
                }
            }
        }
        let n = views.len().max(1) as f64;
        loss /= n;
        gradient.iter_mut().for_each(|g| *g /= n);
        let wall = start.elapsed().as_secs_f64();
        let sum: f64 = own.iter().sum();
        let share = if sum > 0.0 { wall / sum } else { 0.0 };
        let [loss_pass, interior, primary, secondary] = own.map(|s| s * share);
        Ok(ViewsGradient {
            loss,
            gradient,
            invalid_samples,
            stage_seconds: StageSeconds {
                loss_pass,
                interior,
                primary,
                secondary,
                grid_edits: 0.0,
            },
        })
    }
}
