//! Boundary terms of the derivative (DESIGN.md §3 "Boundary integrals"): visibility along a segment jumps
//! where the segment touches a surface tangentially.
//!
//! [`segment`] holds the geometry of one boundary segment `(x_S, x_B, x_D)`: the measure changes
//! (`J^B`, seed §2 eqs. 12–23; the primary `dℓ(x_D)/dℓ(x_B)`, seed eq. 15), the silhouette test, and the
//! normal velocity `V_∂` of the discontinuity curve by AD. [`secondary`] estimates the secondary
//! boundary term (shadows, on every segment of a path after the first) with them, its tangent angles
//! steered towards the emitters by [`tangent_sampling`] and [`subpaths`] estimating the camera and
//! light sides of segments deep in a path; [`primary`] the primary boundary term (silhouettes seen from
//! the camera), with [`emitter_edges`] for the outlines of emitters seen directly. Both integrators
//! (`direct` is `path` with one scattering vertex).

pub mod emitter_edges;
pub mod primary;
pub mod secondary;
pub mod segment;
pub mod subpaths;
pub mod tangent_sampling;

pub use segment::{
    BoundarySegment, boundary_jacobian, boundary_velocity, is_silhouette_direction,
    primary_measure_change, silhouette_tangent,
};

use crate::camera::CameraFrame;
use crate::error::{Error, Result};
use crate::film::Image;
use crate::integrator::attach::{SceneAttach, window_slots};
use crate::integrator::derivative::Directions;
use crate::integrator::path::{
    PathRecord, TraceCounters, VertexKind, contribution, detached, occluded, trace_path,
};
use crate::math::{Ray, Vec3};
use crate::sampler::Sampler;
use crate::scalar::Scalar;
use crate::scene::Scene;
use rayon::prelude::*;

/// The boundary terms exist for both integrators (`direct` is `path` with one scattering vertex) and
/// continuous pixel filters; `term` names the term in the error.
fn check_supported(scene: &Scene, term: &str) -> Result<()> {
    if !scene.camera.filter.is_continuous() {
        return Err(Error::Unsupported(format!(
            "the {term} boundary term with the box filter needs pixel-edge terms: use the tent or \
             gaussian filter"
        )));
    }
    Ok(())
}

/// Runs `pass(windowed scene, width)` once per window of `S::COUNT` parameters of slots `0..count`
/// (the window's slots renumbered from 0) and concatenates the per-parameter images in slot order.
fn in_windows<S: Directions>(
    scene: &Scene,
    count: usize,
    mut pass: impl FnMut(&Scene, usize) -> Vec<Image>,
) -> Vec<Image> {
    let mut out = Vec::with_capacity(count);
    for lo in (0..count).step_by(S::COUNT) {
        let width = (count - lo).min(S::COUNT);
        out.extend(pass(&window_slots(scene, lo, S::COUNT), width));
    }
    out
}

/// One splat of a boundary sample: a pixel, its share of the radiance jump and of the jump of the pixel
/// filter's own integral `W` (0 for the secondary term: its jumps leave `W` unchanged).
pub(crate) struct Splat<S> {
    pixel: usize,
    radiance: Vec3<S>,
    coverage: S,
}

/// Boundary samples per parallel work item (results are gathered in sample order: deterministic).
const CHUNK: u64 = 256;

/// Runs boundary samples `0..samples` in parallel chunks (`state()` once per chunk, `sample(state, k,
/// splats)` for sample `k`) and adds the mean of their splats to `radiance[k]` and `coverage[k]` (the
/// same value in the three channels) for directions `k < width` of `S`. The splats are summed in `f64`
/// in sample order: the result does not depend on the thread count.
pub(crate) fn accumulate_samples<S: Directions, T>(
    scene: &Scene,
    width: usize,
    samples: u64,
    state: impl Fn() -> T + Sync,
    sample: impl Fn(&mut T, u64, &mut Vec<Splat<S>>) + Sync,
    radiance: &mut [Image],
    coverage: &mut [Image],
) {
    if samples == 0 {
        return;
    }
    let chunks: Vec<Vec<Splat<S>>> = (0..samples.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut splats = Vec::new();
            let mut st = state();
            for k in c * CHUNK..((c + 1) * CHUNK).min(samples) {
                sample(&mut st, k, &mut splats);
            }
            splats
        })
        .collect();
    let n = (scene.camera.width * scene.camera.height) as usize;
    let mut acc = vec![0.0f64; 3 * width * n];
    let mut acc_w = vec![0.0f64; width * n];
    for s in chunks.iter().flatten() {
        for k in 0..width {
            let base = 3 * (k * n + s.pixel);
            acc[base] += s.radiance.x.direction(k) as f64;
            acc[base + 1] += s.radiance.y.direction(k) as f64;
            acc[base + 2] += s.radiance.z.direction(k) as f64;
            acc_w[k * n + s.pixel] += s.coverage.direction(k) as f64;
        }
    }
    let inv = 1.0 / samples as f64;
    for (k, image) in radiance.iter_mut().take(width).enumerate() {
        for (d, a) in image.rgb.iter_mut().zip(&acc[3 * k * n..3 * (k + 1) * n]) {
            *d += (a * inv) as f32;
        }
    }
    for (k, image) in coverage.iter_mut().take(width).enumerate() {
        for (d, a) in image
            .rgb
            .chunks_exact_mut(3)
            .zip(&acc_w[k * n..(k + 1) * n])
        {
            for c in d {
                *c += (a * inv) as f32;
            }
        }
    }
}

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

/// Pushes the splats of values `radiance` and `coverage` at film point `(px, py)` to every pixel whose
/// filter covers it, weighted by that filter.
pub(crate) fn splat_filtered<S: Directions>(
    scene: &Scene,
    (px, py): (f32, f32),
    radiance: Vec3<S>,
    coverage: S,
    splats: &mut Vec<Splat<S>>,
) {
    let filter = scene.camera.filter;
    let radius = filter.radius();
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
                let fw = S::constant(fw);
                splats.push(Splat {
                    pixel: (jy * w + jx) as usize,
                    radiance: radiance * fw,
                    coverage: coverage * fw,
                });
            }
        }
    }
}

/// How far outside an edge its background is looked up, in pixels (the primary term's background side).
pub(crate) const BACKGROUND_OFFSET_PIXELS: f32 = 0.02;

/// The world-space length of [`BACKGROUND_OFFSET_PIXELS`] at distance `dist` from the eye (`focal` in
/// pixels), at least `4 eps` so the offset ray clears the edge's own surface.
pub(crate) fn background_offset(scene: &Scene, dist: f32, focal: f32) -> f32 {
    (BACKGROUND_OFFSET_PIXELS * dist / focal).max(4.0 * scene.trace.eps)
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

/// The background radiance beyond an edge at distance `dist` from the eye, seen along the camera `ray`
/// just outside it (`delta` from [`background_offset`]): `None` when something nearer hides the edge;
/// else one camera path of the scene's own estimator, left in `record` (its first vertex is `x_D`), and
/// its detached radiance.
pub(crate) fn background_radiance(
    scene: &Scene,
    ray: Ray,
    dist: f32,
    delta: f32,
    sampler: &mut Sampler,
    record: &mut PathRecord,
    counters: &mut TraceCounters,
) -> Option<glam::Vec3> {
    let margin = 4.0 * delta + 8.0 * scene.trace.eps;
    if occluded(scene, &ray, dist - margin, None, counters) {
        return None;
    }
    let depth = scene.integrator.max_scatter();
    trace_path(scene, ray, depth, sampler, record, counters);
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
