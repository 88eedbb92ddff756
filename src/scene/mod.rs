//! The scene in `f32` (with a [`crate::Param`] for every differentiable number) and ray queries against it.
//! Parsing lives in [`load`]; rendering types never see serde.

mod blocks;
mod bvh;
pub mod frustum;
mod integrator_kind;
pub(crate) mod json;
pub mod packet;
mod params;
pub mod patch;
mod query;
mod reach;
mod selection;
pub mod settings;
pub mod shape_list;

pub(crate) use blocks::visit_scene_selections_mut;
pub use blocks::{BlockKind, GridBlock, GridDirection, ParamBlock, ParameterEntry};
pub use bvh::Bvh;
pub use integrator_kind::IntegratorKind;
pub use json::{load, parse};
pub use selection::Selection;

use crate::bsdf::{At, Bsdf, BsdfSample, MaterialTexture};
use crate::camera::Camera;
use crate::emitter::Emitter;
use crate::error::Result;
use crate::math::Vec3;
use crate::math::{Aabb, Ray};
use crate::scalar::{Param3, Scalar};
use crate::sdf::interval::EnclosureMemo;
use crate::sdf::{EmptySpace, Lipschitz, Sdf};
use crate::trace::{ShapeTrace, TraceSettings, first_crossing_skipping};
use std::sync::Arc;

/// An implicit surface with its material, rigidly translated by `translate` (zero unless a derivative or a
/// finite difference moves the whole shape): the surface is `{x : sdf(x − translate) = 0}`.
#[derive(Clone, Debug, PartialEq)]
pub struct Shape {
    /// Unique name (used for parameter names and `bake --shape`).
    pub name: String,
    /// The implicit function, in the shape's own coordinates.
    pub sdf: Sdf,
    /// The material.
    pub bsdf: Bsdf,
    /// The material's fields given by volume textures ([`crate::bsdf::texture`]); empty for most.
    pub textures: Vec<MaterialTexture>,
    /// Rigid translation of the whole shape (parameters `<name>.translate.x|y|z`).
    pub translate: Param3,
    /// World-space box around the surface: [`Sdf::bounds`] moved by `translate` (possibly infinite).
    pub bounds: Aabb,
    /// Lipschitz bounds of the SDF on each side of its surface, from [`Sdf::lipschitz_sided`].
    pub lipschitz: Lipschitz,
    /// Whether the surface may have crease edges ([`Sdf::creases`]): only next to one can a point pushed
    /// off one face still lie on another ([`Scene::offset_origin`]).
    pub creased: bool,
    /// Whether the solid is convex ([`Sdf::is_convex`]): a ray leaving its surface outward cannot meet
    /// it again ([`Scene::leaving`]).
    pub convex: bool,
    /// Where a grid shape certainly has no surface ([`EmptySpace`]), so that tracing skips it; `None`
    /// for every other shape.
    pub empty_space: Option<Arc<EmptySpace>>,
    /// The enclosures of a grid shape's `φ` and `∇φ` over the silhouette culling's boxes, shared by
    /// every view of the shape ([`EnclosureMemo`]); `None` for every other shape (their enclosures
    /// are cheap). Built anew with the shape: set it to `None` when changing `sdf` in place.
    pub enclosures: Option<Arc<EnclosureMemo>>,
}

impl Shape {
    /// A shape, with its bounds and Lipschitz bound computed from the SDF.
    pub fn new(name: impl Into<String>, sdf: Sdf, bsdf: Bsdf) -> Self {
        Self::translated(name, sdf, bsdf, Param3::new([0.0; 3]))
    }

    /// A shape moved rigidly by `translate`.
    pub fn translated(name: impl Into<String>, sdf: Sdf, bsdf: Bsdf, translate: Param3) -> Self {
        let sdf = sdf.refreshed();
        let t = translate.value();
        let local = sdf.bounds();
        let bounds = Aabb::new(local.min + t, local.max + t);
        // The two walk a grid's patches each: at once, they take half the time of a grid edit's
        // refresh in an optimisation.
        let (lipschitz, empty_space) = rayon::join(
            || sdf.lipschitz_sided(),
            || EmptySpace::of(&sdf).map(Arc::new),
        );
        let creased = sdf.creases().is_some();
        let convex = sdf.is_convex();
        let enclosures = (empty_space.is_some()).then(|| Arc::new(EnclosureMemo::default()));
        Self {
            name: name.into(),
            sdf,
            bsdf,
            textures: Vec::new(),
            translate,
            bounds,
            lipschitz,
            creased,
            convex,
            empty_space,
            enclosures,
        }
    }

