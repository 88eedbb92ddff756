//! The secondary boundary term (docs/theory.md §5; supplemental §2): shadows, i.e. the
//! visibility between a surface point `x_S` and the next vertex `x_D` of a path (an emitter point for
//! the `direct` integrator), which jumps where the segment `x_S x_D` touches an occluder `M`
//! tangentially at `x_B`. The derivation below is the `direct` case; the section "The path integrator"
//! extends it to every segment of a path.
//!
//! # The integral
//!
//! With the `direct` integrator pixel `j` is (the first vertex by area, as in [`crate::integrator::diff`])
//!
//! ```text
//!   I_j = ∫ dA(x_S) w_j(proj x_S) J_film(x_S) ∫ dA(x_D) f(x_S) G(x_S, x_D) V(x_S, x_D) L_e(x_D)    (1)
//! ```
//!
//! (`f` the BSDF towards the camera, `V` the visibility; emission seen directly and environment light
//! take the same form with `dA(x_D)` replaced by a solid angle). For fixed `x_S`, `V` jumps across
//! curves on the emitter: the shadow of `M`'s silhouettes as seen from `x_S`. The interior estimator
//! keeps every visibility fixed at its sampled value; the missing term (supplemental §1 eqs. 4–6) is
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
//! [`super::segment`] (eq. (A) there; the supplemental's eq. 23 misses `sin∠(c_t, c_n)`):
//! `dA(x_S) dℓ(x_D) = J dA(x_B) dθ_B`, `J = |x_S x_B| |x_S x_D| κ_n / (|n_S·ω| sin θ_D)`.
//!
//! One boundary sample: pick a shape `M` uniformly among the `K` area-samplable curved shapes (finite
//! bounds, not [`crate::sdf::Sdf::is_piecewise_flat`]: planes and sharp boxes have no smooth silhouettes), draw one line of
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
//! # The path integrator
//!
//! With `max_depth = D` the primal's expectation is the sum over path lengths of the path integrals
//! `∫ f(x̄) dA(x₁) … dA(x_{k+1})` over paths `x₀ x₁ … x_k x_{k+1}` with `k ≤ D` scattering vertices on
//! shapes and `x_{k+1}` on an emitter (or a direction at infinity); next-event estimation, BSDF sampling
//! and their MIS weights only choose how it is estimated, so any unbiased estimator of the same
//! integrals differentiates it. Every segment `x_i x_{i+1}`, `i ≥ 1`, carries a visibility; the
//! segment `x₀ x₁` is the primary term's. For the segment with `x_S = x_i` (the `i`-th scattering
//! vertex) and `x_D = x_{i+1}`, the path contribution factors as
//! `f(x̄) = W_i(x_S → x_D) · G(x_S, x_D) V(x_S, x_D) · L(x_D → x_S)`: the camera factor (pixel filter,
//! `J_film` and every BSDF, geometry term and visibility from `x₀` to `x_S`, the BSDF at `x_S`
//! included, the other vertices integrated by area) times the radiance leaving `x_D` (its emission if
//! it is an emitter, else what the vertices after it bring). Only `V(x_S, x_D)` jumps across this
//! segment's boundary, so with the measure `dA(x_S) dℓ(x_D)` and `J` of eq. (A) in [`super::segment`]
//! (in its directional form at infinity)
//!
//! ```text
//!   ∂I_j ⊃ Σ_i ∫ dA(x_S) ∫_∂ dℓ(x_D)  Δf V_∂,   Δf = 0 − W_i G L(x_D → x_S)                          (3)
//! ```
//!
//! estimated per boundary sample like (2): `Σ_i Ŵ_i · (−G L̂) · V_∂ · J · K π / p_A(x_B)`, with the
//! camera factor `Ŵ_i` of an adjoint walk from `x_S` connected to the camera at each of its vertices and
//! `L̂` a path continued from `x_D` with the primal's own estimator ([`super::subpaths`], which derives
//! both and their unbiasedness). `x_S` need not be visible from the camera any more (it is for
//! `i = 1`), and `x_D` may be a shape point. Path length: `x_S` is the `i`-th scattering vertex; an
//! emitter or environment end needs `i ≤ D`, a shape end scatters at `x_D` too and the radiance is
//! truncated after `D − i` scattering vertices counting `x_D`, which needs `i ≤ D − 1`. With `D = 1`
//! only `i = 1` and emitter ends remain: the `direct` estimator (2) exactly, with the same random
//! numbers (the walk draws nothing when it has no bounce to make).
//!
//! **Random numbers.** The subpaths of one oriented segment draw from their own stream
//! ([`super::shadow_segment::SUBPATH_STREAM`]) keyed on the bits of `x_B` and `x_S`: independent of the numbers the boundary
//! sample drew (which `x_B` is a function of), deterministic whatever the thread count, and untouched by
//! changes to how `(x_B, θ_B)` are drawn.
//!
//! **Scope.** Both integrators. The same estimator serves segments passing the crease edges of sharp
//! boxes and cylinders and of hard CSG ([`super::crease_shadows`]: one segment estimate, [`super::shadow_segment`], for any
//! occluder); [`SecondarySources`] shares the samples between them and the tear of creased surfaces at
//! later vertices ([`super::crease_tears`]), and the hard shadow edges of delta lights, whose
//! segments start at the light ([`super::delta_shadows`]; crease edges: [`super::delta_creases`]). Not included: the primary boundary (silhouettes seen from the camera,
//! [`super::primary`]), the discontinuity of one-sided emitters and BSDFs across their tangent planes,
//! the creases of hard CSG between unbounded children beyond the scene's crease region.

