//! Implicit surfaces: signed distance functions (and other level sets) as a tree of primitives,
//! combinators and transforms.
//!
//! Conventions: `φ(x) < 0` inside, `> 0` outside; the normal `n = ∇φ/|∇φ|` points outward; the total
//! curvature is `κ = ∇·n = (tr H − nᵀHn)/|∇φ|` (`2/r` on a sphere of radius `r`). Every node evaluates
//! generically ([`Sdf::eval`]) so that the same code gives values in `f32`, gradients with
//! [`crate::scalar::DualVec3`], Hessians with [`crate::scalar::Dual2Vec3`] and parameter derivatives with
//! `Dual32`.

use crate::math::{Aabb, Vec3};
use crate::scalar::{Param, Param3, Scalar};
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
    /// Capsule: points within `radius` of the segment `a`–`b`.
    Capsule {
        /// First end of the segment.
        a: Param3,
        /// Second end of the segment.
        b: Param3,
        /// Radius (> 0).
        radius: Param,
    },
    /// Half-space `normal · p − offset ≤ 0`.
    Plane {
        /// Unit normal (pointing out of the solid).
        normal: glam::Vec3,
        /// Signed distance of the plane from the origin along `normal`.
        offset: Param,
    },
    /// Union (minimum) of the children.
    Union(Vec<Sdf>),
    /// Intersection (maximum) of the children.
    Intersection(Vec<Sdf>),
    /// The first child minus all others.
    Difference(Vec<Sdf>),
    /// Smooth union with blending radius `k` (polynomial smooth minimum, C1; k > 0).
    SmoothUnion {
        /// Children (at least one).
        children: Vec<Sdf>,
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
        /// The transformed node.
        child: Box<Sdf>,
    },
    /// Samples over the box `[bbox_min, bbox_max]`, interpolated with C2 cubic B-splines.
    Grid {
        /// The samples (shared: grids can be large).
        data: Arc<GridData>,
        /// Lower corner of the grid box (first sample).
        bbox_min: glam::Vec3,
        /// Upper corner of the grid box (last sample).
        bbox_max: glam::Vec3,
    },
}

impl Sdf {
    /// `φ(p)`, generic over the scalar type.
    pub fn eval<S: Scalar>(&self, p: Vec3<S>) -> S {
        match self {
            Sdf::Sphere { center, radius } => (p - center.get::<S>()).length() - radius.get::<S>(),
            Sdf::Box {
                center,
                half_size,
                rounding,
            } => {
                let r = rounding.get::<S>();
                let q = (p - center.get::<S>()).abs() - half_size.get::<S>() + Vec3::splat(r);
                q.max_f32(0.0).length() + q.max_element().min(S::zero()) - r
            }
            _ => todo!("sdf: remaining nodes"),
        }
    }

    /// `φ(p)` in `f32`, the tracer's entry point.
    #[inline]
    pub fn eval_f32(&self, p: glam::Vec3) -> f32 {
        self.eval::<f32>(p.into())
    }

    /// `∇φ(p)` (not normalised).
    pub fn gradient(&self, p: glam::Vec3) -> glam::Vec3 {
        let _ = p;
        todo!("sdf: gradient")
    }

    /// Outward unit normal `∇φ/|∇φ|`; `+z` where the gradient vanishes.
    pub fn normal(&self, p: glam::Vec3) -> glam::Vec3 {
        self.gradient(p).try_normalize().unwrap_or(glam::Vec3::Z)
    }

    /// Total curvature `κ = ∇·n` at `p` (sum of principal curvatures; positive on convex surfaces).
    pub fn curvature(&self, p: glam::Vec3) -> f32 {
        let _ = p;
        todo!("sdf: curvature")
    }

    /// A box holding the whole surface and interior (`φ ≤ 0`); [`Aabb::INFINITE`] for unbounded nodes.
    pub fn bounds(&self) -> Aabb {
        todo!("sdf: bounds")
    }

    /// An upper bound on `|∇φ|` everywhere: sphere tracing steps by `φ / L`.
    pub fn lipschitz(&self) -> f32 {
        todo!("sdf: lipschitz")
    }
}
