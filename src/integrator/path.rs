//! Paths traced in `f32` and recorded as vertices, then evaluated through the generic shading code.
//!
//! A camera sample is one chain of BSDF-sampled vertices `x1, x2, …` (a tree with next-event branches:
//! at each scattering vertex one emitter point `y_i` is sampled). Tracing decides everything discrete
//! (what was hit, visibility, multiple importance sampling weights) and stores the detached densities per
//! unit *area* of the vertex they produced (per steradian for vertices at infinity). [`contribution`]
//! then re-evaluates `f(x̄) / p(x̄)` with any scalar type: the BSDFs, geometry terms and emission see the
//! positions and normals returned by an `attach` function (constants for the image, attached vertices
//! for the interior derivative), while densities and MIS weights stay detached.
//!
//! Estimator (Veach 1997, ch. 9, with the power heuristic): at each scattering vertex `x_i`,
//! `L += β_i · w_light · f(x_i) G(x_i, y) L_e(y) / p_A(y)` for the light sample and, for the BSDF-sampled
//! next vertex, `β_{i+1} = β_i f(x_i) G(x_i, x_{i+1}) / p_A(x_{i+1})` with `L += β_{i+1} w_bsdf L_e(x_{i+1})`
//! when it is on an emitter (or at infinity, with `|cos|` and a solid-angle density instead of `G`).
//! In image passes the light sample chooses among the emitters other than a constant environment,
//! which the BSDF-sampled rays alone estimate, with weight 1
//! ([`crate::emitter::Emitter::is_light_sampled`]); passes that differentiate the contribution keep
//! the sky light-sampled ([`LightStrategy`]).
//!
//! # The cosine control variate under a constant sky
//!
//! At a diffuse vertex `x` with a moving normal `n`, the sky's two samples (the light sample `ω_l` and
//! the BSDF sample `ω_b`) contribute `f L |n·ω| w_s / p_s` each where the sky is seen, so the
//! derivative of each carries `f L (∂n·ω) w_s / p_s`: a sample of
//! `f L ∂n·∫_{H} ω dω = π f L (∂n·n) = 0` on a convex part, i.e. pure noise, most of an interior
//! gradient's variance for a shape under a constant sky (the differentiable-rendering form of the
//! well-known fact that a Lambertian surface under a uniform sky looks the same whatever its
//! orientation). Derivative passes under a constant sky therefore record both directions at every
//! diffuse vertex, whatever they meet ([`SkyDirection`]), and subtract from the contribution
//! `f L Σ_s (n·ω_s − n₀·ω_s) w_s / p_s` (`f`, `L` and the weights detached; over the directions on
//! the outgoing side). Its value is zero, so images are unchanged, and its derivative has zero mean
//! for any normal, since the weights of the two strategies sum to one over the hemisphere; where the
//! sky is seen it cancels the cosine's noise exactly, where a shape hides it the noise is the
//! hidden sky's instead of the seen sky's. On the inverse-rendering race's last shape this halves the
//! variance of a grid's gradient (docs/inverse-rendering.md).

use super::shading::{abs_cos, direction, geometry_term};
use crate::bsdf::Bsdf;
use crate::emitter::Emitter;
use crate::math::sampling::power_heuristic;
use crate::math::{Ray, Vec3};
use crate::sampler::Sampler;
use crate::scalar::Scalar;
use crate::scene::{Hit, Intersection, Scene, Surface};

/// What a recorded vertex lies on.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum VertexKind {
    /// Shape `i` of [`Scene::shapes`] (a scattering vertex).
    Shape(usize),
    /// Finite emitter `i` of [`Scene::emitters`] (the path ends there).
    Emitter(usize),
    /// The environment emitter `i` of [`Scene::emitters`], at infinity: `p` holds the unit direction.
    Environment(usize),
}