    /// The shape with `textures` standing in for fields of its material.
    pub fn with_textures(mut self, textures: Vec<MaterialTexture>) -> Self {
        self.textures = textures;
        self
    }

    /// World point `x` in the shape's frame, where its volume textures are read: `x − translate`,
    /// then through the inverse of each transform node at the top of the sdf tree
    /// ([`Sdf::to_root_frame`]), generic (lifted parameters).
    #[inline]
    pub fn material_point<S: Scalar>(&self, x: Vec3<S>) -> Vec3<S> {
        self.sdf.to_root_frame(x - self.translate.get::<S>())
    }

    /// The material's `f(wi, wo)` at world point `x` ([`Bsdf::eval_at`]): its textured fields read at
    /// [`Shape::material_point`] of `x` (not computed for a material without texture).
    #[inline]
    pub fn bsdf_eval<S: Scalar>(
        &self,
        x: Vec3<S>,
        n: Vec3<S>,
        wi: Vec3<S>,
        wo: Vec3<S>,
    ) -> Vec3<S> {
        if self.textures.is_empty() {
            return self.bsdf.eval(n, wi, wo);
        }
        let at = At::new(&self.textures, self.material_point(x));
        self.bsdf.eval_at(&at, n, wi, wo)
    }

    /// The material's sample at world point `p` ([`Bsdf::sample_at`]).
    #[inline]
    pub fn bsdf_sample(
        &self,
        p: glam::Vec3,
        n: glam::Vec3,
        wo: glam::Vec3,
        u: glam::Vec2,
    ) -> Option<BsdfSample> {
        if self.textures.is_empty() {
            return self.bsdf.sample(n, wo, u);
        }
        let at = At::new(&self.textures, self.material_point(Vec3::constant(p)));
        self.bsdf.sample_at(&at, n, wo, u)
    }

    /// The material's density at world point `p` ([`Bsdf::pdf_at`]).
    #[inline]
    pub fn bsdf_pdf(&self, p: glam::Vec3, n: glam::Vec3, wo: glam::Vec3, wi: glam::Vec3) -> f32 {
        if self.textures.is_empty() {
            return self.bsdf.pdf(n, wo, wi);
        }
        let at = At::new(&self.textures, self.material_point(Vec3::constant(p)));
        self.bsdf.pdf_at(&at, n, wo, wi)
    }

    /// `φ(p)` in world coordinates, generic (lifted parameters, translation included).
    #[inline]
    pub fn eval<S: Scalar>(&self, p: Vec3<S>) -> S {
        self.sdf.eval(p - self.translate.get::<S>())
    }

    /// The field of the faces at `p` ([`Sdf::eval_faces`]) in world coordinates, generic (lifted
    /// parameters, translation included).
    #[inline]
    pub fn eval_faces<S: Scalar>(&self, p: Vec3<S>) -> S {
        self.sdf.eval_faces(p - self.translate.get::<S>())
    }

    /// `φ(p)` in `f32`.
    #[inline]
    pub fn eval_f32(&self, p: glam::Vec3) -> f32 {
        self.sdf.eval_f32(p - self.translate.value())
    }

    /// `∇φ(p)` (not normalised).
    #[inline]
    pub fn gradient(&self, p: glam::Vec3) -> glam::Vec3 {
        self.sdf.gradient(p - self.translate.value())
    }

    /// Outward unit normal at a surface point `p`: its face's ([`Sdf::face_normal`]), whichever side
    /// of the tracer's tolerance next to a sharp edge `p` lies on.
    ///
    /// Where the two fields agree (everywhere but the band outside a sharp edge, up to rounding) the
    /// exact distance's normal is kept, bit for bit, so that images do not depend on which formula
    /// computed an equal normal; only inside the band, where the exact distance's normal turns from
    /// one face's to the other's, does the face's replace it.
    #[inline]
    pub fn normal(&self, p: glam::Vec3) -> glam::Vec3 {
        let local = p - self.translate.value();
        let exact = self.sdf.normal(local);
        if !self.creased {
            return exact;
        }
        let face = self.sdf.face_normal(local);
        if exact.dot(face) < 1.0 - 1e-6 {
            face
        } else {
            exact
        }
    }

