//! Forward-mode derivative images: the interior term (DESIGN.md §3 "attached vertices", "interior
//! integral"). Paths are sampled in `f32` exactly as for the image; their contributions are re-evaluated
//! with a dual scalar type at attached vertices ([`super::attach`]).
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
//! pixel's own samples, bit for bit as [`super::render`].
//!
//! **Normalisation** (seed §3). `Fixed`: the estimate above. `Differentiable`: the derivative of `F_j /
//! W_j`, `F_j` the estimate above (primal: the image) and `W_j = ∫ w_j J_film J₁ dA` (`J₁` the first
//! vertex's area factor, which `L` also carries) estimated like `F_j` with `L = 1` (primal 1): both terms,
//! `(1/spp) Σ_{s ∈ j} ∂J₁` and the moving-filter term. The pixel's derivative is `∂F_j − I_j ∂W_j`, a
//! control variate: `Σ_s (∂L_s − I_j ∂J₁)` and `Σ_s (L_s − I_j) ∂(w_j J_film)_s / …`. `E[∂W_j] = 0` only
//! with `W`'s own primary boundary term ([`super::boundary::primary::PrimaryTerm::coverage`]), which
//! [`render_derivatives_with_boundary`] adds; the interior alone is biased near silhouettes.
//!
//! Parameters are processed in passes of the scalar type's width (`DualN<N>` carries `N` directions); each
//! pass traces the same paths (same seed), so passes agree on the image and on shared parameters.

use super::attach::{SceneAttach, window_slots};
use super::path::{Attached, PathRecord, TraceCounters, contribution_parts};
use super::{RenderOptions, RenderStats, trace_sample};
use crate::camera::CameraFrame;
use crate::error::{Error, Result};
use crate::film::{Filter, Image};
use crate::math::Vec3;
use crate::scalar::{Dual32, DualN, Scalar};
use crate::scene::Scene;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// How a pixel's filter weights are normalised (seed §3).
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum Normalization {
    /// Pixel = mean of `w/p · L` over its samples; `W` is treated as the constant it is in expectation.
    Fixed,
    /// Pixel = `F / W` with both sums differentiated (a control variate; unbiased together with `W`'s
    /// own primary boundary term, which [`render_derivatives_with_boundary`] adds). The default: at the
    /// same cost its error is lower (default scene, 64 spp: relative L2 against FD 0.15 instead of 0.49
    /// for `ball.radius`, README "Pixel normalisation").
    #[default]
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
    /// `secondary[k]`: the secondary boundary term (shadows, [`super::boundary::secondary`]) for slot
    /// `k`; empty when it was not computed ([`render_derivatives`] leaves it empty,
    /// [`render_derivatives_with_boundary`] fills it).
    pub secondary: Vec<Image>,
    /// `primary[k]`: the primary boundary term (silhouettes seen by the camera,
    /// [`super::boundary::primary`]) for slot `k`; empty when it was not computed.
    pub primary: Vec<Image>,
    /// Counters.
    pub stats: RenderStats,
}

/// A forward-mode scalar type whose derivative directions can be read back.
pub trait Directions: Scalar {
    /// Number of directions carried.
    const COUNT: usize;
    /// Derivative in direction `k < COUNT`.
    fn direction(&self, k: usize) -> f32;
}

impl<const N: usize> Directions for DualN<N> {
    const COUNT: usize = N;
    #[inline(always)]
    fn direction(&self, k: usize) -> f32 {
        self.eps[k]
    }
}

impl Directions for Dual32 {
    const COUNT: usize = 1;
    #[inline(always)]
    fn direction(&self, _k: usize) -> f32 {
        self.eps
    }
}

/// Calls `$f::<S>(args)` with the narrowest `DualN` that holds `$count` parameters (several passes of
/// eight beyond eight): one dispatch for the interior and both boundary terms.
macro_rules! dispatch_directions {
    ($count:expr, $f:ident($($arg:expr),* $(,)?)) => {
        match $count {
            0 | 1 => $f::<crate::scalar::DualN<1>>($($arg),*),
            2 => $f::<crate::scalar::DualN<2>>($($arg),*),
            3 | 4 => $f::<crate::scalar::DualN<4>>($($arg),*),
            _ => $f::<crate::scalar::DualN<8>>($($arg),*),
        }
    };
}
pub(crate) use dispatch_directions;

