//! The geometry of a boundary segment through a crease edge (docs/theory.md §7.3): the segment from
//! `x_S` passes a sharp edge at `x_B` and ends at `x_D`, and its visibility jumps there because the two
//! faces meeting at the edge lie on opposite sides of it. This is [`super::segment`] with the smooth
//! occluder's tangency replaced by an edge; read that module's notation first.
//!
//! # When the segment is a boundary
//!
//! Near `x_B` the solid is the wedge `{∇F_a·y ≤ 0, ∇F_b·y ≤ 0}` (`y = x − x_B`, `F_a`, `F_b` the face
//! functions of [`crate::sdf::CreaseEdge`]). The line `x_B + s ω` clears it on both sides of `x_B` exactly
//! when `(∇F_a·ω)(∇F_b·ω) < 0`: one face turns towards `x_S`, the other away ([`CreaseSegment::is_boundary`]).
//! Moved across itself by a small `u`, the line is blocked when `c(u) < 0` and clear when `c(u) > 0`,
//!
//! ```text
//!   c(u) = c·u,   c = ∇F_a / |∇F_a·ω| + ∇F_b / |∇F_b·ω|                                          (B1)
//! ```
//!
//! (with, say, `∇F_a·ω > 0 > ∇F_b·ω`, the line through `x_B + u` meets the wedge where
//! `∇F_a·(u + sω) ≤ 0` and `∇F_b·(u + sω) ≤ 0`, i.e. `−∇F_b·u/∇F_b·ω ≤ s ≤ −∇F_a·u/∇F_a·ω`, a non-empty
//! range iff `c·u ≤ 0`). `c` is orthogonal to `ω` and to the edge's tangent `T`.
//!
//! # The change of measure
//!
//! The estimator draws `x_B` on the edge by arc length `σ` and the line's direction `ω` by solid angle.
//! In coordinates `X = ω`, `Y` along `T⊥ = T − (T·ω)ω` and `Z = ω × Y` at `x_B`, moving `x_B` by `δσ` and
//! `ω` by `(δω_Y, δω_Z)` moves the line, at signed distance `s` from `x_B`, across itself by
//! `(sin α δσ + s δω_Y, s δω_Z)`, `sin α = |T⊥|` (`α` the angle between `T` and `ω`). At `x_S`
//! (`s = −|x_S x_B|`) the transverse area is `|n_S·ω| dA(x_S)`; with `x_S` held fixed (`δω_Z = 0`,
//! `sin α δσ = |x_S x_B| δω_Y`) the line turns about `x_S` and moves at `x_D` by `|x_S x_D| δω_Y` along
//! `Y`, which is `sin θ_D dℓ(x_D)` (the discontinuity curve's tangent at `x_D` lies in `span(ω, T)`, so
//! `θ_D` is the angle between `ω` and the section of `x_D`'s surface by that plane). The determinant is
//!
//! ```text
//!   dA(x_S) dℓ(x_D) = |x_S x_B| |x_S x_D| sin α / ( |n_S·ω| sin θ_D ) · dσ dω                        (B2)
//! ```
//!
//! the crease's counterpart of eq. (A) of [`super::segment`] (`κ_n dA(x_B) dθ_B` becomes
//! `sin α dσ dω`). For `x_D` at infinity `dℓ(x_D) sin θ_D / |x_S x_D|` is the angle swept by the
//! direction from `x_S`, and (B2) becomes `|x_S x_B| sin α / |n_S·ω|`.
//!
//! # The velocity, by AD
//!
//! The residual `h(π) = F_a(y)/|∇F_a·ω| + F_b(y)/|∇F_b·ω|`, `y = x_S + t_B (x_D − x_S)` with attached
//! `x_S`, `x_D` and lifted parameters, is `c` applied to the offset of the line from the moved edge (to
//! first order, and 0 at the primal). Moving `x_D` by `δ n_∂` changes it by `t_B c·n_∂ δ`; with `n_∂`
//! oriented towards the clear side (`c·n_∂ > 0`) the curve moves by `V_∂ = −∂πh / (t_B c·n_∂)` along
//! `n_∂`, the convention of [`super::boundary_velocity`] (`V_∂ > 0` grows the blocked side).

