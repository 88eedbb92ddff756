//! The primary boundary term along crease edges seen from the camera (docs/theory.md §7.2): the
//! edges of sharp boxes and cylinders and the curves where hard CSG children cross, where the surface's
//! normal jumps (the rest of the primary term is [`super::primary`]; read its module docs first).
//!
//! # The jump, on both sides
//!
//! Across the image `Γ` of a visible crease the radiance jumps: between the two faces when both face the
//! camera (their shading differs), between a face and the background beyond it when one face turns away
//! (a silhouette made of edges). In film space the pixel's derivative gains `∫_Γ w_j (L₋ − L₊) v dℓ_img`,
//! `v` the edge image's normal velocity towards the `+` side (`n_img`), `L∓` the radiance on either side.
//!
//! The interior term already moves each side's region with its own parametrisation: a face's points
//! move along the face's normal (`x + V n`, docs/theory.md §2), the background's points with theirs. At a
//! smooth silhouette the occluder's normal motion moves its contour exactly (the ray is tangent there);
//! at a crease it does not: the true edge slides along each face relative to that face's attached points,
//! because the two faces move along different normals. What the interior misses on each side is the
//! motion of the edge relative to that side's parametrisation:
//!
//! ```text
//!   ∂I_j ⊃ ∫_Γ w_j [ L₋ (v − u̇₋) − L₊ (v − u̇₊) ] dℓ_img                                          (1)
//! ```
//!
//! `u̇∓ = ∂π P_π(y∓(π))·n_img` the film velocity of the attached first vertex `y∓` seen on that side (a
//! face point next to the edge, or the background point; for a background at infinity the fixed
//! direction projected with the lifted camera, as the interior does). At a smooth silhouette the
//! occluder's `u̇ = v` and (1) is eq. (1) of [`super::primary`]. The pixel filter's own integral `W` has
//! the value 1 on both sides (docs/theory.md §6.2):
//!
//! ```text
//!   ∂W_j ⊃ ∫_Γ w_j [ (v − u̇₋) − (v − u̇₊) ] dℓ_img = ∫_Γ w_j (u̇₊ − u̇₋) dℓ_img                   (2)
//! ```
//!
//! # The edge's velocity, by AD
//!
//! The edge is `{F_a = 0, F_b = 0}` ([`crate::sdf::CreaseEdge`]: the two faces' functions). Its point
//! `x_C` moves, to first order, to `x_C(π) = x_C − α ∇F_a − β ∇F_b` with `(α, β)` solving
//! `[∇F_a·∇F_a  ∇F_a·∇F_b; ∇F_a·∇F_b  ∇F_b·∇F_b] (α, β) = (∂πF_a, ∂πF_b)`, both residuals evaluated with
//! lifted parameters at the fixed `x_C`: the smallest displacement that keeps both faces at zero. Its
//! motion along the edge is arbitrary and projects along `Γ`; so `v = ∂π P_π(x_C(π))·n_img`, the
//! projection with the lifted camera (camera parameters move the image too).
//!
//! # Sampling
//!
//! Edge points are uniform on the total length `Λ` of the edges in view (segments clipped to the view
//! frustum grown by the filter's reach, rims culled whole; the chords of extracted CSG creases culled
//! whole, their points projected onto the crease with density `|T·t|/Λ`, docs/theory.md §7.1, and
//! weighted by its inverse, [`EdgePoint::weight`], in place of `Λ`); the term's integrand is 0 where the edge is
//! not on the shape's surface (a box edge inside another CSG child, or cut away: `|φ| > eps` there) or is
//! hidden (the ray from the eye meets something before it). A sample at `x_C` contributes, to every pixel
//! whose filter covers `u_C = P(x_C)`,
//!
//! ```text
//!   w_j(u_C) · [ L₋ (v − u̇₋) − L₊ (v − u̇₊) ] · |P'T| · Λ                                           (3)
//! ```
//!
//! with `L∓` one camera path each (the integrator's own estimator), averaged over the `N` samples of its
//! own random stream ([`CREASE_STREAM`]): on a side whose face the eye sees, through that face's point
//! a few tracer tolerances across the edge from `x_C`; on a side left to what lies beyond (the face
//! turned away), through `u_C ∓ ε n_img`, `ε` = 1/50 pixel. A face seen nearly edge-on projects to a
//! sliver narrower than `ε`, which a ray at a fixed image offset would cross (`seen_faces`).
//!
//! The shadows of crease edges are the secondary term's ([`super::crease_shadows`]), the tear at
//! vertices after the first [`super::crease_tears`]'s. Not included: the creases between unbounded
//! CSG children beyond the scene's crease region ([`crate::scene::Scene::unsampled_creases`] lists
//! them).
//!
//! # Thin wedges
//!
//! Next to a convex edge whose faces meet at an acute angle, a side's ray passes through a sliver of
//! solid thinner than the tracer's creep step, which may step over it ([`crate::trace`], "thin
//! features"): the side then sees what lies beyond. Such a side takes its first intersection from the
//! faces' tangent planes at the edge point instead (docs/theory.md §7.2).