    /// Total curvature `κ = ∇·n` at `p`.
    #[inline]
    pub fn curvature(&self, p: glam::Vec3) -> f32 {
        self.sdf.curvature(p - self.translate.value())
    }

    /// The ray in the shape's own coordinates (same direction and parameter `t`).
    #[inline]
    pub fn local_ray(&self, ray: &Ray) -> Ray {
        Ray::new(ray.o - self.translate.value(), ray.d)
    }

    /// First crossing of the surface along `ray` in `[t0, t1]` (see [`first_crossing_skipping`]: grid
    /// shapes skip their empty cells).
    #[inline]
    pub fn trace(&self, ray: &Ray, t0: f32, t1: f32, settings: &TraceSettings) -> ShapeTrace {
        first_crossing_skipping(
            &self.sdf,
            self.lipschitz,
            self.empty_space.as_deref(),
            &self.local_ray(ray),
            t0,
            t1,
            settings,
        )
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
    /// Indices of the emitters next-event estimation chooses among, uniformly
    /// ([`crate::emitter::Emitter::is_light_sampled`]).
    pub light_sampled: Vec<usize>,
    /// The hierarchy over the shapes' bounds that ray queries use, built by [`Scene::new`]: after
    /// changing [`Scene::shapes`] in place (their number or bounds), call [`Scene::refresh_bvh`].
    pub bvh: Arc<Bvh>,
    /// Whether ray queries use [`Scene::bvh`] (they give the same results without it, shape by shape
    /// over all of them; tests compare the two).
    #[doc(hidden)]
    pub use_bvh: bool,
}

/// The tracer's tolerance floor relative to the scene's smallest shape: `eps = RELATIVE_EPS · s`, `s` the
/// smallest extent (along any axis) of any finite shape's bounds ([`crate::trace::TraceSettings`]).
pub const RELATIVE_EPS: f32 = 1e-4;

/// How far [`Scene::crease_region`] reaches beyond the scene's finite content, in units of that
/// content's longest side (on every side).
pub const CREASE_REGION_MARGIN: f32 = 2.0;

/// The tracer's tolerance floor `eps₀` of a scene of `shapes` seen by `camera`: `10⁻⁴` of the smallest
/// extent of the finite shapes' bounds, or of the camera's distance to its target when no shape is
/// finite (module `trace`, "Tolerances").
fn base_eps(shapes: &[Shape], camera: &Camera) -> f32 {
    let smallest = (shapes.iter())
        .filter(|s| s.bounds.is_finite() && !s.bounds.is_empty())
        .map(|s| s.bounds.extent().min_element())
        .filter(|e| *e > 0.0)
        .fold(f32::INFINITY, f32::min);
    let scale = if smallest.is_finite() {
        smallest
    } else {
        (camera.target.value() - camera.origin.value()).length()
    };
    (RELATIVE_EPS * scale).max(f32::MIN_POSITIVE)
}

impl Scene {
    /// Assembles a scene and derives the tracer's tolerance floor from its smallest shape (the smallest
    /// extent of a finite shape's bounds; without one, the distance from the camera to its target).
    pub fn new(
        camera: Camera,
        integrator: IntegratorKind,
        spp: u32,
        shapes: Vec<Shape>,
        emitters: Vec<NamedEmitter>,
    ) -> Self {
        // Delta lights are neither: no ray meets them.
        let finite_emitters: Vec<usize> = (0..emitters.len())
            .filter(|&i| !emitters[i].emitter.is_infinite() && !emitters[i].emitter.is_delta())
            .collect();
        let environment = (0..emitters.len()).find(|&i| emitters[i].emitter.is_infinite());
        let light_sampled: Vec<usize> = (0..emitters.len())
            .filter(|&i| emitters[i].emitter.is_light_sampled())
            .collect();
        let trace = TraceSettings {
            eps: base_eps(&shapes, &camera),
            ..TraceSettings::default()
        };
        let bvh = Arc::new(Bvh::build(
            &shapes.iter().map(|s| s.bounds).collect::<Vec<_>>(),
        ));
        Self {
            camera,
            integrator,
            spp,
            shapes,
            emitters,
            trace,
            finite_emitters,
            environment,
            light_sampled,
            bvh,
            use_bvh: true,
        }
    }