use super::segment::{curve_normal_towards, guarded_ratio, sin_to_section};
use crate::math::Vec3;
use crate::scalar::Scalar;
use crate::scene::Shape;
use crate::sdf::CreaseEdge;

/// A segment `x_S → x_D` passing the crease edge at `x_B`, in `f32` (see the [module docs](self)).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct CreaseSegment {
    /// Where the segment starts (a surface point).
    pub x_s: glam::Vec3,
    /// The edge point.
    pub x_b: glam::Vec3,
    /// Where the segment ends, beyond `x_B`.
    pub x_d: glam::Vec3,
    /// Outward unit normal at `x_S`.
    pub n_s: glam::Vec3,
    /// Outward unit normal at `x_D`.
    pub n_d: glam::Vec3,
    /// Unit tangent of the edge at `x_B`.
    pub tangent: glam::Vec3,
    /// `∇F_a` and `∇F_b` at `x_B` (world coordinates).
    pub grads: [glam::Vec3; 2],
}

impl CreaseSegment {
    /// The segment from `x_s` (normal `n_s`) past the edge point `x_b` (unit edge tangent `tangent`,
    /// face gradients `grads` there: `crease_edges::face_gradient`) to
    /// `x_d` (normal `n_d`); `None` if the points are not distinct.
    pub fn new(
        (x_s, x_b, x_d): (glam::Vec3, glam::Vec3, glam::Vec3),
        n_s: glam::Vec3,
        n_d: glam::Vec3,
        tangent: glam::Vec3,
        grads: [glam::Vec3; 2],
    ) -> Option<Self> {
        (x_b - x_s).try_normalize()?;
        (x_d - x_b).try_normalize()?;
        Some(Self {
            x_s,
            x_b,
            x_d,
            n_s,
            n_d,
            tangent,
            grads,
        })
    }

    /// Unit direction of the segment, from `x_S` through `x_B`.
    pub fn omega(&self) -> glam::Vec3 {
        (self.x_b - self.x_s).normalize_or_zero()
    }

    /// Whether the faces lie on opposite sides of the line: `(∇F_a·ω)(∇F_b·ω) < 0`.
    pub fn is_boundary(&self) -> bool {
        let w = self.omega();
        let p = self.grads[0].dot(w) * self.grads[1].dot(w);
        p < 0.0 && p.is_finite()
    }

    /// `c` of (B1): `c·u > 0` for a displacement `u` of the line that clears the edge.
    pub fn clearing(&self) -> glam::Vec3 {
        clearing(self.grads, self.omega())
    }

    /// `T⊥/|T⊥|`: the direction across the line in the plane of the line and the edge.
    fn across(&self) -> glam::Vec3 {
        let w = self.omega();
        (self.tangent - w * self.tangent.dot(w))
            .try_normalize()
            .unwrap_or_else(|| w.any_orthonormal_vector())
    }

    /// `sin α = |T × ω|`.
    pub fn sin_alpha(&self) -> f32 {
        self.tangent.cross(self.omega()).length()
    }

    /// `t_B = |x_S x_B| / |x_S x_D|`.
    pub fn t_b(&self) -> f32 {
        let sd = self.x_s.distance(self.x_d);
        if sd > 0.0 {
            self.x_s.distance(self.x_b) / sd
        } else {
            0.0
        }
    }

    /// `|n_S·ω|`.
    fn cos_s(&self) -> f32 {
        self.n_s.dot(self.omega()).abs()
    }

    /// `sin θ_D`: the angle at `x_D` between the segment and the discontinuity curve.
    pub fn sin_theta_d(&self) -> f32 {
        sin_to_section(self.n_d, self.omega(), self.across())
    }

