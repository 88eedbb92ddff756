//! Similarity transforms of a node: rotation about a unit axis, uniform scale, translation.
//!
//! `x = t + s R p_local`, so `p_local = R⁻¹(x − t)/s` and `φ(x) = s φ_child(p_local)`, which keeps a
//! distance a distance (and the child's Lipschitz bound: `∇φ = R ∇φ_child`). `R` is built from the
//! lifted angle (Rodrigues' formula), so the angle, the scale and the translation are differentiable.
//!
//! [`Similarity`] is the one change of frame between a transform node and its child: evaluation,
//! bounds, carried motions, crease edges, closed-form line crossings and empty-space maps all take
//! points, directions, rays, boxes, gradients and lengths across it with its methods.

use super::Sdf;
use crate::math::{Aabb, Ray, Vec3};
use crate::scalar::{Param, Param3, Scalar};

/// Rotate `v` by the angle with cosine `c` and sine `s` about the unit axis `k` (Rodrigues):
/// `v c + (k × v) s + k (k·v)(1 − c)`. Pass `−s` for the inverse rotation.
#[inline(always)]
pub(super) fn rotate<S: Scalar>(v: Vec3<S>, k: glam::Vec3, c: S, s: S) -> Vec3<S> {
    let kxv = Vec3::new(
        v.z * k.y - v.y * k.z,
        v.x * k.z - v.z * k.x,
        v.y * k.x - v.x * k.y,
    );
    let kv = v.dot_f32(k) * (S::one() - c);
    Vec3::new(
        v.x * c + kxv.x * s + kv * k.x,
        v.y * c + kxv.y * s + kv * k.y,
        v.z * c + kxv.z * s + kv * k.z,
    )
}

/// The cosine and sine of a transform's angle, computed once when the node is built: the tracer
/// evaluates a node whose angle is not differentiated many times per ray. Keyed by the angle's value:
/// an angle changed in place (a parameter set, a finite-difference step) no longer matches and is
/// computed afresh, never served stale.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct AngleTrig {
    /// The angle (degrees) the values belong to.
    pub degrees: f32,
    /// Its cosine.
    pub cos: f32,
    /// Its sine.
    pub sin: f32,
}

impl AngleTrig {
    /// The cosine and sine of `degrees`, rounded exactly as [`Similarity`] computes them from a lifted
    /// angle (and as `degrees.to_radians().sin_cos()` does).
    pub fn of(degrees: f32) -> Self {
        let theta = degrees * (std::f32::consts::PI / 180.0);
        Self {
            degrees,
            cos: theta.cos(),
            sin: theta.sin(),
        }
    }

    /// These values if they belong to `degrees`, else those of `degrees` computed afresh.
    #[inline]
    fn fresh(self, degrees: f32) -> Self {
        if self.degrees == degrees {
            self
        } else {
            Self::of(degrees)
        }
    }
}

/// Recomputes the [`AngleTrig`] of every transform under `sdf` from its angle's current value (after
/// parameters were set in place).
pub(super) fn refresh_trig(sdf: &mut Sdf) {
    match sdf {
        Sdf::Transform {
            angle, trig, child, ..
        } => {
            *trig = AngleTrig::of(angle.value);
            refresh_trig(child);
        }
        Sdf::Union(children)
        | Sdf::Intersection(children)
        | Sdf::Difference(children)
        | Sdf::SmoothUnion { children, .. } => children.iter_mut().for_each(refresh_trig),
        Sdf::Named { child, .. } => refresh_trig(child),
        _ => {}
    }
}

/// The rotation of a [`Similarity`]: the angle's cosine and sine, and the sine the inverse rotation
/// uses. That is `−sin`, kept as each constructor rounds it: negating a lifted constant and lifting a
/// negated value differ in the sign of a zero derivative, which the images' bits can see.
#[derive(Copy, Clone, Debug, PartialEq)]
struct Rotation<S> {
    cos: S,
    sin: S,
    inverse_sin: S,
}

/// The uniform scale of a [`Similarity`] and its reciprocal, as each constructor rounds it.
#[derive(Copy, Clone, Debug, PartialEq)]
struct Scale<S> {
    scale: S,
    inverse: S,
}

