//! Light transport estimators. Paths are traced in `f32`; their contributions are evaluated with the
//! generic shading code.

use crate::film::Image;
use crate::scene::Scene;

/// Which estimator renders the image.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum IntegratorKind {
    /// Emission seen directly plus next-event estimation at the first hit, combined with BSDF sampling
    /// by multiple importance sampling.
    Direct,
    /// Path tracing with next-event estimation and MIS, up to `max_depth` bounces.
    Path {
        /// Longest path in segments after the camera (1 = direct lighting only).
        max_depth: u32,
    },
}

/// What to render apart from the scene itself.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Samples per pixel.
    pub spp: u32,
    /// Seed of the deterministic sampler.
    pub seed: u64,
    /// Show a progress bar (only meaningful on a terminal).
    pub progress: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            spp: 64,
            seed: 0,
            progress: false,
        }
    }
}

/// Counters of a render.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Camera samples taken.
    pub samples: u64,
    /// Rays whose sphere tracing ran out of steps (treated as misses).
    pub exhausted_rays: u64,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// Renders the image of `scene`.
pub fn render(scene: &Scene, options: &RenderOptions) -> (Image, RenderStats) {
    let _ = (scene, options);
    todo!("integrator: render")
}
