//! The two sides of a secondary boundary segment `x_S → x_B → x_D` for integrators with several
//! scattering vertices ([`super::secondary`]): the importance that reaches `x_S` from the camera, and
//! the radiance that leaves `x_D` towards `x_S`. Both are detached `f32` estimates (the boundary term is
//! `Δf V_∂`, already first order), each unbiased for its own integral, drawn with random numbers
//! independent of each other.
//!
//! # Camera side: an adjoint walk from `x_S`, connected to the camera
//!
//! Pixel `j`'s paths through the segment, with `x_S` their `k`-th scattering vertex, are
//! `x₀ x₁ … x_{k−1} x_S x_D …`. Their camera factor (everything before `x_D`, without `G(x_S, x_D)`) is
//!
//! ```text
//!   W_k(x_S → x_D) = ∫ dA(x₁) … dA(x_{k−1})  w_j(proj x₁) J_film(x₁) V(x₀, x₁)
//!                      Π_{i<k} f(x_i; x_{i+1}, x_{i−1}) G(x_i, x_{i+1}) V(x_i, x_{i+1}) · f(x_S; x_D, x_{k−1})
//! ```
//!
//! (`f(x; toward the light, toward the camera)`, `x_k = x_S`, the area convention of the interior
//! term's first vertex; for `k = 1` the integral is empty: `W_1 = w_j J_film V(x₀, x_S) f(x_S; x_D, x₀)`,
//! the `direct` integrator's factor). Write `y₁ = x_S, y₂ = x_{k−1}, …, y_k = x₁` and `y₀ = x_D`. The walk
//! samples `y_{i+1}` from `y_i` by drawing a direction `d` with the BSDF's sampling routine given the
//! direction towards `y_{i−1}` (density `p_ω(d)`) and taking the first surface along it (emitters end
//! the walk: they do not scatter). Its area density is `p_ω |cos θ_{y_{i+1}}| / |y_i y_{i+1}|²` on the
//! visible first hit, so `f G V / p_A = f(y_i; y_{i−1}, d) |n_{y_i}·d| / p_ω(d) =: b_i` (the BSDF is
//! evaluated as it is, so no reciprocity is assumed: any density that covers `f`'s support is unbiased).
//! Connecting `y_k` to the camera (deterministic: the film point is its projection) then gives the
//! unbiased estimate
//!
//! ```text
//!   W_k ≈ (Π_{i<k} b_i) · f(y_k; y_{k−1}, x₀) · w_j(proj y_k) J_film(y_k) V(x₀, y_k)                   (C)
//! ```
//!
//! splatted to every pixel whose filter covers `proj y_k` (light tracing, Veach 1997 §10.2, with one
//! vertex `y_k` per depth). One walk yields one estimate for every `k ≤ K` at once; they estimate
//! different path lengths, so they add without weights.
//!
//! # Light side: a path continued from `x_D`
//!
//! For `x_D` on an emitter the radiance is its emission `L_e(x_D → x_S)` (emitters are not reflective:
//! paths end there, as in [`crate::integrator::path`]); at infinity, the environment's. For `x_D` on a
//! shape it is the radiance `L^{(m)}(x_D → x_S)` of the paths that scatter at `x_D` and at most `m − 1`
//! more vertices, estimated with the primal's own estimator: [`trace_path`] along the segment's ray
//! (whose first hit is `x_D`) with `m` scattering vertices, next-event estimation and BSDF sampling
//! under MIS. Truncating that record after `j ≤ m` scattering vertices (dropping the later vertices and
//! their light samples) is the record the same tracer would produce with `j`: every truncation is an
//! unbiased estimate of `L^{(j)}`, so one trace with the largest `m` needed serves every `k`
//! ([`radiance_by_depth`]).
//!
//! # Path length
//!
//! The primal with `max_depth = D` counts every path with at most `D` scattering vertices (the camera
//! and the emitter vertex are not scattering vertices). A path through the segment with `x_S` its
//! `k`-th vertex ends at `x_D` when `x_D` emits (`k ≤ D`), or scatters at `x_D` (vertex `k + 1`) and at
//! up to `D − k − 1` more: its light side is `L^{(D−k)}`, which needs `k ≤ D − 1`. So the walk runs to
//! `K = D` for emitter ends and `K = D − 1` for shape ends; with `D = 1` (`direct`) only `k = 1` and
//! emitter ends remain, the direct estimator exactly.

use crate::camera::CameraFrame;
use crate::integrator::path::{
    PathRecord, TraceCounters, VertexKind, contribution, detached, occluded, trace_path,
};
use crate::math::{Ray, Vec3};
use crate::sampler::Sampler;
use crate::scene::{Intersection, Scene, Surface};

/// One camera connection of the adjoint walk (eq. (C)): `x_S` as the `depth`-th scattering vertex of
/// paths whose first vertex projects to `film`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct CameraVertex {
    /// `k`: the number of scattering vertices from the camera up to `x_S` included.
    pub depth: u32,
    /// Film position (pixels) of the vertex connected to the camera.
    pub film: glam::Vec2,
    /// The walk's throughput times the BSDF at the connected vertex: `(Π b_i) f(y_k; y_{k−1}, x₀)`.
    pub f: glam::Vec3,
    /// `J_film(y_k)`, the film area per unit area at the connected vertex.
    pub j_film: f32,
}

