//! Implicit surfaces: signed distance functions (and other level sets) as a tree of primitives,
//! combinators and transforms.
//!
//! Conventions: `φ(x) < 0` inside, `> 0` outside; the normal `n = ∇φ/|∇φ|` points outward; the total
//! curvature is `κ = ∇·n = (tr H − nᵀHn)/|∇φ|` (`2/r` on a sphere of radius `r`). Every node evaluates
//! generically ([`Sdf::eval`]) so that the same code gives values in `f32`, gradients with
//! [`crate::scalar::DualVec3`], Hessians with [`crate::scalar::Dual2Vec3`] and parameter derivatives with
//! `Dual32`.
//!
//! Layout: exact-distance primitives (`primitives.rs`), hard CSG and the cubic smooth union (`csg.rs`),
//! similarity transforms (`transform.rs`), B-spline grids (`grid.rs`; their `.npy` files are
//! [`crate::io::npy`]'s) and baking any node onto a grid (`bake.rs`); interval enclosures of `φ` and `∇φ` over boxes (`interval/`, used for
//! certified culling). [`Sdf::Named`] only carries a node's name from the scene file (for
//! parameter names) and delegates everything to its child.
//!
//! Smoothness, which the curvature and the boundary terms care about: sphere, torus, capsule and plane
//! are smooth (C∞) off their medial axes; rounded boxes and cylinders are C1 (the curvature jumps where a
//! flat face meets a rounded edge) and creased when `rounding = 0`; hard CSG creases where the active
//! child switches; the smooth union is C2; grids are C2 everywhere.
//!
//! Grids: the samples are the *control points* of a uniform cubic B-spline, which approximates rather than
//! interpolates: the surface is offset by about `h²/6 ∇²φ` (`h²/(3r)` for a sphere of radius `r`), in
//! exchange for C2 continuity. Faces use a linearly extrapolated ghost layer (no bias for linear fields);
//! outside the box `φ = φ(clamp(x)) + |x − clamp(x)|`. The Lipschitz bound is exact for the spline's
//! per-axis differences patch by patch (`sqrt(Σ L_a²)`, with 1 in place of `L_a²` beyond face `a`), and
//! kept per side of the surface: near 1 outside a sampled convex distance field, `√3` around a medial
//! axis.

mod bake;
mod carried;
mod crease_edges;
mod creases;
mod crossing_creases;
mod csg;
mod culling;
mod empty_space;
mod grid;
mod grid_edit;
mod grid_jet;
pub mod interval;
mod line_crossings;
mod primitive;
mod primitives;
mod spline_basis;
mod transform;
mod validate;

pub use crate::io::npy::{read_npy, write_npy};
pub use bake::{BAKE_PADDING, Baked, bake, bake_dims, bake_padded, bake_padded_by};
pub use crease_edges::{CreaseEdge, EdgeCurve, Face};
pub use creases::surfaces_may_meet;
pub use crossing_creases::CrossingCrease;
pub use culling::{CULL_MIN_CHILDREN, Children};
pub use empty_space::{BoxCells, Candidate, EmptySpace, LatticeRay};
pub use line_crossings::LineCrossings;
pub use primitive::SdfPrimitive;
pub use transform::{AngleTrig, Similarity};

// The primitives kept in files of their own: one line each ([`primitive`]).
primitive::primitives! {
    capsule => Capsule,
}

use crate::declare::{Family, Kind};
use crate::error::Result;
use crate::math::{Aabb, Vec3};
use crate::scalar::{BlockValues, Dual2Vec3, DualVec3, Param, Param3, Scalar};
use std::sync::Arc;

/// Values of a grid SDF: `nx · ny · nz` samples, x fastest (the layout of a C-order `.npy` of shape
/// `[nz, ny, nx]`), spanning a world-space box with the first and last samples on its faces.
#[derive(Clone, Debug, PartialEq)]
pub struct GridData {
    /// Samples along x, y, z (each at least 4 for a cubic B-spline).
    pub dims: [usize; 3],
    /// The samples, `values[(z * ny + y) * nx + x]`.
    pub values: Vec<f32>,
}

/// Lipschitz bounds of an implicit function on each side of its surface ([`Sdf::lipschitz_sided`]).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Lipschitz {
    /// Bound of `|∇φ|` where `φ ≥ 0`.
    pub outside: f32,
    /// Bound of `|∇φ|` where `φ ≤ 0`.
    pub inside: f32,
}

impl From<f32> for Lipschitz {
    /// The same bound on both sides.
    fn from(l: f32) -> Self {
        Self {
            outside: l,
            inside: l,
        }
    }
}

