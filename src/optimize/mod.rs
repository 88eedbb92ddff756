//! Inverse rendering: optimise named parameters and whole grids so that renders from several views
//! match target images, with the reverse-mode gradient ([`crate::integrator::loss_gradient`]) and Adam.
//!
//! One iteration: a subset of the views (all by default; otherwise drawn from the seed), for each view
//! the loss pass and the adjoint pass at the view's camera (the views in parallel,
//! [`Optimization::views_gradient`]), the mean loss and the mean gradient over those views, one Adam
//! step per parameter (grid values and named parameters with their own learning rates), then every
//! value is brought back into its valid range ([`Optimization::step`]).
//!
//! A whole run as an `OPT.json` describes it ([`config`]), with its files (`progress.csv`, the
//! pictures, the target cache, `result.json`), is [`run()`]'s, which the `optimize` command and
//! `implicit_psdr.optimize` call.

mod adam;
pub mod config;
pub mod metrics;
pub mod pictures;
pub mod progress;
pub mod resolution;
pub mod run;
pub mod schedule;
pub mod targets;
mod views;
mod views_gradient;

pub use adam::{Adam, AdamOptions};
pub use progress::Row;
pub use resolution::ImageScale;
pub use run::{Observer, Outcome, Status, run};
pub use schedule::{Decay, Ema, ResolutionPower};
pub use views::{View, orbit};
pub use views_gradient::ViewsGradient;

use crate::error::{Error, Result};
use crate::film::Image;
use crate::integrator::{BoundaryBudget, DiffOptions, GradientLayout, Loss, RenderOptions, render};
use crate::sampler::Sampler;
use crate::scene::BlockKind;
use crate::scene::Scene;

/// Which terms of the derivative the gradient holds.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum Terms {
    /// Interior, primary and secondary terms (the default).
    #[default]
    Complete,
    /// The interior term alone (what renderers without boundary terms compute; the ablation).
    Interior,
}

/// How to optimise: what, how fast, for how long.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// Named parameters to optimise (as [`Scene::parameters`] lists them).
    pub params: Vec<String>,
    /// Blocks whose values are optimised: grid nodes and volume textures (as [`Scene::blocks`] lists
    /// them; a texture's texels step with `learning_rate_grids` too and are kept in their field's
    /// range).
    pub grids: Vec<String>,
    /// Iterations (Adam steps).
    pub iterations: u32,
    /// Samples per pixel per view per iteration (loss pass and adjoint pass each).
    pub spp: u32,
    /// The image loss.
    pub loss: Loss,
    /// Adam's step size for grid values, in the units of the values (scene units), at iteration 0 and
    /// the grids' starting resolution.
    pub learning_rate_grids: f32,
    /// Adam's step size for named parameters, in each parameter's units, at iteration 0.
    pub learning_rate_params: f32,
    /// How both step sizes decay over the run.
    pub learning_rate_decay: Decay,
    /// How a grid's step size follows its lattice spacing after refinements: each refinement `n → n'`
    /// multiplies it by `((n − 1) / (n' − 1))ᵖ`, `p` fixed or chosen per refinement
    /// ([`schedule::ResolutionPower`]).
    pub learning_rate_resolution: ResolutionPower,
    /// Iterations `W` over which every step size ramps up after a refinement (`upsample_at`), which
    /// restarts Adam: the `k`-th iteration after it (from 0) has `min(1, (k + 1) / W)` of the rate
    /// ([`schedule::warmup`]); 0 for none.
    pub learning_rate_warmup: u32,
    /// Adam's hyper-parameters and gradient clamp.
    pub adam: AdamOptions,
    /// Weight `β ∈ [0, 1)` on the past of the exponential moving average of the values
    /// ([`Optimization::averaged_scene`]), the result of the run; 0: the last values.
    pub ema: f32,
    /// Levels of the image pyramid of the loss ([`Loss::multiscale`]); 1: the plain loss.
    pub loss_scales: u32,
    /// The views' image resolution in each grid stage ([`resolution`]); full by default.
    pub image_scale: ImageScale,
    /// Views per iteration, drawn without replacement from the seed (`None`: all).
    pub views_per_iteration: Option<usize>,
    /// Seed of the view choice and of every render.
    pub seed: u64,
    /// Derivative terms.
    pub terms: Terms,
    /// Boundary samples per pixel of each view's gradient with [`Terms::Complete`] (unset rates take
    /// `diff`'s defaults for `spp`, [`BoundaryBudget::resolve`]).
    pub boundary: BoundaryBudget,
    /// Iterations before which every optimised grid is refined `n → 2n − 1` (the same surface,
    /// [`crate::sdf::GridData::refined`]); Adam's state starts afresh.
    pub upsample_at: Vec<u32>,
    /// Every this many iterations, the grids' values are reset to the signed distance of their zero
    /// set ([`crate::sdf::GridData::redistanced`]), which keeps the Lipschitz bound near 1.
    pub redistance_every: Option<u32>,
    /// Weight `λ` of the smoothness term `λ · mean over interior lattice nodes of (Δc)²` (`Δ` the
    /// 7-point Laplacian of the values, in value units) added to the loss; 0 for none.
    pub laplacian: f32,
}

