//! What to compute besides the scene: samples, seed, pixel normalisation and boundary budgets, and how
//! to report progress.

use crate::error::{Error, Result};
use crate::film::Normalization;
use crate::scene::Scene;
use std::sync::Arc;

/// A progress callback: `(stage, done, total)` work items of the named stage ("image", "interior",
/// "primary", "secondary"), called from worker threads as items finish. The default reports nothing.
#[derive(Clone, Default)]
pub struct Progress(Option<Arc<ReportFn>>);

/// The callback behind [`Progress`]: `(stage, done, total)`.
type ReportFn = dyn Fn(&str, u64, u64) + Send + Sync;

impl Progress {
    /// Calls `report(stage, done, total)` as work items finish.
    pub fn new(report: impl Fn(&str, u64, u64) + Send + Sync + 'static) -> Self {
        Self(Some(Arc::new(report)))
    }

    /// Reports `done` of `total` items of `stage`.
    #[inline]
    pub fn report(&self, stage: &str, done: u64, total: u64) {
        if let Some(report) = &self.0 {
            report(stage, done, total);
        }
    }
}

impl std::fmt::Debug for Progress {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(if self.0.is_some() {
            "Progress(callback)"
        } else {
            "Progress(none)"
        })
    }
}

/// Progress reporting never changes what is computed: any two are equal.
impl PartialEq for Progress {
    fn eq(&self, _other: &Self) -> bool {
        true
    }
}

/// What to render apart from the scene itself.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Samples per pixel.
    pub spp: u32,
    /// Seed of the deterministic sampler.
    pub seed: u64,
    /// Called as work finishes (default: nothing).
    pub progress: Progress,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            spp: 64,
            seed: 0,
            progress: Progress::default(),
        }
    }
}

/// Boundary samples per pixel of each boundary term, a number ≥ 0 that may be fractional (the term
/// takes `rate × pixels` samples, rounded, at least one); `None` takes the default for the camera's
/// samples per pixel ([`BoundaryBudget::resolve`]), 0 skips the term.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct BoundaryBudget {
    /// Silhouette-curve samples per pixel for the primary (silhouette) term.
    pub primary_spp: Option<f32>,
    /// Boundary samples per pixel for the secondary (shadow) term.
    pub secondary_spp: Option<f32>,
}

impl BoundaryBudget {
    /// No boundary samples: the interior term alone.
    pub const NONE: Self = Self {
        primary_spp: Some(0.0),
        secondary_spp: Some(0.0),
    };

    /// Samples per pixel `(primary, secondary)` for `spp` camera samples per pixel; the defaults are
    /// `(⌈spp/32⌉, ⌈spp/8⌉)`, which keep the complete derivative within about 3× the image's time;
    /// `examples/boundary_budgets.rs` measures their error × time against other budgets.
    pub fn resolve(&self, spp: u32) -> (f32, f32) {
        (
            (self.primary_spp).unwrap_or(spp.div_ceil(32).max(1) as f32),
            (self.secondary_spp).unwrap_or(spp.div_ceil(8).max(1) as f32),
        )
    }

    /// Samples `(primary, secondary)` for the whole image of `scene`: each rate times the pixels,
    /// rounded, and at least one where the rate is positive.
    pub fn totals(&self, scene: &Scene, spp: u32) -> (u64, u64) {
        let pixels = scene.camera.width as u64 * scene.camera.height as u64;
        let (p, s) = self.resolve(spp);
        let total = |rate: f32| {
            if rate > 0.0 {
                ((rate as f64 * pixels as f64).round() as u64).max(1)
            } else {
                0
            }
        };
        (total(p), total(s))
    }
}

/// What a derivative computes besides the scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DiffOptions {
    /// Samples, seed and progress, as for the image.
    pub render: RenderOptions,
    /// Pixel normalisation.
    pub normalization: Normalization,
    /// Boundary samples of the complete derivative.
    pub boundary: BoundaryBudget,
    /// How the passes move the points of shapes (docs/theory.md §8).
    pub velocity: VelocityField,
}

/// The velocity field by which derivative passes move the points of shapes' surfaces (docs/theory.md
/// §8). Every choice gives the same derivative in expectation; they differ in variance.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum VelocityField {
    /// The shape's known motion ([`crate::sdf::Sdf::carried`]: rigid for translations and rotations, radial for a
    /// torus's major radius) where its curvature radius is below a pixel where the camera sees it,
    /// the normal field elsewhere.
    #[default]
    Auto,
    /// The normal field `x = p + V n` everywhere (`∂πJ = κV`).
    Normal,
    /// The known motion of every shape that has one (without creases), wherever the camera is.
    Carried,
}

impl std::str::FromStr for VelocityField {
    type Err = String;
    /// `"auto"`, `"normal"` or `"carried"`.
    fn from_str(text: &str) -> std::result::Result<Self, String> {
        match text {
            "auto" => Ok(Self::Auto),
            "normal" => Ok(Self::Normal),
            "carried" => Ok(Self::Carried),
            _ => Err(format!(
                "unknown velocity field {text:?} (expected auto, normal or carried)"
            )),
        }
    }
}

/// Derivatives move film points under the pixel filter: refuses a discontinuous (box) filter, whose
/// pixel-edge boundary terms are not implemented; `what` names the derivative term in the error.
pub fn require_continuous_filter(scene: &Scene, what: &str) -> Result<()> {
    if scene.camera.filter.is_continuous() {
        return Ok(());
    }
    Err(Error::field(
        "camera.filter",
        format!(
            "{what} with the box filter needs pixel-edge boundary terms, which are not \
             implemented: use \"tent\" or \"gaussian\""
        ),
    ))
}