/// The change of frame of a transform node, `x = t + s R p` (parent `x`, child `p`; `R` the rotation
/// by an angle about a unit axis, `s > 0` a uniform scale), both ways, generic over the scalar so that
/// lifted parameters carry their derivatives through it (as fidget's `Transformable` maps points for
/// every evaluator type).
///
/// | quantity | into the child's frame | back |
/// |---|---|---|
/// | point | `R⁻¹(x − t)/s` | `t + s R p` |
/// | direction | `R⁻¹ v/s` | `s R v` |
/// | ray `o + τ d` | `R⁻¹(o − t)/s + τ R⁻¹ d/s` (the same `τ`) | `t + s R o + τ s R d` |
/// | gradient of a function | `R⁻¹ g` (with `φ = s φ_child`, the scales cancel) | `R g` |
/// | distance, length | `l/s` | `s l` |
/// | box | the box of the mapped corners | the same |
///
/// The constructors decide where the derivatives come from: [`Similarity::lifted`] lifts every
/// parameter, [`Similarity::primal`] takes their values (with the node's kept [`AngleTrig`]) and
/// [`Similarity::constant`] carries a primal one into another scalar type without derivatives.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Similarity<S = f32> {
    translate: Vec3<S>,
    axis: glam::Vec3,
    /// `None`: no rotation (an angle of exactly 0 that is not differentiated), skipped rather than
    /// multiplied by 1 and 0 (which would turn an infinite coordinate into NaN).
    rotation: Option<Rotation<S>>,
    /// `None`: a scale of exactly 1 that is not differentiated, skipped.
    scale: Option<Scale<S>>,
}

impl<S: Scalar> Similarity<S> {
    /// The similarity of a transform node's parameters, each lifted into `S` ([`Param::get`]): its
    /// maps carry the derivatives of the translation, the angle and the scale. `axis` is a unit vector;
    /// `angle` in degrees.
    #[inline(always)]
    pub fn lifted(translate: &Param3, axis: glam::Vec3, angle: &Param, scale: &Param) -> Self {
        let scale = scale.get::<S>();
        Self {
            translate: translate.get::<S>(),
            axis,
            rotation: Some(Rotation::lifted(angle)),
            scale: Some(Scale {
                scale,
                inverse: scale.recip(),
            }),
        }
    }

    /// [`Similarity::lifted`] for evaluating `φ`, the tracer's inner loop: the node's kept cosine and
    /// sine where the angle is not differentiated, and an angle of 0 or a scale of 1 that is not
    /// differentiated skipped (the identity, with no derivative to lose).
    #[inline(always)]
    pub(super) fn for_eval(
        translate: &Param3,
        axis: glam::Vec3,
        angle: &Param,
        trig: AngleTrig,
        scale: &Param,
    ) -> Self {
        let rotation = if angle.slot.is_none() && trig.degrees == angle.value {
            (angle.value != 0.0).then(|| Rotation {
                cos: S::constant(trig.cos),
                sin: S::constant(trig.sin),
                inverse_sin: S::constant(-trig.sin),
            })
        } else if angle.value != 0.0 || angle.slot.is_some() {
            Some(Rotation::lifted(angle))
        } else {
            None
        };
        let scale = (scale.value != 1.0 || scale.slot.is_some()).then(|| {
            let scale = scale.get::<S>();
            Scale {
                scale,
                inverse: scale.recip(),
            }
        });
        Self {
            translate: translate.get::<S>(),
            axis,
            rotation,
            scale,
        }
    }

    /// The scale `s` (1 where it is skipped).
    #[inline]
    pub fn scale(&self) -> S {
        self.scale.map_or(S::one(), |s| s.scale)
    }

    #[inline(always)]
    fn rotate_forward(&self, v: Vec3<S>) -> Vec3<S> {
        match self.rotation {
            Some(r) => rotate(v, self.axis, r.cos, r.sin),
            None => v,
        }
    }

    #[inline(always)]
    fn rotate_back(&self, v: Vec3<S>) -> Vec3<S> {
        match self.rotation {
            Some(r) => rotate(v, self.axis, r.cos, r.inverse_sin),
            None => v,
        }
    }

    #[inline(always)]
    fn shrink(&self, v: Vec3<S>) -> Vec3<S> {
        match self.scale {
            Some(s) => v * s.inverse,
            None => v,
        }
    }

