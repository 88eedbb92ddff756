//! The secondary boundary term of the `direct` integrator (DESIGN.md §3 "Boundary integrals", seed §2):
//! shadows, i.e. the visibility between a surface point `x_S` seen by the camera and an emitter point
//! `x_D`, which jumps where the segment `x_S x_D` touches an occluder `M` tangentially at `x_B`.
//!
//! # The integral
//!
//! With the `direct` integrator pixel `j` is (the first vertex by area, as in [`super::super::derivative`])
//!
//! ```text
//!   I_j = ∫ dA(x_S) w_j(proj x_S) J_film(x_S) ∫ dA(x_D) f(x_S) G(x_S, x_D) V(x_S, x_D) L_e(x_D)    (1)
//! ```
//!
//! (`f` the BSDF towards the camera, `V` the visibility; emission seen directly and environment light
//! take the same form with `dA(x_D)` replaced by a solid angle). For fixed `x_S`, `V` jumps across
//! curves on the emitter: the shadow of `M`'s silhouettes as seen from `x_S`. The interior estimator
//! keeps every visibility fixed at its sampled value; the missing term (seed §1 eqs. 4–6) is
//!
//! ```text
//!   ∂I_j ⊃ ∫ dA(x_S) w_j J_film ∫_{∂} Δf V_∂ dℓ(x_D),   Δf = f G L_e |blocked side − f G L_e |clear side
//! ```
//!
//! `V_∂` the normal velocity of the curve towards its blocked side ([`super::boundary_velocity`], its
//! sign convention: `V_∂ > 0` grows the blocked side). On the blocked side `M` occludes the segment, so
//! `Δf = −f G L_e` evaluated on the clear segment (the only case where a tangency changes anything: the
//! rest of the segment must be clear, which tracing the tangent line to its first hits guarantees).
//! Everything but `V_∂` is evaluated at the primal: `Δf V_∂` is already first order.
//!
//! # Sampling the segments
//!
//! Change variables from `(x_S, x_D ∈ ∂)` to `(x_B, θ_B)` with the exact area-form Jacobian of
//! [`super::segment`] (eq. (A) there; the seed's eq. 23 misses `sin∠(c_t, c_n)`):
//! `dA(x_S) dℓ(x_D) = J dA(x_B) dθ_B`, `J = |x_S x_B| |x_S x_D| κ_n / (|n_S·ω| sin θ_D)`.
//!
//! One boundary sample: pick a shape `M` uniformly among the `K` area-samplable shapes (finite bounds;
//! unbounded shapes such as planes have no silhouettes of their own), draw one line of
//! [`sample_surface`] (every crossing `x_B` kept, each with the exact hit density `p_A(x_B)`), and for
//! each `x_B` one angle `θ_B ∈ [0, π)` in an orthonormal tangent frame `(t₁, t₂)`. The unoriented line
//! `x_B + t ω`, `ω = cos θ_B t₁ + sin θ_B t₂`, carries **two** segments (`x_D` on either side), both
//! evaluated; `(x_B, θ_B ∈ [0, π), side)` covers every oriented segment exactly once, so
//!
//! ```text
//!   estimate_j = Σ_{hits x_B} Σ_{sides} w_j J_film(x_S) · (−f G L_e) · V_∂ · J · K / (p_A(x_B) p(θ_B))   (2)
//! ```
//!
//! averaged over the `N` boundary samples (a budget independent of the camera's spp, with its own
//! random stream [`BOUNDARY_STREAM`]).
//!
//! **The angle.** Most tangent lines reach no emitter, so `θ_B` is drawn from a one-sample MIS mixture
//! ([`super::tangent_sampling`], balance heuristic): with probability `P_u ≥ 1/4` uniform on `[0, π)`,
//! otherwise uniform on the arc of lines of the tangent plane that reach finite emitter `e` (the chord
//! the plane cuts from a rectangle, the disk it cuts from a sphere, seen from `x_B`), emitter `e` chosen
//! in proportion to its luminance times its arc's width. `p(θ_B)` in (2) is the mixture density
//! `P_u / π + Σ_e P_e 1[θ_B ∈ arc_e] / width_e`, whichever strategy drew `θ_B`; it is at least `1/(4π)`
//! everywhere, so every line (environment, occluded emitters, non-emitter ends) keeps a positive density
//! and (2) stays unbiased. The environment is reached by every escaping line: its share (luminance times
//! `π`) joins the uniform strategy. Where no arc exists `p = 1/π`; with
//! [`TangentSampling::Uniform`] ([`render_secondary_with`]) always, as before steering (same draws).
//! On the floor shadow of `tests/secondary_boundary.rs` steering cuts the variance about 17–20 times at
//! the same cost per sample (`tests/tangent_sampling.rs`).
//!
//! Lines that are not silhouettes (`κ_n ≤ 0`) are rejected (their `J` is 0: they separate nothing).
//! The tangent line is traced from `x_B` pushed `4 eps` outward along `n_B` ([`Scene::offset_origin`]):
//! on a silhouette `M` curves away from the line, so the pushed line clears `M` near `x_B`, and its first
//! hits each way are `x_S` and `x_D`; a trace that runs out of steps counts as a miss, as in the
//! integrator's own paths (the primal lets such a line escape, so its derivative must too). `x_S` must
//! lie on a shape and be visible from the camera (an unoccluded segment `x₀ x_S`), `x_D` on a finite
//! emitter, or the line must escape to the environment: then `dℓ(x_D)` is the angle `dψ` seen from
//! `x_S`, `G L_e dA` becomes `|n_S·ω| L_e dψ`, `J` its directional form, and `V_∂` the angular velocity
//! (the linear velocity on a plane at distance `d` from `x_S`, perpendicular to `ω`, divided by `d`).
//!
//! **Film.** `x_S` is an area-measure first vertex: it contributes to every pixel `j` whose filter
//! covers its projection, with weight `w_j(proj x_S) J_film(x_S)` (film area per unit area, the same
//! convention as the interior term's first vertex). No camera sample is involved.
//!
//! **What a sphere alone returns.** Its self-shadow terminator is not a visibility boundary of this
//! kind: there `f G → 0` continuously (the cosine at `x_S`), and no tangent line of a lone convex shape
//! starts on a shape, so (2) is exactly 0. A scene contributes only where a segment from a visible
//! shape point to an emitter grazes an occluder.
//!
//! **Scope.** Only the `direct` integrator (paths `x₀ x_S x_D`); other integrators are refused with
//! [`crate::Error::Unsupported`]. Not included: the primary boundary (silhouettes seen from the camera), the
//! discontinuity of one-sided emitters and BSDFs across their tangent planes, crease edges.

