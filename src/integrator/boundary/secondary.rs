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
//! ([`SUBPATH_STREAM`]) keyed on the bits of `x_B` and `x_S`: independent of the numbers the boundary
//! sample drew (which `x_B` is a function of), deterministic whatever the thread count, and untouched by
//! changes to how `(x_B, θ_B)` are drawn.
//!
//! **Scope.** Both integrators. The same estimator serves segments passing the crease edges of sharp
//! boxes and cylinders and of hard CSG ([`super::crease_shadows`], through `Occluder`); [`split`] shares the samples
//! between them and the tear of creased surfaces at later vertices ([`super::crease_tears`]). Not included: the primary boundary (silhouettes seen from the camera,
//! [`super::primary`]), the discontinuity of one-sided emitters and BSDFs across their tangent planes,
//! the creases of hard CSG between unbounded children.

use super::crease_segment::CreaseSegment;
use super::crease_shadows::run_crease_shadows;
use super::crease_tears;
use super::segment::{BoundarySegment, boundary_velocity, is_silhouette_direction};
use super::subpaths::{camera_side, radiance_by_depth};
use super::tangent_sampling::{TangentSampler, TangentSampling};
use super::{accumulate_samples, finite_splat, run_samples, splat_on_film, split_equally};
use crate::error::Result;
use crate::film::{Film, Image, SampleSink};
use crate::integrator::attach::SceneAttach;
use crate::integrator::attach::for_each_window;
use crate::integrator::driver::RenderStats;
use crate::integrator::options::{DiffOptions, Progress, require_continuous_filter};
use crate::integrator::path::{PathRecord, TraceCounters};
use crate::integrator::shading::geometry_term;
use crate::integrator::surface_sampling::{SurfaceSample, sample_surface};
use crate::math::{Ray, Vec3};
use crate::sampler::Sampler;
use crate::scalar::{Directions, Scalar, dispatch_directions};
use crate::scene::{Intersection, Scene, Shape, Surface};
use crate::sdf::CreaseEdge;

/// The random stream of boundary samples (distinct from the camera's
/// [`crate::integrator::CAMERA_STREAM`]).
pub const BOUNDARY_STREAM: u64 = 0x5EC0_4DA2;

/// The random stream of the subpaths (camera-side walk, light-side path) of a segment.
pub const SUBPATH_STREAM: u64 = 0x5AB_9A7E;

/// The secondary boundary term of the derivative with respect to the parameters in slots `0..count`
/// (selected with [`Scene::select_parameters`]), estimated with `samples` boundary samples for the whole
/// image (see the [module docs](self)). One image per parameter, the layout of
/// [`crate::integrator::diff::DerivativeImages::interior`]; the seed is `options.render.seed`.
///
/// Errors: a box pixel filter.
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
    Ok(dispatch_directions!(
        count,
        render_secondary_in(scene, count, options, samples, tangent)
    )?
    .0)
}

/// [`render_secondary`] with the counts of the traced rays.
pub fn render_secondary_terms(
    scene: &Scene,
    count: usize,
    options: &DiffOptions,
    samples: u64,
) -> Result<(Vec<Image>, RenderStats)> {
    dispatch_directions!(
        count,
        render_secondary_in(scene, count, options, samples, TangentSampling::Steered)
    )
}

/// [`render_secondary_with`] with a chosen scalar type, in passes of `S::COUNT` parameters.
pub fn render_secondary_in<S: Directions>(
    scene: &Scene,
    count: usize,
    options: &DiffOptions,
    samples: u64,
    tangent: TangentSampling,
) -> Result<(Vec<Image>, RenderStats)> {
    require_continuous_filter(scene, "the secondary boundary term")?;
    let mut stats = RenderStats::default();
    let mut images = Vec::with_capacity(count);
    if count == 0 {
        return Ok((images, stats));
    }
    let seed = options.render.seed;
    let progress = &options.render.progress;
    for (pass_images, pass_stats) in for_each_window(scene, count, S::COUNT, |windowed, width| {
        pass::<S>(windowed, width, seed, samples, tangent, progress)
    }) {
        images.extend(pass_images);
        stats.absorb(pass_stats);
    }
    Ok((images, stats))
}

/// One pass over all boundary samples: directions `0..width` of `S`.
fn pass<S: Directions>(
    scene: &Scene,
    width: usize,
    seed: u64,
    samples: u64,
    tangent: TangentSampling,
    progress: &Progress,
) -> (Vec<Image>, RenderStats) {
    let (w, h) = (scene.camera.width, scene.camera.height);
    let mut images = vec![Image::new(w, h); width];
    let mut stats = RenderStats::default();
    for (source, n) in split(scene, samples) {
        stats.absorb(accumulate_samples::<S>(
            scene,
            width,
            n,
            |film| run_source::<S, _>(scene, source, seed, n, tangent, progress, film),
            &mut images,
            &mut [],
        ));
    }
    (images, stats)
}