use super::crease_shadows::CreaseShadows;
use super::crease_tears::CreaseTears;
use super::delta_creases::DeltaCreases;
use super::delta_shadows::DeltaShadows;
use super::segment::is_silhouette_direction;
use super::shadow_segment::{Occluder, segment};
use super::source::{BoundarySource, BoundaryTerm, Pass, Scratch, term_images};
use super::tangent_sampling::{TangentSampler, TangentSampling};
use crate::error::Result;
use crate::film::{Image, SampleSink};
use crate::integrator::driver::RenderStats;
use crate::integrator::options::{DiffOptions, require_continuous_filter};
use crate::integrator::path::TraceCounters;
use crate::integrator::surface_sampling::{SurfaceSample, sample_surface};
use crate::math::Ray;
use crate::sampler::Sampler;
use crate::scalar::{Directions, dispatch_directions};
use crate::scene::{Intersection, Scene, Selection};

/// The random stream of boundary samples (distinct from the camera's
/// [`crate::integrator::CAMERA_STREAM`]).
pub const BOUNDARY_STREAM: u64 = 0x5EC0_4DA2;

/// The secondary boundary term of the derivative of `scene` with respect to the parameters of
/// `selection`, estimated with `samples` boundary samples for the whole
/// image (see the [module docs](self)). One image per parameter, the layout of
/// [`crate::integrator::diff::DerivativeImages::interior`]; the seed is `options.render.seed`.
///
/// Errors: a selection `scene` does not have, a box pixel filter.
pub fn render_secondary(
    scene: &Scene,
    selection: &Selection,
    options: &DiffOptions,
    samples: u64,
) -> Result<Vec<Image>> {
    render_secondary_with(scene, selection, options, samples, TangentSampling::Steered)
}

/// [`render_secondary`] with a chosen way of drawing the tangent angles `θ_B` (the default,
/// [`TangentSampling::Steered`], has less variance; both have the same expectation).
pub fn render_secondary_with(
    scene: &Scene,
    selection: &Selection,
    options: &DiffOptions,
    samples: u64,
    tangent: TangentSampling,
) -> Result<Vec<Image>> {
    let selected = selection.apply(scene)?;
    Ok(secondary_term(&selected, selection.len(), options, samples, tangent)?.0)
}

/// [`render_secondary_with`] of a scene with its selection applied (slots `0..count`), with the counts
/// of the traced rays, in passes of the widest dual number `count` needs.
pub(crate) fn secondary_term(
    scene: &Scene,
    count: usize,
    options: &DiffOptions,
    samples: u64,
    tangent: TangentSampling,
) -> Result<(Vec<Image>, RenderStats)> {
    require_continuous_filter(scene, "the secondary boundary term")?;
    if count == 0 {
        return Ok((Vec::new(), RenderStats::default()));
    }
    let sources = SecondarySources::of(scene, tangent);
    let (images, _, stats) = dispatch_directions!(
        count,
        term_images(scene, count, options, samples, &sources, false)
    );
    Ok((images, stats))
}