/// One finished iteration.
#[derive(Clone, Debug, PartialEq)]
pub struct Iteration {
    /// 0-based index.
    pub index: u32,
    /// Mean loss over the iteration's views (before the step).
    pub loss: f64,
    /// Euclidean norm of the mean gradient.
    pub gradient_norm: f64,
    /// Wall-clock seconds of the iteration.
    pub seconds: f64,
    /// Samples whose gradient was dropped as non-finite.
    pub invalid_samples: u64,
    /// Where the time went, in seconds: the grid edits (refinement, redistancing), and the wall time
    /// of the views shared among the loss passes and the adjoint passes' interior, primary and
    /// secondary terms ([`ViewsGradient::stage_seconds`]).
    pub stage_seconds: StageSeconds,
}

/// Seconds of an iteration by stage (see [`Iteration::stage_seconds`]).
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct StageSeconds {
    /// Loss passes (the image of each view and its loss).
    pub loss_pass: f64,
    /// The adjoint passes' interior term.
    pub interior: f64,
    /// The adjoint passes' primary boundary term.
    pub primary: f64,
    /// The adjoint passes' secondary boundary term.
    pub secondary: f64,
    /// Grid refinement and redistancing before the iteration.
    pub grid_edits: f64,
}

/// One refinement of an optimised grid (`upsample_at`) and the step-size power it took
/// ([`Settings::learning_rate_resolution`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Refinement {
    /// The iteration it came before (0-based).
    pub iteration: u32,
    /// The grid's node.
    pub node: String,
    /// Adam's signal ratio over the grid's values at the last step of the stage that ended
    /// ([`Adam::signal_ratio`]); `None` if the stage took no step.
    pub signal_ratio: Option<f64>,
    /// What zero-mean noise would have given at that step ([`Adam::noise_ratio`]).
    pub noise_ratio: f64,
    /// The power of the lattice spacing taken.
    pub power: f32,
    /// The factor it put on the grid's rate.
    pub rate_scale: f32,
}

/// An optimisation in progress: the scene, its views and their targets, and Adam's state.
pub struct Optimization {
    /// The scene being optimised (its current parameter values).
    pub scene: Scene,
    /// The views.
    pub views: Vec<View>,
    /// One target image per view.
    pub targets: Vec<Image>,
    /// The settings.
    pub settings: Settings,
    layout: GradientLayout,
    adam: Adam,
    /// The moving average of the values in layout order (`None` when `ema` is 0).
    ema: Option<Ema>,
    /// The refinements so far, in order ([`Settings::learning_rate_resolution`]).
    refinements: Vec<Refinement>,
    /// The divisor of the film's width and height in each grid stage ([`Settings::image_scale`]).
    pub stage_divisors: Vec<u32>,
    /// The targets reduced by each divisor > 1 that a stage uses.
    reduced_targets: Vec<(u32, Vec<Image>)>,
    /// Iterations done.
    pub done: u32,
}