    /// The shape called `name`. Errors: no such shape (the message lists the scene's shapes).
    pub fn shape_named(&self, name: &str) -> Result<&Shape> {
        self.shapes.iter().find(|s| s.name == name).ok_or_else(|| {
            let names: Vec<&str> = self.shapes.iter().map(|s| s.name.as_str()).collect();
            crate::Error::Unsupported(format!(
                "no shape named {name:?} (shapes: {})",
                names.join(", ")
            ))
        })
    }

    /// The crease edges the estimators sample ([`Sdf::crease_edges`]: sharp boxes' edges, sharp
    /// cylinders' rims, and the chords of the curves where hard CSG children cross), as
    /// `(shape index, edge)` with the edge in the shape's own coordinates (add its `translate` for world
    /// coordinates). Extracts the CSG crossings: cost grows with their number.
    /// Creases between unbounded children (two planes) are extracted within [`Scene::crease_region`].
    pub fn creased_shapes(&self) -> Vec<(usize, crate::sdf::CreaseEdge)> {
        let region = self.crease_region();
        let region = &region;
        (self.shapes.iter().enumerate())
            .flat_map(|(i, s)| {
                let t = s.translate.value();
                let local = Aabb::new(region.min - t, region.max - t);
                (s.sdf.crease_edges_within(&local).into_iter()).map(move |e| (i, e))
            })
            .collect()
    }

    /// The box (world coordinates) within which the creases that no finite box of their shape holds
    /// (two planes crossing, [`Sdf::unsampled_creases`]) are extracted and sampled: the box of the
    /// scene's finite content (bounded shapes, the camera's origin, the area and point lights) grown on
    /// every side by [`CREASE_REGION_MARGIN`] times its longest side.
    pub fn crease_region(&self) -> Aabb {
        let point = |p: glam::Vec3| Aabb::new(p, p);
        let eye = self.camera.origin.value();
        let mut content = point(eye);
        for s in self.shapes.iter().filter(|s| s.bounds.is_finite()) {
            content = content.union(&s.bounds);
        }
        for e in &self.emitters {
            if let Some(b) = e.emitter.bounds() {
                content = content.union(&b);
            }
            if let Emitter::Point { position, .. } = &e.emitter {
                content = content.union(&point(position.value()));
            }
        }
        let size = content.extent().max_element().max(f32::MIN_POSITIVE);
        content.expanded(CREASE_REGION_MARGIN * size)
    }

    /// Whether any shape has crease edges ([`Sdf::has_crease_edges`]), without extracting them.
    pub fn has_crease_edges(&self) -> bool {
        self.shapes.iter().any(|s| s.sdf.has_crease_edges())
    }

    /// The shapes with crease curves whose boundary terms are not sampled whole, as `(shape name,
    /// reason)` ([`Sdf::unsampled_creases`]: hard CSG of unbounded children that nothing bounds, sampled
    /// only within [`Scene::crease_region`]): derivatives that move those curves beyond it (any
    /// geometric parameter of the scene, through the camera, the lights or the shape) miss those terms.
    /// The edges of sharp boxes and cylinders and bounded hard CSG creases are sampled, seen from the
    /// camera, past area lights and from delta lights alike.
    pub fn unsampled_creases(&self) -> Vec<(String, String)> {
        let region = self.crease_region();
        let corner = |p: glam::Vec3| format!("[{:.3}, {:.3}, {:.3}]", p.x, p.y, p.z);
        let within = format!(
            "sampled only within {} to {}",
            corner(region.min),
            corner(region.max)
        );
        self.shapes
            .iter()
            .filter_map(|s| {
                (s.sdf.unsampled_creases()).map(|r| (s.name.clone(), format!("{r}, {within}")))
            })
            .collect()
    }

    /// The first surface hit by `ray` in `(0, t_max)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Intersection {
        self.nearest(ray, t_max, f32::INFINITY, None)
    }

    /// [`Scene::intersect`] for a ray that must resolve detail down to `spread · t` at parameter `t`
    /// ([`TraceSettings::spread`]): a camera ray, with [`crate::camera::CameraFrame::spread`].
    #[inline]
    pub fn intersect_resolving(&self, ray: &Ray, t_max: f32, spread: f32) -> Intersection {
        self.nearest(ray, t_max, spread, None)
    }

