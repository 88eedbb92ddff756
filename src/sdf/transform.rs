//! Similarity transforms of a node: rotation about a unit axis, uniform scale, translation.
//!
//! `x = t + s R p_local`, so `p_local = R⁻¹(x − t)/s` and `φ(x) = s φ_child(p_local)`, which keeps a
//! distance a distance (and the child's Lipschitz bound: `∇φ = R ∇φ_child`). `R` is built from the
//! lifted angle (Rodrigues' formula), so the angle, the scale and the translation are differentiable.

use super::Sdf;
use crate::math::{Aabb, Vec3};
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
    /// The cosine and sine of `degrees`, rounded exactly as `eval` computes them.
    pub fn of(degrees: f32) -> Self {
        let theta = degrees * (std::f32::consts::PI / 180.0);
        Self {
            degrees,
            cos: theta.cos(),
            sin: theta.sin(),
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
    let mut q = p - translate.get::<S>();
    // A zero, undifferentiated angle is the identity: skip the sine and cosine (the common case of a
    // translated or scaled node) without losing any derivative.
    if angle.slot.is_none() && trig.degrees == angle.value {
        if angle.value != 0.0 {
            q = rotate(q, axis, S::constant(trig.cos), S::constant(-trig.sin));
        }
    } else if angle.value != 0.0 || angle.slot.is_some() {
        let theta = angle.get::<S>() * (std::f32::consts::PI / 180.0);
        let (c, s) = (theta.cos(), theta.sin());
        q = rotate(q, axis, c, -s);
    }
    let s = scale.get::<S>();
    if scale.value == 1.0 && scale.slot.is_none() {
        return child.eval(q);
    }
    child.eval(q * s.recip()) * s
}

/// Box of the child's box's eight corners mapped by the transform (infinite or empty stays so).
pub(super) fn bounds(
    translate: &Param3,
    axis: glam::Vec3,
    angle: &Param,
    scale: &Param,
    child: &Sdf,
) -> Aabb {
    let b = child.bounds();
    if b.is_empty() {
        return b;
    }
    if !b.is_finite() {
        return Aabb::INFINITE;
    }
    let theta = angle.value.to_radians();
    let (s, c) = theta.sin_cos();
    let t = translate.value();
    let mut out = Aabb::EMPTY;
    for corner in b.corners() {
        let r: glam::Vec3 = rotate(Vec3::<f32>::from(corner), axis, c, s).into();
        let x = t + r * scale.value;
        out = out.union(&Aabb::new(x, x));
    }
    // Rounding of the rotation: grow by a few ulps of the box size so sampled boundary points stay inside.
    out.expanded(1e-6 * (out.extent().max_element() + t.abs().max_element()))
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
            Field {
                key: "translate",
                value: Value::Vector {
                    access: on!(Sdf::Transform { translate, .. } => translate),
                    components: Xyz,
                    default: Some(0.0),
                    rule: Rule::Any,
                },
            },
            Field {
                key: "rotate",
                value: Value::Rotation {
                    axis: on!(Sdf::Transform { axis, .. } => axis),
                    angle: on!(Sdf::Transform { angle, .. } => angle),
                },
            },
            Field {
                key: "scale",
                value: Value::Number {
                    access: on!(Sdf::Transform { scale, .. } => scale),
                    default: Some(1.0),
                    rule: Rule::Positive,
                },
            },
            Field {
                key: "child",
                value: Value::Child(on!(Sdf::Transform { child, .. } => child)),
            },
        ],
        blank: || {
            let placeholder = Sdf::Union(Vec::new());
            Sdf::transform(placeholder, glam::Vec3::ZERO, glam::Vec3::Y, 0.0, 1.0)
        },
        example: r#"{"type": "transform", "translate": [0.1, 0.2, 0], "rotate": {"axis": [0, 0, 1], "angle": 30},
                     "scale": 1.5, "child": {"type": "sphere", "center": [0, 0.3, 0], "radius": 0.4}}"#,
    };
}