/// One kind of occluder the secondary term samples.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum SecondarySource {
    /// Smooth silhouettes of curved shapes (tangent lines, this module).
    Silhouettes,
    /// Crease edges of sharp boxes and cylinders ([`super::crease_shadows`]).
    CreaseEdges,
    /// The tear of creased surfaces' parametrisation at vertices after the first
    /// ([`super::crease_tears`]; integrators with two or more scattering vertices).
    CreaseTears,
}

/// How `samples` secondary samples are shared: equally between the kinds of occluder the scene has.
pub fn split(scene: &Scene, samples: u64) -> Vec<(SecondarySource, u64)> {
    split_equally(
        samples,
        &[
            (
                SecondarySource::Silhouettes,
                !curved_shapes(scene).is_empty(),
            ),
            (SecondarySource::CreaseEdges, scene.has_crease_edges()),
            (SecondarySource::CreaseTears, crease_tears::applies(scene)),
        ],
    )
}

/// `samples` samples of one kind into any film (their shares not yet divided by `samples`).
pub(crate) fn run_source<S: Directions, F: Film>(
    scene: &Scene,
    source: SecondarySource,
    seed: u64,
    samples: u64,
    tangent: TangentSampling,
    progress: &Progress,
    film: &mut F,
) -> RenderStats
where
    F::Tile: SampleSink<S>,
{
    match source {
        SecondarySource::Silhouettes => {
            run_segments::<S, F>(scene, seed, samples, tangent, progress, film)
        }
        SecondarySource::CreaseEdges => {
            run_crease_shadows::<S, F>(scene, seed, samples, progress, film)
        }
        SecondarySource::CreaseTears => {
            crease_tears::run_crease_tears::<S, F>(scene, seed, samples, progress, film)
        }
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

/// The boundary samples `0..samples` into any film (their shares not yet divided by `samples`).
fn run_segments<S: Directions, F: Film>(
    scene: &Scene,
    seed: u64,
    samples: u64,
    tangent: TangentSampling,
    progress: &Progress,
    film: &mut F,
) -> RenderStats
where
    F::Tile: SampleSink<S>,
{
    let ctx = Context::new(scene, tangent);
    if ctx.candidates.is_empty() {
        return RenderStats::default();
    }
    run_samples::<S, F, _>(
        film,
        samples,
        ("secondary", progress),
        (seed, BOUNDARY_STREAM),
        Vec::new,
        |hits, sampler, counters, splats| {
            ctx.sample(sampler, hits, splats, counters);
        },
    )
}

/// What every boundary sample needs.
pub(crate) struct Context<'a> {
    pub(crate) scene: &'a Scene,
    attach: SceneAttach<'a>,
    /// Curved shapes with finite bounds (the ones [`sample_surface`] can sample and whose tangent lines
    /// can be silhouettes), chosen uniformly.
    candidates: Vec<usize>,
    /// Draws `θ_B` (towards the emitters).
    tangent: TangentSampler,
}

/// What blocks a boundary segment at `x_B`.
#[derive(Copy, Clone, Debug)]
pub(crate) enum Occluder<'a> {
    /// A smooth silhouette of shape `m`: the line is tangent there ([`BoundarySegment`]).
    Silhouette(usize),
    /// A crease edge of shape `m` (the edge in the shape's coordinates, its unit tangent and its faces'
    /// gradients at `x_B`): the line passes the edge ([`CreaseSegment`]).
    Crease(usize, &'a CreaseEdge, glam::Vec3, [glam::Vec3; 2]),
}

/// A boundary segment's geometry, with what its velocity is evaluated on.
enum Blocked<'a> {
    Silhouette(&'a Shape, BoundarySegment),
    Crease(&'a Shape, &'a CreaseEdge, CreaseSegment),
}

impl<'a> Occluder<'a> {
    /// The segment `x_s → x_d` past `x_b` (normals `n_s`, `n_d`); `None` for coincident points or a
    /// vanishing gradient.
    fn segment(
        self,
        scene: &'a Scene,
        x_s: glam::Vec3,
        x_b: glam::Vec3,
        x_d: glam::Vec3,
        n_s: glam::Vec3,
        n_d: glam::Vec3,
    ) -> Option<Blocked<'a>> {
        Some(match self {
            Occluder::Silhouette(m) => {
                let shape = &scene.shapes[m];
                let seg = BoundarySegment::from_shape(shape, x_s, x_b, x_d, n_s, n_d)?;
                Blocked::Silhouette(shape, seg)
            }
            Occluder::Crease(m, edge, tangent, grads) => {
                let shape = &scene.shapes[m];
                let seg = CreaseSegment::new((x_s, x_b, x_d), n_s, n_d, tangent, grads)?;
                Blocked::Crease(shape, edge, seg)
            }
        })
    }
}