use super::segment::{BoundarySegment, boundary_velocity, is_silhouette_direction};
use super::tangent_sampling::{TangentSampler, TangentSampling};
use super::{check_supported, in_windows};
use crate::error::Result;
use crate::film::Image;
use crate::integrator::attach::SceneAttach;
use crate::integrator::derivative::{DiffOptions, Directions, dispatch_directions};
use crate::integrator::path::{TraceCounters, occluded};
use crate::integrator::shading::geometry_term;
use crate::integrator::surface_sampling::{SurfaceSample, sample_surface};
use crate::math::{Ray, Vec3};
use crate::sampler::Sampler;
use crate::scene::{Intersection, Scene, Surface};
use rayon::prelude::*;

/// The random stream of boundary samples (distinct from the camera's
/// [`crate::integrator::CAMERA_STREAM`]).
pub const BOUNDARY_STREAM: u64 = 0x5EC0_4DA2;

/// Boundary samples per parallel work item (results are gathered in sample order: deterministic).
const CHUNK: u64 = 256;

/// The secondary boundary term of the derivative with respect to the parameters in slots `0..count`
/// (selected with [`Scene::select_parameters`]), estimated with `samples` boundary samples for the whole
/// image (see the [module docs](self)). One image per parameter, the layout of
/// [`super::super::derivative::DerivativeImages::interior`]; the seed is `options.render.seed`.
///
/// Errors: an integrator other than `direct`, a box pixel filter.
pub fn render_secondary(
    scene: &Scene,
    count: usize,
    options: &DiffOptions,
    samples: u64,
) -> Result<Vec<Image>> {
    render_secondary_with(scene, count, options, samples, TangentSampling::Steered)
}