/// Everything the secondary term samples, prepared once per render: the tangent lines of smooth
/// silhouettes (this module), lines past crease edges ([`super::crease_shadows`]), the tear of
/// creased surfaces at vertices after the first ([`super::crease_tears`]) and the hard shadow edges
/// of delta lights ([`super::delta_shadows`], [`super::delta_creases`]), which share its samples equally (those the scene has no
/// occluder or light for take no share).
pub struct SecondarySources {
    /// Tangent lines of curved shapes.
    pub silhouettes: SilhouetteShadows,
    /// Lines past crease edges.
    pub crease_shadows: CreaseShadows,
    /// The tear of creased surfaces.
    pub crease_tears: CreaseTears,
    /// The silhouettes seen from delta lights.
    pub delta_shadows: DeltaShadows,
    /// The crease edges whose shadows delta lights cast.
    pub delta_creases: DeltaCreases,
}

impl SecondarySources {
    /// The occluders of `scene`, tangent angles drawn by `tangent`. The crease edges are listed (and
    /// extracted) only where a crease term exists.
    pub fn of(scene: &Scene, tangent: TangentSampling) -> Self {
        let crease_shadows = CreaseShadows::of(scene);
        let crease_tears = CreaseTears::of(scene, crease_shadows.edges());
        let delta_creases = DeltaCreases::of(scene, crease_shadows.edges());
        Self {
            silhouettes: SilhouetteShadows::of(scene, tangent),
            crease_shadows,
            crease_tears,
            delta_shadows: DeltaShadows::of(scene),
            delta_creases,
        }
    }
}

impl BoundaryTerm for SecondarySources {
    fn sources<S: Directions>(&self) -> Vec<&dyn BoundarySource<S>> {
        vec![
            &self.silhouettes,
            &self.crease_shadows,
            &self.crease_tears,
            &self.delta_shadows,
            &self.delta_creases,
        ]
    }
}

/// The curved shapes with finite bounds: the ones [`sample_surface`] can sample and whose tangent
/// lines can be silhouettes (flat shapes have no silhouette directions, `κ_n = 0`).
fn curved_shapes(scene: &Scene) -> Vec<usize> {
    (0..scene.shapes.len())
        .filter(|&i| {
            let b = scene.shapes[i].bounds;
            b.is_finite() && !b.is_empty() && !scene.shapes[i].sdf.is_piecewise_flat()
        })
        .collect()
}

/// The tangent lines of smooth silhouettes: eq. (2)'s boundary samples.
pub struct SilhouetteShadows {
    /// Curved shapes with finite bounds (the ones [`sample_surface`] can sample and whose tangent lines
    /// can be silhouettes), chosen uniformly.
    candidates: Vec<usize>,
    /// Draws `θ_B` (towards the emitters).
    tangent: TangentSampler,
}

impl SilhouetteShadows {
    /// The curved shapes of `scene`, `θ_B` drawn by `tangent`.
    pub fn of(scene: &Scene, tangent: TangentSampling) -> Self {
        Self {
            candidates: curved_shapes(scene),
            tangent: TangentSampler::new(scene, tangent),
        }
    }
}

impl<S: Directions> BoundarySource<S> for SilhouetteShadows {
    fn stage(&self) -> &'static str {
        "secondary"
    }

    fn stream(&self) -> u64 {
        BOUNDARY_STREAM
    }

    fn takes_share(&self) -> bool {
        !self.candidates.is_empty()
    }

    fn sample(
        &self,
        pass: &Pass,
        sampler: &mut Sampler,
        scratch: &mut Scratch,
        counters: &mut TraceCounters,
        sink: &mut dyn SampleSink<S>,
    ) {
        self.sample_lines(pass, sampler, &mut scratch.hits, sink, counters);
    }
}

impl SilhouetteShadows {
    /// One boundary sample: a shape, a line of area samples on it, one tangent angle per hit; pushes the
    /// weighted contributions `(pixel, value)` of eq. (2) (not yet divided by the sample count).
    fn sample_lines<S: Directions>(
        &self,
        pass: &Pass,
        sampler: &mut Sampler,
        hits: &mut Vec<SurfaceSample>,
        splats: &mut dyn SampleSink<S>,
        counters: &mut TraceCounters,
    ) {
        let scene = pass.scene;
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
            let o = scene.offset_origin(m, hit.p, hit.n, hit.n);
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
                let occluder = Occluder::Silhouette(m);
                let line = (hit.p, o);
                segment(pass, occluder, line, s_end, d_end, weight, splats, counters);
            }
        }
    }
}