/// A vertex of the BSDF-sampled chain.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PathVertex {
    /// Position (for [`VertexKind::Environment`], the unit direction towards infinity).
    pub p: glam::Vec3,
    /// Outward unit normal (unused at infinity).
    pub n: glam::Vec3,
    /// What the vertex lies on.
    pub kind: VertexKind,
    /// Detached density of this vertex given the previous one: per unit area (per steradian at
    /// infinity). The first vertex has density 1: its pixel filter is sampled exactly, so its weight is 1.
    pub pdf: f32,
    /// MIS weight of the emission found at this vertex (1 when seen from the camera).
    pub mis: f32,
}

/// A next-event sample: a point on an emitter connected to scattering vertex `from`, known unoccluded.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct LightVertex {
    /// Index in [`PathRecord::vertices`] of the scattering vertex it lights.
    pub from: usize,
    /// Emitter index in [`Scene::emitters`].
    pub emitter: usize,
    /// Point on the emitter (for the environment, the unit direction).
    pub p: glam::Vec3,
    /// Emitter normal at `p` (unused for the environment).
    pub n: glam::Vec3,
    /// Detached density per unit area of `p` (per steradian for the environment), including the
    /// probability of choosing this emitter.
    pub pdf: f32,
    /// MIS weight against BSDF sampling.
    pub mis: f32,
}

/// A direction sampled towards a constant sky at a diffuse scattering vertex in a derivative pass,
/// recorded whatever the ray met: a term of the cosine control variate (module docs).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct SkyDirection {
    /// Index in [`PathRecord::vertices`] of the scattering vertex it leaves.
    pub from: usize,
    /// Unit direction.
    pub w: glam::Vec3,
    /// The sample's MIS weight against the other strategy over its density per steradian (with the
    /// probability of choosing the sky for a light sample).
    pub weight: f32,
}

/// Which emitters a path's light samples choose among.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum LightStrategy {
    /// The emitters [`crate::emitter::Emitter::is_light_sampled`] names: a constant sky is left to
    /// the BSDF's samples, with weight 1 (the least noisy image).
    #[default]
    Image,
    /// Every emitter, the constant sky too, with MIS. For passes that differentiate the contribution
    /// at scattering vertices: the derivative of `|n·ω|` through the normal over the cosine density
    /// alone, `(ω·∂n) / |n·ω|`, has an infinite second moment at grazing directions (logarithmically);
    /// the MIS weight against the uniform light sample bounds it.
    Derivative,
}

impl LightStrategy {
    /// How many emitters the light sample chooses among.
    #[inline]
    fn count(self, scene: &Scene) -> usize {
        match self {
            LightStrategy::Image => scene.light_sampled.len(),
            LightStrategy::Derivative => scene.emitters.len(),
        }
    }

    /// The `i`-th of them, as an index of [`Scene::emitters`].
    #[inline]
    fn pick(self, scene: &Scene, i: usize) -> usize {
        match self {
            LightStrategy::Image => scene.light_sampled[i],
            LightStrategy::Derivative => i,
        }
    }
}

/// One camera sample's path.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PathRecord {
    /// Camera origin (the vertex `x0`).
    pub camera: glam::Vec3,
    /// The BSDF-sampled chain `x1, x2, …`.
    pub vertices: Vec<PathVertex>,
    /// Next-event samples, in the order of their `from` vertex.
    pub lights: Vec<LightVertex>,
    /// Sky directions of the cosine control variate, in the order of their `from` vertex (derivative
    /// passes under a constant sky only).
    pub sky_directions: Vec<SkyDirection>,
    /// Which emitters the light samples choose among: set by the pass, kept by every trace.
    pub strategy: LightStrategy,
}

/// Counters kept while tracing, and what one shadow ray tells the next.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct TraceCounters {
    /// Rays (camera, shadow or continuation) whose sphere tracing ran out of steps.
    pub exhausted: u64,
    /// The shape that blocked the last shadow ray that walked the scene, if one did: the next shadow
    /// ray tests it first, since shadow rays from nearby points to one light tend to meet the same
    /// occluder ([`occluded`]).
    pub blocker: Option<u32>,
}