use super::frustum::Frustum;
use super::source::{BoundarySource, Pass, Scratch};
use super::{
    BACKGROUND_OFFSET_PIXELS, attached_first_vertex, background_offset, film_velocity,
    finite_splat, hidden_before, on_film, projection_jacobian, splat_on_film,
};
use crate::film::SampleSink;
use crate::integrator::path::{
    PathRecord, TraceCounters, contribution, detached, trace_path_after,
};
use crate::math::Ray;
use crate::math::Vec3;
use crate::sampler::Sampler;
use crate::scalar::{Directions, Scalar};
use crate::scene::{Hit, Intersection, Scene, Shape, Surface};
use crate::sdf::{CreaseEdge, EdgeCurve};

/// The random stream of crease-edge samples (distinct from the silhouettes', outlines' and camera's).
pub const CREASE_STREAM: u64 = 0xC2EA_5E0E;

/// One piece of a crease edge in view, in world coordinates.
#[derive(Clone, Debug, PartialEq)]
struct Piece {
    /// Index of the shape in [`Scene::shapes`].
    shape: usize,
    /// Index of the edge in `CreaseEdges::edges`.
    edge: usize,
    /// The (clipped) curve.
    curve: EdgeCurve,
}

/// A sampled edge point.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct EdgePoint {
    /// The point (world coordinates).
    pub x: glam::Vec3,
    /// Unit tangent of the edge.
    pub tangent: glam::Vec3,
    /// Index of the shape in [`Scene::shapes`].
    pub shape: usize,
    /// Index of the edge among the [`CreaseEdges`]' edges.
    pub edge: usize,
    /// `1/p`, `p` the density per unit length of the point (`Λ` for a segment or circle,
    /// `Λ/|T·t|` for a point projected from a chord: [`crate::sdf::Sdf::crease_point`]).
    pub weight: f32,
}

/// Crease edges of the scene's shapes (those that may project onto the film, or all), for sampling by
/// length.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CreaseEdges {
    /// Every shape's edges, in the shape's own coordinates (`(shape, edge)`).
    edges: Vec<(usize, CreaseEdge)>,
    pieces: Vec<Piece>,
    /// Cumulative lengths (`cumulative[i]` = total length of pieces `0..=i`).
    cumulative: Vec<f32>,
}

impl CreaseEdges {
    /// The crease edges of `scene`'s shapes ([`Scene::creased_shapes`]) in view from its camera.
    pub fn seen_from(scene: &Scene) -> Self {
        Self::collect(scene, Some(&Frustum::of(scene)))
    }

    /// Every crease edge of `scene`'s shapes, whole (the shadow term's: an edge out of view can cast a
    /// shadow in view).
    pub fn all(scene: &Scene) -> Self {
        Self::collect(scene, None)
    }

