//! The contribution of one oriented boundary segment `x_S → x_B → x_D` blocked at `x_B`
//! (docs/theory.md §5; the derivation is in [`super::secondary`]'s module docs, eqs. (2) and (3)):
//! `Δf V_∂ J` with the camera and light sides of [`super::subpaths`], for any occluder, a smooth
//! silhouette ([`super::segment`]) or a crease edge ([`super::crease_segment`]). The sources of the
//! secondary term draw the segments; this module weighs them.

use super::crease_segment::CreaseSegment;
use super::segment::{BoundarySegment, boundary_velocity};
use super::source::Pass;
use super::subpaths::{camera_side, radiance_by_depth};
use super::{finite_splat, splat_on_film};
use crate::film::SampleSink;
use crate::integrator::path::{PathRecord, TraceCounters};
use crate::integrator::shading::geometry_term;
use crate::math::{Ray, Vec3};
use crate::sampler::Sampler;
use crate::scalar::{Directions, Scalar};
use crate::scene::{Intersection, Scene, Shape, Surface};
use crate::sdf::CreaseEdge;

/// The random stream of the subpaths (camera-side walk, light-side path) of a segment.
pub const SUBPATH_STREAM: u64 = 0x5AB_9A7E;

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
/// `x_S` ([`super::secondary`]'s module docs, "Random numbers").
pub(crate) fn subpath_sampler(x_b: glam::Vec3, x_s: glam::Vec3) -> Sampler {
    let bits = |p: glam::Vec3| {
        (p.x.to_bits() as u64 | (p.y.to_bits() as u64) << 32)
            ^ (p.z.to_bits() as u64).rotate_left(17)
    };
    Sampler::new(bits(x_b), SUBPATH_STREAM, bits(x_s), 0)
}

/// The segment from the hit `s_end` past `x_b` (where `occluder` blocks it) to `d_end`, if it is a
/// visibility boundary of some camera path: pushes its contributions (eq. (2), with the camera and
/// light sides of [`super::subpaths`] for integrators with several scattering vertices).
/// `line_origin` is `x_b` pushed off the occluder, where the line was traced from.
#[allow(clippy::too_many_arguments)]
pub(crate) fn segment<S: Directions>(
    pass: &Pass,
    occluder: Occluder,
    (x_b, line_origin): (glam::Vec3, glam::Vec3),
    s_end: &Intersection,
    d_end: &Intersection,
    weight: f32,
    splats: &mut dyn SampleSink<S>,
    counters: &mut TraceCounters,
) {
    let (scene, attach) = (pass.scene, &pass.attach);
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
    let xs_s = attach.shape_vertex::<S>(si, x_s, n_s).x;
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
            let le = scene.emitters[e]
                .emitter
                .emitted::<f32>(x_d.into(), n_d.into(), (-w).into());
            let xd_s = attach.emitter_vertex::<S>(e, x_d, n_d).x;
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
            let xd_s = attach.shape_vertex::<S>(d, x_d, n_d).x;
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
            let le = scene.emitters[e]
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