/// An implicit-surface node. Parameters are [`Param`]s so that any of them can be differentiated.
#[derive(Clone, Debug, PartialEq)]
pub enum Sdf {
    /// Sphere: `|p − center| − radius`.
    Sphere {
        /// Centre.
        center: Param3,
        /// Radius (> 0).
        radius: Param,
    },
    /// Box with half extents `half_size`, its edges rounded by `rounding` (0 gives a sharp, creased box).
    /// The rounded box keeps the outer extents: it is the box shrunk by `rounding`, dilated by `rounding`.
    Box {
        /// Centre.
        center: Param3,
        /// Half extents along x, y, z (> 0).
        half_size: Param3,
        /// Edge radius, in `[0, min(half_size)]`.
        rounding: Param,
    },
    /// Torus around `axis` through `center`.
    Torus {
        /// Centre.
        center: Param3,
        /// Unit axis of revolution.
        axis: glam::Vec3,
        /// Distance from the centre to the tube's centre line (> minor_radius).
        major_radius: Param,
        /// Tube radius (> 0).
        minor_radius: Param,
    },
    /// Capped cylinder around `axis` through `center`, its rims rounded by `rounding` (0: creased).
    Cylinder {
        /// Centre.
        center: Param3,
        /// Unit axis.
        axis: glam::Vec3,
        /// Radius (> 0).
        radius: Param,
        /// Half of the length along the axis (> 0).
        half_height: Param,
        /// Rim radius, in `[0, min(radius, half_height)]`.
        rounding: Param,
    },
    /// A primitive kept in a file of its own ([`Primitive`]).
    Primitive(Primitive),
    /// Half-space `normal · p − offset ≤ 0`.
    Plane {
        /// Unit normal (pointing out of the solid).
        normal: glam::Vec3,
        /// Signed distance of the plane from the origin along `normal`.
        offset: Param,
    },
    /// Union (minimum) of the children.
    Union(Children),
    /// Intersection (maximum) of the children.
    Intersection(Children),
    /// The first child minus all others.
    Difference(Children),
    /// Smooth union with blending radius `k`: the cubic polynomial smooth minimum (C2, at most `k/6` below
    /// the minimum, equal to it where the children differ by more than `k`), folded over the children.
    SmoothUnion {
        /// Children (at least one).
        children: Children,
        /// Blending radius, in scene units.
        k: Param,
    },
    /// The child rotated by `angle` degrees about `axis`, uniformly scaled by `scale`, then translated.
    Transform {
        /// Translation.
        translate: Param3,
        /// Unit rotation axis.
        axis: glam::Vec3,
        /// Rotation angle in degrees (right-handed about `axis`).
        angle: Param,
        /// Uniform scale (> 0).
        scale: Param,
        /// `cos` and `sin` of `angle`, computed when the node was built ([`AngleTrig`]).
        trig: AngleTrig,
        /// The transformed node.
        child: Box<Sdf>,
    },
    /// Samples over the box `[bbox_min, bbox_max]`, the control points of a C2 cubic B-spline (see the
    /// module notes: it approximates the samples with an `O(h²)` smoothing).
    Grid {
        /// The samples (shared: grids can be large).
        data: Arc<GridData>,
        /// Lower corner of the grid box (first sample).
        bbox_min: glam::Vec3,
        /// Upper corner of the grid box (last sample).
        bbox_max: glam::Vec3,
        /// Iso-level: the node is `spline − level`, so a positive level dilates the surface by about
        /// `level / |∇φ|` and a negative one erodes it (0 keeps the baked surface).
        level: Param,
        /// How the samples are differentiated in the current pass (the parameter block
        /// `<node>.values`; constants unless selected).
        selection: BlockValues,
    },
    /// A node given a `name` in the scene file, so that its parameters are `<name>.<field>` (see
    /// [`crate::scene::Scene::parameters`]). It is the child in every respect: evaluation, gradient,
    /// bounds and Lipschitz bound all delegate.
    Named {
        /// The node's unique name (ASCII letters, digits, `_`, `-`).
        name: String,
        /// The named node.
        child: Box<Sdf>,
    },
}

/// Every sdf node kind ([`crate::declare`]), in the order the scene file's errors list them: the
/// primitives (those in files of their own after the others), the plane, CSG, transforms and grids.
static KINDS: std::sync::LazyLock<Vec<&'static Kind<Sdf>>> = std::sync::LazyLock::new(|| {
    let before: [&'static Kind<Sdf>; 4] = [
        &primitives::kinds::SPHERE,
        &primitives::kinds::BOX,
        &primitives::kinds::TORUS,
        &primitives::kinds::CYLINDER,
    ];
    let after: [&'static Kind<Sdf>; 7] = [
        &primitives::kinds::PLANE,
        &csg::kinds::UNION,
        &csg::kinds::INTERSECTION,
        &csg::kinds::DIFFERENCE,
        &csg::kinds::SMOOTH_UNION,
        &transform::kinds::TRANSFORM,
        &grid::kinds::GRID,
    ];
    (before.into_iter())
        .chain(PRIMITIVE_KINDS.iter().copied())
        .chain(after)
        .collect()
});

