//! Reverse mode: the gradient of one scalar loss of the image with respect to every selected parameter
//! at once, grid values included, with the complete derivative (interior + primary + secondary terms)
//! (docs/theory.md §10).
//!
//! Every estimator runs exactly as for derivative images, with the reverse-mode [`Rev`] as its number
//! type and an [`AdjointFilm`] in place of an image: each sample's shares of the pixels become the scalar
//! `Σ_j g_j · (its contribution to pixel j)`, swept backwards into the gradient. The result is
//! `Σ_j g_j · ∂I_j`, term by term the dot product of the pixel adjoint with forward mode's derivative
//! images of the same samples.
//!
//! **Two seeds.** For a loss `L(I)`, the adjoint `g = ∂L/∂I` depends on the image; estimating `I` in `g`
//! and `∂I` with the same samples biases the gradient of a nonlinear loss (for L2, by the covariance of
//! the two). [`loss_gradient`] renders the loss pass with `seed` and the adjoint pass with `seed + 1`.
//!
//! **The pixel value in `∂F − I ∂W`.** The differentiable normalisation subtracts `I_j ∂W_j`, a control
//! variate whose expectation is zero for any constant `I_j` (`E[∂W_j] = 0` with `W`'s primary term).
//! [`render_gradient`] uses the image of its own samples (rendered with its interior pass's light
//! strategy, not the image passes'), as forward mode does, so that the two agree to rounding;
//! [`loss_gradient`] uses the loss pass's image, independent of the adjoint pass's samples, which saves
//! rendering the adjoint pass's image and keeps the gradient unbiased.

pub mod loss;

pub use loss::Loss;

use crate::error::{Error, Result};
use crate::film::{AdjointFilm, Image, Normalization};
use crate::integrator::boundary::primary::PrimarySources;
use crate::integrator::boundary::secondary::SecondarySources;
use crate::integrator::boundary::source::{Pass, run_term};
use crate::integrator::boundary::tangent_sampling::TangentSampling;
use crate::integrator::diff::interior;
use crate::integrator::driver::RenderStats;
use crate::integrator::options::{DiffOptions, RenderOptions, require_continuous_filter};
use crate::integrator::path::LightStrategy;
use crate::integrator::primal::{render, render_with};
use crate::scalar::{BlockValues, MAX_GRADIENT_ENTRY, Rev};
use crate::scene::{GridBlock, Scene, Selection};

/// Reverse mode's selection: where each selected parameter sits in the gradient, named parameters
/// first (entry `k` for the `k`-th name), then each selected grid's values as a block.
#[derive(Clone, Debug, PartialEq)]
pub struct GradientLayout {
    /// The named parameters, in entry order.
    pub params: Vec<String>,
    /// The selected grids with the entry of their first value.
    pub grids: Vec<(GridBlock, usize)>,
    /// Total number of entries.
    pub entries: usize,
    /// The selection the estimators apply to the scene.
    selection: Selection,
}

impl GradientLayout {
    /// Selects `params` (names as [`Scene::parameters`] lists them) and the values of the grid nodes
    /// `grids` (as [`Scene::grid_blocks`] lists them) of `scene` for reverse mode. Errors: unknown or
    /// repeated names; more entries than a gradient can index.
    pub fn select(scene: &Scene, params: &[String], grids: &[String]) -> Result<Self> {
        let blocks = scene.blocks();
        let mut entries = params.len();
        let mut chosen = Vec::new();
        let mut selection = Vec::new();
        for node in grids {
            // Unknown and repeated nodes are reported by `Selection::new` below.
            if let Some(block) = blocks.iter().find(|b| &b.node == node)
                && !chosen
                    .iter()
                    .any(|(b, _): &(GridBlock, usize)| &b.node == node)
            {
                chosen.push((block.clone(), entries));
                selection.push((
                    node.clone(),
                    BlockValues::Gradient {
                        first: entries as u32,
                    },
                ));
                entries += block.len();
            } else {
                selection.push((node.clone(), BlockValues::Constant));
            }
            if entries > MAX_GRADIENT_ENTRY as usize {
                return Err(Error::field(
                    "grids",
                    format!("{entries} gradient entries is more than reverse mode can index"),
                ));
            }
        }
        let selection = Selection::new(scene, params.to_vec(), selection, params.to_vec())?;
        Ok(Self {
            params: params.to_vec(),
            grids: chosen,
            entries,
            selection,
        })
    }