impl Optimization {
    /// Checks the problem (a target per view, of the scene's image size; known parameters and grids;
    /// at least one of them) and selects the parameters.
    pub fn new(
        scene: Scene,
        views: Vec<View>,
        targets: Vec<Image>,
        settings: Settings,
    ) -> Result<Self> {
        if views.is_empty() {
            return Err(Error::field("views", "at least one view is needed"));
        }
        if targets.len() != views.len() {
            return Err(Error::field(
                "target",
                format!(
                    "{} target images for {} views (one per view)",
                    targets.len(),
                    views.len()
                ),
            ));
        }
        let size = (scene.camera.width, scene.camera.height);
        if let Some(k) = targets.iter().position(|t| (t.width, t.height) != size) {
            return Err(Error::field(
                format!("target.images[{k}]"),
                format!(
                    "is {}x{}, the scene's image {}x{}",
                    targets[k].width, targets[k].height, size.0, size.1
                ),
            ));
        }
        if settings.params.is_empty() && settings.grids.is_empty() {
            return Err(Error::field(
                "optimize",
                "nothing to optimise: name grids or params",
            ));
        }
        let layout = GradientLayout::select(&scene, &settings.params, &settings.grids)?;
        let adam = Adam::with_options(layout.entries, settings.adam);
        let ema = (settings.ema > 0.0).then(|| Ema::new(layout.entries, settings.ema as f64));
        let stage_divisors = resolution::divisors(
            &settings.image_scale,
            &scene,
            &views,
            &settings.grids,
            settings.upsample_at.len() + 1,
        )?;
        let mut reduced_targets: Vec<(u32, Vec<Image>)> = Vec::new();
        for &d in &stage_divisors {
            if d > 1 && !reduced_targets.iter().any(|(e, _)| *e == d) {
                let images = targets.iter().map(|t| resolution::reduce(t, d)).collect();
                reduced_targets.push((d, images));
            }
        }
        Ok(Self {
            scene,
            views,
            targets,
            settings,
            layout,
            adam,
            ema,
            refinements: Vec::new(),
            stage_divisors,
            reduced_targets,
            done: 0,
        })
    }

    /// The parameters' current values, in gradient-entry order.
    pub fn values(&self) -> Result<Vec<f32>> {
        let mut out = Vec::with_capacity(self.layout.entries);
        for p in &self.layout.params {
            out.push(self.scene.parameter(p)?);
        }
        for (block, _) in &self.layout.grids {
            out.extend_from_slice(&self.scene.block_values(&block.node)?);
        }
        Ok(out)
    }

    /// The names of the shapes whose grids are optimised, in layout order, each once.
    pub fn grid_shapes(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for (block, _) in &self.layout.grids {
            if block.kind == BlockKind::Grid && !out.contains(&block.shape_name) {
                out.push(block.shape_name.clone());
            }
        }
        out
    }

    /// The views of iteration `index`: all, or `views_per_iteration` of them drawn from the seed.
    pub fn views_of(&self, index: u32) -> Vec<usize> {
        let n = self.views.len();
        let mut order: Vec<usize> = (0..n).collect();
        let Some(k) = self.settings.views_per_iteration.filter(|&k| k < n) else {
            return order;
        };
        let mut sampler = Sampler::new(self.settings.seed, VIEW_STREAM, index as u64, 0);
        // A partial Fisher–Yates shuffle.
        for i in 0..k {
            let j = i + ((sampler.next_1d() * (n - i) as f32) as usize).min(n - i - 1);
            order.swap(i, j);
        }
        order.truncate(k);
        order.sort_unstable();
        order
    }