impl Family for Sdf {
    fn kinds() -> &'static [&'static Kind<Sdf>] {
        &KINDS
    }

    fn kind(&self) -> &'static Kind<Sdf> {
        match self {
            Sdf::Sphere { .. } => &primitives::kinds::SPHERE,
            Sdf::Box { .. } => &primitives::kinds::BOX,
            Sdf::Torus { .. } => &primitives::kinds::TORUS,
            Sdf::Cylinder { .. } => &primitives::kinds::CYLINDER,
            Sdf::Primitive(primitive) => primitive.kind(),
            Sdf::Plane { .. } => &primitives::kinds::PLANE,
            Sdf::Union(_) => &csg::kinds::UNION,
            Sdf::Intersection(_) => &csg::kinds::INTERSECTION,
            Sdf::Difference(_) => &csg::kinds::DIFFERENCE,
            Sdf::SmoothUnion { .. } => &csg::kinds::SMOOTH_UNION,
            Sdf::Transform { .. } => &transform::kinds::TRANSFORM,
            Sdf::Grid { .. } => &grid::kinds::GRID,
            Sdf::Named { child, .. } => child.kind(),
        }
    }

    fn named(&self) -> Option<(&str, &Self)> {
        match self {
            Sdf::Named { name, child } => Some((name, child)),
            _ => None,
        }
    }

    fn named_mut(&mut self) -> Option<(&str, &mut Self)> {
        match self {
            Sdf::Named { name, child } => Some((name, child)),
            _ => None,
        }
    }
}

impl Sdf {
    /// `φ(p)`, generic over the scalar type.
    ///
    /// Allocation-free; with `f32` this is the sphere tracer's inner loop.
    #[inline]
    pub fn eval<S: Scalar>(&self, p: Vec3<S>) -> S {
        self.eval_as::<S, false>(p)
    }

    /// The field of the faces: `φ` with the exterior distance of every sharp primitive (a box or a
    /// cylinder with `rounding = 0`) replaced by the largest of its faces' own fields (`max_i q_i` for
    /// a box, `max(ρ − R, |h| − H)` for a cylinder), everything else as [`Sdf::eval`].
    ///
    /// The same surface and the same values inside and next to each face, but level sets that stay
    /// flat (a cylinder's side: cylindrical) up to the edges instead of rounding around them. A point
    /// the tracer returns lies within its tolerance of the surface, on either side: outside a sharp
    /// edge by a tiny `φ`, the exact distance's level set is a cylinder of radius `φ` about the edge,
    /// of curvature `1/φ` and with a normal turning over a distance `φ`, while the point belongs to a
    /// face, flat. The geometry that moves a surface point with the parameters (the normal velocity,
    /// the curvature in `∂πJ = κV`, the moving normal; docs/theory.md §2.1–§2.3) is read from this
    /// field, so that it is the face's whichever side of the tolerance the point lies on.
    pub fn eval_faces<S: Scalar>(&self, p: Vec3<S>) -> S {
        self.eval_as::<S, true>(p)
    }

    /// [`Sdf::eval`] (`FACES = false`) or [`Sdf::eval_faces`]; chosen at compile time, so the
    /// tracer's `f32` evaluation is unchanged.
    pub(super) fn eval_as<S: Scalar, const FACES: bool>(&self, p: Vec3<S>) -> S {
        match self {
            Sdf::Sphere { center, radius } => primitives::sphere(p, center, radius),
            Sdf::Box {
                center,
                half_size,
                rounding,
            } => primitives::cuboid::<S, FACES>(p, center, half_size, rounding),
            Sdf::Torus {
                center,
                axis,
                major_radius,
                minor_radius,
            } => primitives::torus(p, center, *axis, major_radius, minor_radius),
            Sdf::Cylinder {
                center,
                axis,
                radius,
                half_height,
                rounding,
            } => primitives::cylinder::<S, FACES>(p, center, *axis, radius, half_height, rounding),
            Sdf::Primitive(primitive) => primitive.eval(p),
            Sdf::Plane { normal, offset } => primitives::plane(p, *normal, offset),
            Sdf::Union(children) => match culling::hierarchy::<S>(children).filter(|_| !FACES) {
                Some(bvh) => culling::union::<S, FACES>(children, bvh, p),
                None => csg::union::<S, FACES>(children, p),
            },
            Sdf::Intersection(children) => csg::intersection::<S, FACES>(children, p),
            Sdf::Difference(children) => match culling::hierarchy::<S>(children).filter(|_| !FACES)
            {
                Some(bvh) => culling::difference::<S, FACES>(children, bvh, p),
                None => csg::difference::<S, FACES>(children, p),
            },
            Sdf::SmoothUnion { children, k } => {
                match culling::hierarchy::<S>(children).filter(|_| !FACES) {
                    Some(bvh) => culling::smooth_union::<S, FACES>(children, bvh, k.get::<S>(), p),
                    None => csg::smooth_union::<S, FACES>(children, k.get::<S>(), p),
                }
            }
            Sdf::Transform {
                translate,
                axis,
                angle,
                scale,
                child,
                trig,
            } => transform::eval::<S, FACES>(p, translate, *axis, angle, *trig, scale, child),
            Sdf::Grid {
                data,
                bbox_min,
                bbox_max,
                level,
                selection,
            } => grid::eval(data, *bbox_min, *bbox_max, selection, p) - level.get::<S>(),
            Sdf::Named { child, .. } => child.eval_as::<S, FACES>(p),
        }
    }