    /// The edges, clipped to `frustum` if given.
    fn collect(scene: &Scene, frustum: Option<&Frustum>) -> Self {
        let mut edges = Vec::new();
        let mut pieces = Vec::new();
        for (i, e) in scene.creased_shapes() {
            let t = scene.shapes[i].translate.value();
            let curve = match e.curve {
                EdgeCurve::Segment { a, b } => match frustum {
                    Some(f) => f.clip(a + t, b + t),
                    None => Some((a + t, b + t)),
                }
                .map(|(a, b)| EdgeCurve::Segment { a, b }),
                // Kept whole (its samples are projected onto the crease, which clipping the chord
                // would not follow): culled only when the view misses its ball.
                EdgeCurve::Chord { a, b } => {
                    let (mid, half) = ((a + b) * 0.5 + t, (b - a).length() * 0.5);
                    (!frustum.is_some_and(|f| f.misses_ball(mid, half)))
                        .then_some(EdgeCurve::Chord { a: a + t, b: b + t })
                }
                EdgeCurve::Circle {
                    centre,
                    radius,
                    e1,
                    e2,
                } => (!frustum.is_some_and(|f| f.misses_ball(centre + t, radius))).then_some(
                    EdgeCurve::Circle {
                        centre: centre + t,
                        radius,
                        e1,
                        e2,
                    },
                ),
            };
            if let Some(curve) = curve
                && curve.length() > 0.0
                && curve.length().is_finite()
            {
                pieces.push(Piece {
                    shape: i,
                    edge: edges.len(),
                    curve,
                });
            }
            edges.push((i, e));
        }
        let mut total = 0.0;
        let cumulative = pieces
            .iter()
            .map(|p| {
                total += p.curve.length();
                total
            })
            .collect();
        Self {
            edges,
            pieces,
            cumulative,
        }
    }

    /// True when no crease edge is in view.
    pub fn is_empty(&self) -> bool {
        self.pieces.is_empty()
    }

    /// Total length `Λ` of the edges in view (scene units, chords' lengths for extracted creases); the
    /// sampling density is `1/Λ` per unit length on segments and circles ([`EdgePoint::weight`]).
    pub fn total_length(&self) -> f32 {
        self.cumulative.last().copied().unwrap_or(0.0)
    }

    /// [`Self::sample`] with two numbers of `sampler`, and the point's shape index and edge; `None` when
    /// empty or when the point is not on the shape's surface ([`on_surface`]), where every crease
    /// term's integrand is 0.
    pub(crate) fn sample_on_surface(
        &self,
        scene: &Scene,
        sampler: &mut Sampler,
    ) -> Option<(EdgePoint, usize, &CreaseEdge)> {
        let (u0, u1) = (sampler.next_1d(), sampler.next_1d());
        let pt = self.sample(scene, [u0, u1])?;
        let (m, edge) = &self.edges[pt.edge];
        on_surface(scene, &scene.shapes[*m], pt.x).then_some((pt, *m, edge))
    }

    /// A point on the edges of `scene` (the scene they were listed from) from two uniform numbers in
    /// `[0, 1)`: a piece by length, then a point uniform on it (projected onto the crease for a chord);
    /// `None` when empty or when the projection fails.
    pub fn sample(&self, scene: &Scene, u: [f32; 2]) -> Option<EdgePoint> {
        if self.pieces.is_empty() {
            return None;
        }
        let target = u[0] * self.total_length();
        let i = self
            .cumulative
            .partition_point(|&c| c <= target)
            .min(self.pieces.len() - 1);
        let piece = &self.pieces[i];
        let (x, tangent, cosine) = match piece.curve {
            EdgeCurve::Chord { .. } => {
                // Projected in the shape's own frame, where the chord was extracted.
                let shape = &scene.shapes[piece.shape];
                let (x, tangent, cosine) =
                    (shape.sdf).crease_point(&self.edges[piece.edge].1, u[1])?;
                (x + shape.translate.value(), tangent, cosine)
            }
            curve => {
                let (x, tangent) = curve.at(u[1]);
                (x, tangent, 1.0)
            }
        };
        let weight = self.total_length() / cosine;
        weight.is_finite().then_some(EdgePoint {
            x,
            tangent,
            shape: piece.shape,
            edge: piece.edge,
            weight,
        })
    }
}