    /// (B2): `dA(x_S) dℓ(x_D) / (dσ dω) = |x_S x_B| |x_S x_D| sin α / (|n_S·ω| sin θ_D)`; 0 when the
    /// segment is not a boundary or for a measure-zero configuration.
    pub fn jacobian(&self) -> f32 {
        if !self.is_boundary() {
            return 0.0;
        }
        let num = self.x_s.distance(self.x_b) * self.x_s.distance(self.x_d) * self.sin_alpha();
        guarded_ratio(num, self.cos_s() * self.sin_theta_d())
    }

    /// (B2) with `x_D` at infinity: `|x_S x_B| sin α / |n_S·ω|` (`x_d` unused).
    pub fn jacobian_directional(&self) -> f32 {
        if !self.is_boundary() {
            return 0.0;
        }
        guarded_ratio(self.x_s.distance(self.x_b) * self.sin_alpha(), self.cos_s())
    }

    /// The unit curve normal `n_∂` at `x_D`, towards the clear side (`c·n_∂ > 0`); `None` where the
    /// segment grazes `x_D`'s surface.
    pub fn curve_normal(&self) -> Option<glam::Vec3> {
        curve_normal_towards(self.n_d, self.omega(), self.across(), self.clearing())
    }

    /// `V_∂` at `x_D` along [`Self::curve_normal`] by AD (module docs), with the attached `x_s`, `x_d`
    /// and `shape`'s lifted parameters; 0 where the curve normal or the rate is undefined.
    pub fn velocity<S: Scalar>(
        &self,
        shape: &Shape,
        edge: &CreaseEdge,
        x_s: Vec3<S>,
        x_d: Vec3<S>,
    ) -> S {
        let Some(n_curve) = self.curve_normal() else {
            return S::zero();
        };
        let t_b = self.t_b();
        let rate = t_b * self.clearing().dot(n_curve);
        if !(rate > 0.0 && rate.is_finite()) {
            return S::zero();
        }
        let y = x_s + (x_d - x_s) * S::constant(t_b);
        let Some(h) = clearing_residual(shape, edge, self.grads, self.omega(), y) else {
            return S::zero();
        };
        -(h - h.detach()) / rate
    }
}

/// `c` of (B1) for a line along `w` past an edge whose faces have the gradients `grads` there:
/// `∇F_a / |∇F_a·w| + ∇F_b / |∇F_b·w|`, orthogonal to `w` and to the edge when the faces lie on
/// opposite sides of the line.
pub(crate) fn clearing(grads: [glam::Vec3; 2], w: glam::Vec3) -> glam::Vec3 {
    let [a, b] = grads;
    a / a.dot(w).abs() + b / b.dot(w).abs()
}