    /// `φ(p)` in `f32`, the tracer's entry point.
    #[inline]
    pub fn eval_f32(&self, p: glam::Vec3) -> f32 {
        self.eval::<f32>(p.into())
    }

    /// `∇φ(p)` (not normalised), by forward-mode AD ([`DualVec3`]), with analytic fast paths for the
    /// sphere, the box and a grid inside its box. Zero (never NaN) where `φ` is not differentiable in a
    /// way `safe_sqrt` guards, e.g. at a sphere's centre.
    pub fn gradient(&self, p: glam::Vec3) -> glam::Vec3 {
        match self {
            Sdf::Sphere { center, .. } => {
                // ∇|p − c| = (p − c)/|p − c|; zero at the centre, as AD with safe_sqrt gives.
                (p - center.value()).normalize_or_zero()
            }
            Sdf::Box {
                center,
                half_size,
                rounding,
            } => box_gradient(p - center.value(), half_size.value(), rounding.value, false),
            Sdf::Grid { .. } | Sdf::Transform { .. } => match self.grid_jet::<false>(p) {
                Some((_, g, _)) => g,
                None => self.ad_gradient(p),
            },
            // The child's fast path, if it has one.
            Sdf::Named { child, .. } => child.gradient(p),
            _ => self.ad_gradient(p),
        }
    }

    /// `φ(p)` and `∇φ(p)` in one evaluation of a grid's taps, for a grid under names and similarity
    /// transforms, inside its box; `None` elsewhere and for every other node. The value is
    /// [`Sdf::eval_f32`]'s to rounding (bit for bit for a grid without transforms).
    pub fn value_and_gradient(&self, p: glam::Vec3) -> Option<(f32, glam::Vec3)> {
        self.grid_jet::<false>(p).map(|(v, g, _)| (v, g))
    }

    /// Whether [`Sdf::value_and_gradient`]'s value, where it answers, is [`Sdf::eval_f32`]'s bit for
    /// bit: a grid under names only (a transform's maps round differently).
    pub fn value_and_gradient_is_exact(&self) -> bool {
        match self {
            Sdf::Grid { .. } => true,
            Sdf::Named { child, .. } => child.value_and_gradient_is_exact(),
            _ => false,
        }
    }

    /// The gradient of the field of the faces ([`Sdf::eval_faces`]): [`Sdf::gradient`] except next
    /// to a sharp primitive's edges (outside it, within the distance to them), where it is the nearest
    /// face's.
    pub fn gradient_faces(&self, p: glam::Vec3) -> glam::Vec3 {
        match self {
            Sdf::Sphere { .. } => self.gradient(p),
            Sdf::Box {
                center,
                half_size,
                rounding,
            } => box_gradient(p - center.value(), half_size.value(), rounding.value, true),
            Sdf::Named { child, .. } => child.gradient_faces(p),
            _ => gradient_by_ad(p, |q| Some(self.eval_faces(q))),
        }
    }

    /// `∇φ(p)` by forward-mode AD, for every node (the reference the fast paths are tested against).
    pub fn ad_gradient(&self, p: glam::Vec3) -> glam::Vec3 {
        gradient_by_ad(p, |q| Some(self.eval(q)))
    }

    /// Outward unit normal `∇φ/|∇φ|`; `+z` where the gradient vanishes.
    pub fn normal(&self, p: glam::Vec3) -> glam::Vec3 {
        self.gradient(p).try_normalize().unwrap_or(glam::Vec3::Z)
    }

    /// The normal of the field of the faces ([`Sdf::gradient_faces`]): a surface point's normal, that
    /// of its face even where the point lies outside a sharp edge by a tracer's tolerance (where
    /// [`Sdf::normal`] turns from one face's to the other's); `+z` where the gradient vanishes.
    pub fn face_normal(&self, p: glam::Vec3) -> glam::Vec3 {
        self.gradient_faces(p)
            .try_normalize()
            .unwrap_or(glam::Vec3::Z)
    }