/// The connection of the surface point `x` (normal `n`, shape `shape`) to the camera, for light
/// arriving from direction `wi`: `None` if `x` projects outside the filter's reach of the image, is
/// hidden from the camera, or reflects nothing towards it. `f` holds `f(x; wi, x₀)` (no throughput).
pub fn connect_to_camera(
    scene: &Scene,
    frame: &CameraFrame<f32>,
    shape: usize,
    x: glam::Vec3,
    n: glam::Vec3,
    wi: glam::Vec3,
    counters: &mut TraceCounters,
) -> Option<CameraVertex> {
    let (px, py) = frame.project(Vec3::constant(x))?;
    let radius = scene.camera.filter.radius();
    let (wf, hf) = (scene.camera.width as f32, scene.camera.height as f32);
    if px <= -radius || py <= -radius || px >= wf + radius || py >= hf + radius {
        return None;
    }
    let eye: glam::Vec3 = frame.origin.primal();
    let to_x = x - eye;
    let dist = to_x.length();
    if !(dist > 0.0 && dist.is_finite()) {
        return None;
    }
    let margin = 8.0 * scene.trace.eps_at_point(x) + 1e-5 * dist;
    if occluded(
        scene,
        &Ray::new(eye, to_x / dist),
        dist - margin,
        None,
        None,
        counters,
    ) {
        return None;
    }
    let wo = -to_x / dist;
    let f = scene.shapes[shape].bsdf_eval::<f32>(x.into(), n.into(), wi.into(), wo.into());
    let f: glam::Vec3 = f.into();
    if f == glam::Vec3::ZERO {
        return None;
    }
    let j_film = frame.film_area_jacobian(Vec3::constant(x), Vec3::constant(n));
    Some(CameraVertex {
        depth: 1,
        film: glam::Vec2::new(px, py),
        f,
        j_film,
    })
}

/// The camera side of a segment starting at `x_s` (normal `n_s`, on shape `shape`) towards direction
/// `w_d` (unit, towards `x_D`): pushes the camera connections of eq. (C) for depths `1..=max_depth`
/// into `out` (cleared first). The walk draws one 2D number per bounce from `sampler` (only when
/// `max_depth > 1`).
#[allow(clippy::too_many_arguments)]
pub fn camera_side(
    scene: &Scene,
    frame: &CameraFrame<f32>,
    shape: usize,
    x_s: glam::Vec3,
    n_s: glam::Vec3,
    w_d: glam::Vec3,
    max_depth: u32,
    sampler: &mut Sampler,
    out: &mut Vec<CameraVertex>,
    counters: &mut TraceCounters,
) {
    out.clear();
    let (mut s, mut x, mut n, mut wi) = (shape, x_s, n_s, w_d);
    let mut beta = glam::Vec3::ONE;
    for depth in 1..=max_depth {
        if let Some(mut c) = connect_to_camera(scene, frame, s, x, n, wi, counters) {
            c.depth = depth;
            // β = 1 at the first vertex: the product is exact, so `direct` is unchanged bit for bit.
            c.f *= beta;
            out.push(c);
        }
        if depth == max_depth {
            return;
        }
        let surface = &scene.shapes[s];
        let Some(bs) = surface.bsdf_sample(x, n, wi, sampler.next_2d()) else {
            return;
        };
        let f: glam::Vec3 = surface
            .bsdf_eval::<f32>(x.into(), n.into(), wi.into(), bs.wi.into())
            .into();
        beta *= f * (n.dot(bs.wi).abs() / bs.pdf);
        if beta == glam::Vec3::ZERO || !beta.is_finite() {
            return;
        }
        let ray = Ray::new(scene.offset_origin(s, x, n, bs.wi), bs.wi);
        match scene.intersect(&ray, f32::INFINITY) {
            Intersection::Hit(h) => match h.surface {
                Surface::Shape(next) => {
                    (s, x, n, wi) = (next, h.p, h.n, -bs.wi);
                }
                // Emitters absorb: no path scatters there.
                Surface::Emitter(_) => return,
            },
            Intersection::Miss => return,
            Intersection::Exhausted => {
                counters.exhausted += 1;
                return;
            }
        }
    }
}

/// The light side of a segment ending on a shape: traces `ray` (the segment's ray, whose first hit is
/// the shape point `x_D`) with `max_scatter` scattering vertices and writes `out[j] = L^{(j)}(x_D → ray.o)`
/// for `j = 0..=max_scatter` (`out[0] = 0`: a shape does not emit). Returns `false` (and leaves `out`
/// empty) when the trace's first vertex is not the shape `shape` (a different first hit than the
/// caller's, which only a mismatch of tracers could cause).
#[allow(clippy::too_many_arguments)]
pub fn radiance_by_depth(
    scene: &Scene,
    ray: Ray,
    shape: usize,
    max_scatter: u32,
    sampler: &mut Sampler,
    record: &mut PathRecord,
    scratch: &mut PathRecord,
    out: &mut Vec<glam::Vec3>,
    counters: &mut TraceCounters,
) -> bool {
    out.clear();
    trace_path(
        scene,
        ray,
        f32::INFINITY,
        max_scatter,
        sampler,
        record,
        counters,
    );
    if record.vertices.first().map(|v| v.kind) != Some(VertexKind::Shape(shape)) {
        return false;
    }
    out.push(glam::Vec3::ZERO);
    for j in 1..=max_scatter as usize {
        // Vertex j (if any) is reached by the BSDF sample of vertex j − 1; its emission counts with j
        // scattering vertices, its own light samples (from = j) do not.
        scratch.camera = record.camera;
        scratch.vertices.clear();
        scratch
            .vertices
            .extend_from_slice(&record.vertices[..(j + 1).min(record.vertices.len())]);
        scratch.lights.clear();
        scratch
            .lights
            .extend(record.lights.iter().filter(|l| l.from < j).copied());
        out.push(contribution::<f32>(scene, scratch, detached).into());
    }
    true
}