/// Whether the edge point `x` lies on `shape`'s surface (`|φ|` within a tolerance there): not inside
/// another CSG child, not cut away. False for a NaN value.
pub(crate) fn on_surface(scene: &Scene, shape: &Shape, x: glam::Vec3) -> bool {
    let phi = shape.eval_f32(x).abs();
    phi <= scene.trace.eps_at_point(x)
}

/// `∇F` of face `face` (0 or 1) of `edge` on `shape` at the world point `x` ([`crate::sdf::Sdf::face_gradient`]).
pub(crate) fn face_gradient(
    shape: &Shape,
    edge: &CreaseEdge,
    face: usize,
    x: glam::Vec3,
) -> glam::Vec3 {
    shape
        .sdf
        .face_gradient(&edge.path, edge.faces[face], x - shape.translate.value())
}

/// The edge point `x_C` moved with the lifted parameters (see the [module docs](self)): `x_C` minus the
/// smallest displacement that keeps both faces at zero. `None` where the faces' gradients are (nearly)
/// parallel or a face does not evaluate.
pub fn moving_edge_point<S: Scalar>(
    shape: &Shape,
    edge: &CreaseEdge,
    x: glam::Vec3,
) -> Option<Vec3<S>> {
    let p = Vec3::<S>::constant(x) - shape.translate.get::<S>();
    let residual = |face: usize| -> Option<S> {
        let f = shape.sdf.face_value(&edge.path, edge.faces[face], p)?;
        Some(f - f.detach())
    };
    let (ra, rb) = (residual(0)?, residual(1)?);
    let (ga, gb) = (
        face_gradient(shape, edge, 0, x),
        face_gradient(shape, edge, 1, x),
    );
    let (aa, ab, bb) = (ga.dot(ga), ga.dot(gb), gb.dot(gb));
    let det = aa * bb - ab * ab;
    if !(det > 1e-6 * aa * bb && det.is_finite()) {
        return None;
    }
    let alpha = (ra * bb - rb * ab) / det;
    let beta = (rb * aa - ra * ab) / det;
    Some(Vec3::constant(x) - Vec3::constant(ga) * alpha - Vec3::constant(gb) * beta)
}

/// The crease edges in view ([`CreaseEdges::seen_from`]): eq. (3)'s samples.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CreasesInView(pub CreaseEdges);

impl<S: Directions> BoundarySource<S> for CreasesInView {
    fn stage(&self) -> &'static str {
        "primary (crease edges)"
    }

    fn stream(&self) -> u64 {
        CREASE_STREAM
    }

    fn takes_share(&self) -> bool {
        !self.0.is_empty()
    }

    fn sample(
        &self,
        pass: &Pass,
        sampler: &mut Sampler,
        scratch: &mut Scratch,
        counters: &mut TraceCounters,
        sink: &mut dyn SampleSink<S>,
    ) {
        sample(pass, &self.0, sampler, &mut scratch.record, sink, counters);
    }
}

