//! The scene in `f32` (with a [`crate::Param`] for every differentiable number) and ray queries against it.
//! Parsing lives in [`load`]; rendering types never see serde.

mod json;

pub use json::{load, parse};

use crate::bsdf::Bsdf;
use crate::camera::Camera;
use crate::emitter::Emitter;
use crate::integrator::IntegratorKind;
use crate::math::{Aabb, Ray};
use crate::sdf::Sdf;
use crate::trace::{ShapeTrace, TraceSettings, sphere_trace};

/// An implicit surface with its material.
#[derive(Clone, Debug, PartialEq)]
pub struct Shape {
    /// Unique name (used for parameter names and `bake --shape`).
    pub name: String,
    /// The implicit function.
    pub sdf: Sdf,
    /// The material.
    pub bsdf: Bsdf,
    /// Box around the surface, from [`Sdf::bounds`] (possibly infinite).
    pub bounds: Aabb,
    /// Lipschitz bound of the SDF, from [`Sdf::lipschitz`].
    pub lipschitz: f32,
}

impl Shape {
    /// A shape, with its bounds and Lipschitz bound computed from the SDF.
    pub fn new(name: impl Into<String>, sdf: Sdf, bsdf: Bsdf) -> Self {
        let bounds = sdf.bounds();
        let lipschitz = sdf.lipschitz();
        Self {
            name: name.into(),
            sdf,
            bsdf,
            bounds,
            lipschitz,
        }
    }
}

/// A light source with its name.
#[derive(Clone, Debug, PartialEq)]
pub struct NamedEmitter {
    /// Unique name.
    pub name: String,
    /// The emitter.
    pub emitter: Emitter,
}

/// What a ray hits first.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Surface {
    /// Shape `i` of [`Scene::shapes`].
    Shape(usize),
    /// Finite emitter `i` of [`Scene::emitters`].
    Emitter(usize),
}

/// The first surface along a ray.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Hit point.
    pub p: glam::Vec3,
    /// Outward unit normal at the hit.
    pub n: glam::Vec3,
    /// What was hit.
    pub surface: Surface,
}

/// Outcome of a scene query.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Intersection {
    /// A surface was hit.
    Hit(Hit),
    /// Nothing was hit (the ray escapes to the environment).
    Miss,
    /// Some shape's sphere tracing ran out of steps and nothing nearer was hit; treated as a miss by
    /// integrators, which count it.
    Exhausted,
}

/// A complete scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The camera and film.
    pub camera: Camera,
    /// The estimator.
    pub integrator: IntegratorKind,
    /// Default samples per pixel.
    pub spp: u32,
    /// Implicit surfaces.
    pub shapes: Vec<Shape>,
    /// Light sources.
    pub emitters: Vec<NamedEmitter>,
    /// Tracer tolerances, set from the scene scale.
    pub trace: TraceSettings,
    /// Indices of finite emitters in [`Scene::emitters`] (tested by rays).
    pub finite_emitters: Vec<usize>,
    /// Index of the environment emitter, if any (at most one).
    pub environment: Option<usize>,
}

/// The nearest surface found so far by [`Scene::intersect`].
struct Nearest {
    t: f32,
    surface: Option<Surface>,
    /// Normal of an emitter hit (shape normals are computed once, for the final hit only).
    normal: glam::Vec3,
    exhausted: bool,
}

/// Scenes with at most this many shapes have them traced nearest-bounds-first (sorted on the stack).
const MAX_SORTED_SHAPES: usize = 16;

/// Relative hit tolerance: `eps = RELATIVE_EPS · scene scale`.
pub const RELATIVE_EPS: f32 = 1e-5;

impl Scene {
    /// Assembles a scene and derives the tracer tolerance from its scale (the extent of the finite
    /// shape bounds, emitters and camera).
    pub fn new(
        camera: Camera,
        integrator: IntegratorKind,
        spp: u32,
        shapes: Vec<Shape>,
        emitters: Vec<NamedEmitter>,
    ) -> Self {
        let mut extent = Aabb::around(camera.origin.value(), glam::Vec3::ZERO);
        for s in &shapes {
            if s.bounds.is_finite() {
                extent = extent.union(&s.bounds);
            }
        }
        for e in &emitters {
            if let Some(b) = e.emitter.bounds() {
                extent = extent.union(&b);
            }
        }
        let finite_emitters: Vec<usize> = (0..emitters.len())
            .filter(|&i| !emitters[i].emitter.is_infinite())
            .collect();
        let environment = (0..emitters.len()).find(|&i| emitters[i].emitter.is_infinite());
        let scale = extent.extent().max_element().max(1e-3);
        let trace = TraceSettings {
            eps: RELATIVE_EPS * scale,
            ..TraceSettings::default()
        };
        Self {
            camera,
            integrator,
            spp,
            shapes,
            emitters,
            trace,
            finite_emitters,
            environment,
        }
    }