    #[inline(always)]
    fn grow(&self, v: Vec3<S>) -> Vec3<S> {
        match self.scale {
            Some(s) => v * s.scale,
            None => v,
        }
    }

    /// A point into the child's frame: `R⁻¹(x − t) · (1/s)`.
    #[inline(always)]
    pub fn to_child_point(&self, x: Vec3<S>) -> Vec3<S> {
        self.shrink(self.rotate_back(x - self.translate))
    }

    /// A point of the child's frame out into the parent's: `t + (R p) · s`.
    #[inline(always)]
    pub fn from_child_point(&self, p: Vec3<S>) -> Vec3<S> {
        self.translate + self.grow(self.rotate_forward(p))
    }

    /// A direction (a difference of points) into the child's frame: `R⁻¹ v · (1/s)`.
    #[inline]
    pub fn to_child_vector(&self, v: Vec3<S>) -> Vec3<S> {
        self.shrink(self.rotate_back(v))
    }

    /// A direction of the child's frame out into the parent's: `(R v) · s`.
    #[inline]
    pub fn from_child_vector(&self, v: Vec3<S>) -> Vec3<S> {
        self.grow(self.rotate_forward(v))
    }

    /// The gradient `g = ∇φ(x)` of a node's function as the gradient of its child's at the mapped
    /// point: `∇φ_child(p) = R⁻¹ g`, since `φ(x) = s φ_child(R⁻¹(x − t)/s)` (the scales cancel).
    #[inline]
    pub fn to_child_gradient(&self, g: Vec3<S>) -> Vec3<S> {
        self.rotate_back(g)
    }

    /// The gradient of the node's function from its child's: `∇φ(x) = R ∇φ_child(p)`.
    #[inline]
    pub fn from_child_gradient(&self, g: Vec3<S>) -> Vec3<S> {
        self.rotate_forward(g)
    }

    /// A length or distance into the child's frame: `l · (1/s)`.
    #[inline]
    pub fn to_child_length(&self, l: S) -> S {
        match self.scale {
            Some(s) => l * s.inverse,
            None => l,
        }
    }

    /// A length or distance (the child's value of `φ`) out into the parent's frame: `l · s`.
    #[inline(always)]
    pub fn from_child_length(&self, l: S) -> S {
        match self.scale {
            Some(s) => l * s.scale,
            None => l,
        }
    }
}

impl<S: Scalar> Rotation<S> {
    /// The cosine and sine of the lifted angle, in degrees.
    #[inline(always)]
    fn lifted(angle: &Param) -> Self {
        let theta = angle.get::<S>() * (std::f32::consts::PI / 180.0);
        let (cos, sin) = (theta.cos(), theta.sin());
        Self {
            cos,
            sin,
            inverse_sin: -sin,
        }
    }
}

impl Similarity<f32> {
    /// The similarity of a transform node's parameter values, its sine and cosine from `trig` when it
    /// belongs to `angle`'s value (the same values as computed afresh).
    pub fn primal(
        translate: &Param3,
        axis: glam::Vec3,
        angle: &Param,
        trig: AngleTrig,
        scale: &Param,
    ) -> Self {
        Self::with_trig(
            translate.value(),
            axis,
            trig.fresh(angle.value),
            scale.value,
        )
    }

    /// `x = translate + scale R p`, `R` the rotation by `degrees` about the unit `axis`.
    pub fn new(translate: glam::Vec3, axis: glam::Vec3, degrees: f32, scale: f32) -> Self {
        Self::with_trig(translate, axis, AngleTrig::of(degrees), scale)
    }

    fn with_trig(translate: glam::Vec3, axis: glam::Vec3, trig: AngleTrig, scale: f32) -> Self {
        Self {
            translate: translate.into(),
            axis,
            rotation: Some(Rotation {
                cos: trig.cos,
                sin: trig.sin,
                inverse_sin: -trig.sin,
            }),
            scale: Some(Scale {
                scale,
                inverse: scale.recip(),
            }),
        }
    }

    /// The same map in `S`, with no derivatives.
    #[inline]
    pub fn constant<S: Scalar>(&self) -> Similarity<S> {
        Similarity {
            translate: Vec3::constant(self.translate.into()),
            axis: self.axis,
            rotation: self.rotation.map(|r| Rotation {
                cos: S::constant(r.cos),
                sin: S::constant(r.sin),
                inverse_sin: S::constant(r.inverse_sin),
            }),
            scale: self.scale.map(|s| Scale {
                scale: S::constant(s.scale),
                inverse: S::constant(s.inverse),
            }),
        }
    }