impl Blocked<'_> {
    /// `dA(x_S) dℓ(x_D)` per unit of the sampled measure (eq. (A) of [`super::segment`], (B2) of
    /// [`super::crease_segment`]).
    fn jacobian(&self) -> f32 {
        match self {
            Blocked::Silhouette(_, seg) => seg.jacobian(),
            Blocked::Crease(_, _, seg) => seg.jacobian(),
        }
    }

    /// The same with `x_D` at infinity.
    fn jacobian_directional(&self) -> f32 {
        match self {
            Blocked::Silhouette(_, seg) => seg.jacobian_directional(),
            Blocked::Crease(_, _, seg) => seg.jacobian_directional(),
        }
    }

    /// `V_∂` by AD with the attached ends.
    fn velocity<S: Scalar>(&self, x_s: Vec3<S>, x_d: Vec3<S>) -> S {
        match self {
            Blocked::Silhouette(shape, seg) => boundary_velocity(shape, seg, x_s, x_d),
            Blocked::Crease(shape, edge, seg) => seg.velocity(shape, edge, x_s, x_d),
        }
    }
}

/// The end `x_D` of a segment.
#[derive(Copy, Clone)]
enum End {
    /// A point of finite emitter `e` with its normal.
    Emitter(usize, glam::Vec3, glam::Vec3),
    /// The environment emitter `e`, at infinity.
    Environment(usize),
    /// A point of shape `i` with its normal (where the path scatters again).
    Shape(usize, glam::Vec3, glam::Vec3),
}

/// The random numbers of the subpaths of one oriented segment: a stream keyed on the bits of `x_B` and
/// `x_S` (module docs, "Random numbers").
fn subpath_sampler(x_b: glam::Vec3, x_s: glam::Vec3) -> Sampler {
    let bits = |p: glam::Vec3| {
        (p.x.to_bits() as u64 | (p.y.to_bits() as u64) << 32)
            ^ (p.z.to_bits() as u64).rotate_left(17)
    };
    Sampler::new(bits(x_b), SUBPATH_STREAM, bits(x_s), 0)
}

impl<'a> Context<'a> {
    /// The context of `scene`'s boundary samples, `θ_B` drawn by `tangent`.
    pub(crate) fn new(scene: &'a Scene, tangent: TangentSampling) -> Self {
        let candidates = curved_shapes(scene);
        Self {
            scene,
            attach: SceneAttach::new(scene),
            candidates,
            tangent: TangentSampler::new(scene, tangent),
        }
    }
}