    /// One iteration: mean loss and gradient over the iteration's views, one Adam step, values brought
    /// back into range. Errors: a render failure.
    pub fn step(&mut self) -> Result<Iteration> {
        let start = std::time::Instant::now();
        let index = self.done;
        self.edit_grids(index)?;
        let grid_edits = start.elapsed().as_secs_f64();
        let views = self.views_of(index);
        let ViewsGradient {
            mut loss,
            mut gradient,
            invalid_samples,
            stage_seconds,
        } = self.views_gradient(index, &views)?;
        if self.settings.laplacian > 0.0 {
            for (block, first) in &self.layout.grids {
                if block.kind != BlockKind::Grid {
                    continue;
                }
                let data = self.scene.grid_values(&block.node)?;
                let entries = &mut gradient[*first..*first + block.len()];
                loss += smoothness(&data, self.settings.laplacian as f64, entries);
            }
        }
        let norm = gradient.iter().map(|g| g * g).sum::<f64>().sqrt();
        let rates = self.rates(index);
        let mut values = self.values()?;
        let proposed = self.adam.step(&values, &gradient, &rates);
        self.apply(&mut values, &proposed)?;
        if self.ema.is_some() {
            let values = self.values()?;
            if let Some(ema) = &mut self.ema {
                ema.push(&values);
            }
        }
        self.done += 1;
        Ok(Iteration {
            index,
            loss,
            gradient_norm: norm,
            seconds: start.elapsed().as_secs_f64(),
            invalid_samples,
            stage_seconds: StageSeconds {
                grid_edits,
                ..stage_seconds
            },
        })
    }

    /// The refinements done so far, in order: each grid's step-size power and what decided it.
    pub fn refinements(&self) -> &[Refinement] {
        &self.refinements
    }

    /// The divisor of the film's width and height at iteration `index` (its grid stage's).
    pub fn divisor_at(&self, index: u32) -> u32 {
        let stage = resolution::stage_of(index, &self.settings.upsample_at);
        self.stage_divisors.get(stage).copied().unwrap_or(1)
    }

    /// The step size of every entry at iteration `index`: the named parameters' and the grids' rates
    /// times the decay's and the warm-up's factors, a grid's also times its resolution's scale.
    fn rates(&self, index: u32) -> Vec<f32> {
        let s = &self.settings;
        let decay = s.learning_rate_decay.factor(index, s.iterations)
            * schedule::warmup(index, &s.upsample_at, s.learning_rate_warmup);
        let mut rates = vec![s.learning_rate_params * decay; self.layout.params.len()];
        for (block, _) in &self.layout.grids {
            let scale: f32 = self
                .refinements
                .iter()
                .filter(|r| r.node == block.node)
                .map(|r| r.rate_scale)
                .product();
            let rate = s.learning_rate_grids * decay * scale;
            rates.extend(std::iter::repeat_n(rate, block.len()));
        }
        rates
    }

    /// The scene at the moving average of the values (the run's result, and what its metrics
    /// measure); the current scene when `ema` is 0 or before the first step. A named parameter whose
    /// average its field rejects keeps its current value.
    pub fn averaged_scene(&self) -> Result<Scene> {
        let Some(values) = self.ema.as_ref().and_then(Ema::value) else {
            return Ok(self.scene.clone());
        };
        let mut scene = self.scene.clone();
        for (k, name) in self.layout.params.iter().enumerate() {
            if let Ok(s) = scene.with_parameter(name, values[k]) {
                scene = s;
            }
        }
        for (block, first) in &self.layout.grids {
            let values = values[*first..*first + block.len()].to_vec();
            if block.kind == BlockKind::Grid {
                scene.set_grid_values(&block.node, values)?;
            } else {
                scene.set_block_values(&block.node, values)?;
            }
        }
        Ok(scene)
    }

