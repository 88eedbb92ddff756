//! Forward-mode derivative images: the orchestrator of the complete derivative, interior term
//! ([`interior`]) plus the primary and secondary boundary terms ([`crate::integrator::boundary`]).
//!
//! Parameters are selected with [`Scene::select`] (a [`Selection`], derivative `k` in slot `k`) and
//! processed in passes of the scalar type's width (`DualN<N>` carries `N` directions); each pass traces the same paths
//! (same seed), so passes agree on the image and on shared parameters.

pub mod interior;

use crate::error::Result;
use crate::film::{Channels, Image};
use crate::integrator::boundary::tangent_sampling::TangentSampling;
use crate::integrator::boundary::{primary, secondary};
use crate::integrator::driver::RenderStats;
use crate::integrator::options::DiffOptions;
use crate::scalar::dispatch_directions;
use crate::scene::{Scene, Selection};

/// The image and one derivative image per selected parameter, term by term.
#[derive(Clone, Debug, PartialEq)]
pub struct DerivativeImages {
    /// The image (identical to [`crate::integrator::render`]'s for the same seed and spp).
    pub image: Image,
    /// `interior[k]`: interior term of the derivative with respect to the parameter in slot `k`.
    pub interior: Vec<Image>,
    /// `secondary[k]`: the secondary boundary term (shadows, [`secondary`]) for slot `k`; empty when
    /// it was not computed (budget 0).
    pub secondary: Vec<Image>,
    /// `primary[k]`: the primary boundary term (silhouettes seen by the camera, [`primary`]) for slot
    /// `k`; empty when it was not computed (budget 0).
    pub primary: Vec<Image>,
    /// Counters.
    pub stats: RenderStats,
}

/// The image and the complete derivative (interior, primary and secondary terms) of `scene` with
/// respect to the parameters of `selection`, with the boundary budgets of `options.boundary` (samples
/// per pixel; a term with budget 0 is skipped). Errors: a selection `scene` does not have, a box pixel
/// filter, a failed silhouette extraction.
pub fn render_derivatives(
    scene: &Scene,
    selection: &Selection,
    options: &DiffOptions,
) -> Result<DerivativeImages> {
    let selected = selection.apply(scene)?;
    let (primary, secondary) = options.boundary.totals(&selected, options.render.spp);
    derivatives(&selected, selection.len(), options, primary, secondary)
}

/// The image and the interior term alone (the boundary budgets of `options` are ignored): what
/// renderers without boundary terms return, biased wherever edges move.
///
/// Dispatches on the number of derivatives to `DualN<1|2|4|8>`; more than eight take several passes
/// of eight. Errors: a selection `scene` does not have.
pub fn render_interior(
    scene: &Scene,
    selection: &Selection,
    options: &DiffOptions,
) -> Result<DerivativeImages> {
    interior_images(&selection.apply(scene)?, selection.len(), options)
}

/// [`render_interior`] with a chosen scalar type `S`, in passes of `S::COUNT` parameters.
pub fn render_interior_in<S: crate::scalar::Directions>(
    scene: &Scene,
    selection: &Selection,
    options: &DiffOptions,
) -> Result<DerivativeImages> {
    interior_images_in::<S>(&selection.apply(scene)?, selection.len(), options)
}

/// The interior term plus the boundary terms with explicit budgets for the whole image:
/// `primary_samples` silhouette samples and `secondary_samples` boundary samples (0 skips a term).
/// Errors as [`render_derivatives`].
pub fn render_derivatives_with_boundary(
    scene: &Scene,
    selection: &Selection,
    options: &DiffOptions,
    primary_samples: u64,
    secondary_samples: u64,
) -> Result<DerivativeImages> {
    let selected = selection.apply(scene)?;
    let count = selection.len();
    derivatives(
        &selected,
        count,
        options,
        primary_samples,
        secondary_samples,
    )
}

/// [`render_interior`] of a scene with its selection applied, slots `0..count`.
fn interior_images(
    selected: &Scene,
    count: usize,
    options: &DiffOptions,
) -> Result<DerivativeImages> {
    dispatch_directions!(count, interior_images_in(selected, count, options))
}

/// [`render_interior_in`] of a scene with its selection applied, slots `0..count`.
fn interior_images_in<S: crate::scalar::Directions>(
    selected: &Scene,
    count: usize,
    options: &DiffOptions,
) -> Result<DerivativeImages> {
    let start = std::time::Instant::now();
    let (image, interior, mut stats) = interior::images::<S>(selected, count, options)?;
    stats.seconds = start.elapsed().as_secs_f64();
    Ok(DerivativeImages {
        image,
        interior,
        secondary: Vec::new(),
        primary: Vec::new(),
        stats,
    })
}