    /// Value, gradient and Hessian at `p` by second-order forward AD ([`Dual2Vec3`]), or from a grid's
    /// taps inside its box (the same numbers to rounding, several times faster).
    pub fn hessian(&self, p: glam::Vec3) -> (f32, glam::Vec3, glam::Mat3) {
        self.hessian_as::<false>(p)
    }

    /// [`Sdf::hessian`] of the field of the faces ([`Sdf::eval_faces`]).
    pub fn hessian_faces(&self, p: glam::Vec3) -> (f32, glam::Vec3, glam::Mat3) {
        self.hessian_as::<true>(p)
    }

    fn hessian_as<const FACES: bool>(&self, p: glam::Vec3) -> (f32, glam::Vec3, glam::Mat3) {
        if let Some(jet) = self.grid_jet::<true>(p) {
            return jet;
        }
        self.ad_hessian_as::<FACES>(p)
    }

    /// [`Sdf::hessian_as`] by second-order forward AD on every node (the reference of the fast path).
    fn ad_hessian_as<const FACES: bool>(&self, p: glam::Vec3) -> (f32, glam::Vec3, glam::Mat3) {
        let v = self.eval_as::<_, FACES>(Vec3::new(
            Dual2Vec3::from_re(p.x).derivative(0),
            Dual2Vec3::from_re(p.y).derivative(1),
            Dual2Vec3::from_re(p.z).derivative(2),
        ));
        let g =
            v.v1.0
                .map_or(glam::Vec3::ZERO, |g| glam::Vec3::new(g[0], g[1], g[2]));
        let h = v.v2.0.map_or(glam::Mat3::ZERO, |h| {
            glam::Mat3::from_cols_array_2d(&std::array::from_fn(|c| {
                std::array::from_fn(|r| h[(r, c)])
            }))
        });
        (v.re, g, h)
    }

    /// The value, gradient and, with `SECOND`, Hessian (zero without) of a grid under names and
    /// similarity transforms from the grid's taps ([`grid_jet`]), inside the grid's box; `None`
    /// elsewhere and for every other node.
    fn grid_jet<const SECOND: bool>(&self, p: glam::Vec3) -> Option<(f32, glam::Vec3, glam::Mat3)> {
        match self {
            Sdf::Grid {
                data,
                bbox_min,
                bbox_max,
                level,
                ..
            } => grid_jet::jet::<SECOND>(data, *bbox_min, *bbox_max, p)
                .map(|(v, g, h)| (v - level.value, g, h)),
            Sdf::Named { child, .. } => child.grid_jet::<SECOND>(p),
            // Checked first: mapping the point costs more than the walk, and the normal of every hit
            // on a transformed primitive comes this way before falling back to AD.
            Sdf::Transform { child, .. } if child.is_placed_grid() => {
                // φ(x) = s φ_c(R⁻¹(x − t)/s): ∇φ = R ∇φ_c and H = R H_c Rᵀ / s.
                let (frame, child) = self.frame()?;
                let q: glam::Vec3 = frame.to_child_point(p.into()).into();
                let (v, g, h) = child.grid_jet::<SECOND>(q)?;
                let rotate =
                    |v: glam::Vec3| -> glam::Vec3 { frame.from_child_gradient(v.into()).into() };
                let h = if SECOND {
                    let r = glam::Mat3::from_cols(
                        rotate(glam::Vec3::X),
                        rotate(glam::Vec3::Y),
                        rotate(glam::Vec3::Z),
                    );
                    r * h * r.transpose() * frame.to_child_length(1.0)
                } else {
                    h
                };
                Some((frame.from_child_length(v), rotate(g), h))
            }
            _ => None,
        }
    }

    /// Whether this node is a grid under names and transforms only (what [`Sdf::grid_jet`] handles).
    fn is_placed_grid(&self) -> bool {
        match self {
            Sdf::Grid { .. } => true,
            Sdf::Named { child, .. } | Sdf::Transform { child, .. } => child.is_placed_grid(),
            _ => false,
        }
    }

    /// Total curvature `κ = ∇·n = (tr H − nᵀHn)/|∇φ|` of the level set through `p` (sum of principal
    /// curvatures; positive on convex surfaces). Zero where the gradient vanishes or the result is not
    /// finite.
    pub fn curvature(&self, p: glam::Vec3) -> f32 {
        let (_, g, h) = self.hessian(p);
        curvature_from(g, h)
    }

    /// Normal curvature `κ_n(ω) = ωᵀHω/|∇φ|` along the tangent direction `ω` (unit, `ω·n = 0`): the
    /// curvature of the surface's section along `ω`, positive where the surface curves away from `ω`
    /// (convex). Zero where the gradient vanishes.
    pub fn normal_curvature(&self, p: glam::Vec3, omega: glam::Vec3) -> f32 {
        let (_, g, h) = self.hessian(p);
        let gl = g.length();
        if gl.is_nan() || gl <= 1e-12 {
            return 0.0;
        }
        let k = omega.dot(h * omega) / gl;
        if k.is_finite() { k } else { 0.0 }
    }