    /// The grid edits due before iteration `index`: refinement (`upsample_at`, which also restarts
    /// Adam and re-selects the grids) and redistancing (`redistance_every`).
    fn edit_grids(&mut self, index: u32) -> Result<()> {
        let nodes: Vec<String> = self
            .layout
            .grids
            .iter()
            .filter(|(b, _)| b.kind == BlockKind::Grid)
            .map(|(b, _)| b.node.clone())
            .collect();
        let upsample = self.settings.upsample_at.contains(&index);
        let redistance = self
            .settings
            .redistance_every
            .is_some_and(|k| k > 0 && index > 0 && index.is_multiple_of(k));
        if nodes.is_empty() || !(upsample || redistance) {
            return Ok(());
        }
        if upsample && let Some(ema) = &mut self.ema {
            // Refinement is linear: refine the average's grids too (its named parameters and
            // textures stay as they are, in the same order).
            let mut refined = Vec::new();
            let mut result: Result<()> = Ok(());
            ema.remap(|values| {
                refined.extend_from_slice(&values[..self.layout.params.len()]);
                for (block, first) in &self.layout.grids {
                    let part = values[*first..*first + block.len()].to_vec();
                    if block.kind != BlockKind::Grid {
                        refined.extend(part);
                        continue;
                    }
                    let dims = match self.scene.grid_values(&block.node) {
                        Ok(d) => d.dims,
                        Err(e) => {
                            result = Err(e);
                            return Vec::new();
                        }
                    };
                    match crate::sdf::GridData::new(dims, part, &block.node) {
                        Ok(g) => refined.extend(g.refined().values),
                        Err(e) => {
                            result = Err(e);
                            return Vec::new();
                        }
                    }
                }
                refined
            });
            result?;
        }
        for node in &nodes {
            let mut data = (*self.scene.grid_values(node)?).clone();
            if upsample {
                let before = data.dims;
                data = data.refined();
                // How far the stage that ends still moved the grid (Adam restarts after the loop).
                let signal = (self.layout.grids.iter())
                    .find(|(b, _)| b.node == *node)
                    .and_then(|(b, first)| self.adam.signal_ratio(*first..*first + b.len()));
                let noise = self.adam.noise_ratio();
                let power = match self.settings.learning_rate_resolution {
                    ResolutionPower::Fixed(p) => p,
                    ResolutionPower::Auto => schedule::auto_power(signal, noise),
                };
                self.refinements.push(Refinement {
                    iteration: index,
                    node: node.clone(),
                    signal_ratio: signal,
                    noise_ratio: noise,
                    power,
                    rate_scale: schedule::refinement_scale(before, data.dims, power),
                });
            }
            if redistance {
                let [lo, hi] = self.scene.grid_box(node)?;
                let level = self.scene.parameter(&format!("{node}.level"))?;
                data = data.redistanced(lo, hi, level);
            }
            self.scene.set_grid(node, data)?;
        }
        if upsample {
            self.layout =
                GradientLayout::select(&self.scene, &self.settings.params, &self.settings.grids)?;
            self.adam = Adam::with_options(self.layout.entries, self.settings.adam);
        }
        Ok(())
    }

    /// The render options of view `view` at iteration `index`: seeds that differ per iteration and
    /// view (the adjoint pass takes the next one, so the loss seeds are spaced by 2).
    fn options(&self, index: u32, view: usize) -> DiffOptions {
        let per_iteration = 2 * self.views.len() as u64;
        let seed = self
            .settings
            .seed
            .wrapping_mul(0x9E37_79B9)
            .wrapping_add(index as u64 * per_iteration + 2 * view as u64);
        DiffOptions {
            render: RenderOptions {
                spp: self.settings.spp,
                seed,
                ..RenderOptions::default()
            },
            boundary: match self.settings.terms {
                Terms::Complete => self.settings.boundary,
                Terms::Interior => BoundaryBudget::NONE,
            },
            ..DiffOptions::default()
        }
    }

    /// Sets the proposed values, each brought back into its valid range: a named parameter that its
    /// field rejects (a radius ≤ 0, an albedo > 1, ...) moves halfway back towards its old value, up
    /// to 20 times, else keeps it; grid values are clamped to `±` the grid box's diagonal.
    fn apply(&mut self, old: &mut [f32], proposed: &[f32]) -> Result<()> {
        for (k, name) in self.layout.params.iter().enumerate() {
            let mut value = proposed[k];
            for _ in 0..20 {
                if let Ok(scene) = self.scene.with_parameter(name, value) {
                    self.scene = scene;
                    old[k] = value;
                    break;
                }
                value = 0.5 * (value + old[k]);
            }
        }
        for (block, first) in &self.layout.grids {
            if let Some((lo, hi)) = self.scene.texture_range(&block.node) {
                let values = proposed[*first..*first + block.len()]
                    .iter()
                    .map(|v| v.clamp(lo, hi))
                    .collect();
                self.scene.set_block_values(&block.node, values)?;
                continue;
            }
            let bound = self.scene.grid_diagonal(&block.node)?;
            let values = proposed[*first..*first + block.len()]
                .iter()
                .map(|v| v.clamp(-bound, bound))
                .collect();
            self.scene.set_grid_values(&block.node, values)?;
        }
        Ok(())
    }