    /// A copy of `scene` with the layout's entries selected. Errors: a parameter or grid `scene` does
    /// not have, a grid whose dimensions changed since the layout was made (select again).
    fn apply(&self, scene: &Scene) -> Result<Scene> {
        let blocks = scene.blocks();
        for (block, _) in &self.grids {
            if let Some(now) = blocks.iter().find(|b| b.node == block.node)
                && now.shape != block.shape
            {
                return Err(Error::field(
                    "grids",
                    format!(
                        "block {:?} has shape {:?}, but was selected with shape {:?}: select it again",
                        block.node, now.shape, block.shape
                    ),
                ));
            }
        }
        self.selection.apply(scene)
    }
}

/// The gradient of `Σ_j g_j · I_j` (for a pixel adjoint `g`), term by term, indexed by a
/// [`GradientLayout`].
#[derive(Clone, Debug, PartialEq)]
pub struct Gradient {
    /// The interior term.
    pub interior: Vec<f64>,
    /// The primary boundary term (silhouettes and emitter outlines seen by the camera); zeros when its
    /// budget is 0.
    pub primary: Vec<f64>,
    /// The secondary boundary term (shadows); zeros when its budget is 0.
    pub secondary: Vec<f64>,
    /// Counters (`invalid_derivatives`: samples whose gradient was not finite, dropped).
    pub stats: RenderStats,
    /// Wall-clock seconds of the interior, primary and secondary terms.
    pub term_seconds: [f64; 3],
}

impl Gradient {
    /// The complete gradient: the sum of the three terms.
    pub fn total(&self) -> Vec<f64> {
        (0..self.interior.len())
            .map(|i| self.interior[i] + self.primary[i] + self.secondary[i])
            .collect()
    }
}

/// The gradient of `Σ_j g_j · I_j` of `scene` with respect to the parameters of `layout` (made by
/// [`GradientLayout::select`]), `g` = `adjoint`, with the samples of `options.render` (seed, spp) and
/// the boundary budgets of `options.boundary`: `Σ_j g_j · ∂I_j` for the complete derivative images of
/// the same seed (with the differentiable normalisation, the image of the same samples is rendered
/// first). Errors: a layout `scene` does not fit, a box pixel filter, an adjoint of another size, a
/// failed silhouette extraction.
pub fn render_gradient(
    scene: &Scene,
    layout: &GradientLayout,
    adjoint: &Image,
    options: &DiffOptions,
) -> Result<Gradient> {
    let scene = &layout.apply(scene)?;
    let image = match options.normalization {
        Normalization::Differentiable => Some(render_with(
            scene,
            &options.render,
            LightStrategy::Derivative,
        )),
        Normalization::Fixed => None,
    };
    let (image, stats) = image.unwrap_or_else(|| {
        let blank = Image::new(scene.camera.width, scene.camera.height);
        (blank, RenderStats::default())
    });
    let mut gradient = gradient_with_image(scene, layout, adjoint, &image, options)?;
    gradient.stats.absorb(stats);
    Ok(gradient)
}