/// Whether anything blocks the segment `ray.o + t ray.d`, `t ∈ (0, t_max)`. The emitter `skip` (the one
/// being connected to) is not tested: its own sampled point faces the reference, so it cannot occlude it.
/// Nor is the shape `leaving` that the ray leaves ([`Scene::leaving`]). Exhausted traces count as
/// unoccluded (as misses, like [`Scene::intersect`]).
///
/// The shape that blocked the previous shadow ray ([`TraceCounters::blocker`]) is tested first
/// ([`Scene::shapes_block_after`]).
pub fn occluded(
    scene: &Scene,
    ray: &Ray,
    t_max: f32,
    skip: Option<usize>,
    leaving: Option<usize>,
    counters: &mut TraceCounters,
) -> bool {
    for &i in &scene.finite_emitters {
        if Some(i) != skip && scene.emitters[i].emitter.intersect(ray, t_max).is_some() {
            return true;
        }
    }
    scene.shapes_block_after(
        ray,
        t_max,
        leaving,
        &mut counters.blocker,
        &mut counters.exhausted,
    )
}

/// What a ray sees, when only emission along it matters (the last segment of a path).
enum Next {
    /// The first surface along the ray.
    Surface(Hit),
    /// Nothing: the ray escapes to the environment (if any).
    Escape,
    /// Something that does not emit blocks the ray.
    Blocked,
}

/// The nearest emitter along `ray`, tested for occlusion by shapes; shapes are traced only up to the
/// emitter, or not at all when no emitter is hit and the scene has no environment (a segment that can
/// carry no light costs no sphere tracing). Equivalent to [`Scene::intersect`] followed by discarding
/// shape hits.
fn emission_along(
    scene: &Scene,
    ray: &Ray,
    leaving: Option<usize>,
    counters: &mut TraceCounters,
) -> Next {
    let mut best: Option<(f32, glam::Vec3, usize)> = None;
    for &i in &scene.finite_emitters {
        let t_max = best.map_or(f32::INFINITY, |b| b.0);
        if let Some((t, n)) = scene.emitters[i].emitter.intersect(ray, t_max) {
            best = Some((t, n, i));
        }
    }
    match best {
        Some((t, n, i)) => {
            if occluded(scene, ray, t, Some(i), leaving, counters) {
                Next::Blocked
            } else {
                Next::Surface(Hit {
                    t,
                    p: ray.at(t),
                    n,
                    surface: Surface::Emitter(i),
                })
            }
        }
        None if scene.environment.is_none() => Next::Blocked,
        None => {
            if occluded(scene, ray, f32::INFINITY, None, leaving, counters) {
                Next::Blocked
            } else {
                Next::Escape
            }
        }
    }
}

/// Density per steradian, including the selection probability, with which next-event estimation from
/// `reference` would have produced the point `p` (normal `n`) of emitter `emitter` in direction `wi`.
#[inline]
pub fn light_pdf(
    scene: &Scene,
    strategy: LightStrategy,
    emitter: usize,
    reference: glam::Vec3,
    wi: glam::Vec3,
    p: glam::Vec3,
    n: glam::Vec3,
) -> f32 {
    let e = &scene.emitters[emitter].emitter;
    if strategy == LightStrategy::Image && !e.is_light_sampled() {
        return 0.0;
    }
    let select = 1.0 / strategy.count(scene) as f32;
    select * e.pdf_li(reference, wi, p, n)
}