    /// [`Scene::intersect`] for a ray leaving the surface of shape `leaving` ([`Scene::leaving`]), which
    /// is then not traced.
    #[inline]
    pub fn intersect_leaving(&self, ray: &Ray, t_max: f32, leaving: Option<usize>) -> Intersection {
        self.nearest(ray, t_max, f32::INFINITY, leaving)
    }

    /// The shape a ray from a point of shape `shape` (unit normal `n`) in direction `w` need not trace:
    /// `shape` itself when it is convex and `w` leaves it outward (`n·w > 0`; the ray's origin is then
    /// pushed off to the outside, [`Scene::offset_origin`], and the solid lies behind the tangent plane
    /// there), else none. Tracing it would find no crossing but at the level of the float noise.
    #[inline]
    pub fn leaving(&self, shape: usize, n: glam::Vec3, w: glam::Vec3) -> Option<usize> {
        (self.shapes[shape].convex && n.dot(w) > 0.0).then_some(shape)
    }

    /// The tracer's settings for `shape`: the scene's, with the tolerance floor raised to `RELATIVE_EPS`
    /// times the shape's own smallest extent (a large shape need not be resolved as finely as the
    /// smallest one; unbounded shapes keep the scene's floor).
    #[inline]
    pub fn shape_trace(&self, shape: &Shape) -> TraceSettings {
        let size = shape.bounds.extent().min_element();
        let own = if size.is_finite() {
            RELATIVE_EPS * size
        } else {
            0.0
        };
        TraceSettings {
            eps: self.trace.eps.max(own),
            ..self.trace
        }
    }

    /// The interval of `ray` in `(0, t_max)` where `shape` must be traced: its bounds grown by a margin.
    ///
    /// Bounds may be tight (a box's faces lie on them): a ray entering exactly on the surface would start
    /// its trace at `φ = 0`, where the tracer cannot tell entering from leaving. The margin, the local
    /// tolerance where the ray enters the bounds, starts it outside.
    #[inline]
    pub fn trace_interval(&self, shape: &Shape, ray: &Ray, t_max: f32) -> Option<(f32, f32)> {
        // The margin is the local tolerance where the ray enters, not at the bounds' far corners: a ray
        // leaving a huge floor near the origin must not march inside a margin sized for its rim.
        let origin = ray.o.abs().max_element();
        (shape.bounds).clip_with_margin(ray, 0.0, t_max, |entry| self.trace.eps_at(origin + entry))
    }

