//! The tear of a creased surface's parametrisation at vertices after the first (docs/theory.md §7.4),
//! for the `path` integrator: the boundary term along a sharp box's edges and a sharp cylinder's rims
//! for paths that reach them after a bounce.
//!
//! # The term
//!
//! The interior term moves each face's points along that face's normal (`x + V n`). At a crease the two
//! faces move along different normals, so the moving edge slides along each face relative to the face's
//! attached points: in the reference domain of face `f` the face's region grows by `ẋ_C·m_f` per unit
//! length of edge, `m_f` the unit tangent of face `f` across the edge pointing out of the face's region
//! (`∇F_other·m_f > 0`) and `ẋ_C` the edge point's velocity ([`super::crease_edges::moving_edge_point`]).
//! The face's own attached points move along `n_f ⊥ m_f`, so no relative term appears. For a path
//! integral over a vertex `x_k` on the creased surface (docs/theory.md §2.4, §5.6),
//!
//! ```text
//!   ∂I_j ⊃ Σ_f ∫_edge F_f(x_C) (ẋ_C·m_f) dℓ                                                         (1)
//! ```
//!
//! `F_f` the path integrand with `x_k = x_C` on face `f` (its normal for the BSDF and the geometry
//! terms), every other vertex integrated. The first vertex (`k = 1`) is the primary crease term's
//! ([`super::crease_edges`], whose `v − u̇` holds this sliding in film space); here `k ≥ 2`.
//!
//! # The estimator
//!
//! `x_C` uniform on the total length `Λ` of the scene's crease edges; for each face `f`, one direction
//! `ω` of the next segment from the mixture of [`super::crease_shadows`] (uniform on the sphere or
//! towards an emitter, density `p(ω)`), the radiance `L(ω)` arriving along it (emission, the
//! environment, or a path continued with the primal's estimator, truncated per depth as in
//! [`super::subpaths::radiance_by_depth`]), and the camera side of [`super::subpaths::camera_side`] from
//! `x_C` with normal `n_f` towards `ω` (its connections at depth `k ≥ 2`). One sample contributes
//!
//! ```text
//!   Σ_f Σ_{k ≥ 2} W_k · L^{(D−k)}(ω) |n_f·ω| / p(ω) · (ẋ_C·m_f) · Λ                                  (2)
//! ```
//!
//! splatted where each camera connection projects. Delta lights, which no sampled direction reaches,
//! add their light at `x_C` as next-event estimation finds it: `L |n_f·ω| / p(ω)` becomes the
//! irradiance `E(x_C)` towards the light, if visible, for every delta light.

use super::crease_edges::{CreaseEdges, face_gradient, moving_edge_point};
use super::crease_shadows::sample_direction;
use super::source::{BoundarySource, Pass, Scratch};
use super::subpaths::{camera_side, radiance_by_depth};
use super::{finite_splat, splat_on_film};
use crate::film::SampleSink;
use crate::integrator::path::{TraceCounters, occluded};
use crate::math::{Ray, Vec3};
use crate::sampler::Sampler;
use crate::scalar::Directions;
use crate::scene::{Intersection, Scene, Surface};

/// The random stream of crease-tear samples.
pub const CREASE_TEAR_STREAM: u64 = 0x7EA2_C2EA;

/// Whether the scene's paths can reach a crease after a bounce (the term exists): an integrator with
/// two or more scattering vertices and a crease edge.
pub fn applies(scene: &Scene) -> bool {
    scene.integrator.max_scatter() >= 2 && scene.has_crease_edges()
}

/// The crease edges where paths reach them after a bounce ([`applies`]): eq. (2)'s samples.
#[derive(Clone, Debug, Default)]
pub struct CreaseTears {
    /// Whether the term exists (it takes a share of the samples).
    applies: bool,
    edges: CreaseEdges,
}

