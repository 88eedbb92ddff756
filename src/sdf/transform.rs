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
fn rotate<S: Scalar>(v: Vec3<S>, k: glam::Vec3, c: S, s: S) -> Vec3<S> {
    let [x, y, z] = rotate_components([v.x, v.y, v.z], k, c, s, S::one());
    Vec3::new(x, y, z)
}

/// [`rotate`]'s formula for coordinates of any type `T` and a cosine and sine of type `C` (`1` is
/// `one`): one formula for a scalar type (`T = C`) and for eight rays' coordinates in SIMD lanes
/// with the `f32` cosine and sine, so that all give the same bits.
#[inline(always)]
fn rotate_components<T, C>([x, y, z]: [T; 3], k: glam::Vec3, c: C, s: C, one: C) -> [T; 3]
where
    T: Copy
        + std::ops::Add<Output = T>
        + std::ops::Sub<Output = T>
        + std::ops::Mul<f32, Output = T>
        + std::ops::Mul<C, Output = T>,
    C: Copy + std::ops::Sub<Output = C>,
{
    let kxv = [z * k.y - y * k.z, x * k.z - z * k.x, y * k.x - x * k.y];
    let kv = (x * k.x + y * k.y + z * k.z) * (one - c);
    [
        x * c + kxv[0] * s + kv * k.x,
        y * c + kxv[1] * s + kv * k.y,
        z * c + kxv[2] * s + kv * k.z,
    ]
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
    crate::declare::walk_mut(sdf, "", &mut |_, node| {
        if let Sdf::Transform { angle, trig, .. } = node {
            *trig = AngleTrig::of(angle.value);
        }
    });
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
        let (o, d) = self.to_child_ray_lanes(ray.o.to_array(), ray.d.to_array());
        Ray::new(o.into(), d.into())
    }

    /// [`Similarity::to_child_ray`] of rays whose coordinates are of type `T`: `f32` for one ray,
    /// `wide::f32x8` for eight rays in SIMD lanes, with the same operations in the same order, so
    /// each lane's ray is that ray's [`Similarity::to_child_ray`] bit for bit.
    pub fn to_child_ray_lanes<T>(&self, o: [T; 3], d: [T; 3]) -> ([T; 3], [T; 3])
    where
        T: Copy
            + std::ops::Add<Output = T>
            + std::ops::Sub<Output = T>
            + std::ops::Sub<f32, Output = T>
            + std::ops::Mul<f32, Output = T>
            + std::ops::Div<f32, Output = T>,
    {
        let back = |v: [T; 3]| match self.rotation {
            Some(r) => rotate_components(v, self.axis, r.cos, r.inverse_sin, 1.0),
            None => v,
        };
        let s = self.scale();
        let t = self.translate;
        let o = back([o[0] - t.x, o[1] - t.y, o[2] - t.z]);
        (o.map(|v| v / s), back(d).map(|v| v / s))
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

impl Sdf {
    /// A transform node's change of frame and its child; `None` for any other node (names are not
    /// looked through).
    ///
    /// The similarity is the node's [`Similarity::primal`] (its parameter values, without
    /// derivatives): its `from_child_*` methods map a point `p` of the child's frame out to
    /// `x = t + s R p` in this node's, its `to_child_*` methods map `x` back to `R⁻¹(x − t)/s`.
    #[inline]
    pub fn frame(&self) -> Option<(Similarity, &Sdf)> {
        match self {
            Sdf::Transform {
                translate,
                axis,
                angle,
                scale,
                trig,
                child,
            } => Some((
                Similarity::primal(translate, *axis, angle, *trig, scale),
                child,
            )),
            _ => None,
        }
    }

    /// Point `p` of this node's frame in the frame of the chain of transform nodes at the top of the
    /// tree (names skipped): through each transform's inverse, down to the first node that is neither
    /// (`p` itself when the tree has no transform at its top). Volume textures are read there.
    #[inline]
    pub fn to_root_frame<S: Scalar>(&self, p: Vec3<S>) -> Vec3<S> {
        match self {
            Sdf::Named { child, .. } => child.to_root_frame(p),
            Sdf::Transform {
                translate,
                axis,
                angle,
                trig,
                scale,
                child,
            } => {
                let frame = Similarity::<S>::for_eval(translate, *axis, angle, *trig, scale);
                child.to_root_frame(frame.to_child_point(p))
            }
            _ => p,
        }
    }
}

/// `φ(x) = s φ_child(R⁻¹(x − t)/s)`.
#[inline(always)]
pub(super) fn eval<S: Scalar, const FACES: bool>(
    p: Vec3<S>,
    translate: &Param3,
    axis: glam::Vec3,
    angle: &Param,
    trig: AngleTrig,
    scale: &Param,
    child: &Sdf,
) -> S {
    let frame = Similarity::<S>::for_eval(translate, axis, angle, trig, scale);
    frame.from_child_length(child.eval_as::<S, FACES>(frame.to_child_point(p)))
}

/// The declaration of the transform node's fields ([`crate::declare`]).
pub(super) mod kinds {
    use crate::declare::{Components::Xyz, Field, Kind, Rule, Value, on};
    use crate::sdf::Sdf;

    /// `{"type": "transform", "translate" (default 0), "rotate": {"axis", "angle"} (default none),
    /// "scale" (default 1), "child"}`.
    pub(in crate::sdf) const TRANSFORM: Kind<Sdf> = Kind {
        type_name: "transform",
        fields: &[
            Field::vector(
                "translate",
                on!(Sdf::Transform { translate, .. } => translate),
                Xyz,
                Some(0.0),
                Rule::Any,
            ),
            Field {
                key: "rotate",
                value: Value::Rotation {
                    axis: on!(Sdf::Transform { axis, .. } => axis),
                    angle: on!(Sdf::Transform { angle, .. } => angle),
                    keyed: false,
                },
            },
            Field::number(
                "scale",
                on!(Sdf::Transform { scale, .. } => scale),
                Some(1.0),
                Rule::Positive,
            ),
            Field {
                key: "child",
                value: Value::Child(on!(Sdf::Transform { child, .. } => child)),
            },
        ],
        blank: || {
            let placeholder = Sdf::union(Vec::new());
            Sdf::transform(placeholder, glam::Vec3::ZERO, glam::Vec3::Y, 0.0, 1.0)
        },
        example: r#"{"type": "transform", "translate": [0.1, 0.2, 0], "rotate": {"axis": [0, 0, 1], "angle": 30},
                     "scale": 1.5, "child": {"type": "sphere", "center": [0, 0.3, 0], "radius": 0.4}}"#,
    };
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scalar::Dual32;

    /// Transforms with rotations about skew and coordinate axes, small and large scales, and the
    /// identity, to map across.
    fn frames() -> Vec<Similarity> {
        vec![
            Similarity::new(
                glam::Vec3::new(1.0, 2.0, -0.5),
                glam::Vec3::new(1.0, 2.0, 3.0).normalize(),
                37.0,
                1.7,
            ),
            Similarity::new(glam::Vec3::new(-3.0, 0.25, 4.0), glam::Vec3::Z, -120.0, 0.3),
            Similarity::new(glam::Vec3::ZERO, glam::Vec3::X, 90.0, 4.0),
            Similarity::new(glam::Vec3::ZERO, glam::Vec3::Y, 0.0, 1.0),
        ]
    }

    /// Points around the origin, on the axes and off them, near and far.
    fn points() -> Vec<glam::Vec3> {
        let mut out = vec![glam::Vec3::ZERO];
        for i in 0..27 {
            let c = glam::Vec3::new((i % 3) as f32, ((i / 3) % 3) as f32, (i / 9) as f32) - 1.0;
            out.push(c * 0.7 + glam::Vec3::new(0.1, -0.2, 0.3) * (i as f32 / 9.0));
        }
        out.push(glam::Vec3::new(50.0, -20.0, 10.0));
        out
    }

    fn close(a: glam::Vec3, b: glam::Vec3, tol: f32) -> bool {
        (a - b).length() <= tol * (1.0 + a.length().max(b.length()))
    }

    /// Into the child's frame and back (and back and in) is the identity, for points, directions,
    /// gradients, lengths and rays; directions and lengths scale alike.
    #[test]
    fn round_trips() {
        for f in frames() {
            for x in points() {
                let xs = Vec3::<f32>::from(x);
                let p: glam::Vec3 = f.to_child_point(xs).into();
                assert!(
                    close(f.from_child_point(p.into()).into(), x, 1e-6),
                    "{f:?} {x}"
                );
                let back: glam::Vec3 = f.to_child_point(f.from_child_point(xs)).into();
                assert!(close(back, x, 1e-6), "{f:?} {x}");
                let v: glam::Vec3 = f.to_child_vector(xs).into();
                assert!(close(f.from_child_vector(v.into()).into(), x, 1e-6));
                assert!((v.length() - x.length() / f.scale()).abs() <= 1e-6 * (1.0 + v.length()));
                let g: glam::Vec3 = f.to_child_gradient(xs).into();
                assert!(close(f.from_child_gradient(g.into()).into(), x, 1e-6));
                assert!((g.length() - x.length()).abs() <= 1e-6 * (1.0 + x.length()));
                let l = x.length();
                let back = f.from_child_length(f.to_child_length(l));
                assert!((back - l).abs() <= 1e-6 * (1.0 + l));
                assert!((f.to_child_length(l) - v.length()).abs() <= 1e-6 * (1.0 + l));
                let ray = Ray::new(x, glam::Vec3::new(0.3, -0.8, 0.52).normalize());
                let local = f.to_child_ray(&ray);
                let again = f.from_child_ray(&local);
                assert!(close(again.o, ray.o, 1e-6) && close(again.d, ray.d, 1e-6));
                // The same parameter on both sides.
                for t in [-2.0, 0.0, 0.5, 3.0] {
                    let p: glam::Vec3 = f.to_child_point(ray.at(t).into()).into();
                    assert!(close(local.at(t), p, 1e-6), "{f:?} {x} {t}");
                }
            }
        }
    }

    /// A rotation about the `z` axis by 90° and a scale of 2 map as a hand calculation says.
    #[test]
    fn maps_by_hand() {
        let f = Similarity::new(glam::Vec3::new(1.0, 0.0, 0.0), glam::Vec3::Z, 90.0, 2.0);
        let out: glam::Vec3 = f.from_child_point(Vec3::new(1.0, 0.0, 0.0)).into();
        assert!(close(out, glam::Vec3::new(1.0, 2.0, 0.0), 1e-6), "{out}");
        let v: glam::Vec3 = f.to_child_vector(Vec3::new(0.0, 2.0, 0.0)).into();
        assert!(close(v, glam::Vec3::new(1.0, 0.0, 0.0), 1e-6), "{v}");
        let g: glam::Vec3 = f.from_child_gradient(Vec3::new(1.0, 0.0, 0.0)).into();
        assert!(close(g, glam::Vec3::Y, 1e-6), "{g}");
        assert_eq!(f.from_child_length(0.5), 1.0);
    }

    /// A mapped box holds its mapped corners and the mapped points inside it, both ways; empty and
    /// infinite boxes stay so.
    #[test]
    fn boxes_hold_their_mapped_points() {
        let b = Aabb::new(
            glam::Vec3::new(-0.5, 0.2, -1.0),
            glam::Vec3::new(0.7, 0.9, 2.0),
        );
        for f in frames() {
            let (out, into) = (f.from_child_box(&b), f.to_child_box(&b));
            for i in 0..=4 {
                for j in 0..=4 {
                    for k in 0..=4 {
                        let u = glam::Vec3::new(i as f32, j as f32, k as f32) / 4.0;
                        let p = b.min + (b.max - b.min) * u;
                        assert!(
                            out.contains(f.from_child_point(p.into()).into()),
                            "{f:?} {p}"
                        );
                        assert!(
                            into.contains(f.to_child_point(p.into()).into()),
                            "{f:?} {p}"
                        );
                    }
                }
            }
            // Not much more than the mapped box: a rotation grows a box by at most √3.
            let grow = |a: &Aabb| a.extent().length();
            assert!(grow(&out) <= 3f32.sqrt() * f.scale() * grow(&b) * 1.001);
            assert!(grow(&into) <= 3f32.sqrt() / f.scale() * grow(&b) * 1.001);
            assert!(f.from_child_box(&Aabb::EMPTY).is_empty());
            assert!(f.to_child_box(&Aabb::EMPTY).is_empty());
            let half = Aabb::new(
                glam::Vec3::splat(-1.0),
                glam::Vec3::new(1.0, 1.0, f32::INFINITY),
            );
            assert_eq!(f.from_child_box(&half), Aabb::INFINITE);
            assert_eq!(f.to_child_box(&half), Aabb::INFINITE);
        }
    }

    /// The matrix form maps as the point map does.
    #[test]
    fn affine_form_maps_points() {
        for f in frames() {
            let (m, c) = f.to_child_affine();
            for x in points() {
                let p: glam::Vec3 = f.to_child_point(x.into()).into();
                assert!(close(m * x + c, p, 1e-6), "{f:?} {x}");
            }
        }
    }

    /// The gradient of a transformed node is its child's gradient mapped out
    /// ([`Similarity::from_child_gradient`]) and matches central differences of its value.
    #[test]
    fn gradients_map_with_eval() {
        let child = Sdf::cuboid([0.1, -0.2, 0.3], [0.5, 0.7, 0.9], 0.2);
        for f in frames() {
            let node = Sdf::transform(
                child.clone(),
                glam::Vec3::from(f.translate),
                f.axis,
                angle_of(&f),
                f.scale(),
            );
            for x in points() {
                let g = node.gradient(x);
                let p: glam::Vec3 = f.to_child_point(x.into()).into();
                let mapped: glam::Vec3 = f.from_child_gradient(child.gradient(p).into()).into();
                assert!(close(g, mapped, 1e-5), "{f:?} {x}: {g} vs {mapped}");
                let back: glam::Vec3 = f.to_child_gradient(g.into()).into();
                assert!(close(back, child.gradient(p), 1e-5));
                let h = 1e-3;
                let fd = glam::Vec3::from_array(std::array::from_fn(|i| {
                    let mut e = glam::Vec3::ZERO;
                    e[i] = h;
                    (node.eval_f32(x + e) - node.eval_f32(x - e)) / (2.0 * h)
                }));
                assert!(close(fd, g, 2e-2), "{f:?} {x}: {fd} vs {g}");
            }
        }
    }

    /// The angle of one of [`frames`], recovered from its cosine and sine.
    fn angle_of(f: &Similarity) -> f32 {
        let r = f.rotation.unwrap();
        r.sin.atan2(r.cos).to_degrees()
    }

    /// With the angle lifted into a dual number, a mapped point carries its derivative with respect to
    /// the angle (both ways), which matches central differences.
    #[test]
    fn lifted_angle_differentiates_mapped_points() {
        let (translate, axis) = (
            Param3::from([0.3, -1.0, 2.0]),
            glam::Vec3::new(-1.0, 0.5, 2.0).normalize(),
        );
        let scale = Param::new(1.3);
        for degrees in [0.0, 25.0, -140.0] {
            let angle = Param {
                value: degrees,
                slot: Some(0),
            };
            let f = Similarity::<Dual32>::lifted(&translate, axis, &angle, &scale);
            let at = |d: f32| Similarity::new(translate.value(), axis, d, scale.value);
            let h = 0.05;
            for x in points() {
                let xs = Vec3::<Dual32>::constant(x);
                for into in [true, false] {
                    let map = |f: Similarity<Dual32>| {
                        if into {
                            f.to_child_point(xs)
                        } else {
                            f.from_child_point(xs)
                        }
                    };
                    let mapped = map(f);
                    let primal = |d: f32| map(at(d).constant()).primal();
                    let derivative = glam::Vec3::new(mapped.x.eps, mapped.y.eps, mapped.z.eps);
                    let fd = (primal(degrees + h) - primal(degrees - h)) / (2.0 * h);
                    assert!(
                        close(derivative, fd, 2e-3),
                        "{degrees} {x}: {derivative} vs {fd}"
                    );
                    assert!(close(mapped.primal(), primal(degrees), 1e-6));
                }
            }
        }
    }

    /// The primal frame with the node's kept cosine and sine maps bit for bit as the frame lifted into
    /// `f32` (computing them afresh), and a stale [`AngleTrig`] is not used.
    #[test]
    fn kept_trig_is_exact_and_never_stale() {
        let (translate, scale) = (Param3::from([0.3, -1.0, 2.0]), Param::new(0.7));
        let axis = glam::Vec3::new(2.0, -1.0, 0.5).normalize();
        for degrees in [0.0, 1e-3, 17.5, 90.0, -33.3, 179.9, 360.0, 1234.5] {
            let angle = Param::new(degrees);
            let kept = Similarity::primal(&translate, axis, &angle, AngleTrig::of(degrees), &scale);
            let stale = Similarity::primal(
                &translate,
                axis,
                &angle,
                AngleTrig::of(degrees + 1.0),
                &scale,
            );
            let lifted = Similarity::<f32>::lifted(&translate, axis, &angle, &scale);
            assert_eq!(kept, lifted);
            assert_eq!(stale, lifted);
            let (s, c) = degrees.to_radians().sin_cos();
            let r = kept.rotation.unwrap();
            assert_eq!(
                (r.cos.to_bits(), r.sin.to_bits()),
                (c.to_bits(), s.to_bits())
            );
        }
    }
}