/// [`render_secondary`] with a chosen way of drawing the tangent angles `θ_B` (the default,
/// [`TangentSampling::Steered`], has less variance; both have the same expectation).
pub fn render_secondary_with(
    scene: &Scene,
    count: usize,
    options: &DiffOptions,
    samples: u64,
    tangent: TangentSampling,
) -> Result<Vec<Image>> {
    dispatch_directions!(
        count,
        render_secondary_in(scene, count, options, samples, tangent)
    )
}

/// [`render_secondary_with`] with a chosen scalar type, in passes of `S::COUNT` parameters.
pub fn render_secondary_in<S: Directions>(
    scene: &Scene,
    count: usize,
    options: &DiffOptions,
    samples: u64,
    tangent: TangentSampling,
) -> Result<Vec<Image>> {
    check_supported(scene, "secondary")?;
    Ok(in_windows::<S>(scene, count, |windowed, width| {
        pass::<S>(windowed, width, options.render.seed, samples, tangent)
    }))
}

/// One pass over all boundary samples: directions `0..width` of `S`.
fn pass<S: Directions>(
    scene: &Scene,
    width: usize,
    seed: u64,
    samples: u64,
    tangent: TangentSampling,
) -> Vec<Image> {
    let (w, h) = (scene.camera.width, scene.camera.height);
    let candidates: Vec<usize> = (0..scene.shapes.len())
        .filter(|&i| {
            let b = scene.shapes[i].bounds;
            b.is_finite() && !b.is_empty()
        })
        .collect();
    let mut images = vec![Image::new(w, h); width];
    if candidates.is_empty() || samples == 0 {
        return images;
    }
    let ctx = Context {
        scene,
        attach: SceneAttach::new(scene),
        candidates,
        tangent: TangentSampler::new(scene, tangent),
    };
    let chunks: Vec<Vec<(usize, Vec3<S>)>> = (0..samples.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut splats = Vec::new();
            let mut hits = Vec::new();
            let mut counters = TraceCounters::default();
            for k in c * CHUNK..((c + 1) * CHUNK).min(samples) {
                let mut sampler = Sampler::new(seed, BOUNDARY_STREAM, 0, k);
                ctx.sample(&mut sampler, &mut hits, &mut splats, &mut counters);
            }
            splats
        })
        .collect();
    let inv = 1.0 / samples as f64;
    // Sum in f64 in sample order: the same result whatever the thread count.
    let mut acc = vec![0.0f64; 3 * width * (w * h) as usize];
    for (pixel, v) in chunks.iter().flatten() {
        for k in 0..width {
            let base = 3 * (k * (w * h) as usize + pixel);
            acc[base] += v.x.direction(k) as f64;
            acc[base + 1] += v.y.direction(k) as f64;
            acc[base + 2] += v.z.direction(k) as f64;
        }
    }
    for (k, image) in images.iter_mut().enumerate() {
        let (off, len) = (3 * k * (w * h) as usize, image.rgb.len());
        for (d, a) in image.rgb.iter_mut().zip(&acc[off..off + len]) {
            *d = (a * inv) as f32;
        }
    }
    images
}

/// What every boundary sample needs.
struct Context<'a> {
    scene: &'a Scene,
    attach: SceneAttach<'a>,
    /// Shapes with finite bounds (the ones [`sample_surface`] can sample), chosen uniformly.
    candidates: Vec<usize>,
    /// Draws `θ_B` (towards the emitters).
    tangent: TangentSampler,
}

/// The end `x_D` of a segment.
#[derive(Copy, Clone)]
enum End {
    /// A point of finite emitter `e` with its normal.
    Emitter(usize, glam::Vec3, glam::Vec3),
    /// The environment emitter `e`, at infinity.
    Environment(usize),
}

