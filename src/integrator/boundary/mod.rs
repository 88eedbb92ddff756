//! Boundary terms of the derivative (docs/theory.md §3, §7): visibility along a segment jumps
//! where the segment touches a surface tangentially or passes a crease edge.
//!
//! [`segment`] holds the geometry of one boundary segment `(x_S, x_B, x_D)`: the measure changes
//! (`J^B`, supplemental §2 eqs. 12–23; the primary `dℓ(x_D)/dℓ(x_B)`, supplemental eq. 15), the silhouette test, and the
//! normal velocity `V_∂` of the discontinuity curve by AD. [`secondary`] estimates the secondary
//! boundary term (shadows, on every segment of a path after the first) with them, its tangent angles
//! steered towards the emitters by [`tangent_sampling`] and [`subpaths`] estimating the camera and
//! light sides of segments deep in a path; [`primary`] the primary boundary term (silhouettes seen from
//! the camera), with [`emitter_edges`] for the outlines of emitters seen directly. Crease edges of sharp
//! boxes and cylinders: [`crease_edges`] (seen from the camera), [`crease_segment`] (the geometry of a
//! segment passing an edge), [`crease_shadows`] (their secondary term) and [`crease_tears`] (the tear
//! of a creased surface's parametrisation at later vertices). The hard shadow edges of point and
//! directional lights: [`delta_shadows`] (silhouettes seen from the light) and [`delta_creases`] (crease
//! edges seen from the light). Each of those estimators is a
//! [`source::BoundarySource`], run by the one loop of [`source`]. Both integrators (`direct` is `path`
//! with one scattering vertex).

pub mod crease_edges;
pub mod crease_segment;
pub mod crease_shadows;
pub mod crease_tears;
pub mod delta_creases;
pub mod delta_shadows;
pub mod emitter_edges;
mod frustum;
pub mod motion;
pub mod primary;
pub mod secondary;
pub mod segment;
pub mod shadow_segment;
pub mod source;
pub mod subpaths;
pub mod tangent_sampling;

pub use segment::{
    BoundarySegment, boundary_jacobian, boundary_velocity, is_silhouette_direction,
    primary_measure_change, silhouette_tangent,
};

use crate::camera::CameraFrame;
use crate::film::{SampleSink, splat_filtered};
use crate::integrator::attach::SceneAttach;
use crate::integrator::path::{
    PathRecord, TraceCounters, VertexKind, contribution, detached, occluded, trace_path,
};
use crate::math::{Ray, Vec3};
use crate::sampler::Sampler;
use crate::scalar::{Directions, Scalar};
use crate::scene::Scene;

/// Whether a film point `(px, py)` (pixels) lies within the filter's reach of some pixel of the image.
pub(crate) fn on_film(scene: &Scene, px: f32, py: f32) -> bool {
    let r = scene.camera.filter.radius();
    let (w, h) = (scene.camera.width as f32, scene.camera.height as f32);
    px > -r && py > -r && px < w + r && py < h + r
}

/// Whether every direction of a splat's values is finite.
pub(crate) fn finite_splat<S: Directions>(radiance: &Vec3<S>, coverage: S) -> bool {
    (0..S::COUNT).all(|k| {
        radiance.x.direction(k).is_finite()
            && radiance.y.direction(k).is_finite()
            && radiance.z.direction(k).is_finite()
            && coverage.direction(k).is_finite()
    })
}

/// Splats `radiance` and `coverage` at film point `(px, py)` to every pixel whose filter covers it,
/// weighted by that filter.
pub(crate) fn splat_on_film<S: Scalar>(
    scene: &Scene,
    (px, py): (f32, f32),
    radiance: Vec3<S>,
    coverage: S,
    tile: &mut dyn SampleSink<S>,
) {
    let camera = &scene.camera;
    splat_filtered(
        tile,
        &camera.filter,
        (camera.width, camera.height),
        glam::Vec2::new(px, py),
        radiance,
        coverage,
    );
}

/// How far outside an edge its background is looked up, in pixels (the primary term's background side).
pub(crate) const BACKGROUND_OFFSET_PIXELS: f32 = 0.02;

/// The world-space length of [`BACKGROUND_OFFSET_PIXELS`] at distance `dist` from the eye (`focal` in
/// pixels), at least four of a camera ray's tolerances there so the offset ray clears the edge's own
/// surface.
pub(crate) fn background_offset(scene: &Scene, dist: f32, focal: f32) -> f32 {
    let spread = crate::camera::PIXEL_RESOLUTION / focal;
    (BACKGROUND_OFFSET_PIXELS * dist / focal).max(4.0 * camera_ray_eps(scene, spread, dist))
}