    /// The first surface hit by `ray` in `(0, t_max)`.
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Intersection {
        let mut nearest = Nearest {
            t: t_max,
            surface: None,
            normal: glam::Vec3::ZERO,
            exhausted: false,
        };
        for &i in &self.finite_emitters {
            if let Some((t, n)) = self.emitters[i].emitter.intersect(ray, nearest.t) {
                nearest = Nearest {
                    t,
                    surface: Some(Surface::Emitter(i)),
                    normal: n,
                    ..nearest
                };
            }
        }
        // Trace shapes in the order the ray enters their bounds, so a near hit cuts the intervals of
        // the shapes behind it (most of a floor's pixels never march through the object above it).
        let mut intervals = [(0.0f32, 0.0f32, 0usize); MAX_SORTED_SHAPES];
        let mut count = 0;
        let sorted = self.shapes.len() <= MAX_SORTED_SHAPES;
        for (i, shape) in self.shapes.iter().enumerate() {
            let Some((t0, t1)) = self.trace_interval(shape, ray, nearest.t) else {
                continue;
            };
            if sorted {
                let mut k = count;
                while k > 0 && intervals[k - 1].0 > t0 {
                    intervals[k] = intervals[k - 1];
                    k -= 1;
                }
                intervals[k] = (t0, t1, i);
                count += 1;
            } else {
                self.trace_shape(i, ray, t0, t1, &mut nearest);
            }
        }
        for &(t0, t1, i) in &intervals[..count] {
            if t0 < nearest.t {
                self.trace_shape(i, ray, t0, t1.min(nearest.t), &mut nearest);
            }
        }
        match nearest.surface {
            Some(surface) => {
                let p = ray.at(nearest.t);
                let n = match surface {
                    Surface::Shape(i) => self.shapes[i].sdf.normal(p),
                    Surface::Emitter(_) => nearest.normal,
                };
                Intersection::Hit(Hit {
                    t: nearest.t,
                    p,
                    n,
                    surface,
                })
            }
            None if nearest.exhausted => Intersection::Exhausted,
            None => Intersection::Miss,
        }
    }

    /// Traces shape `i` over `[t0, t1]` and keeps its hit if it is the nearest so far.
    #[inline]
    fn trace_shape(&self, i: usize, ray: &Ray, t0: f32, t1: f32, nearest: &mut Nearest) {
        let shape = &self.shapes[i];
        match sphere_trace(&shape.sdf, shape.lipschitz, ray, t0, t1, &self.trace) {
            ShapeTrace::Hit(t) if t < nearest.t => {
                nearest.t = t;
                nearest.surface = Some(Surface::Shape(i));
            }
            ShapeTrace::Exhausted(_) => nearest.exhausted = true,
            _ => {}
        }
    }

    /// The interval of `ray` in `(0, t_max)` where `shape` must be traced: its bounds grown by a margin.
    ///
    /// Bounds may be tight (a box's faces lie on them): a ray entering exactly on the surface would start
    /// its trace at `φ = 0`, where the tracer cannot tell entering from leaving. The margin starts it
    /// outside.
    #[inline]
    pub fn trace_interval(&self, shape: &Shape, ray: &Ray, t_max: f32) -> Option<(f32, f32)> {
        shape.bounds.expanded(self.trace.eps).clip(ray, 0.0, t_max)
    }

    /// Origin of a ray leaving the surface point `p` (normal `n`) along `w`: `p` moved off the surface by
    /// `4 eps` to `w`'s side, but never by less than about 32 ulps of `p`'s largest coordinate, so that a
    /// tolerance too small for the coordinates (a tiny finite extent next to unbounded shapes) cannot
    /// make a ray start inside the surface noise and hit its own origin.
    #[inline]
    pub fn offset_origin(&self, p: glam::Vec3, n: glam::Vec3, w: glam::Vec3) -> glam::Vec3 {
        let floor = p.abs().max_element() * (32.0 * f32::EPSILON);
        let offset = (4.0 * self.trace.eps).max(floor);
        p + n * if n.dot(w) >= 0.0 { offset } else { -offset }
    }
}
