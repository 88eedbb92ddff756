//! The secondary boundary term along crease edges (docs/theory.md §7.3): the shadows of sharp boxes'
//! edges and sharp cylinders' rims, and every other visibility change along a path where a segment
//! passes such an edge. The estimator is [`super::secondary`]'s (read its module docs first) with the
//! tangent line replaced by a line through an edge point ([`super::crease_segment`]).
//!
//! # Sampling
//!
//! One sample draws a point `x_B` uniformly on the total length `Λ` of the scene's crease edges
//! ([`CreaseEdges::all`]: an edge out of view can cast a shadow in view), and a direction `ω` by
//! one-sample MIS over solid angle (Veach 1997, §9.2.4): uniform on the sphere with probability
//! [`UNIFORM_SHARE`], else towards a point of an emitter chosen uniformly
//! ([`crate::emitter::Emitter::sample_li`]), weighted by the mixture density
//!
//! ```text
//!   p(ω) = P_u / 4π + (1 − P_u) Σ_e p_e(ω) / n_e                                                  (1)
//! ```
//!
//! (`p_e` the emitter's density per steradian from `x_B`, zero where `ω` misses it; `n_e` the number of
//! emitters). `P_u > 0` keeps `p` positive everywhere, so segments ending on shapes (continued by the
//! `path` integrator) or on occluded emitters keep their share. The line through `x_B` along `ω` is
//! traced both ways from `x_B` pushed off the edge along its faces' mean normal; its first hits are
//! `x_D` (along `ω`) and `x_S` (along `−ω`): one oriented segment per sample, whose direction is `ω`.
//! Unless the faces lie on opposite sides of the line ([`super::crease_segment::CreaseSegment::is_boundary`]) the sample
//! contributes nothing, nor on a concave edge ([`crate::sdf::CreaseEdge::inverted`]: every line through
//! it enters the solid on both sides). It contributes eq. (2) of [`super::secondary`] with the crease's change of
//! measure ((B2) of [`super::crease_segment`]) in place of eq. (A), weighted by `Λ / p(ω)`. Points of an
//! edge that are not on the shape's surface (inside another CSG child, or cut away) contribute 0.

use super::crease_edges::{CreaseEdges, face_gradient};
use super::shadow_segment::{Occluder, segment};
use super::source::{BoundarySource, Pass, Scratch};
use crate::film::SampleSink;
use crate::integrator::path::TraceCounters;
use crate::math::Ray;
use crate::math::sampling::{UNIFORM_SPHERE_PDF, uniform_sphere};
use crate::sampler::Sampler;
use crate::scalar::Directions;
use crate::scene::{Intersection, Scene};

/// The random stream of crease-shadow samples.
pub const CREASE_SHADOW_STREAM: u64 = 0x5ADE_C2EA;

/// The probability `P_u` of drawing the direction uniformly on the sphere (eq. (1)).
pub const UNIFORM_SHARE: f32 = 0.5;

/// The emitters a direction can be drawn towards: all but the delta lights, which no direction found
/// by sampling a sphere of directions reaches (their hard shadows are [`super::delta_shadows`]'s).
fn steering_emitters(scene: &Scene) -> impl Iterator<Item = &crate::emitter::Emitter> {
    (scene.emitters.iter())
        .map(|e| &e.emitter)
        .filter(|e| !e.is_delta())
}

/// The density (1) of direction `w` from `x`: uniform share plus the emitters' solid-angle densities.
fn direction_pdf(scene: &Scene, x: glam::Vec3, w: glam::Vec3) -> f32 {
    let n = steering_emitters(scene).count();
    if n == 0 {
        return UNIFORM_SPHERE_PDF;
    }
    let ray = Ray::new(x, w);
    let towards: f32 = steering_emitters(scene)
        .map(|e| {
            if e.is_infinite() {
                e.pdf_li(x, w, x + w, -w)
            } else {
                e.intersect(&ray, f32::INFINITY)
                    .map_or(0.0, |(t, normal)| e.pdf_li(x, w, ray.at(t), normal))
            }
        })
        .filter(|p| p.is_finite())
        .sum();
    UNIFORM_SHARE * UNIFORM_SPHERE_PDF + (1.0 - UNIFORM_SHARE) * towards / n as f32
}