    /// A box holding the whole surface and interior (`φ ≤ 0`); [`Aabb::INFINITE`] for unbounded nodes.
    ///
    /// Unions unite boxes, intersections intersect them, a difference keeps its first child's box, a
    /// smooth union grows the union by its blend (by `k`, see the smooth-minimum notes in the source), a transform boxes the eight mapped
    /// corners, a grid is its box grown by any negative face value.
    pub fn bounds(&self) -> Aabb {
        match self {
            Sdf::Sphere { center, radius } => primitives::sphere_bounds(center, radius),
            Sdf::Box {
                center, half_size, ..
            } => primitives::cuboid_bounds(center, half_size),
            Sdf::Torus {
                center,
                axis,
                major_radius,
                minor_radius,
            } => primitives::torus_bounds(center, *axis, major_radius, minor_radius),
            Sdf::Cylinder {
                center,
                axis,
                radius,
                half_height,
                ..
            } => primitives::cylinder_bounds(center, *axis, radius, half_height),
            Sdf::Primitive(primitive) => primitive.bounds(),
            Sdf::Plane { .. } => Aabb::INFINITE,
            Sdf::Union(children) => csg::union_bounds(children),
            Sdf::Intersection(children) => csg::intersection_bounds(children),
            Sdf::Difference(children) => children.first().map_or(Aabb::EMPTY, Sdf::bounds),
            Sdf::SmoothUnion { children, k } => csg::smooth_union_bounds(children, k.value),
            Sdf::Transform { .. } => {
                let (frame, child) = self.frame().expect("a transform has a frame");
                frame.from_child_box(&child.bounds())
            }
            Sdf::Grid {
                data,
                bbox_min,
                bbox_max,
                level,
                ..
            } => grid::bounds(data, *bbox_min, *bbox_max, level.value),
            Sdf::Named { child, .. } => child.bounds(),
        }
    }

    /// An upper bound on `|∇φ|` everywhere: sphere tracing steps by `φ / L`.
    ///
    /// 1 for the primitives (exact distances; `|n|` for a plane), the largest child's for CSG and smooth
    /// unions (min, max and the smooth min's convex weights keep it), the child's for a transform (the
    /// scale cancels), the spline's exact bound for a grid.
    pub fn lipschitz(&self) -> f32 {
        let sided = self.lipschitz_sided();
        sided.outside.max(sided.inside)
    }

    /// Lipschitz bounds of `φ` over the outside (`φ ≥ 0`) and over the inside (`φ ≤ 0`): what sphere
    /// tracing on each side needs (the segment from a point to the nearest surface point stays on its
    /// side). They differ for grids, whose patches around the medial axis (deep inside a shape) have
    /// steeper splines than any near the surface (the grid module's `lipschitz_sided`); for hard CSG each side
    /// is the children's largest on the side the active child is on (min and max keep the sign of the
    /// active child; a subtracted child's sides swap); everything else has one bound for both.
    pub fn lipschitz_sided(&self) -> Lipschitz {
        let max_of = |sides: &mut dyn Iterator<Item = Lipschitz>| {
            sides.fold(
                Lipschitz {
                    outside: 0.0,
                    inside: 0.0,
                },
                |a, b| Lipschitz {
                    outside: a.outside.max(b.outside),
                    inside: a.inside.max(b.inside),
                },
            )
        };
        match self {
            Sdf::Union(children) | Sdf::Intersection(children) if !children.is_empty() => {
                max_of(&mut children.iter().map(Sdf::lipschitz_sided))
            }
            Sdf::Difference(children) if !children.is_empty() => {
                max_of(&mut children.iter().enumerate().map(|(i, c)| {
                    let l = c.lipschitz_sided();
                    if i == 0 {
                        l
                    } else {
                        Lipschitz {
                            outside: l.inside,
                            inside: l.outside,
                        }
                    }
                }))
            }
            Sdf::Grid {
                data,
                bbox_min,
                bbox_max,
                level,
                ..
            } => {
                let (outside, inside) =
                    grid::lipschitz_sided(data, *bbox_min, *bbox_max, level.value);
                Lipschitz { outside, inside }
            }
            Sdf::Transform { child, .. } | Sdf::Named { child, .. } => child.lipschitz_sided(),
            _ => Lipschitz::from(self.lipschitz_unsided()),
        }
    }

    /// One bound for both sides, for the nodes [`Sdf::lipschitz_sided`] does not split.
    fn lipschitz_unsided(&self) -> f32 {
        match self {
            Sdf::Plane { normal, .. } => normal.length().max(1.0),
            Sdf::Union(children) | Sdf::Intersection(children) | Sdf::Difference(children) => {
                csg::max_lipschitz(children)
            }
            Sdf::SmoothUnion { children, .. } => csg::max_lipschitz(children),
            _ => 1.0,
        }
    }
}