/// One next-event sample from the scattering point `p` (normal `n`, outgoing `wo`, shape `shape`):
/// picks an emitter uniformly among those of `strategy` with `u_pick`, samples it with `u`,
/// tests visibility. `None` when the sample carries no light (no such emitter, back side, zero BSDF,
/// occluded). `from` is stored in the result. With `sky` given, a sample of the sky (occluded or not)
/// is also recorded there ([`SkyDirection`]).
#[allow(clippy::too_many_arguments)]
pub fn sample_light(
    scene: &Scene,
    strategy: LightStrategy,
    from: usize,
    shape: usize,
    p: glam::Vec3,
    n: glam::Vec3,
    wo: glam::Vec3,
    u_pick: f32,
    u: glam::Vec2,
    sky: Option<&mut Vec<SkyDirection>>,
    counters: &mut TraceCounters,
) -> Option<LightVertex> {
    let count = strategy.count(scene);
    if count == 0 {
        return None;
    }
    let k = strategy.pick(scene, ((u_pick * count as f32) as usize).min(count - 1));
    let emitter = &scene.emitters[k].emitter;
    if emitter.is_delta() {
        return sample_delta_light(scene, count, from, shape, k, p, n, wo, counters);
    }
    let es = emitter.sample_li(p, u)?;
    let surface = &scene.shapes[shape];
    let bsdf_pdf = surface.bsdf_pdf(p, n, wo, es.wi);
    let f = surface.bsdf_eval::<f32>(p.into(), n.into(), es.wi.into(), wo.into());
    if f.x <= 0.0 && f.y <= 0.0 && f.z <= 0.0 {
        return None;
    }
    let select = 1.0 / count as f32;
    let pdf_w = select * es.pdf;
    let o = scene.offset_origin(shape, p, n, es.wi);
    let infinite = emitter.is_infinite();
    let (t_max, pdf) = if infinite {
        (f32::INFINITY, pdf_w)
    } else {
        // Per unit area at the light: p_ω |cos θ_y| / d² (the inverse of the solid-angle conversion).
        let to = es.p - p;
        let pdf_a = pdf_w * es.n.dot(es.wi).abs() / to.length_squared();
        ((es.p - o).dot(es.wi) * (1.0 - 1e-4), pdf_a)
    };
    if !(pdf > 0.0 && pdf.is_finite()) {
        return None;
    }
    if let Some(sky) = sky.filter(|_| scene.environment == Some(k)) {
        sky.push(SkyDirection {
            from,
            w: es.wi,
            weight: power_heuristic(pdf_w, bsdf_pdf) / pdf_w,
        });
    }
    let ray = Ray::new(o, es.wi);
    let skip = (!infinite).then_some(k);
    if occluded(
        scene,
        &ray,
        t_max,
        skip,
        scene.leaving(shape, n, es.wi),
        counters,
    ) {
        return None;
    }
    Some(LightVertex {
        from,
        emitter: k,
        p: if infinite { es.wi } else { es.p },
        n: es.n,
        pdf,
        mis: power_heuristic(pdf_w, bsdf_pdf),
    })
}

/// The next-event "sample" of delta light `k` (chosen with probability `1/count`, `count` the
/// emitters the light sample chooses among) from the scattering point `p` (normal `n`, outgoing
/// `wo`, shape `shape`): the one direction towards it, tested for visibility; density `1/count`
/// standing for the delta, MIS weight 1 (no BSDF-sampled ray reaches a delta light,
/// [`crate::emitter::delta`]).
#[allow(clippy::too_many_arguments)]
fn sample_delta_light(
    scene: &Scene,
    count: usize,
    from: usize,
    shape: usize,
    k: usize,
    p: glam::Vec3,
    n: glam::Vec3,
    wo: glam::Vec3,
    counters: &mut TraceCounters,
) -> Option<LightVertex> {
    let es = scene.emitters[k].emitter.sample_delta_li(p)?;
    let f = scene.shapes[shape].bsdf_eval::<f32>(p.into(), n.into(), es.wi.into(), wo.into());
    if f.x <= 0.0 && f.y <= 0.0 && f.z <= 0.0 {
        return None;
    }
    let o = scene.offset_origin(shape, p, n, es.wi);
    let t_max = if es.dist.is_finite() {
        (es.p - o).dot(es.wi)
    } else {
        f32::INFINITY
    };
    let ray = Ray::new(o, es.wi);
    if occluded(
        scene,
        &ray,
        t_max,
        None,
        scene.leaving(shape, n, es.wi),
        counters,
    ) {
        return None;
    }
    Some(LightVertex {
        from,
        emitter: k,
        p: es.p,
        n: es.n,
        pdf: 1.0 / count as f32,
        mis: 1.0,
    })
}