impl CreaseTears {
    /// The term of `scene`, sampling `edges` (every crease edge of `scene`, [`CreaseEdges::all`]),
    /// kept only where the term exists.
    pub fn of(scene: &Scene, edges: &CreaseEdges) -> Self {
        let applies = applies(scene);
        Self {
            applies,
            edges: if applies {
                edges.clone()
            } else {
                CreaseEdges::default()
            },
        }
    }
}

impl<S: Directions> BoundarySource<S> for CreaseTears {
    fn stage(&self) -> &'static str {
        "secondary (crease tears)"
    }

    fn stream(&self) -> u64 {
        CREASE_TEAR_STREAM
    }

    fn takes_share(&self) -> bool {
        self.applies
    }

    fn sample(
        &self,
        pass: &Pass,
        sampler: &mut Sampler,
        scratch: &mut Scratch,
        counters: &mut TraceCounters,
        sink: &mut dyn SampleSink<S>,
    ) {
        // Edges that extract to nothing take their share but have nothing to sample.
        if !self.edges.is_empty() {
            sample(pass.scene, &self.edges, sampler, scratch, sink, counters);
        }
    }
}

/// One sample of eq. (2): pushes its splats (not yet divided by the sample count).
fn sample<S: Directions>(
    scene: &Scene,
    edges: &CreaseEdges,
    sampler: &mut Sampler,
    scratch: &mut Scratch,
    splats: &mut dyn SampleSink<S>,
    counters: &mut TraceCounters,
) {
    let Some((pt, m, edge)) = edges.sample_on_surface(scene, sampler) else {
        return;
    };
    let shape = &scene.shapes[m];
    let x = pt.x;
    let Some(moving) = moving_edge_point::<S>(shape, edge, x) else {
        return;
    };
    let velocity = moving - Vec3::constant(x);
    let grads = [0, 1].map(|f| face_gradient(shape, edge, f, x));
    let depth = scene.integrator.max_scatter();
    let frame = scene.camera.frame::<f32>();
    // The surface's outward normal: the face's, reversed inside a subtracted child.
    let outward = if edge.inverted { -1.0 } else { 1.0 };
    for f in 0..2 {
        let Some(n) = (grads[f] * outward).try_normalize() else {
            continue;
        };
        // Across the edge in face f's tangent plane, out of the face's region (towards the other
        // face's outside).
        let Some(mut across) = pt.tangent.cross(n).try_normalize() else {
            continue;
        };
        if across.dot(grads[1 - f]) < 0.0 {
            across = -across;
        }
        let rate = velocity.dot(Vec3::constant(across));
        delta_lights(
            scene,
            (m, x, n),
            pt.weight,
            rate,
            sampler,
            scratch,
            splats,
            counters,
        );
        let Some((w, pdf)) = sample_direction(scene, x, sampler) else {
            continue;
        };
        let cos = n.dot(w);
        if cos.is_nan() || cos <= 0.0 {
            continue;
        }
        // The radiance arriving along w, per number of scattering vertices after x_C (index j):
        // emission and the environment at every j ≥ 0, a shape's continued path L^{(j)}.
        let origin = scene.offset_origin(m, x, n, w);
        let ray = Ray::new(origin, w);
        // `None`: a shape's continued path, `scratch.by_depth[j]` = L^{(j)}.
        let (constant, max_k): (Option<glam::Vec3>, u32) =
            match scene.intersect(&ray, f32::INFINITY) {
                Intersection::Hit(h) => match h.surface {
                    Surface::Emitter(e) => {
                        let le = scene.emitters[e].emitter.emitted::<f32>(
                            h.p.into(),
                            h.n.into(),
                            (-w).into(),
                        );
                        (Some(le.into()), depth)
                    }
                    Surface::Shape(d) if depth >= 3 => {
                        if !radiance_by_depth(
                            scene,
                            ray,
                            d,
                            depth - 2,
                            sampler,
                            &mut scratch.record,
                            &mut scratch.truncated,
                            &mut scratch.by_depth,
                            counters,
                        ) {
                            continue;
                        }
                        (None, depth - 1)
                    }
                    Surface::Shape(_) => continue,
                },
                Intersection::Miss => match scene.environment {
                    Some(e) => {
                        let le = scene.emitters[e].emitter.emitted::<f32>(
                            x.into(),
                            (-w).into(),
                            (-w).into(),
                        );
                        (Some(le.into()), depth)
                    }
                    None => continue,
                },
                Intersection::Exhausted => {
                    counters.exhausted += 1;
                    continue;
                }
            };
        camera_side(
            scene,
            &frame,
            m,
            x,
            n,
            w,
            max_k,
            sampler,
            &mut scratch.cams,
            counters,
        );
        for cam in scratch.cams.iter().filter(|c| c.depth >= 2) {
            // x_C is the k-th scattering vertex: the radiance after it has at most D − k more.
            let l = constant.unwrap_or_else(|| scratch.by_depth[(depth - cam.depth) as usize]);
            let scale = cam.f * l * (cos / pdf * cam.j_film * pt.weight);
            if scale == glam::Vec3::ZERO || !scale.is_finite() {
                continue;
            }
            let value = Vec3::<S>::constant(scale) * rate;
            if finite_splat(&value, S::zero()) {
                splat_on_film(scene, (cam.film.x, cam.film.y), value, S::zero(), splats);
            }
        }
    }
}