/// The residual `F_a(y)/|∇F_a·w| + F_b(y)/|∇F_b·w|` at the world point `y` with `shape`'s lifted
/// parameters (module docs, "The velocity"): to first order `c·u`, `u` the offset of `y` from the
/// moved edge across the line along `w` (`grads` the faces' gradients at the edge point, as in
/// [`clearing`]). `None` where a face does not evaluate.
pub(crate) fn clearing_residual<S: Scalar>(
    shape: &Shape,
    edge: &CreaseEdge,
    grads: [glam::Vec3; 2],
    w: glam::Vec3,
    y: Vec3<S>,
) -> Option<S> {
    let y = y - shape.translate.get::<S>();
    let face = |f: usize| -> Option<S> {
        let v = shape.sdf.face_value(&edge.path, edge.faces[f], y)?;
        Some(v / grads[f].dot(w).abs())
    };
    Some(face(0)? + face(1)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::Bsdf;
    use crate::scalar::{Dual32, Param, Param3};
    use crate::sdf::Sdf;

    /// `V_∂` by AD against finite differences of the shadow edge's position: a unit cube's edge
    /// `x = 0.5, y = 0.5` seen from `x_S` below and to the side (the `+x` face turned towards it) or
    /// above and to the side (the `+y` face), projected onto the plane `y = 3` or `y = −3`; the cube
    /// moved along x, along y, and grown along x. The curve normal points to where the segment clears the
    /// cube.
    #[test]
    fn velocity_matches_the_moving_shadow_edge() {
        for (x_s, plane) in [
            (glam::Vec3::new(1.6, -1.0, 0.2), 3.0),
            (glam::Vec3::new(-1.0, 2.0, -0.3), -3.0),
        ] {
            velocity_case(x_s, plane);
        }
    }

    fn velocity_case(x_s: glam::Vec3, plane: f32) {
        let n_s = glam::Vec3::Y;
        let n_d = -glam::Vec3::Y;
        for (k, (center, half)) in [
            (glam::Vec3::X, glam::Vec3::ZERO),
            (glam::Vec3::Y, glam::Vec3::ZERO),
            (glam::Vec3::ZERO, glam::Vec3::X),
        ]
        .into_iter()
        .enumerate()
        {
            // The cube with the moved parameter slotted (Dual32 seeds slot 0).
            let param = |v: f32, d: f32| Param {
                value: v,
                slot: (d != 0.0).then_some(0),
            };
            let shape = Shape::new(
                "cube",
                Sdf::Box {
                    center: Param3 {
                        c: [0, 1, 2].map(|i| param(0.0, center[i])),
                    },
                    half_size: Param3 {
                        c: [0, 1, 2].map(|i| param(0.5, half[i])),
                    },
                    rounding: Param::new(0.0),
                },
                Bsdf::Diffuse {
                    albedo: Param3::new([0.5; 3]),
                },
            );
            let edge = shape
                .sdf
                .crease_edges()
                .into_iter()
                .find(|e| match e.curve {
                    crate::sdf::EdgeCurve::Segment { a, b } => {
                        (a - glam::Vec3::new(0.5, 0.5, -0.5)).length() < 1e-6
                            && (b - glam::Vec3::new(0.5, 0.5, 0.5)).length() < 1e-6
                    }
                    _ => false,
                })
                .expect("the edge x = y = 0.5");
            let x_b = glam::Vec3::new(0.5, 0.5, 0.1);
            let through = |x_s: glam::Vec3, x_b: glam::Vec3| {
                let w = x_b - x_s;
                x_s + w * ((plane - x_s.y) / w.y)
            };
            let x_d = through(x_s, x_b);
            let grads = [0, 1].map(|f| {
                crate::integrator::boundary::crease_edges::face_gradient(&shape, &edge, f, x_b)
            });
            let seg = CreaseSegment::new((x_s, x_b, x_d), n_s, n_d, glam::Vec3::Z, grads).unwrap();
            assert!(seg.is_boundary(), "case {k}");
            let v: Dual32 = seg.velocity(&shape, &edge, Vec3::constant(x_s), Vec3::constant(x_d));
            // The moved edge point's shadow: the edge is x = 0.5 + δ(c_x + h_x), y = 0.5 + δ c_y.
            let delta = 1e-3;
            let moved = x_b + (center + half) * delta * glam::Vec3::new(1.0, 1.0, 0.0);
            let shift = (through(x_s, moved) - x_d).dot(seg.curve_normal().unwrap()) / delta;
            assert!(
                (v.eps - shift).abs() <= 1e-2 * shift.abs().max(0.1),
                "case {k}: AD {} vs finite difference {shift}",
                v.eps
            );
            assert!(
                shift.abs() > 0.1,
                "case {k}: the edge should move its shadow"
            );
            // Clear towards the curve normal, blocked the other way (φ along the segment).
            let n = seg.curve_normal().unwrap();
            let lowest = |end: glam::Vec3| {
                (0..=2000)
                    .map(|i| shape.eval_f32(x_s + (end - x_s) * (i as f32 / 2000.0)))
                    .fold(f32::INFINITY, f32::min)
            };
            assert!(
                lowest(x_d + n * 0.05) > 0.0,
                "case {k}: the clear side is blocked"
            );
            assert!(
                lowest(x_d - n * 0.05) < 0.0,
                "case {k}: the blocked side is clear"
            );
        }
    }
}