/// The constant sky whose directions a pass with `strategy` records for the cosine control variate:
/// derivative passes under a [`Emitter::Constant`] environment.
fn control_variate_sky(scene: &Scene, strategy: LightStrategy) -> Option<usize> {
    let env = scene.environment?;
    let constant = matches!(scene.emitters[env].emitter, Emitter::Constant { .. });
    (strategy == LightStrategy::Derivative && constant).then_some(env)
}

/// Traces the camera ray `ray` in `f32` and records its path: up to `max_scatter` scattering vertices,
/// each with one light sample and one BSDF sample. Draws from `sampler` in a fixed order per vertex
/// (emitter choice, light point, BSDF direction). The first ray resolves detail down to `spread · t`
/// ([`crate::trace::TraceSettings::spread`]; a camera ray's [`crate::camera::CameraFrame::spread`],
/// infinite for none).
pub fn trace_path(
    scene: &Scene,
    ray: Ray,
    spread: f32,
    max_scatter: u32,
    sampler: &mut Sampler,
    record: &mut PathRecord,
    counters: &mut TraceCounters,
) {
    let first = (max_scatter > 0).then(|| scene.intersect_resolving(&ray, f32::INFINITY, spread));
    trace_path_after(scene, ray, first, max_scatter, sampler, record, counters);
}