impl Sdf {
    /// Whether the surface is made of flat pieces only (planes, sharp boxes, hard CSG of them): its
    /// curvature is 0 wherever it is smooth, so it has no smooth silhouettes (`κ_n = 0` along every
    /// tangent line) and the boundary estimators skip it. Its crease edges are another matter.
    pub fn is_piecewise_flat(&self) -> bool {
        match self {
            Sdf::Plane { .. } => true,
            Sdf::Box { rounding, .. } => rounding.value == 0.0,
            Sdf::Union(children) | Sdf::Intersection(children) | Sdf::Difference(children) => {
                children.iter().all(Sdf::is_piecewise_flat)
            }
            Sdf::Transform { child, .. } | Sdf::Named { child, .. } => child.is_piecewise_flat(),
            _ => false,
        }
    }
}

/// The spatial gradient at `p` of a function evaluated in [`DualVec3`] (forward-mode AD); zero where
/// it does not evaluate or carries no derivative.
pub(super) fn gradient_by_ad(
    p: glam::Vec3,
    f: impl FnOnce(Vec3<DualVec3>) -> Option<DualVec3>,
) -> glam::Vec3 {
    let q = Vec3::new(
        DualVec3::from_re(p.x).derivative(0),
        DualVec3::from_re(p.y).derivative(1),
        DualVec3::from_re(p.z).derivative(2),
    );
    match f(q).and_then(|v| v.eps.0) {
        Some(g) => glam::Vec3::new(g[0], g[1], g[2]),
        None => glam::Vec3::ZERO,
    }
}

/// `κ = (tr H − gᵀHg/|g|²)/|g|`, guarded: 0 where `|g|` vanishes or the result is not finite.
fn curvature_from(g: glam::Vec3, h: glam::Mat3) -> f32 {
    let g2 = g.length_squared();
    if g2.is_nan() || g2 <= 1e-24 {
        return 0.0;
    }
    let tr = h.x_axis.x + h.y_axis.y + h.z_axis.z;
    let k = (tr - g.dot(h * g) / g2) / g2.sqrt();
    if k.is_finite() { k } else { 0.0 }
}

/// Analytic gradient of the rounded box at `d = p − center`, branch for branch as [`Sdf::eval`] (and so
/// as AD): outside the shrunk box, the direction from its closest point; inside, the axis of the largest
/// `q_i` (ties to the lower axis, as `max_element`), signed by `d` (the positive branch at 0, as `abs`).
/// With `faces` and no rounding, as [`Sdf::eval_faces`]: the axis of the largest `q_i` everywhere.
fn box_gradient(d: glam::Vec3, half_size: glam::Vec3, rounding: f32, faces: bool) -> glam::Vec3 {
    let sign = glam::Vec3::select(d.cmplt(glam::Vec3::ZERO), -glam::Vec3::ONE, glam::Vec3::ONE);
    let q = d.abs() - half_size + glam::Vec3::splat(rounding);
    let (mut axis, mut m) = (0, q.x);
    if q.y > m {
        (axis, m) = (1, q.y);
    }
    if q.z > m {
        (axis, m) = (2, q.z);
    }
    if m > 0.0 && !(faces && rounding == 0.0) {
        q.max(glam::Vec3::ZERO).normalize_or_zero() * sign
    } else {
        let mut g = glam::Vec3::ZERO;
        g[axis] = sign[axis];
        g
    }
}