/// [`render_gradient`] with the pixel values `image` in the differentiable normalisation's `∂F − I ∂W`
/// (ignored with the fixed one): the adjoint pass's own image, or one independent of its samples
/// (module docs); `scene` has the layout applied. Errors as [`render_gradient`], and an image of
/// another size.
fn gradient_with_image(
    scene: &Scene,
    layout: &GradientLayout,
    adjoint: &Image,
    image: &Image,
    options: &DiffOptions,
) -> Result<Gradient> {
    require_continuous_filter(scene, "reverse mode")?;
    let (w, h) = (scene.camera.width, scene.camera.height);
    if (adjoint.width, adjoint.height) != (w, h) {
        return Err(Error::field(
            "adjoint",
            format!(
                "the adjoint image is {}x{}, the image {w}x{h}",
                adjoint.width, adjoint.height
            ),
        ));
    }
    let norm = options.normalization;
    if norm == Normalization::Differentiable && (image.width, image.height) != (w, h) {
        return Err(Error::field(
            "image",
            format!(
                "the pixel values are {}x{}, the image {w}x{h}",
                image.width, image.height
            ),
        ));
    }
    let start = std::time::Instant::now();
    let n = layout.entries;
    let render_options = &options.render;
    let spp = render_options.spp.max(1);
    let mut stats = RenderStats::default();
    let film = |scale: f32| AdjointFilm::new(adjoint, image, norm, scale, n);
    let mut invalid = 0;
    let clock = std::time::Instant::now();
    let mut term_seconds = [0.0; 3];
    let mut lap = |term: usize| {
        term_seconds[term] = clock.elapsed().as_secs_f64() - term_seconds.iter().sum::<f64>();
    };
    // Samples that land only on pixels of zero adjoint add exactly nothing: not traced.
    let mut interior_film =
        film(1.0 / spp as f32).skipping_zero_adjoint(w, scene.camera.filter.radius());
    let s = interior::pass::<Rev, _>(scene, 0, options, &mut interior_film);
    lap(0);
    stats.absorb(s);
    invalid += interior_film.invalid;
    let (n_primary, n_secondary) = options.boundary.totals(scene, spp);
    let pass = Pass::new(scene, options.velocity);
    let mut primary = vec![0.0; n];
    if n_primary > 0 {
        let sources = PrimarySources::of(scene)?;
        stats.absorb(run_term::<Rev, _>(
            &sources,
            &pass,
            n_primary,
            render_options,
            |samples| film(1.0 / samples as f32),
            |f, _| {
                invalid += f.invalid;
                add(&mut primary, &f.gradient);
            },
        ));
    }
    lap(1);
    let mut secondary = vec![0.0; n];
    if n_secondary > 0 {
        let sources = SecondarySources::of(scene, TangentSampling::Steered);
        stats.absorb(run_term::<Rev, _>(
            &sources,
            &pass,
            n_secondary,
            render_options,
            |samples| film(1.0 / samples as f32),
            |f, _| {
                invalid += f.invalid;
                add(&mut secondary, &f.gradient);
            },
        ));
    }
    lap(2);
    stats.invalid_derivatives += invalid;
    if invalid > 0 && stats.first_invalid.is_none() {
        stats.first_invalid = Some(format!(
            "{invalid} samples with a non-finite gradient (dropped)"
        ));
    }
    stats.samples = spp as u64 * w as u64 * h as u64;
    stats.seconds = start.elapsed().as_secs_f64();
    Ok(Gradient {
        interior: interior_film.gradient,
        primary,
        secondary,
        stats,
        term_seconds,
    })
}

/// `total += part`, entry by entry.
fn add(total: &mut [f64], part: &[f64]) {
    for (t, p) in total.iter_mut().zip(part) {
        *t += p;
    }
}

/// A loss, its gradient, and the image of the loss pass.
#[derive(Clone, Debug, PartialEq)]
pub struct LossGradient {
    /// The loss of the loss pass's image against the target.
    pub loss: f64,
    /// The loss pass's image (seed `seed`).
    pub image: Image,
    /// The gradient of the loss, from the adjoint pass (seed `seed + 1`).
    pub gradient: Gradient,
    /// Wall-clock seconds of the loss pass.
    pub loss_seconds: f64,
}

/// The seed of the adjoint pass for a loss pass of seed `seed` (module docs, "Two seeds").
pub fn adjoint_seed(seed: u64) -> u64 {
    seed.wrapping_add(1)
}

/// The loss of `scene`'s image against `target` and its gradient with respect to the parameters of
/// `layout`: the loss pass renders with `options.render.seed`, the adjoint pass
/// (the same estimators as [`render_gradient`], with the loss pass's image as the pixel values) with
/// [`adjoint_seed`] of it. Errors: a target of another size, and those of [`render_gradient`].
pub fn loss_gradient(
    scene: &Scene,
    layout: &GradientLayout,
    target: &Image,
    loss: Loss,
    options: &DiffOptions,
) -> Result<LossGradient> {
    let start = std::time::Instant::now();
    let scene = &layout.apply(scene)?;
    let (image, loss_stats) = render(scene, &options.render);
    let (value, adjoint) = loss.evaluate(&image, target, "target")?;
    let loss_seconds = start.elapsed().as_secs_f64();
    let adjoint_options = DiffOptions {
        render: RenderOptions {
            seed: adjoint_seed(options.render.seed),
            ..options.render.clone()
        },
        ..options.clone()
    };
    let mut gradient = gradient_with_image(scene, layout, &adjoint, &image, &adjoint_options)?;
    gradient.stats.absorb(loss_stats);
    gradient.stats.seconds = start.elapsed().as_secs_f64();
    Ok(LossGradient {
        loss: value,
        image,
        gradient,
        loss_seconds,
    })
}