/// The delta lights' part of eq. (2) at the edge point `x` of face `n` (shape `m`): no sampled
/// direction reaches a delta light, so each one's light arriving at `x` is added as the path
/// integrator's next-event estimation finds it (the one direction towards it, density 1, visibility
/// tested), `L |n·ω| / p(ω)` becoming the irradiance `E(x)` ([`crate::emitter::delta`]), with the
/// camera side connected at depths `2 ≤ k ≤ D` (the light ends the path). `weight` is `Λ` (the edge
/// point's `1/p`), `rate` the sliding `ẋ_C·m_f`.
#[allow(clippy::too_many_arguments)]
fn delta_lights<S: Directions>(
    scene: &Scene,
    (m, x, n): (usize, glam::Vec3, glam::Vec3),
    weight: f32,
    rate: S,
    sampler: &mut Sampler,
    scratch: &mut Scratch,
    splats: &mut dyn SampleSink<S>,
    counters: &mut TraceCounters,
) {
    let depth = scene.integrator.max_scatter();
    let frame = scene.camera.frame::<f32>();
    for light in scene.emitters.iter().map(|e| &e.emitter) {
        if !light.is_delta() {
            continue;
        }
        let Some(es) = light.sample_delta_li(x) else {
            continue;
        };
        let cos = n.dot(es.wi);
        if cos.is_nan() || cos <= 0.0 {
            continue;
        }
        let o = scene.offset_origin(m, x, n, es.wi);
        let (t_max, irradiance) = if es.dist.is_finite() {
            let d2 = es.dist * es.dist;
            ((es.p - o).dot(es.wi), light.mean_radiance() / d2)
        } else {
            (f32::INFINITY, light.mean_radiance())
        };
        let ray = Ray::new(o, es.wi);
        let leaving = scene.leaving(m, n, es.wi);
        if occluded(scene, &ray, t_max, None, leaving, counters) {
            continue;
        }
        camera_side(
            scene,
            &frame,
            m,
            x,
            n,
            es.wi,
            depth,
            sampler,
            &mut scratch.cams,
            counters,
        );
        for cam in scratch.cams.iter().filter(|c| c.depth >= 2) {
            let scale = cam.f * irradiance * (cos * cam.j_film * weight);
            if scale == glam::Vec3::ZERO || !scale.is_finite() {
                continue;
            }
            let value = Vec3::<S>::constant(scale) * rate;
            if finite_splat(&value, S::zero()) {
                splat_on_film(scene, (cam.film.x, cam.film.y), value, S::zero(), splats);
            }
        }
    }
}