/// The hit tolerance of a camera ray resolving `spread` ([`crate::trace::TraceSettings::spread`]) at
/// distance `dist` from the eye.
fn camera_ray_eps(scene: &Scene, spread: f32, dist: f32) -> f32 {
    let settings = crate::trace::TraceSettings {
        spread,
        ..scene.trace
    };
    settings.eps_along(scene.camera.origin.value().abs().max_element(), dist)
}

/// The rows `(∂u/∂x, ∂v/∂x)` of the film projection's 2×3 Jacobian at `x_B = eye + q` (`None` behind
/// the camera): `P'_u = f (r z − f̂ (q·r)) / z²`, `P'_v = −f (up z − f̂ (q·up)) / z²`, `z = q·f̂`.
pub(crate) fn projection_jacobian(
    frame: &CameraFrame<f32>,
    q: glam::Vec3,
) -> Option<(glam::Vec3, glam::Vec3)> {
    let (right, up, fwd): (glam::Vec3, glam::Vec3, glam::Vec3) =
        (frame.right.into(), frame.up.into(), frame.forward.into());
    let z = q.dot(fwd);
    if z.is_nan() || z <= 0.0 {
        return None;
    }
    let k = frame.focal / (z * z);
    Some((
        (right * z - fwd * q.dot(right)) * k,
        -(up * z - fwd * q.dot(up)) * k,
    ))
}

/// Whether the camera `ray` (`frame` the camera's) meets anything before an edge at distance `dist`
/// from the eye, less a margin of four `delta` (from [`background_offset`]) and eight camera-ray
/// tolerances: the edge's own faces, met near `dist` by a ray passing next to it, do not count.
pub(crate) fn hidden_before(
    scene: &Scene,
    frame: &CameraFrame<f32>,
    ray: Ray,
    dist: f32,
    delta: f32,
    counters: &mut TraceCounters,
) -> bool {
    let margin = 4.0 * delta + 8.0 * camera_ray_eps(scene, frame.spread(ray.d), dist);
    occluded(scene, &ray, dist - margin, None, None, counters)
}

/// The background radiance beyond an edge at distance `dist` from the eye, seen along the camera `ray`
/// just outside it (`delta` from [`background_offset`]; `frame` the camera's, whose
/// [`CameraFrame::spread`] the ray resolves): `None` when something nearer hides the edge; else one
/// camera path of the scene's own estimator, left in `record` (its first vertex is `x_D`), and its
/// detached radiance.
#[allow(clippy::too_many_arguments)]
pub(crate) fn background_radiance(
    scene: &Scene,
    frame: &CameraFrame<f32>,
    ray: Ray,
    dist: f32,
    delta: f32,
    sampler: &mut Sampler,
    record: &mut PathRecord,
    counters: &mut TraceCounters,
) -> Option<glam::Vec3> {
    if hidden_before(scene, frame, ray, dist, delta, counters) {
        return None;
    }
    let spread = frame.spread(ray.d);
    let depth = scene.integrator.max_scatter();
    trace_path(scene, ray, spread, depth, sampler, record, counters);
    Some(contribution::<f32>(scene, record, detached).into())
}

/// The attached position of a camera path's first vertex (`x_D` of the primary term), `None` for a
/// direction at infinity or an empty path.
pub(crate) fn attached_first_vertex<S: Scalar>(
    attach: &SceneAttach,
    record: &PathRecord,
) -> Option<Vec3<S>> {
    record.vertices.first().and_then(|v| match v.kind {
        VertexKind::Shape(i) => Some(attach.shape_vertex::<S>(i, v.p, v.n).x),
        VertexKind::Emitter(e) => Some(attach.emitter_vertex::<S>(e, v.p, v.n).x),
        VertexKind::Environment(_) => None,
    })
}

/// The film velocity `∂π P_π(x)` of an attached point (derivative parts only; primal 0).
#[inline]
pub(crate) fn film_velocity<S: Scalar>(frame: &CameraFrame<S>, x: Vec3<S>) -> Option<(S, S)> {
    let (px, py) = frame.project(x)?;
    Some((px - px.detach(), py - py.detach()))
}
