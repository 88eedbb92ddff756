//! The interior term of forward-mode derivative images (docs/theory.md, "attached vertices" and
//! "interior integral"). Paths are sampled in `f32` exactly as for the image; their contributions are re-evaluated
//! with a dual scalar type at attached vertices ([`crate::integrator::attach`]).
//!
//! **The moving pixel filter.** Pixel `j` is `I_j = ∫ w_j(proj x1) J_film(x1) L(x̄) dA(x1)` over the
//! reference surface (`J_film` the film area per unit area of `x1`; `L` includes the area factors `J` of
//! the attached vertices): as `x1` and the camera move, the film position of `x1` moves under the filter.
//! By the product rule `∂I_j = ∫ w_j J_film ∂L + ∫ ∂(w_j J_film) L`:
//! - the first term is estimated exactly like the image, from pixel `j`'s own samples (density
//!   `w_j J_film`): `(1/spp) Σ_{s ∈ j} ∂L_s`. A parameter that moves nothing (an albedo, a radiance) has
//!   only this term, so its derivative image is the image's own estimator differentiated, per pixel;
//! - the second term is estimated from the samples of all pixels whose film point falls under `w_j`,
//!   with their mixture density `Σ_i w_i` (1 for the tent inside the image, whose translates partition
//!   unity): `(1/spp) Σ_s L_s ∂(w_j J_film)_s / (J_film Σ_i w_i)_s`, denominators detached. Dividing by the
//!   sample's own `w(o)` instead would have infinite variance (`∂w/w ~ 1/(1 − |o|)` at the tent's edge;
//!   measured: relative noise above 1 at 64 spp on a moving sphere).
//!
//! Directions at infinity (the environment seen directly, or a camera ray that escapes) use the film
//! area per steradian, `J_ω = f²/cos³θ_c`, in place of `J_film`. The image channel is the mean of each
//! pixel's own samples, bit for bit as [`crate::integrator::render`] except under a constant sky,
//! which this pass light-samples ([`crate::integrator::path::LightStrategy::Derivative`]) and the image
//! leaves to BSDF samples: there the two images agree in expectation.
//!
//! **Normalisation** (supplemental §3; docs/theory.md §6). `Fixed`: the estimate above. `Differentiable`: the derivative of `F_j /
//! W_j`, `F_j` the estimate above (primal: the image) and `W_j = ∫ w_j J_film J₁ dA` (`J₁` the first
//! vertex's area factor, which `L` also carries) estimated like `F_j` with `L = 1` (primal 1): both terms,
//! `(1/spp) Σ_{s ∈ j} ∂J₁` and the moving-filter term. The pixel's derivative is `∂F_j − I_j ∂W_j`, a
//! control variate: `Σ_s (∂L_s − I_j ∂J₁)` and `Σ_s (L_s − I_j) ∂(w_j J_film)_s / …`. `E[∂W_j] = 0` only
//! with `W`'s own primary boundary term ([`crate::integrator::boundary::primary::PrimaryTerm::coverage`]), which
//! [`super::render_derivatives`] adds; the interior alone is biased near silhouettes.
//!
//! Parameters are processed in passes of the scalar type's width (`DualN<N>` carries `N` directions); each
//! pass traces the same paths (same seed), so passes agree on the image and on shared parameters.

use crate::camera::CameraFrame;
use crate::error::Result;
use crate::film::{Film, Filter, Image, PixelFilm, SampleSink};
use crate::integrator::attach::{SceneAttach, for_each_window};
use crate::integrator::driver::{self, RenderStats};
use crate::integrator::options::{DiffOptions, require_continuous_filter};
use crate::integrator::path::{
    Attached, LightStrategy, PathRecord, TraceCounters, contribution_parts,
};
use crate::integrator::primal::trace_samples;
use crate::math::Vec3;
use crate::scalar::{Directions, Scalar, finite_directions};
use crate::scene::Scene;
use crate::scene::frustum::PixelShapes;
use crate::scene::packet;