/// [`render_derivatives_with_boundary`] of a scene with its selection applied, slots `0..count`.
fn derivatives(
    selected: &Scene,
    count: usize,
    options: &DiffOptions,
    primary_samples: u64,
    secondary_samples: u64,
) -> Result<DerivativeImages> {
    let start = std::time::Instant::now();
    let mut out = interior_images(selected, count, options)?;
    if secondary_samples > 0 {
        let steered = TangentSampling::Steered;
        let (images, stats) =
            secondary::secondary_term(selected, count, options, secondary_samples, steered)?;
        out.secondary = images;
        out.stats.absorb(stats);
    }
    if primary_samples > 0 {
        let term = primary::primary_terms(selected, count, options, primary_samples)?;
        out.primary = term.combine(&out.image, options.normalization);
        out.stats.absorb(term.stats);
    }
    out.stats.seconds = start.elapsed().as_secs_f64();
    Ok(out)
}

impl DerivativeImages {
    /// The derivative images: `interior[k] + secondary[k] + primary[k]`, each boundary term where it
    /// was computed.
    pub fn total(&self) -> Vec<Image> {
        let mut total = self.interior.clone();
        for term in [&self.secondary, &self.primary] {
            for (t, s) in total.iter_mut().zip(term) {
                for (a, b) in t.rgb.iter_mut().zip(&s.rgb) {
                    *a += b;
                }
            }
        }
        total
    }

    /// The EXR channels of a derivative command: `R`, `G`, `B` (the image), `d.P.R|G|B` per parameter
    /// `P` of `names` (the complete derivative), and with `terms` each term, `d_interior.P.*`,
    /// `d_primary.P.*`, `d_secondary.P.*` (they sum to `d.P`; a term not computed has no channels).
    pub fn channels(&self, names: &[String], terms: bool) -> Channels {
        let mut channels = self.image.rgb_channels("");
        for (p, d) in names.iter().zip(&self.total()) {
            channels.extend(d.rgb_channels(&format!("d.{p}.")));
        }
        if terms {
            for (term, images) in [
                ("d_interior", &self.interior),
                ("d_primary", &self.primary),
                ("d_secondary", &self.secondary),
            ] {
                for (p, d) in names.iter().zip(images) {
                    channels.extend(d.rgb_channels(&format!("{term}.{p}.")));
                }
            }
        }
        channels
    }

    /// A one-line note for the user: which terms the derivative holds, and the shapes with crease
    /// curves whose boundary terms are not sampled (`(name, what)`, [`Scene::unsampled_creases`]).
    pub fn note(&self, creased: &[(String, String)]) -> String {
        terms_note(
            ("derivatives hold", "d.P"),
            !self.primary.is_empty(),
            !self.secondary.is_empty(),
            creased,
        )
    }
}

/// The one-line note of a derivative or gradient: which terms it holds (`primary`, `secondary`: whether
/// those terms were computed) and the shapes with crease curves whose boundary terms are not sampled.
/// `(holds, result)` words the subject: `("derivatives hold", "d.P")`, `("the gradient holds", "the
/// gradient")`.
pub fn terms_note(
    (holds, result): (&str, &str),
    primary: bool,
    secondary: bool,
    creased: &[(String, String)],
) -> String {
    if !primary && !secondary {
        return format!(
            "{holds} the interior term only (both boundary budgets are 0); the silhouette and \
             shadow terms are missing, so {result} is wrong where edges move"
        );
    }
    let mut held = vec!["interior"];
    let mut skipped = Vec::new();
    for (on, name) in [
        (secondary, "secondary (shadow)"),
        (primary, "primary (silhouette)"),
    ] {
        if on { &mut held } else { &mut skipped }.push(name);
    }
    let held = match held.as_slice() {
        [rest @ .., last] if !rest.is_empty() => format!("{} and {last}", rest.join(", ")),
        _ => held.join(""),
    };
    let mut note = format!("{holds} the {held} terms");
    if !skipped.is_empty() {
        note += &format!("; skipped: {} (budget 0)", skipped.join(", "));
    }
    if !creased.is_empty() {
        let list: Vec<String> = creased.iter().map(|(n, r)| format!("{n} ({r})")).collect();
        note += &format!(
            "; not sampled along crease curves, so where they move or hide what moves {result} \
             misses those boundary terms: {}",
            list.join(", ")
        );
    }
    note
}