/// One sample of eq. (3): pushes `(pixel, radiance, coverage)` splats (not yet divided by `N`).
fn sample<S: Directions>(
    pass: &Pass,
    creases: &CreaseEdges,
    sampler: &mut Sampler,
    record: &mut PathRecord,
    splats: &mut dyn SampleSink<S>,
    counters: &mut TraceCounters,
) {
    let (scene, attach) = (pass.scene, &pass.attach);
    let Some((pt, m, edge)) = creases.sample_on_surface(scene, sampler) else {
        return;
    };
    let shape = &scene.shapes[m];
    let x = pt.x;
    let frame = scene.camera.frame::<f32>();
    let eye: glam::Vec3 = frame.origin.into();
    let q = x - eye;
    let dist = q.length();
    if !(dist > 0.0 && dist.is_finite()) {
        return;
    }
    let Some((px, py)) = frame.project(Vec3::constant(x)) else {
        return;
    };
    if !on_film(scene, px, py) {
        return;
    }
    let Some((du, dv)) = projection_jacobian(&frame, q) else {
        return;
    };
    let t_img = glam::Vec2::new(du.dot(pt.tangent), dv.dot(pt.tangent));
    let len_img = t_img.length();
    if !(len_img > 0.0 && len_img.is_finite()) {
        return;
    }
    let n_img = glam::Vec2::new(-t_img.y, t_img.x) / len_img;
    let delta = background_offset(scene, dist, frame.focal);
    let Some(to_edge) = q.try_normalize() else {
        return;
    };
    if hidden_before(
        scene,
        &frame,
        crate::math::Ray::new(eye, to_edge),
        dist,
        delta,
        counters,
    ) {
        return;
    }
    let fs = scene.camera.frame::<S>();
    let Some(x_c) = moving_edge_point::<S>(shape, edge, x) else {
        return;
    };
    let Some((ex, ey)) = film_velocity(&fs, x_c) else {
        return;
    };
    let v = ex * n_img.x + ey * n_img.y;
    // Each side: its radiance and its parametrisation's film velocity along n_img, seen along a camera
    // ray passing `delta` from the edge (at least four camera-ray tolerances).
    let z = q.dot(frame.forward.into());
    let off_pixels = (delta * frame.focal / z).max(BACKGROUND_OFFSET_PIXELS);
    // The wedge of solid at a convex edge, as the two faces' tangent planes there (see `Wedge`).
    let wedge = (!edge.inverted).then(|| {
        let normals = [0, 1].map(|f| face_gradient(shape, edge, f, x).normalize_or_zero());
        Wedge {
            apex: x,
            normals,
            reach: 8.0 * off_pixels * z / frame.focal,
            shape: m,
        }
    });
    // The faces the eye sees, each with the image side it lies on and a point of it next to the edge.
    let seen = seen_faces(shape, edge, x, pt.tangent, eye, (du, dv), n_img, delta);
    let mut side = |sign: f32| -> Option<(glam::Vec3, S)> {
        let off = sign * off_pixels;
        let ray = match seen.iter().flatten().find(|(s, _)| *s == sign) {
            Some((_, y)) => Ray::new(eye, (*y - eye).try_normalize()?),
            None => frame.generate_ray(glam::Vec2::new(px + off * n_img.x, py + off * n_img.y)),
        };
        let depth = scene.integrator.max_scatter();
        let first = (depth > 0).then(|| {
            let found = scene.intersect_resolving(&ray, f32::INFINITY, frame.spread(ray.d));
            wedge.as_ref().map_or(found, |w| w.correct(&ray, found))
        });
        trace_path_after(scene, ray, first, depth, sampler, record, counters);
        let l: glam::Vec3 = contribution::<f32>(scene, record, detached).into();
        let y = attached_first_vertex::<S>(attach, record)
            .unwrap_or_else(|| fs.origin + Vec3::constant(ray.d));
        let (yx, yy) = film_velocity(&fs, y)?;
        Some((l, yx * n_img.x + yy * n_img.y))
    };
    let Some((l_minus, u_minus)) = side(-1.0) else {
        return;
    };
    let Some((l_plus, u_plus)) = side(1.0) else {
        return;
    };
    let measure = len_img * pt.weight;
    if !(measure.is_finite() && l_minus.is_finite() && l_plus.is_finite()) {
        return;
    }
    let value = (Vec3::<S>::constant(l_minus * measure) * (v - u_minus))
        - (Vec3::<S>::constant(l_plus * measure) * (v - u_plus));
    let cover = (u_plus - u_minus) * S::constant(measure);
    if finite_splat(&value, cover) {
        splat_on_film(scene, (px, py), value, cover, splats);
    }
}