/// [`trace_path`] with the camera ray's first intersection `first` already found (by the caller, who
/// may know better than the tracer: the crease-edge estimator's rays next to a thin wedge); `None`
/// only when `max_scatter` is 0 (the camera ray then only looks for emission).
pub(crate) fn trace_path_after(
    scene: &Scene,
    ray: Ray,
    first: Option<Intersection>,
    max_scatter: u32,
    sampler: &mut Sampler,
    record: &mut PathRecord,
    counters: &mut TraceCounters,
) {
    let mut first = first;
    record.camera = ray.o;
    record.vertices.clear();
    record.lights.clear();
    record.sky_directions.clear();
    let sky = control_variate_sky(scene, record.strategy);
    let mut ray = ray;
    // The BSDF density (per steradian) of the current ray; `None` for the camera ray.
    let mut bsdf_pdf: Option<f32> = None;
    let mut prev = ray.o;
    // The convex shape the current ray leaves outward, which it need not trace (`Scene::leaving`).
    let mut leaving = None;
    let mut scatter = 0;
    loop {
        // After the last scattering vertex only emission along the ray counts.
        let next = if scatter >= max_scatter {
            emission_along(scene, &ray, leaving, counters)
        } else {
            let found = first.take();
            match found.unwrap_or_else(|| scene.intersect_leaving(&ray, f32::INFINITY, leaving)) {
                Intersection::Hit(h) => Next::Surface(h),
                Intersection::Miss => Next::Escape,
                Intersection::Exhausted => {
                    counters.exhausted += 1;
                    Next::Escape
                }
            }
        };
        let hit = match next {
            Next::Surface(h) => Some(h),
            Next::Escape => None,
            Next::Blocked => return,
        };
        let Some(h) = hit else {
            if let Some(env) = scene.environment {
                let (pdf, mis) = match bsdf_pdf {
                    None => (1.0, 1.0),
                    Some(pb) => {
                        let pl = light_pdf(
                            scene,
                            record.strategy,
                            env,
                            prev,
                            ray.d,
                            prev + ray.d,
                            -ray.d,
                        );
                        (pb, power_heuristic(pb, pl))
                    }
                };
                record.vertices.push(PathVertex {
                    p: ray.d,
                    n: -ray.d,
                    kind: VertexKind::Environment(env),
                    pdf,
                    mis,
                });
            }
            return;
        };
        let pdf = match bsdf_pdf {
            None => 1.0,
            Some(pb) => pb * h.n.dot(ray.d).abs() / (h.p - prev).length_squared(),
        };
        if !(pdf > 0.0 && pdf.is_finite()) {
            return;
        }
        match h.surface {
            Surface::Emitter(i) => {
                let mis = match bsdf_pdf {
                    None => 1.0,
                    Some(pb) => {
                        let pl = light_pdf(scene, record.strategy, i, prev, ray.d, h.p, h.n);
                        power_heuristic(pb, pl)
                    }
                };
                record.vertices.push(PathVertex {
                    p: h.p,
                    n: h.n,
                    kind: VertexKind::Emitter(i),
                    pdf,
                    mis,
                });
                return;
            }
            Surface::Shape(s) => {
                let index = record.vertices.len();
                record.vertices.push(PathVertex {
                    p: h.p,
                    n: h.n,
                    kind: VertexKind::Shape(s),
                    pdf,
                    mis: 0.0,
                });
                if scatter >= max_scatter {
                    return;
                }
                scatter += 1;
                let wo = -ray.d;
                let u_pick = sampler.next_1d();
                let u_light = sampler.next_2d();
                let u_bsdf = sampler.next_2d();
                let sky = sky.filter(|_| matches!(scene.shapes[s].bsdf, Bsdf::Diffuse { .. }));
                if let Some(lv) = sample_light(
                    scene,
                    record.strategy,
                    index,
                    s,
                    h.p,
                    h.n,
                    wo,
                    u_pick,
                    u_light,
                    sky.map(|_| &mut record.sky_directions),
                    counters,
                ) {
                    record.lights.push(lv);
                }
                let Some(bs) = scene.shapes[s].bsdf_sample(h.p, h.n, wo, u_bsdf) else {
                    return;
                };
                if let Some(env) = sky.filter(|_| bs.pdf > 0.0 && bs.pdf.is_finite()) {
                    let pl =
                        light_pdf(scene, record.strategy, env, h.p, bs.wi, h.p + bs.wi, -bs.wi);
                    record.sky_directions.push(SkyDirection {
                        from: index,
                        w: bs.wi,
                        weight: power_heuristic(bs.pdf, pl) / bs.pdf,
                    });
                }
                bsdf_pdf = Some(bs.pdf);
                prev = h.p;
                ray = Ray::new(scene.offset_origin(s, h.p, h.n, bs.wi), bs.wi);
                leaving = scene.leaving(s, h.n, bs.wi);
            }
        }
    }
}

/// Which recorded point an [`Attach`] is asked to attach.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Anchor {
    /// The camera origin `x0` (a point: its `J` is ignored).
    Camera,
    /// A point on shape `i` of [`Scene::shapes`].
    Shape(usize),
    /// A point on finite emitter `i` of [`Scene::emitters`].
    Emitter(usize),
}

/// A recorded vertex in scalar type `S`: its position, unit normal and area factor `J` (the density of
/// the vertex is per unit area of the reference surface, docs/theory.md §2.4, so the contribution carries `J`).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Attached<S> {
    /// Position.
    pub x: Vec3<S>,
    /// Unit normal.
    pub n: Vec3<S>,
    /// Area element of the moving surface per unit area of the reference surface (1 at the primal).
    pub j: S,
}

/// How the recorded `f32` vertices of a path enter the contribution in `S`.
///
/// Any `Fn(p, n) -> (x, n)` closure (such as [`detached`]) is an `Attach` with `J = 1` that ignores the
/// anchor; the derivative pass uses [`super::attach::SceneAttach`].
pub trait Attach<S: Scalar> {
    /// The vertex recorded at `p` with normal `n`, lying on `at`, in `S`.
    fn attach(&self, at: Anchor, p: glam::Vec3, n: glam::Vec3) -> Attached<S>;
}