    /// The image of view `view` at the current values, `spp` samples per pixel, seed `seed`.
    pub fn render_view(&self, view: usize, spp: u32, seed: u64) -> Result<Image> {
        let scene = self.views[view].apply(&self.scene)?;
        let options = RenderOptions {
            spp,
            seed,
            ..RenderOptions::default()
        };
        Ok(render(&scene, &options).0)
    }
}

/// The shapes an optimisation of `params` and `grids` changes, each once, in order: the shapes
/// holding the grids, then the shapes named by the parameters (`SHAPE.…`).
pub fn optimized_shapes(scene: &Scene, params: &[String], grids: &[String]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for block in scene.grid_blocks() {
        if grids.contains(&block.node) && !out.contains(&block.shape_name) {
            out.push(block.shape_name.clone());
        }
    }
    for p in params {
        if let Some((shape, _)) = p.split_once('.')
            && scene.shape_named(shape).is_ok()
            && !out.iter().any(|s| s == shape)
        {
            out.push(shape.to_string());
        }
    }
    out
}

/// The random stream of the views' choice.
const VIEW_STREAM: u64 = 0x71E5_0F17;

/// The target images of `views` rendered from `scene` at `spp` samples per pixel, seeds `seed + k`.
pub fn render_targets(scene: &Scene, views: &[View], spp: u32, seed: u64) -> Result<Vec<Image>> {
    targets::render_targets_with(
        scene,
        views,
        spp,
        seed,
        &crate::integrator::Progress::default,
    )
}

/// The smoothness term `λ · mean_i (Δc)_i²` over the interior nodes of `data` (`Δ` the 7-point
/// Laplacian in value units); adds its gradient `(2λ/n) Δᵀ(Δc)` to `gradient` and returns its value.
fn smoothness(data: &crate::sdf::GridData, lambda: f64, gradient: &mut [f64]) -> f64 {
    let [nx, ny, nz] = data.dims;
    let index = |x: usize, y: usize, z: usize| (z * ny + y) * nx + x;
    let c = &data.values;
    let interior = (nx - 2) * (ny - 2) * (nz - 2);
    if interior == 0 {
        return 0.0;
    }
    let scale = 2.0 * lambda / interior as f64;
    let mut sum = 0.0;
    for z in 1..nz - 1 {
        for y in 1..ny - 1 {
            for x in 1..nx - 1 {
                let i = index(x, y, z);
                let neighbours = [
                    index(x - 1, y, z),
                    index(x + 1, y, z),
                    index(x, y - 1, z),
                    index(x, y + 1, z),
                    index(x, y, z - 1),
                    index(x, y, z + 1),
                ];
                let lap: f64 =
                    neighbours.iter().map(|&j| c[j] as f64).sum::<f64>() - 6.0 * c[i] as f64;
                sum += lap * lap;
                gradient[i] -= 6.0 * scale * lap;
                for j in neighbours {
                    gradient[j] += scale * lap;
                }
            }
        }
    }
    lambda * sum / interior as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sdf::GridData;

    /// The smoothness term's gradient against central differences of its value.
    #[test]
    fn smoothness_gradient_matches_differences() {
        let dims = [5, 4, 6];
        let values: Vec<f32> = (0..120)
            .map(|i| ((i * 31 % 17) as f32 - 8.0) * 0.1)
            .collect();
        let data = GridData::new(dims, values.clone(), "test").unwrap();
        let mut gradient = vec![0.0; 120];
        smoothness(&data, 0.7, &mut gradient);
        for i in [0, 7, 33, 61, 119] {
            let at = |d: f32| {
                let mut v = values.clone();
                v[i] += d;
                smoothness(
                    &GridData::new(dims, v, "test").unwrap(),
                    0.7,
                    &mut [0.0; 120],
                )
            };
            let h = 1e-2;
            let fd = (at(h) - at(-h)) / (2.0 * h as f64);
            assert!(
                (gradient[i] - fd).abs() < 1e-4 * fd.abs().max(1.0),
                "{i}: {} vs {fd}",
                gradient[i]
            );
        }
    }
}