/// The image and the interior term of the derivative with respect to the parameters in slots
/// `0..count`, with a chosen scalar type `S`, in passes of `S::COUNT` parameters (each pass traces the
/// same paths). Errors: a discontinuous (box) pixel filter.
pub(crate) fn images<S: Directions>(
    scene: &Scene,
    count: usize,
    options: &DiffOptions,
) -> Result<(Image, Vec<Image>, RenderStats)> {
    require_continuous_filter(scene, "the interior term")?;
    let spp = options.render.spp.max(1);
    let passes = for_each_window(scene, count, S::COUNT, |windowed, width| {
        let mut film = PixelFilm::<S>::new(
            scene.camera.width,
            scene.camera.height,
            PixelFilm::<S>::splat_reach(scene.camera.filter.radius()),
        );
        let stats = pass::<S, _>(windowed, width, options, &mut film);
        (film, width, stats)
    });
    let mut image = None;
    let mut stats = RenderStats::default();
    let mut derivatives = Vec::with_capacity(count);
    for (film, width, pass_stats) in passes {
        if image.is_none() {
            image = Some(film.image(spp));
            stats = pass_stats;
        } else {
            stats.invalid_derivatives += pass_stats.invalid_derivatives;
        }
        derivatives.extend(film.derivatives(spp, width, options.normalization));
    }
    stats.samples = spp as u64 * scene.camera.width as u64 * scene.camera.height as u64;
    let image = image.unwrap_or_else(|| Image::new(scene.camera.width, scene.camera.height));
    Ok((image, derivatives, stats))
}

/// One pass: every camera sample into `film`, derivatives in directions `0..width` of `S`.
pub(crate) fn pass<S: Directions, F: Film>(
    scene: &Scene,
    width: usize,
    options: &DiffOptions,
    film: &mut F,
) -> RenderStats
where
    F::Tile: SampleSink<S>,
{
    let (w, h) = (scene.camera.width, scene.camera.height);
    let (wi, hi) = (w as i64, h as i64);
    let spp = options.render.spp.max(1);
    let seed = options.render.seed;
    let frame32 = scene.camera.frame::<f32>();
    let attach = SceneAttach::new(scene, options.velocity);
    let filter = scene.camera.filter;
    driver::run(
        film,
        h as usize,
        "interior",
        &options.render.progress,
        |y, tile, stats| {
            let y = y as u32;
            // Per item, not per pass: a reverse-mode tape holds the values of its own thread only.
            let frame = scene.camera.frame::<S>();
            let mut record = PathRecord {
                strategy: LightStrategy::Derivative,
                ..PathRecord::default()
            };
            let mut counters = TraceCounters::default();
            let mut pixel_shapes = PixelShapes::default();
            for x in 0..w {
                let pixel = (y * w + x) as usize;
                if !tile.needs_pixel(pixel) {
                    continue;
                }
                let shapes = pixel_shapes.gather(scene, &frame32, x, y, spp);
                let centre = glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                for first in (0..spp).step_by(packet::LANES) {
                    let samples = first..(first + packet::LANES as u32).min(spp);
                    trace_samples(
                        scene,
                        &frame32,
                        seed,
                        x,
                        y,
                        samples,
                        shapes,
                        &mut record,
                        &mut counters,
                        |s, offset, ray, record| {
                            tile.begin_sample();
                            let (mut l, first) = contribution_parts::<S, _>(scene, record, &attach);
                            let primal = l.primal();
                            if !primal.is_finite() {
                                stats.invalid(false, || {
                                    format!(
                                        "non-finite radiance {primal} at pixel ({x}, {y}), \
                                         sample {s}"
                                    )
                                });
                                l = Vec3::zero();
                            }
                            let film_point = film_point(&frame, ray.d, first);
                            // Density of the film point among all pixels' samples (per pixel's
                            // spp), times the film area per unit of x1's measure: the detached
                            // density of x1.
                            let motion = film_point.and_then(|((px, py), jacobian)| {
                                let density = mixture_density(&filter, centre + offset, wi, hi)
                                    * jacobian.primal();
                                (density > 0.0 && density.is_finite())
                                    .then(|| (px, py, jacobian / density))
                            });
                            let ok = finite_directions(l.x, width)
                                && finite_directions(l.y, width)
                                && finite_directions(l.z, width)
                                && motion.is_none_or(|(px, py, scale)| {
                                    finite_directions(px, width)
                                        && finite_directions(py, width)
                                        && finite_directions(scale, width)
                                });
                            if !ok {
                                stats.invalid(true, || {
                                    format!(
                                        "non-finite derivative at pixel ({x}, {y}), sample \
                                         {s}: {l:?}, film motion {motion:?}"
                                    )
                                });
                                l = l.detach();
                            }
                            // ∂L at a fixed filter weight: the pixel's own sample, as for the
                            // image; W's integrand is 1 · J₁ (its derivative only: W's primal is 1
                            // by construction).
                            let j1 = match first {
                                Some(a) if ok => a.j - a.j.detach(),
                                _ => S::zero(),
                            };
                            tile.add_own(pixel, l, j1);
                            if let Some((px, py, scale)) = motion.filter(|_| ok) {
                                // L ∂(w_j J_film): splatted to every pixel j the film point
                                // reaches.
                                tile.add_motion(&filter, (px, py), scale, l.primal(), (w, h));
                            }
                            tile.end_sample();
                        },
                    );
                }
            }
            stats.exhausted_rays += counters.exhausted;
        },
    )
}