/// Renders the image and the interior derivative with respect to the parameters in slots `0..count`
/// (selected with [`Scene::select_parameters`]). Errors: a discontinuous (box) pixel filter.
///
/// Dispatches on `count` to `DualN<1|2|4|8>`; more than eight parameters take several passes of eight.
pub fn render_derivatives(
    scene: &Scene,
    count: usize,
    options: &DiffOptions,
) -> Result<DerivativeImages> {
    dispatch_directions!(count, render_derivatives_in(scene, count, options))
}

/// [`render_derivatives`] with a chosen scalar type `S`, in passes of `S::COUNT` parameters.
pub fn render_derivatives_in<S: Directions>(
    scene: &Scene,
    count: usize,
    options: &DiffOptions,
) -> Result<DerivativeImages> {
    if !scene.camera.filter.is_continuous() {
        return Err(Error::Unsupported(
            "derivatives with the box filter need pixel-edge terms, which are not implemented: use the \
             tent or gaussian filter"
                .into(),
        ));
    }
    let start = std::time::Instant::now();
    let passes = count.div_ceil(S::COUNT).max(1);
    let bar = options.render.progress.then(|| {
        let bar = indicatif::ProgressBar::new(scene.camera.height as u64 * passes as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} rows {elapsed}/{eta}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar
    });
    let reported = AtomicBool::new(false);
    let mut image = None;
    let mut stats = RenderStats::default();
    let mut interior = Vec::with_capacity(count);
    for pass in 0..passes {
        let lo = pass * S::COUNT;
        let width = count.saturating_sub(lo).min(S::COUNT);
        let windowed = window_slots(scene, lo, S::COUNT);
        let out = render_pass::<S>(&windowed, width, lo, options, bar.as_ref(), &reported);
        if pass == 0 {
            image = Some(out.image);
            stats = out.stats;
        } else {
            stats.invalid_derivatives += out.stats.invalid_derivatives;
        }
        interior.extend(out.derivatives);
    }
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    stats.seconds = start.elapsed().as_secs_f64();
    Ok(DerivativeImages {
        image: image.unwrap_or_else(|| Image::new(scene.camera.width, scene.camera.height)),
        interior,
        secondary: Vec::new(),
        primary: Vec::new(),
        stats,
    })
}

/// `diff`'s default boundary budgets in samples per pixel, `(primary, secondary)`, for `spp` camera
/// samples per pixel: `(⌈spp/32⌉, ⌈spp/8⌉)`. These proportions gave the lowest error × time on the
/// default scene (README, "Boundary sample budgets"); the optimum is broad.
pub fn default_boundary_spp(spp: u32) -> (u32, u32) {
    (spp.div_ceil(32).max(1), spp.div_ceil(8).max(1))
}