    /// Origin of a ray leaving the surface of shape `shape` at `p` (normal `n`) along `w`: `p` moved off
    /// the surface by four times the local tolerance at `p` to `w`'s side, so that a ray cannot start
    /// inside the surface noise and hit its own origin.
    ///
    /// Next to a crease the normal of one face does not clear the other: a point on a room's wall within
    /// a tolerance of its ceiling, pushed off the wall, is still on the ceiling, and a ray from there up
    /// into the ceiling would start on the surface and pass through it (the tracer reports no crossing
    /// at a start on the surface, see [`crate::trace`]). On a shape that may have creases
    /// ([`Shape::creased`]), where the pushed point is less than half the offset from the surface on
    /// `w`'s side, one Newton step along `∇φ` there moves it to the full offset from the face it is
    /// near. (A smooth surface's other parts are farther than four tolerances, unless thinner than
    /// the tracer resolves.)
    #[inline]
    pub fn offset_origin(
        &self,
        shape: usize,
        p: glam::Vec3,
        n: glam::Vec3,
        w: glam::Vec3,
    ) -> glam::Vec3 {
        let offset = 4.0 * self.trace.eps_at_point(p);
        let side = if n.dot(w) >= 0.0 { 1.0 } else { -1.0 };
        let o = p + n * (side * offset);
        let shape = &self.shapes[shape];
        if !shape.creased {
            return o;
        }
        let g = side * shape.eval_f32(o);
        // Far enough already (or a NaN value: nothing better to do).
        if g >= 0.5 * offset || g.is_nan() {
            return o;
        }
        let grad = shape.gradient(o);
        let pushed = o + grad * (side * (offset - g) / grad.length_squared());
        if pushed.is_finite() { pushed } else { o }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::Filter;

    fn scene_with(shape: Shape) -> Scene {
        let camera = Camera::new(
            glam::Vec3::new(0.0, 0.0, 5.0),
            glam::Vec3::ZERO,
            glam::Vec3::Y,
            40.0,
            8,
            8,
            Filter::Tent,
        );
        Scene::new(camera, IntegratorKind::Direct, 1, vec![shape], vec![])
    }

    #[test]
    fn creased_shapes_list_their_edges_and_what_is_not_sampled() {
        let bsdf = Bsdf::Diffuse {
            albedo: Param3::new([0.5; 3]),
        };
        let mut scene = scene_with(Shape::new("ball", Sdf::sphere([0.0; 3], 1.0), bsdf.clone()));
        assert!(scene.creased_shapes().is_empty());
        assert!(scene.unsampled_creases().is_empty());
        scene.shapes.push(Shape::new(
            "crate",
            Sdf::cuboid([2.0, 0.0, 0.0], [0.5; 3], 0.0),
            bsdf.clone(),
        ));
        let edges = scene.creased_shapes();
        assert_eq!(edges.len(), 12);
        assert!(edges.iter().all(|(i, _)| *i == 1));
        // The sharp box's edges are sampled; so are bounded hard CSG creases (as chords of the
        // extracted curve); those of unbounded children within the crease region only.
        assert!(scene.unsampled_creases().is_empty());
        scene.shapes.push(Shape::new(
            "lens",
            Sdf::intersection(vec![
                Sdf::sphere([0.0, 3.0, 0.0], 1.0),
                Sdf::sphere([0.5, 3.0, 0.0], 1.0),
            ]),
            bsdf.clone(),
        ));
        assert!(scene.unsampled_creases().is_empty());
        let edges = scene.creased_shapes();
        let chords = edges.iter().filter(|(i, _)| *i == 2);
        use crate::sdf::EdgeCurve;
        assert!(chords.clone().count() > 12);
        assert!(
            chords
                .clone()
                .all(|(_, e)| matches!(e.curve, EdgeCurve::Chord { .. }))
        );
        let length: f32 = chords.map(|(_, e)| e.curve.length()).sum();
        let exact = std::f32::consts::TAU * (1.0f32 - 0.25f32 * 0.25).sqrt();
        assert!((length / exact - 1.0).abs() < 1e-3, "{length} vs {exact}");
        scene.shapes.push(Shape::new(
            "wedge",
            Sdf::intersection(vec![
                Sdf::Plane {
                    normal: glam::Vec3::Y,
                    offset: 0.0.into(),
                },
                Sdf::Plane {
                    normal: glam::Vec3::X,
                    offset: 0.0.into(),
                },
            ]),
            bsdf.clone(),
        ));
        let region = scene.crease_region();
        let named = scene.unsampled_creases();
        assert_eq!(named.len(), 1);
        assert_eq!(named[0].0, "wedge");
        assert!(
            named[0].1.starts_with(
                "hard CSG of unbounded children (planes) whose crease no bounded child cuts, \
                 sampled only within ["
            ),
            "{named:?}"
        );
        // The planes' crease (the z axis) is extracted as chords across the whole region.
        let axis: Vec<_> = (scene.creased_shapes().into_iter())
            .filter(|(i, _)| *i == 3)
            .collect();
        let length: f32 = axis.iter().map(|(_, e)| e.curve.length()).sum();
        let across = region.max.z - region.min.z;
        assert!((length / across - 1.0).abs() < 0.05, "{length} of {across}");
        // Cut by a ball, the same crease needs no region: the ball's box holds it.
        let cut = Sdf::intersection(vec![
            Sdf::Plane {
                normal: glam::Vec3::Y,
                offset: 0.0.into(),
            },
            Sdf::Plane {
                normal: glam::Vec3::X,
                offset: 0.0.into(),
            },
            Sdf::sphere([0.0, 0.0, 0.0], 1.0),
        ]);
        assert_eq!(cut.unsampled_creases(), None);
        assert!(!cut.crossing_creases().is_empty());
    }

    #[test]
    fn only_rays_leaving_convex_shapes_outward_skip_them() {
        let bsdf = Bsdf::Diffuse {
            albedo: Param3::new([0.5; 3]),
        };
        let ring = Sdf::Torus {
            center: Param3::new([0.0; 3]),
            axis: glam::Vec3::Y,
            major_radius: 1.0.into(),
            minor_radius: 0.25.into(),
        };
        let lens = Sdf::intersection(vec![
            Sdf::sphere([0.0; 3], 1.0),
            Sdf::transform(
                Sdf::sphere([0.0; 3], 1.0),
                [0.5, 0.0, 0.0],
                glam::Vec3::Z,
                30.0,
                2.0,
            ),
        ]);
        let pair = Sdf::union(vec![
            Sdf::sphere([0.0; 3], 1.0),
            Sdf::sphere([3.0, 0.0, 0.0], 1.0),
        ]);
        let mut scene = scene_with(Shape::new("ball", Sdf::sphere([0.0; 3], 1.0), bsdf.clone()));
        for (name, sdf) in [("ring", ring), ("lens", lens), ("pair", pair)] {
            scene.shapes.push(Shape::new(name, sdf, bsdf.clone()));
        }
        let convex: Vec<bool> = scene.shapes.iter().map(|s| s.convex).collect();
        assert_eq!(convex, [true, false, true, false]);
        let (n, out, grazing) = (glam::Vec3::Y, glam::Vec3::new(0.6, 0.8, 0.0), glam::Vec3::X);
        for (i, &is_convex) in convex.iter().enumerate() {
            let expected = is_convex.then_some(i);
            assert_eq!(scene.leaving(i, n, out), expected, "shape {i}");
            assert_eq!(scene.leaving(i, n, -out), None, "shape {i}, entering");
            assert_eq!(scene.leaving(i, n, grazing), None, "shape {i}, grazing");
        }
    }

    #[test]
    fn translated_shape_matches_moved_primitive() {
        let bsdf = Bsdf::Diffuse {
            albedo: Param3::new([0.5; 3]),
        };
        let moved = scene_with(Shape::new(
            "a",
            Sdf::sphere([0.3, -0.2, 0.1], 1.0),
            bsdf.clone(),
        ));
        let translated = scene_with(Shape::translated(
            "a",
            Sdf::sphere([0.0, 0.0, 0.0], 1.0),
            bsdf.clone(),
            Param3::new([0.3, -0.2, 0.1]),
        ));
        assert_eq!(moved.shapes[0].bounds, translated.shapes[0].bounds);
        for (x, y) in [(0.0, 0.0), (0.5, -0.4), (-0.9, 0.3), (1.2, 1.2)] {
            let ray = Ray::new(glam::Vec3::new(x, y, 5.0), -glam::Vec3::Z);
            match (
                moved.intersect(&ray, f32::INFINITY),
                translated.intersect(&ray, f32::INFINITY),
            ) {
                (Intersection::Hit(a), Intersection::Hit(b)) => {
                    assert!(
                        (a.t - b.t).abs() < 1e-4 && (a.n - b.n).length() < 1e-4,
                        "{a:?} {b:?}"
                    );
                    let p = crate::math::Vec3::<f32>::from(b.p);
                    assert!(translated.shapes[0].eval(p).abs() < 1e-4);
                }
                (Intersection::Miss, Intersection::Miss) => {}
                other => panic!("({x}, {y}): {other:?}"),
            }
        }
    }

    #[test]
    fn a_new_camera_shares_the_shapes_and_equals_a_rebuilt_scene() {
        let bsdf = Bsdf::Diffuse {
            albedo: Param3::new([0.5; 3]),
        };
        let (lo, hi) = (glam::Vec3::splat(-1.0), glam::Vec3::splat(1.0));
        let ball = crate::sdf::bake(&Sdf::sphere([0.0; 3], 0.7), lo, hi, 12);
        let grid = Shape::new("blob", Sdf::grid(ball, lo, hi).unwrap(), bsdf.clone());
        let floor = Shape::new("floor", Sdf::plane(glam::Vec3::Y, 1.0), bsdf);
        let mut camera = scene_with(floor.clone()).camera;
        camera.origin = Param3::new([3.0, 40.0, -2.0]);
        let mut both = scene_with(grid.clone());
        both.shapes.push(floor.clone());
        let both = both.refreshed();
        // A scene with a grid takes its tolerance from the grid; the floor's alone, from the camera.
        for scene in [scene_with(grid), scene_with(floor), both] {
            let moved = scene.with_camera(camera.clone());
            let mut rebuilt = scene.clone();
            rebuilt.camera = camera.clone();
            assert_eq!(moved, rebuilt.refreshed());
            for (a, b) in moved.shapes.iter().zip(&scene.shapes) {
                let (a, b) = (a.empty_space.as_ref(), b.empty_space.as_ref());
                assert!(a.zip(b).is_none_or(|(a, b)| Arc::ptr_eq(a, b)));
            }
        }
    }
}