/// A direction from `x` drawn by (1), with its density; `None` when the emitter sample fails.
pub(crate) fn sample_direction(
    scene: &Scene,
    x: glam::Vec3,
    sampler: &mut Sampler,
) -> Option<(glam::Vec3, f32)> {
    let n = steering_emitters(scene).count();
    let pick = sampler.next_1d();
    let u = sampler.next_2d();
    let w = if n == 0 || pick < UNIFORM_SHARE {
        uniform_sphere(u)
    } else {
        let k = (((pick - UNIFORM_SHARE) / (1.0 - UNIFORM_SHARE) * n as f32) as usize).min(n - 1);
        steering_emitters(scene).nth(k)?.sample_li(x, u)?.wi
    };
    let pdf = direction_pdf(scene, x, w);
    (pdf > 0.0 && pdf.is_finite()).then_some((w, pdf))
}

/// Every crease edge of the scene, whole ([`CreaseEdges::all`]): the lines of the module docs.
#[derive(Clone, Debug, Default)]
pub struct CreaseShadows {
    /// Whether the scene's shapes have crease edges (the term takes a share of the samples).
    creased: bool,
    edges: CreaseEdges,
}

impl CreaseShadows {
    /// The crease edges of `scene` (extracted only when a shape has some).
    pub fn of(scene: &Scene) -> Self {
        let creased = scene.has_crease_edges();
        Self {
            creased,
            edges: if creased {
                CreaseEdges::all(scene)
            } else {
                CreaseEdges::default()
            },
        }
    }

    /// The edges.
    pub fn edges(&self) -> &CreaseEdges {
        &self.edges
    }
}

impl<S: Directions> BoundarySource<S> for CreaseShadows {
    fn stage(&self) -> &'static str {
        "secondary (crease edges)"
    }

    fn stream(&self) -> u64 {
        CREASE_SHADOW_STREAM
    }

    fn takes_share(&self) -> bool {
        self.creased
    }

    fn sample(
        &self,
        pass: &Pass,
        sampler: &mut Sampler,
        _scratch: &mut Scratch,
        counters: &mut TraceCounters,
        sink: &mut dyn SampleSink<S>,
    ) {
        // Edges that extract to nothing take their share but have nothing to sample.
        if !self.edges.is_empty() {
            sample(pass, &self.edges, sampler, sink, counters);
        }
    }
}

/// One sample (module docs): pushes its contributions, not yet divided by the sample count.
fn sample<S: Directions>(
    pass: &Pass,
    edges: &CreaseEdges,
    sampler: &mut Sampler,
    splats: &mut dyn SampleSink<S>,
    counters: &mut TraceCounters,
) {
    let scene = pass.scene;
    let Some((pt, m, edge)) = edges.sample_on_surface(scene, sampler) else {
        return;
    };
    // A concave edge (inside a subtracted child) blocks every line through it on both sides.
    if edge.inverted {
        return;
    }
    let shape = &scene.shapes[m];
    let x_b = pt.x;
    let Some((w, pdf)) = sample_direction(scene, x_b, sampler) else {
        return;
    };
    let grads = [0, 1].map(|f| face_gradient(shape, edge, f, x_b));
    let side = grads[0].dot(w) * grads[1].dot(w);
    // The faces must lie on opposite sides of the line (NaN: no).
    if side.is_nan() || side >= 0.0 {
        return;
    }
    let weight = pt.weight / pdf;
    if !weight.is_finite() {
        return;
    }
    let Some(mean_normal) =
        (grads[0].normalize_or_zero() + grads[1].normalize_or_zero()).try_normalize()
    else {
        return;
    };
    let o = scene.offset_origin(m, x_b, mean_normal, mean_normal);
    // Exhausted traces count as misses, as in the integrator's own paths (see `secondary`).
    let [d_end, s_end] = [w, -w].map(|d| match scene.intersect(&Ray::new(o, d), f32::INFINITY) {
        Intersection::Exhausted => {
            counters.exhausted += 1;
            Intersection::Miss
        }
        end => end,
    });
    let occluder = Occluder::Crease(m, edge, pt.tangent, grads);
    segment(
        pass,
        occluder,
        (x_b, o),
        &s_end,
        &d_end,
        weight,
        splats,
        counters,
    );
}