/// Convenience constructors: plain values in, [`Param`]s (undifferentiated) out; axes normalised.
impl Sdf {
    /// A sphere.
    pub fn sphere(center: impl Into<Param3>, radius: impl Into<Param>) -> Self {
        Sdf::Sphere {
            center: center.into(),
            radius: radius.into(),
        }
    }
    /// A box with half extents `half_size`, edges rounded by `rounding` (outer extents kept).
    pub fn cuboid(
        center: impl Into<Param3>,
        half_size: impl Into<Param3>,
        rounding: impl Into<Param>,
    ) -> Self {
        Sdf::Box {
            center: center.into(),
            half_size: half_size.into(),
            rounding: rounding.into(),
        }
    }
    /// A torus about `axis` (normalised; `+z` if zero).
    pub fn torus(
        center: impl Into<Param3>,
        axis: glam::Vec3,
        major_radius: impl Into<Param>,
        minor_radius: impl Into<Param>,
    ) -> Self {
        Sdf::Torus {
            center: center.into(),
            axis: axis.try_normalize().unwrap_or(glam::Vec3::Z),
            major_radius: major_radius.into(),
            minor_radius: minor_radius.into(),
        }
    }
    /// A capped cylinder about `axis` (normalised; `+z` if zero), rims rounded by `rounding`.
    pub fn cylinder(
        center: impl Into<Param3>,
        axis: glam::Vec3,
        radius: impl Into<Param>,
        half_height: impl Into<Param>,
        rounding: impl Into<Param>,
    ) -> Self {
        Sdf::Cylinder {
            center: center.into(),
            axis: axis.try_normalize().unwrap_or(glam::Vec3::Z),
            radius: radius.into(),
            half_height: half_height.into(),
            rounding: rounding.into(),
        }
    }
    /// The half-space `normal·p ≤ offset` (`normal` normalised; `+z` if zero).
    pub fn plane(normal: glam::Vec3, offset: impl Into<Param>) -> Self {
        Sdf::Plane {
            normal: normal.try_normalize().unwrap_or(glam::Vec3::Z),
            offset: offset.into(),
        }
    }
    /// A hard union (the minimum of the children), with its culling hierarchy.
    pub fn union(children: Vec<Sdf>) -> Self {
        Sdf::Union(children.into())
    }
    /// A hard intersection (the maximum of the children).
    pub fn intersection(children: Vec<Sdf>) -> Self {
        Sdf::Intersection(children.into())
    }
    /// The first child minus the others, with its culling hierarchy.
    pub fn difference(children: Vec<Sdf>) -> Self {
        Sdf::Difference(children.into())
    }
    /// A smooth union with blending radius `k`.
    pub fn smooth_union(children: Vec<Sdf>, k: impl Into<Param>) -> Self {
        Sdf::SmoothUnion {
            children: children.into(),
            k: k.into(),
        }
    }
    /// `child` rotated by `angle_deg` about `axis` (normalised; `+z` if zero), scaled by `scale`, then
    /// translated by `translate`.
    pub fn transform(
        child: Sdf,
        translate: impl Into<Param3>,
        axis: glam::Vec3,
        angle_deg: impl Into<Param>,
        scale: impl Into<Param>,
    ) -> Self {
        let angle: Param = angle_deg.into();
        Sdf::Transform {
            translate: translate.into(),
            axis: axis.try_normalize().unwrap_or(glam::Vec3::Z),
            trig: AngleTrig::of(angle.value),
            angle,
            scale: scale.into(),
            child: Box::new(child),
        }
    }
    /// This node with the values it keeps for speed ([`AngleTrig`], the CSG nodes' culling hierarchies
    /// over their children's boxes) recomputed from its parameters, after they were set in place.
    pub fn refreshed(mut self) -> Self {
        transform::refresh_trig(&mut self);
        culling::refresh(&mut self);
        self
    }

    /// `child` under a name (see [`Sdf::Named`]); the name is not checked here (the scene parser checks
    /// names).
    pub fn named(name: impl Into<String>, child: Sdf) -> Self {
        Sdf::Named {
            name: name.into(),
            child: Box::new(child),
        }
    }
    /// Whether the solid `φ ≤ 0` is convex whatever the parameters' values: spheres, boxes, cylinders,
    /// capsules and half-spaces, intersections of convex solids, and transforms of these. A ray leaving
    /// a convex solid's surface outward cannot meet that solid again (the solid lies behind the tangent
    /// plane at the ray's origin), so ray queries need not trace it ([`crate::scene::Scene::leaving`]).
    pub fn is_convex(&self) -> bool {
        match self {
            Sdf::Sphere { .. } | Sdf::Box { .. } | Sdf::Cylinder { .. } | Sdf::Plane { .. } => true,
            Sdf::Primitive(primitive) => primitive.is_convex(),
            Sdf::Intersection(children) => children.iter().all(Sdf::is_convex),
            Sdf::Transform { child, .. } | Sdf::Named { child, .. } => child.is_convex(),
            _ => false,
        }
    }
    /// The node under any [`Sdf::Named`] wrappers: what to match on when the name does not matter.
    pub fn unnamed(&self) -> &Sdf {
        match self {
            Sdf::Named { child, .. } => child.unnamed(),
            other => other,
        }
    }
    /// A grid node over `[bbox_min, bbox_max]`, after checking the data ([`GridData::validate`]) and that
    /// the box is finite with `bbox_min < bbox_max`.
    pub fn grid(data: GridData, bbox_min: glam::Vec3, bbox_max: glam::Vec3) -> Result<Self> {
        data.validate("grid")?;
        if !(bbox_min.is_finite() && bbox_max.is_finite() && bbox_min.cmplt(bbox_max).all()) {
            return Err(crate::Error::field(
                "grid.bbox",
                format!("must be finite with min < max, got {bbox_min} .. {bbox_max}"),
            ));
        }
        Ok(Sdf::Grid {
            data: Arc::new(data),
            bbox_min,
            bbox_max,
            level: Param::new(0.0),
            selection: BlockValues::Constant,
        })
    }
}