/// `Σ_i w_i(film)` over the image's pixels `i`: the density of a film point among the samples of all
/// pixels, per sample per pixel. Exactly 1 for the tent away from the image border (its translates
/// partition unity), where it is not computed.
#[inline]
fn mixture_density(filter: &Filter, film: glam::Vec2, width: i64, height: i64) -> f32 {
    let r = filter.radius();
    let inside = |v: f32, n: i64| v >= r && v <= n as f32 - r;
    if *filter == Filter::Tent && inside(film.x, width) && inside(film.y, height) {
        return 1.0;
    }
    // Pixels whose centre is within r of v: i + 0.5 in (v − r, v + r).
    let floor = |v: f32| {
        let i = v as i64;
        if (i as f32) > v { i - 1 } else { i }
    };
    let range = |v: f32, n: i64| floor(v - r - 0.5).max(0)..=(floor(v + r - 0.5) + 1).min(n - 1);
    let mut sum = 0.0;
    for jy in range(film.y, height) {
        for jx in range(film.x, width) {
            sum += filter.eval::<f32>(film.x - (jx as f32 + 0.5), film.y - (jy as f32 + 0.5));
        }
    }
    sum
}

/// The moving film position of the first vertex and the film area per unit of its measure (per unit
/// area, `J_film`, for the attached point `first`; per steradian, `f²/cos³θ_c`, for a camera ray reaching
/// infinity along `dir`). `None` behind the camera.
#[inline]
fn film_point<S: Scalar>(
    frame: &CameraFrame<S>,
    dir: glam::Vec3,
    first: Option<Attached<S>>,
) -> Option<((S, S), S)> {
    match first {
        Some(a) => frame.film_position(a.x, a.n),
        None => {
            let d = Vec3::<S>::constant(dir);
            let z = d.dot(frame.forward);
            if z.primal() <= 0.0 {
                return None;
            }
            let k = frame.focal / z;
            Some((
                (
                    k * d.dot(frame.right) + frame.center.0,
                    -(k * d.dot(frame.up)) + frame.center.1,
                ),
                frame.focal * frame.focal / (z * z * z),
            ))
        }
    }
}