/// The faces of `edge` at its point `x` (unit tangent `tangent`) that face the eye at `eye`, each as
/// `(sign, y)`: the side of the edge's image it lies on (`±1` along `n_img`, through the projection's
/// Jacobian rows `jac`) and its point `y` at `delta` from `x` across the edge.
///
/// A side whose face the eye sees is seen at that face's point next to the edge, not along a ray
/// passing the edge's image at a fixed offset: a face seen nearly edge-on projects to a sliver
/// narrower than any such offset, and that ray would cross it and see what lies beyond (another face,
/// the background) on both edges bounding the sliver, counting the jump between those twice. A face
/// turned away leaves its side to the background, seen past the edge.
#[allow(clippy::too_many_arguments)]
fn seen_faces(
    shape: &Shape,
    edge: &CreaseEdge,
    x: glam::Vec3,
    tangent: glam::Vec3,
    eye: glam::Vec3,
    (du, dv): (glam::Vec3, glam::Vec3),
    n_img: glam::Vec2,
    delta: f32,
) -> [Option<(f32, glam::Vec3)>; 2] {
    let grads = [0, 1].map(|f| face_gradient(shape, edge, f, x));
    [0, 1].map(|f| {
        // The surface's outward normal on face f (−∇F inside a subtracted child).
        let outward = if edge.inverted { -grads[f] } else { grads[f] };
        if outward.dot(eye - x) <= 0.0 {
            return None;
        }
        // Across the edge within face f: orthogonal to the edge and to ∇F_f, towards the other face's
        // inside (`F_other < 0` on face f).
        let across = tangent.cross(grads[f]).try_normalize()?;
        let across = if across.dot(grads[1 - f]) > 0.0 {
            -across
        } else {
            across
        };
        let image = n_img.dot(glam::Vec2::new(du.dot(across), dv.dot(across)));
        (image != 0.0 && image.is_finite()).then(|| (image.signum(), x + across * delta))
    })
}

/// The solid next to a convex crease point `apex`, to first order: the wedge where both faces' tangent
/// planes (outward unit `normals`) have the point behind them. The tracer may step over a thin wedge
/// (its creep steps skip crossings whose chord is shorter than they are, see [`crate::trace`]), and the
/// sides' rays pass the edge at a fiftieth of a pixel, where an acute wedge is that thin: a lens's rim
/// or a scoop's lip, where both sides then saw the background and the term vanished.
struct Wedge {
    apex: glam::Vec3,
    normals: [glam::Vec3; 2],
    /// How far from the apex the tangent planes stand for the faces (eight side offsets).
    reach: f32,
    /// Index of the shape.
    shape: usize,
}

impl Wedge {
    /// Where `ray` enters the wedge within `reach` of the apex, and the face it enters through.
    fn entry(&self, ray: &Ray) -> Option<(f32, usize)> {
        let (mut t_in, mut face, mut t_out) = (0.0f32, None, f32::INFINITY);
        for (k, n) in self.normals.iter().enumerate() {
            let (s0, rate) = (n.dot(ray.o - self.apex), n.dot(ray.d));
            if rate < 0.0 {
                let t = -s0 / rate;
                if t > t_in {
                    (t_in, face) = (t, Some(k));
                }
            } else if rate > 0.0 {
                t_out = t_out.min(-s0 / rate);
            } else if s0 > 0.0 {
                return None;
            }
        }
        let face = face?;
        (t_in < t_out && (ray.at(t_in) - self.apex).length() <= self.reach).then_some((t_in, face))
    }

    /// The tracer's first intersection `found` along `ray`, or the wedge's face where the ray enters the
    /// wedge if the tracer found nothing before it (a miss, or a hit beyond the wedge).
    fn correct(&self, ray: &Ray, found: Intersection) -> Intersection {
        let Some((t, face)) = self.entry(ray) else {
            return found;
        };
        match found {
            Intersection::Hit(h) if h.t <= t + self.reach => found,
            _ => Intersection::Hit(Hit {
                t,
                p: ray.at(t),
                n: self.normals[face],
                surface: Surface::Shape(self.shape),
            }),
        }
    }
}