/// [`render_derivatives`] plus the boundary terms: the primary term with `primary_samples` curve samples
/// and the secondary term with `secondary_samples` boundary samples for the whole image (0 skips a term).
/// Errors as each term (both integrators have both terms).
pub fn render_derivatives_with_boundary(
    scene: &Scene,
    count: usize,
    options: &DiffOptions,
    primary_samples: u64,
    secondary_samples: u64,
) -> Result<DerivativeImages> {
    let start = std::time::Instant::now();
    let mut out = render_derivatives(scene, count, options)?;
    if secondary_samples > 0 {
        out.secondary =
            super::boundary::secondary::render_secondary(scene, count, options, secondary_samples)?;
    }
    if primary_samples > 0 {
        out.primary =
            super::boundary::primary::render_primary_terms(scene, count, options, primary_samples)?
                .combine(&out.image, options.normalization);
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
}

/// One pass: the image and the derivatives in directions `0..width` of `S`.
struct PassOutput {
    image: Image,
    derivatives: Vec<Image>,
    stats: RenderStats,
}

/// What the samples of one row contribute: its image row, its own sums, and the derivatives of the
/// filter-weighted sums `F` and `W` they splat into the `band` rows around it (row `y − reach + b` in band
/// row `b`).
struct Row<S> {
    rgb: Vec<f32>,
    /// Per pixel of the row: the sum of its own samples' contributions in `S`.
    own: Vec<Vec3<S>>,
    /// Per pixel of the row: the sum of its own samples' `∂J₁` (the first vertex's area factor), `W`'s
    /// share of the first term.
    own_w: Vec<S>,
    f: Vec<Vec3<S>>,
    w: Vec<S>,
    exhausted: u64,
    invalid: u64,
    invalid_d: u64,
}

fn render_pass<S: Directions>(
    scene: &Scene,
    width: usize,
    lo: usize,
    options: &DiffOptions,
    bar: Option<&indicatif::ProgressBar>,
    reported: &AtomicBool,
) -> PassOutput {
    let (w, h) = (scene.camera.width, scene.camera.height);
    let (wi, hi) = (w as i64, h as i64);
    let spp = options.render.spp.max(1);
    let seed = options.render.seed;
    let frame32 = scene.camera.frame::<f32>();
    let frame = scene.camera.frame::<S>();
    let attach = SceneAttach::new(scene);
    let filter = scene.camera.filter;
    let radius = filter.radius();
    // A film point within `radius` of its own pixel centre reaches centres less than `2 radius` away.
    let reach = ((2.0 * radius).ceil() as i64 - 1).max(0);
    let band = (2 * reach + 1) as usize;
    let row_len = 3 * w as usize;
    let rows: Vec<Row<S>> = (0..h)
        .into_par_iter()
        .map(|y| {
            let mut record = PathRecord::default();
            let mut counters = TraceCounters::default();
            let mut row = Row {
                rgb: vec![0.0; row_len],
                own: vec![Vec3::zero(); w as usize],
                own_w: vec![S::zero(); w as usize],
                f: vec![Vec3::zero(); band * w as usize],
                w: vec![S::zero(); band * w as usize],
                exhausted: 0,
                invalid: 0,
                invalid_d: 0,
            };
            for x in 0..w {
                let centre = glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let mut sum = glam::Vec3::ZERO;
                for s in 0..spp {
                    let (offset, ray) =
                        trace_sample(scene, &frame32, seed, x, y, s, &mut record, &mut counters);
                    let (l, first) = contribution_parts::<S, _>(scene, &record, &attach);
                    let primal = l.primal();
                    let mut l = l;
                    if primal.is_finite() {
                        sum += primal;
                    } else {
                        if row.invalid == 0 && !reported.swap(true, Ordering::Relaxed) {
                            eprintln!(
                                "non-finite radiance {primal} at pixel ({x}, {y}), sample {s}"
                            );
                        }
                        row.invalid += 1;
                        l = Vec3::zero();
                    }
                    let film_point = film_point(&frame, ray.d, first);
                    // Density of the film point among all pixels' samples (per pixel's spp), times the
                    // film area per unit of x1's measure: the detached density of x1.
                    let motion = film_point.and_then(|((px, py), jacobian)| {
                        let density =
                            mixture_density(&filter, centre + offset, wi, hi) * jacobian.primal();
                        (density > 0.0 && density.is_finite()).then(|| (px, py, jacobian / density))
                    });
                    let ok = finite(l.x, width)
                        && finite(l.y, width)
                        && finite(l.z, width)
                        && motion.is_none_or(|(px, py, scale)| {
                            finite(px, width) && finite(py, width) && finite(scale, width)
                        });
                    if !ok {
                        if row.invalid_d == 0 && !reported.swap(true, Ordering::Relaxed) {
                            eprintln!(
                                "non-finite derivative (parameters {lo}..{}) at pixel ({x}, {y}), \
                                 sample {s}: {l:?}, film motion {motion:?}",
                                lo + width
                            );
                        }
                        row.invalid_d += 1;
                        l = l.detach();
                    }
                    // ∂L at a fixed filter weight: the pixel's own sample, as for the image; W's
                    // integrand is 1 · J₁.
                    row.own[x as usize] += l;
                    if ok && let Some(a) = first {
                        row.own_w[x as usize] += a.j - a.j.detach();
                    }
                    let Some((px, py, scale)) = motion.filter(|_| ok) else {
                        continue;
                    };
                    // L ∂(w_j J_film): splatted to every pixel j the film point reaches.
                    let lp = Vec3::<S>::constant(l.primal());
                    for jy in (y as i64 - reach).max(0)..=(y as i64 + reach).min(hi - 1) {
                        let dy = py - (jy as f32 + 0.5);
                        if dy.primal().abs() >= radius {
                            continue;
                        }
                        let band_row = (jy - y as i64 + reach) as usize * w as usize;
                        for jx in (x as i64 - reach).max(0)..=(x as i64 + reach).min(wi - 1) {
                            let dx = px - (jx as f32 + 0.5);
                            if dx.primal().abs() >= radius {
                                continue;
                            }
                            let weight = filter.eval(dx, dy) * scale;
                            let dw = weight - weight.detach();
                            let i = band_row + jx as usize;
                            row.f[i] += lp * dw;
                            row.w[i] += dw;
                        }
                    }
                }
                let mean = sum / spp as f32;
                let i = 3 * x as usize;
                row.rgb[i..i + 3].copy_from_slice(&mean.to_array());
            }
            row.exhausted = counters.exhausted;
            if let Some(bar) = bar {
                bar.inc(1);
            }
            row
        })
        .collect();
    // Gather the splats in a fixed order (source rows ascending): the same sums whatever the threads.
    let n = (w * h) as usize;
    let mut own = vec![Vec3::<S>::zero(); n];
    let mut own_w = vec![S::zero(); n];
    let mut f_sum = vec![Vec3::<S>::zero(); n];
    let mut w_sum = vec![S::zero(); n];
    let mut image = Image::new(w, h);
    let mut stats = RenderStats {
        samples: spp as u64 * w as u64 * h as u64,
        ..RenderStats::default()
    };
    for (y, row) in rows.iter().enumerate() {
        image.rgb[y * row_len..(y + 1) * row_len].copy_from_slice(&row.rgb);
        own[y * w as usize..(y + 1) * w as usize].copy_from_slice(&row.own);
        own_w[y * w as usize..(y + 1) * w as usize].copy_from_slice(&row.own_w);
        for b in 0..band {
            let jy = y as i64 - reach + b as i64;
            if jy < 0 || jy >= hi {
                continue;
            }
            for jx in 0..w as usize {
                let (src, dst) = (b * w as usize + jx, jy as usize * w as usize + jx);
                f_sum[dst] += row.f[src];
                w_sum[dst] += row.w[src];
            }
        }
        stats.exhausted_rays += row.exhausted;
        stats.invalid_samples += row.invalid;
        stats.invalid_derivatives += row.invalid_d;
    }
    let mut derivatives = vec![Image::new(w, h); width];
    let inv_spp = S::constant(1.0 / spp as f32);
    for p in 0..n {
        // F = (own + motion)/spp with primal the image; W = 1 + (Σ ∂J₁ + Σ ∂(w J)/(J Σw))/spp.
        let f = (own[p] + f_sum[p]) * inv_spp;
        let pixel = match options.normalization {
            Normalization::Fixed => f,
            // ∂(F/W) = ∂F/W − F ∂W/W² with W = 1 at the primal (seed §3, eq. 26).
            Normalization::Differentiable => {
                f - Vec3::constant(f.primal()) * ((own_w[p] + w_sum[p]) * inv_spp)
            }
        };
        for (k, d) in derivatives.iter_mut().enumerate() {
            d.rgb[3 * p] = pixel.x.direction(k);
            d.rgb[3 * p + 1] = pixel.y.direction(k);
            d.rgb[3 * p + 2] = pixel.z.direction(k);
        }
    }
    PassOutput {
        image,
        derivatives,
        stats,
    }
}

/// All directions `0..width` of `v` are finite.
#[inline]
fn finite<S: Directions>(v: S, width: usize) -> bool {
    (0..width).all(|k| v.direction(k).is_finite())
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
        Some(a) => Some((frame.project(a.x)?, frame.film_area_jacobian(a.x, a.n))),
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