impl Context<'_> {
    /// One boundary sample: a shape, a line of area samples on it, one tangent angle per hit; pushes the
    /// weighted contributions `(pixel, value)` of eq. (2) (not yet divided by the sample count).
    fn sample<S: Directions>(
        &self,
        sampler: &mut Sampler,
        hits: &mut Vec<SurfaceSample>,
        splats: &mut Vec<(usize, Vec3<S>)>,
        counters: &mut TraceCounters,
    ) {
        let scene = self.scene;
        let k = self.candidates.len();
        let pick = ((sampler.next_1d() * k as f32) as usize).min(k - 1);
        let m = self.candidates[pick];
        let shape = &scene.shapes[m];
        let u_axis = sampler.next_1d();
        let u_face = sampler.next_2d();
        let Ok(line) = sample_surface(shape, &scene.trace, u_axis, u_face, hits) else {
            return;
        };
        if line.exhausted.is_some() {
            counters.exhausted += 1;
        }
        for hit in hits.iter() {
            let (t1, t2) = hit.n.any_orthonormal_pair();
            let angles = self.tangent.distribution(hit.p, t1, t2, hit.n);
            let theta = angles.sample(sampler.next_1d());
            let omega = t1 * theta.cos() + t2 * theta.sin();
            if !is_silhouette_direction(shape, hit.p, omega) {
                continue;
            }
            // 1 / (shape choice · hit density · angle density); the mixture density is at least
            // UNIFORM_SHARE / π and finite, `hit.pdf` positive and finite (sample_surface).
            let weight = k as f32 / (hit.pdf * angles.pdf(theta));
            if !weight.is_finite() {
                continue;
            }
            let o = scene.offset_origin(hit.p, hit.n, hit.n);
            // An exhausted trace counts as a miss, as in the integrator's own paths
            // (`path::trace_path`, `occluded`): the primal treats such a line as escaping, so its
            // derivative must too (typically a line leaving at a shallow angle above an infinite
            // floor, which sphere tracing never finishes; dropping those lost the lower silhouettes'
            // shadows in an environment-lit scene).
            let ends =
                [omega, -omega].map(|d| match scene.intersect(&Ray::new(o, d), f32::INFINITY) {
                    Intersection::Exhausted => {
                        counters.exhausted += 1;
                        Intersection::Miss
                    }
                    end => end,
                });
            for (s_end, d_end) in [(&ends[1], &ends[0]), (&ends[0], &ends[1])] {
                self.segment(m, hit.p, s_end, d_end, weight, splats, counters);
            }
        }
    }

    /// The segment from the hit `s_end` through `x_b` (on shape `m`) to `d_end`, if it is a shadow
    /// boundary of a visible point: pushes its contributions.
    #[allow(clippy::too_many_arguments)]
    fn segment<S: Directions>(
        &self,
        m: usize,
        x_b: glam::Vec3,
        s_end: &Intersection,
        d_end: &Intersection,
        weight: f32,
        splats: &mut Vec<(usize, Vec3<S>)>,
        counters: &mut TraceCounters,
    ) {
        let scene = self.scene;
        let Intersection::Hit(s_hit) = s_end else {
            return;
        };
        let Surface::Shape(si) = s_hit.surface else {
            return;
        };
        let end = match d_end {
            Intersection::Hit(h) => match h.surface {
                Surface::Emitter(e) => End::Emitter(e, h.p, h.n),
                Surface::Shape(_) => return,
            },
            Intersection::Miss => match scene.environment {
                Some(e) => End::Environment(e),
                None => return,
            },
            Intersection::Exhausted => {
                counters.exhausted += 1;
                return;
            }
        };
        let (x_s, n_s) = (s_hit.p, s_hit.n);
        // The camera must see x_S.
        let frame = scene.camera.frame::<f32>();
        let Some((px, py)) = frame.project(Vec3::constant(x_s)) else {
            return;
        };
        let filter = scene.camera.filter;
        let radius = filter.radius();
        let (wf, hf) = (scene.camera.width as f32, scene.camera.height as f32);
        if px <= -radius || py <= -radius || px >= wf + radius || py >= hf + radius {
            return;
        }
        let eye: glam::Vec3 = frame.origin.primal();
        let to_s = x_s - eye;
        let dist = to_s.length();
        if !(dist > 0.0 && dist.is_finite()) {
            return;
        }
        let margin = 8.0 * scene.trace.eps + 1e-5 * dist;
        if occluded(
            scene,
            &Ray::new(eye, to_s / dist),
            dist - margin,
            None,
            counters,
        ) {
            return;
        }
        let shape = &scene.shapes[m];
        let wo = -to_s / dist;
        let bsdf = &scene.shapes[si].bsdf;
        let xs_s = self.attach.shape_vertex::<S>(si, x_s, n_s).x;
        // Primal f G L_e (or f |cos| L_e at infinity), the measure change J and V_∂ in S.
        let (fgl, jac, v) = match end {
            End::Emitter(e, x_d, n_d) => {
                let Some(seg) = BoundarySegment::from_shape(shape, x_s, x_b, x_d, n_s, n_d) else {
                    return;
                };
                let w = seg.omega();
                let f = bsdf.eval::<f32>(n_s.into(), w.into(), wo.into());
                let g = geometry_term::<f32>(x_s.into(), n_s.into(), x_d.into(), n_d.into());
                let le =
                    scene.emitters[e]
                        .emitter
                        .emitted::<f32>(x_d.into(), n_d.into(), (-w).into());
                let xd_s = self.attach.emitter_vertex::<S>(e, x_d, n_d).x;
                let v = boundary_velocity(shape, &seg, xs_s, xd_s);
                (f.primal() * le.primal() * g, seg.jacobian(), v)
            }
            End::Environment(e) => {
                // A stand-in x_D on the plane perpendicular to ω at a distance well beyond x_B.
                let w = (x_b - x_s).normalize_or_zero();
                let d = 1e3 * x_s.distance(x_b).max(1.0);
                let x_d = x_s + w * d;
                let Some(seg) = BoundarySegment::from_shape(shape, x_s, x_b, x_d, n_s, -w) else {
                    return;
                };
                let f = bsdf.eval::<f32>(n_s.into(), w.into(), wo.into());
                let le =
                    scene.emitters[e]
                        .emitter
                        .emitted::<f32>(x_d.into(), (-w).into(), (-w).into());
                let v = boundary_velocity(shape, &seg, xs_s, Vec3::constant(x_d)) / d;
                (
                    f.primal() * le.primal() * n_s.dot(w).abs(),
                    seg.jacobian_directional(),
                    v,
                )
            }
        };
        let j_film = frame.film_area_jacobian(Vec3::constant(x_s), Vec3::constant(n_s));
        // Δf = −(f G L_e) on the clear side (the blocked side is 0).
        let scale = -fgl * (jac * weight * j_film);
        if scale == glam::Vec3::ZERO || !scale.is_finite() {
            return;
        }
        let value = Vec3::<S>::constant(scale) * v;
        if !(0..S::COUNT).all(|k| {
            value.x.direction(k).is_finite()
                && value.y.direction(k).is_finite()
                && value.z.direction(k).is_finite()
        }) {
            return;
        }
        let (w, h) = (scene.camera.width as i64, scene.camera.height as i64);
        let reach = radius.ceil() as i64;
        let (cx, cy) = (px.floor() as i64, py.floor() as i64);
        for jy in (cy - reach).max(0)..=(cy + reach).min(h - 1) {
            let dy = py - (jy as f32 + 0.5);
            if dy.abs() >= radius {
                continue;
            }
            for jx in (cx - reach).max(0)..=(cx + reach).min(w - 1) {
                let dx = px - (jx as f32 + 0.5);
                if dx.abs() >= radius {
                    continue;
                }
                let fw = filter.eval::<f32>(dx, dy);
                if fw != 0.0 {
                    splats.push(((jy * w + jx) as usize, value * S::constant(fw)));
                }
            }
        }
    }
}