impl Context<'_> {
    /// One boundary sample: a shape, a line of area samples on it, one tangent angle per hit; pushes the
    /// weighted contributions `(pixel, value)` of eq. (2) (not yet divided by the sample count).
    fn sample<S: Directions>(
        &self,
        sampler: &mut Sampler,
        hits: &mut Vec<SurfaceSample>,
        splats: &mut impl SampleSink<S>,
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
                self.segment(occluder, (hit.p, o), s_end, d_end, weight, splats, counters);
            }
        }
    }

    /// The segment from the hit `s_end` past `x_b` (where `occluder` blocks it) to `d_end`, if it is a
    /// visibility boundary of some camera path: pushes its contributions (eq. (2), with the camera and
    /// light sides of [`super::subpaths`] for integrators with several scattering vertices).
    /// `line_origin` is `x_b` pushed off the occluder, where the line was traced from.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn segment<S: Directions>(
        &self,
        occluder: Occluder,
        (x_b, line_origin): (glam::Vec3, glam::Vec3),
        s_end: &Intersection,
        d_end: &Intersection,
        weight: f32,
        splats: &mut impl SampleSink<S>,
        counters: &mut TraceCounters,
    ) {
        let scene = self.scene;
        let depth = scene.integrator.max_scatter();
        let Intersection::Hit(s_hit) = s_end else {
            return;
        };
        let Surface::Shape(si) = s_hit.surface else {
            return;
        };
        let end = match d_end {
            Intersection::Hit(h) => match h.surface {
                Surface::Emitter(e) => End::Emitter(e, h.p, h.n),
                // x_D scatters: the path needs one more scattering vertex than x_S's depth.
                Surface::Shape(d) if depth >= 2 => End::Shape(d, h.p, h.n),
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
        let Some(w) = (x_b - x_s).try_normalize() else {
            return;
        };
        // The subpaths' numbers, keyed on the oriented segment (module docs, "Random numbers").
        let mut sampler = subpath_sampler(x_b, x_s);
        let frame = scene.camera.frame::<f32>();
        let max_k = match end {
            End::Shape(..) => depth - 1,
            _ => depth,
        };
        let mut cams = Vec::new();
        camera_side(
            scene,
            &frame,
            si,
            x_s,
            n_s,
            w,
            max_k,
            &mut sampler,
            &mut cams,
            counters,
        );
        if cams.is_empty() {
            return;
        }
        let xs_s = self.attach.shape_vertex::<S>(si, x_s, n_s).x;
        // Per depth k the radiance arriving at x_S (times G or |cos| at infinity), the measure change J
        // and V_∂ in S.
        let mut radiance = Vec::new();
        let (jac, v) = match end {
            End::Emitter(e, x_d, n_d) => {
                let Some(seg) = occluder.segment(scene, x_s, x_b, x_d, n_s, n_d) else {
                    return;
                };
                let w = (x_b - x_s).normalize_or_zero();
                let g = geometry_term::<f32>(x_s.into(), n_s.into(), x_d.into(), n_d.into());
                let le =
                    scene.emitters[e]
                        .emitter
                        .emitted::<f32>(x_d.into(), n_d.into(), (-w).into());
                let xd_s = self.attach.emitter_vertex::<S>(e, x_d, n_d).x;
                let v = seg.velocity(xs_s, xd_s);
                radiance.push((le.primal(), g));
                (seg.jacobian(), v)
            }
            End::Shape(d, x_d, n_d) => {
                let Some(seg) = occluder.segment(scene, x_s, x_b, x_d, n_s, n_d) else {
                    return;
                };
                let jac = seg.jacobian();
                if jac == 0.0 {
                    return;
                }
                let g = geometry_term::<f32>(x_s.into(), n_s.into(), x_d.into(), n_d.into());
                // The segment's own line (x_S and x_D lie on it; x_B is pushed off M like the traced
                // line), continued from its first hit x_D.
                let kmin = cams.iter().map(|c| c.depth).min().unwrap_or(1);
                let o = line_origin;
                let Some(w) = (x_d - x_s).try_normalize() else {
                    return;
                };
                let mut by_depth = Vec::new();
                let (mut record, mut scratch) = (PathRecord::default(), PathRecord::default());
                if !radiance_by_depth(
                    scene,
                    Ray::new(o, w),
                    d,
                    depth - kmin,
                    &mut sampler,
                    &mut record,
                    &mut scratch,
                    &mut by_depth,
                    counters,
                ) {
                    return;
                }
                // radiance[k − 1] = (L^{(D−k)}, G) for the depths k the camera side reached.
                for k in 1..=max_k {
                    let l = by_depth.get((depth - k) as usize).copied();
                    radiance.push((l.unwrap_or(glam::Vec3::ZERO), g));
                }
                let xd_s = self.attach.shape_vertex::<S>(d, x_d, n_d).x;
                (jac, seg.velocity(xs_s, xd_s))
            }
            End::Environment(e) => {
                // A stand-in x_D on the plane perpendicular to ω at a distance well beyond x_B.
                let w = (x_b - x_s).normalize_or_zero();
                let d = 1e3 * x_s.distance(x_b).max(1.0);
                let x_d = x_s + w * d;
                let Some(seg) = occluder.segment(scene, x_s, x_b, x_d, n_s, -w) else {
                    return;
                };
                let le =
                    scene.emitters[e]
                        .emitter
                        .emitted::<f32>(x_d.into(), (-w).into(), (-w).into());
                let v = seg.velocity(xs_s, Vec3::constant(x_d)) / d;
                radiance.push((le.primal(), n_s.dot(w).abs()));
                (seg.jacobian_directional(), v)
            }
        };
        for cam in &cams {
            // Emitter and environment ends: the same radiance at every depth.
            let (l, g) = radiance[((cam.depth - 1) as usize).min(radiance.len() - 1)];
            // Δf = −(camera side · G · radiance) on the clear side (the blocked side is 0).
            let scale = -(cam.f * l * g) * (jac * weight * cam.j_film);
            if scale == glam::Vec3::ZERO || !scale.is_finite() {
                continue;
            }
            let value = Vec3::<S>::constant(scale) * v;
            if finite_splat(&value, S::zero()) {
                splat_on_film(scene, (cam.film.x, cam.film.y), value, S::zero(), splats);
            }
        }
    }
}