    /// A ray into the child's frame, `o' = R⁻¹(o − t)/s`, `d' = R⁻¹ d/s`: the point at parameter `τ`
    /// maps to the point at the same `τ` (`d'` is not a unit vector unless `s = 1`).
    ///
    /// Divides by `s` where [`Similarity::to_child_point`] multiplies by `1/s`: the two can differ in the
    /// last bit, and the closed-form crossings ([`Sdf::line_crossings`]) have always divided.
    pub fn to_child_ray(&self, ray: &Ray) -> Ray {
        let back = |v: glam::Vec3| -> glam::Vec3 { self.rotate_back(v.into()).into() };
        let s = self.scale();
        Ray::new(
            back(ray.o - glam::Vec3::from(self.translate)) / s,
            back(ray.d) / s,
        )
    }

    /// A ray of the child's frame out into the parent's: `o = t + s R o'`, `d = s R d'`, the same
    /// parameter `τ` (the inverse of [`Similarity::to_child_ray`]).
    pub fn from_child_ray(&self, ray: &Ray) -> Ray {
        Ray::new(
            self.from_child_point(ray.o.into()).into(),
            self.from_child_vector(ray.d.into()).into(),
        )
    }

    /// The box of a child's box's eight corners mapped out (empty stays empty, infinite infinite),
    /// grown by a few ulps of its size and of the translation for the rounding of the rotation, so
    /// that points sampled on the child's surface and mapped stay inside.
    pub fn from_child_box(&self, b: &Aabb) -> Aabb {
        let t = glam::Vec3::from(self.translate).abs().max_element();
        map_box(
            b,
            |p| self.from_child_point(p.into()).into(),
            |out| 1e-6 * (out.extent().max_element() + t),
        )
    }

    /// The box of a box's eight corners mapped into the child's frame (empty stays empty, infinite
    /// infinite), grown by a few ulps of its size and of its distance from the child's origin.
    pub fn to_child_box(&self, b: &Aabb) -> Aabb {
        map_box(
            b,
            |x| self.to_child_point(x.into()).into(),
            |out| 1e-6 * (out.extent().max_element() + out.magnitude()),
        )
    }

    /// The map into the child's frame as a matrix and an offset: `p = M x + c` with `M = R⁻¹/s`
    /// (its columns the rotated axes times `1/s`) and `c = −M t`.
    pub fn to_child_affine(&self) -> (glam::Mat3, glam::Vec3) {
        let back = |v: glam::Vec3| -> glam::Vec3 { self.rotate_back(v.into()).into() };
        let m = glam::Mat3::from_cols(
            back(glam::Vec3::X),
            back(glam::Vec3::Y),
            back(glam::Vec3::Z),
        ) * (1.0 / self.scale());
        (m, -(m * glam::Vec3::from(self.translate)))
    }
}

/// The box of `b`'s eight corners under `map`, grown by `margin` of it; an empty box stays empty and
/// an unbounded one maps to the whole space.
fn map_box(
    b: &Aabb,
    map: impl Fn(glam::Vec3) -> glam::Vec3,
    margin: impl Fn(&Aabb) -> f32,
) -> Aabb {
    if b.is_empty() {
        return *b;
    }
    if !b.is_finite() {
        return Aabb::INFINITE;
    }
    let mut out = Aabb::EMPTY;
    for corner in b.corners() {
        let x = map(corner);
        out = out.union(&Aabb::new(x, x));
    }
    out.expanded(margin(&out))
}

/// `φ(x) = s φ_child(R⁻¹(x − t)/s)`.
#[inline(always)]
pub(super) fn eval<S: Scalar>(
    p: Vec3<S>,
    translate: &Param3,
    axis: glam::Vec3,
    angle: &Param,
    trig: AngleTrig,
    scale: &Param,
    child: &Sdf,
) -> S {
    let frame = Similarity::<S>::for_eval(translate, axis, angle, trig, scale);
    frame.from_child_length(child.eval(frame.to_child_point(p)))
}
