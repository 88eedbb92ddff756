//! Forward-mode derivative images: the interior term (DESIGN.md §3 "attached vertices", "interior
//! integral"). Paths are sampled in `f32` exactly as for the image; their contributions are re-evaluated
//! with a dual scalar type at attached vertices.

use super::{RenderOptions, RenderStats};
use crate::error::Result;
use crate::film::Image;
use crate::scene::Scene;

/// How a pixel's filter weights are normalised (seed §3).
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum Normalization {
    /// Pixel = mean of `w/p · L` over its samples; `W` is treated as the constant it is in expectation.
    #[default]
    Fixed,
    /// Pixel = `F / W` with both sums differentiated (a control variate; unbiased only with `W`'s own
    /// primary boundary term).
    Differentiable,
}

/// What to compute besides the scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DiffOptions {
    /// Samples, seed and progress, as for the image.
    pub render: RenderOptions,
    /// Pixel normalisation.
    pub normalization: Normalization,
}

/// The image and one derivative image per selected parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct DerivativeImages {
    /// The image (identical to [`super::render`]'s for the same seed and spp).
    pub image: Image,
    /// `interior[k]`: interior term of the derivative with respect to the parameter in slot `k`.
    pub interior: Vec<Image>,
    /// Counters.
    pub stats: RenderStats,
}

/// Renders the image and the interior derivative with respect to the parameters in slots `0..count`
/// (selected with [`Scene::select_parameters`]). Errors: a discontinuous (box) pixel filter.
pub fn render_derivatives(
    scene: &Scene,
    count: usize,
    options: &DiffOptions,
) -> Result<DerivativeImages> {
    let _ = (scene, count, options);
    todo!("derivative: render_derivatives")
}