impl<S: Scalar, F: Fn(glam::Vec3, glam::Vec3) -> (Vec3<S>, Vec3<S>)> Attach<S> for F {
    #[inline(always)]
    fn attach(&self, _at: Anchor, p: glam::Vec3, n: glam::Vec3) -> Attached<S> {
        let (x, n) = self(p, n);
        Attached { x, n, j: S::one() }
    }
}

/// Positions and normals of recorded vertices as constants (the image pass).
#[inline]
pub fn detached<S: Scalar>(p: glam::Vec3, n: glam::Vec3) -> (Vec3<S>, Vec3<S>) {
    (Vec3::constant(p), Vec3::constant(n))
}

/// The contribution `f(x̄) / p(x̄)` of a recorded path (with its next-event branches), evaluated in `S`.
///
/// `attach` gives each finite vertex's position, normal and area factor in `S` (use [`detached`] for the
/// image); it is applied to the camera, the chain vertices and the light points, not to directions at
/// infinity. Every attached vertex but the camera multiplies the contribution by its `J`.
#[inline]
pub fn contribution<S: Scalar>(
    scene: &Scene,
    record: &PathRecord,
    attach: impl Attach<S>,
) -> Vec3<S> {
    contribution_parts(scene, record, &attach).0
}

/// [`contribution`], also returning the attached first vertex `x1` when it is a finite point (the
/// derivative pass needs its moving projection onto the film).
pub fn contribution_parts<S: Scalar, A: Attach<S> + ?Sized>(
    scene: &Scene,
    record: &PathRecord,
    attach: &A,
) -> (Vec3<S>, Option<Attached<S>>) {
    let mut radiance = Vec3::<S>::zero();
    let mut beta = Vec3::splat(S::one());
    let mut first = None;
    let mut prev_p = attach
        .attach(Anchor::Camera, record.camera, glam::Vec3::ZERO)
        .x;
    // The previous scattering vertex: (position, normal, outgoing direction, shape index).
    type Scatter<S> = (Vec3<S>, Vec3<S>, Vec3<S>, usize);
    let mut scatter: Option<Scatter<S>> = None;
    let mut lights = record.lights.iter().peekable();
    let mut sky_at = 0;
    for (i, v) in record.vertices.iter().enumerate() {
        match v.kind {
            VertexKind::Environment(e) => {
                let w = Vec3::<S>::constant(v.p);
                if let Some((xp, xn, wo, s)) = scatter {
                    let f = scene.shapes[s].bsdf_eval(xp, xn, w, wo);
                    beta = beta * f * (abs_cos(xn, w) / v.pdf);
                }
                let le = scene.emitters[e].emitter.emitted(prev_p, -w, -w);
                radiance += beta * le * S::constant(v.mis);
                return (radiance, first);
            }
            VertexKind::Emitter(e) | VertexKind::Shape(e) => {
                let anchor = match v.kind {
                    VertexKind::Emitter(_) => Anchor::Emitter(e),
                    _ => Anchor::Shape(e),
                };
                let a = attach.attach(anchor, v.p, v.n);
                if i == 0 {
                    first = Some(a);
                }
                let (x, n) = (a.x, a.n);
                if let Some((xp, xn, wo, s)) = scatter {
                    let f = scene.shapes[s].bsdf_eval(xp, xn, direction(xp, x), wo);
                    beta = beta * f * (geometry_term(xp, xn, x, n) / v.pdf);
                }
                beta = beta * a.j;
                let wo = direction(x, prev_p);
                if let VertexKind::Emitter(_) = v.kind {
                    let le = scene.emitters[e].emitter.emitted(x, n, wo);
                    radiance += beta * le * S::constant(v.mis);
                    return (radiance, first);
                }
                let s = e;
                while let Some(l) = lights.next_if(|l| l.from == i) {
                    let emitter = &scene.emitters[l.emitter].emitter;
                    let surface = &scene.shapes[s];
                    let contrib = if emitter.is_delta() {
                        // A point light's position is attached (it may move); the sun's direction
                        // is the emitter's own parameter.
                        let y = attach.attach(Anchor::Emitter(l.emitter), l.p, l.n).x;
                        let a = emitter.delta_arrival(x, y);
                        surface.bsdf_eval(x, n, a.wi, wo)
                            * (abs_cos(n, a.wi) / l.pdf)
                            * a.irradiance
                    } else if emitter.is_infinite() {
                        let w = Vec3::<S>::constant(l.p);
                        surface.bsdf_eval(x, n, w, wo)
                            * (abs_cos(n, w) / l.pdf)
                            * emitter.emitted(x, -w, -w)
                    } else {
                        let y = attach.attach(Anchor::Emitter(l.emitter), l.p, l.n);
                        let wl = direction(x, y.x);
                        surface.bsdf_eval(x, n, wl, wo)
                            * (geometry_term(x, n, y.x, y.n) / l.pdf)
                            * emitter.emitted(y.x, y.n, -wl)
                            * y.j
                    };
                    radiance += beta * contrib * S::constant(l.mis);
                }
                // Image passes record no sky directions: one comparison there.
                if record
                    .sky_directions
                    .get(sky_at)
                    .is_some_and(|d| d.from == i)
                {
                    let skies = &record.sky_directions[sky_at..];
                    let here = skies.iter().take_while(|d| d.from == i).count();
                    let cv = sky_control_variate(scene, s, (x, n, wo), &skies[..here]);
                    radiance -= beta.detach() * cv;
                    sky_at += here;
                }
                scatter = Some((x, n, wo, s));
                prev_p = x;
            }
        }
    }
    (radiance, first)
}

/// The cosine control variate at a diffuse vertex `x` (normal `n`, outgoing `wo`) of shape `shape`
/// lit by a constant sky, over the recorded `directions`: `f L Σ (s n·ω − s n₀·ω) w / p` over the
/// directions on `wo`'s side `s`, with the diffuse `f` and the sky's `L` detached (both the same for
/// every direction). Its value is zero and its derivative `f L s ∂n·Σ ω w / p` has expectation
/// `f L s ∂n·∫ ω dω = π f L ∂n·n₀ = 0` over the hemisphere (the two strategies' weights sum to one):
/// subtracted from the contribution, it removes the noise of the cosine's derivative where the sky is
/// seen, and changes no expectation.
fn sky_control_variate<S: Scalar>(
    scene: &Scene,
    shape: usize,
    (x, n, wo): (Vec3<S>, Vec3<S>, Vec3<S>),
    directions: &[SkyDirection],
) -> Vec3<S> {
    let Some(env) = scene.environment else {
        return Vec3::zero();
    };
    let (x0, n0, wo0) = (x.primal(), n.primal(), wo.primal());
    let side = if n0.dot(wo0) >= 0.0 { 1.0 } else { -1.0 };
    // `s Σ ω w / p` over the directions on `wo`'s side: one dot product with the moving normal.
    let mut sum = glam::Vec3::ZERO;
    let mut seen = None;
    for d in directions.iter().filter(|d| side * n0.dot(d.w) > 0.0) {
        sum += d.w * (side * d.weight);
        seen = Some(d.w);
    }
    let Some(w) = seen else {
        return Vec3::zero();
    };
    let w = Vec3::<f32>::constant(w);
    let f = scene.shapes[shape].bsdf_eval::<f32>(
        Vec3::constant(x0),
        Vec3::constant(n0),
        w,
        Vec3::constant(wo0),
    );
    let le = scene.emitters[env]
        .emitter
        .emitted::<f32>(Vec3::constant(x0), -w, -w);
    let c = n.dot_f32(sum);
    Vec3::constant((f * le).primal()) * (c - S::constant(c.primal()))
}
