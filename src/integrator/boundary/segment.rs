//! The geometry of one boundary segment `(x_S, x_B, x_D)`: the segment starts at `x_S`, touches the
//! surface `M` tangentially at `x_B` and ends at `x_D` (docs/theory.md §3.2; supplemental document of Zhou et al. 2024, §2).
//!
//! # Notation
//!
//! `ω = (x_B − x_S)/|x_S x_B|` is the segment's unit direction (from `x_S` towards `x_D`); `n_S`, `n_B`,
//! `n_D` are the outward unit normals; `e = n_B × ω / |n_B × ω|` is the tangent direction at `x_B`
//! perpendicular to `ω`; `κ_n = ωᵀHω/|∇φ|` is the normal curvature of `M` at `x_B` along `ω` (positive where
//! `M` curves away from the line: only those tangent directions are silhouettes, see
//! [`is_silhouette_direction`]).
//!
//! # Which measures (supplemental eqs. 12–23; docs/theory.md §5.2)
//!
//! The secondary boundary integral of path-space differentiable rendering runs over boundary segments with
//! the measure `dA(x_S) dℓ(x_D)`: `x_S` anywhere on its surface (area), `x_D` on the discontinuity curve
//! that `x_S` sees on `x_D`'s surface (the shadow of `M`'s silhouette as seen from `x_S`), `ℓ` its arc
//! length. The sampler draws `x_B` by area on `M` and an angle `θ_B` in the tangent plane at `x_B`
//! (measured from any orthonormal tangent frame that varies smoothly with `x_B`: a frame rotation only
//! shifts `θ_B`, so `dA(x_B) dθ_B` does not depend on the frame). The exact change of measure is
//!
//! ```text
//!   dA(x_S) dℓ(x_D) = |x_S x_B| |x_S x_D| κ_n / (|n_S·ω| sin θ_D) · dA(x_B) dθ_B          (A)
//! ```
//!
//! (derivation: in coordinates `X = ω, Y = e, Z = n_B` at `x_B`, with `M: Z = −½ (X,Y) K (X,Y)ᵀ`, a
//! displacement `(δx, δy)` of `x_B` and `δθ` of the angle moves the line, at signed distance `s` from
//! `x_B`, by `(Y, Z) = (δy + s δθ, −s (K₁₁ δx + K₁₂ δy))` across itself. At `x_S` (`s = −|x_S x_B|`) the
//! transverse area becomes `dA(x_S)` after dividing by `|n_S·ω|`; with `x_S` held fixed the line moves at
//! `x_D` only along `e`, by `|x_S x_D|/|x_S x_B|` times the motion of `x_B` across `ω`, which is
//! `dℓ(x_D) sin θ_D`; the 3×3 determinant is `|x_S x_B| |x_S x_D| K₁₁`.) [`boundary_jacobian`] returns (A);
//! it is what an estimator over `dA(x_S) dℓ(x_D)` must use.
//!
//! The supplemental's eq. 23, `J^B = |x_S x_D| κ_n |x_S x_B| / (sin θ_D sin θ^B sin θ_S)`, uses these angles:
//! - `θ_D` (eqs. 14–15): at `x_D`, between the line and the tangent of the discontinuity curve. That
//!   tangent lies in the plane spanned by `ω` and `e` (see above), so
//!   `sin θ_D = |n_D·ω| / √((n_D·ω)² + (n_D·e)²)`.
//! - `θ_S` (eq. 20, Fig. 3): at `x_S`, between the line and the curve `c_t` that `x_S` traces when `θ_B`
//!   turns, i.e. the section of `x_S`'s surface by the tangent plane of `M` at `x_B` (spanned by `ω`,
//!   `e`): `sin θ_S = |n_S·ω| / √((n_S·ω)² + (n_S·e)²)`.
//! - `θ^B` (eqs. 17–19, Fig. 2): despite its name also **at `x_S`**, between the line and the curve `c_n`
//!   that `x_S` traces when `x_B` moves along the normal section (the plane spanned by `ω`, `n_B`):
//!   `sin θ^B = |n_S·ω| / √((n_S·ω)² + (n_S·n_B)²)`.
//!
//! Its numerator `dℓ_t(x_S) dℓ_n(x_S)` is a product of arc lengths along `c_t` and `c_n`, which are
//! oblique in general: `dA(x_S) = dℓ_t dℓ_n sin∠(c_t, c_n)`, and indeed
//! `sin θ_S sin θ^B = |n_S·ω| sin∠(c_t, c_n)`. So (A) `= J^B · sin∠(c_t, c_n)`: eq. 23 is exact for its
//! oblique measure and equals the area Jacobian only when `n_S·e = 0` or `n_S·n_B = 0`
//! ([`BoundarySegment::seed_jacobian`] evaluates it literally, for comparison). In the denominator of
//! eq. 12, `dℓ_n(x_B) dℓ(x_B)` is `dA(x_B)`: `ℓ_n` runs along `ω`, and eq. 13 reads `dℓ(x_B)` as the
//! motion of `x_B` across `ω` (the silhouette itself runs along the direction conjugate to `ω`, which is
//! oblique; its component across `ω` times `dℓ_n` is the area).
//!
//! **Primary boundary** (supplemental eq. 15, `x_S = c` the camera; docs/theory.md §4.5): with `dℓ(x_B)` the arc length of the
//! silhouette curve `{φ = 0, ψ = 0}`, the exact ratio is
//! `dℓ(x_D)/dℓ(x_B) = |c x_D| sin α_B / (|c x_B| sin θ_D)`, `α_B` the angle between the silhouette
//! tangent and the view ray; the silhouette tangent is the direction conjugate to `ω` ([`silhouette_tangent`]).
//! The supplemental's eq. 15 is the case `α_B = 90°` (a sphere); [`primary_measure_change`] includes `sin α_B`.
//!
//! **`x_D` at infinity** (the environment): `dℓ(x_D)` becomes the angle `dψ = dℓ(x_D) sin θ_D/|x_S x_D|`
//! swept by the direction from `x_S`, and (A) becomes `|x_S x_B| κ_n / |n_S·ω| · dA(x_B) dθ_B`
//! ([`BoundarySegment::jacobian_directional`]).
//!
//! # Guards
//!
//! A Jacobian is 0 (the sample is rejected) when `κ_n ≤ 0` (not a silhouette), when a sine or `|n_S·ω|`
//! is exactly 0, or when the result is not finite. These configurations (the line grazing `x_S`'s or
//! `x_D`'s surface, a parabolic direction) have measure zero in `(x_B, θ_B)`, so rejecting them leaves every
//! density exact; nothing is clamped at a positive threshold, which would drop a set of positive measure
//! (bias). The remaining `1/sin` singularities are integrable: they cost variance, not bias.
//!
//! # Normal velocity `V_∂` by AD (docs/theory.md §3.3)
//!
//! The curve normal `n_∂` at `x_D` is the unit tangent of `x_D`'s surface perpendicular to the
//! discontinuity curve, oriented towards the side where the segment clears `M` (`n_∂·n_B > 0`). The
//! tangency residual `h(π) = φ(x_S + t_B (x_D − x_S); π)`, `t_B = |x_S x_B|/|x_S x_D|`, with attached
//! `x_S`, `x_D` and lifted parameters changes by `∂πh`; moving `x_D` by `δ n_∂` changes it by
//! `t_B ∇φ(x_B)·n_∂ δ` (the line is tangent at `x_B`, so to first order the minimum of `φ` along the
//! segment stays at `t_B`). The curve therefore moves by `V_∂ = −∂πh / (t_B ∇φ(x_B)·n_∂)` along `n_∂`
//! ([`boundary_velocity`]). `V_∂ > 0` means the blocked side grows: the boundary term is `Δf · V_∂`
//! with `Δf = f(x_D − ε n_∂) − f(x_D + ε n_∂)` (blocked side minus clear side).

use crate::math::Vec3;
use crate::scalar::Scalar;
use crate::scene::Shape;

/// One boundary segment in `f32`: the three points, their outward unit normals, and at `x_B` the
/// (unnormalised) gradient of `M`'s implicit function, the normal curvature along the segment and the
/// silhouette tangent. See the [module notes](self) for the conventions.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct BoundarySegment {
    /// Where the segment starts (a surface point, or the camera for the primary boundary).
    pub x_s: glam::Vec3,
    /// The tangent point on `M`.
    pub x_b: glam::Vec3,
    /// Where the segment ends, beyond `x_B`.
    pub x_d: glam::Vec3,
    /// Outward unit normal at `x_S` (unused for the primary boundary).
    pub n_s: glam::Vec3,
    /// Outward unit normal of `M` at `x_B`.
    pub n_b: glam::Vec3,
    /// Outward unit normal at `x_D`.
    pub n_d: glam::Vec3,
    /// `∇φ(x_B)`, not normalised (the rate in [`boundary_velocity`] needs its length).
    pub grad_b: glam::Vec3,
    /// Normal curvature `κ_n` of `M` at `x_B` along `ω` (positive: convex).
    pub kappa_n: f32,
    /// Unit tangent at `x_B` of the silhouette curve seen from `x_S` (conjugate to `ω`).
    pub tangent_b: glam::Vec3,
}

/// True if the tangent direction `ω` at `x_b` (on `shape`, `ω·n = 0`) makes the tangent line a
/// silhouette: `M` curves away from the line there (`κ_n > 0`). Lines along concave (`κ_n < 0`) or
/// parabolic (`κ_n = 0`) directions do not separate visible from hidden and carry no boundary term.
pub fn is_silhouette_direction(shape: &Shape, x_b: glam::Vec3, omega: glam::Vec3) -> bool {
    let k = shape
        .sdf
        .normal_curvature(x_b - shape.translate.value(), omega);
    convex(k)
}

/// `κ_n > 0` and finite: the line is a silhouette (NaN is not).
fn convex(kappa_n: f32) -> bool {
    kappa_n > 0.0 && kappa_n.is_finite()
}

/// Unit tangent at a silhouette point of the silhouette curve for the view direction `omega`: the
/// direction `t` conjugate to `ω` (`tᵀHω = 0`, `t·n = 0`, so `t ∝ n × Hω`), which keeps
/// `∇φ(x)·(x − x_S)` at zero to first order. `hessian` is `φ`'s Hessian at the point. Falls back to
/// `n × ω` (the sphere's answer) where `Hω` is parallel to `n` (then `κ_n = 0`: no silhouette anyway).
pub fn silhouette_tangent(n: glam::Vec3, hessian: glam::Mat3, omega: glam::Vec3) -> glam::Vec3 {
    n.cross(hessian * omega)
        .try_normalize()
        .or_else(|| n.cross(omega).try_normalize())
        .unwrap_or(glam::Vec3::X)
}

impl BoundarySegment {
    /// The segment through `x_b` on `shape` from `x_s` (normal `n_s`) to `x_d` (normal `n_d`), with
    /// `n_B`, `∇φ`, `κ_n` and the silhouette tangent evaluated on `shape` (world coordinates, the shape's
    /// translation included). `None` if the points are not distinct or the gradient vanishes at `x_b`.
    pub fn from_shape(
        shape: &Shape,
        x_s: glam::Vec3,
        x_b: glam::Vec3,
        x_d: glam::Vec3,
        n_s: glam::Vec3,
        n_d: glam::Vec3,
    ) -> Option<Self> {
        let omega = (x_b - x_s).try_normalize()?;
        (x_d - x_b).try_normalize()?;
        let (_, grad_b, h) = shape.sdf.hessian(x_b - shape.translate.value());
        let gl = grad_b.length();
        if !(gl > 1e-12 && gl.is_finite()) {
            return None;
        }
        let n_b = grad_b / gl;
        let kappa_n = omega.dot(h * omega) / gl;
        Some(Self {
            x_s,
            x_b,
            x_d,
            n_s,
            n_b,
            n_d,
            grad_b,
            kappa_n: if kappa_n.is_finite() { kappa_n } else { 0.0 },
            tangent_b: silhouette_tangent(n_b, h, omega),
        })
    }

    /// Unit direction of the segment, from `x_S` through `x_B`.
    pub fn omega(&self) -> glam::Vec3 {
        (self.x_b - self.x_s).normalize_or_zero()
    }

    /// `e = n_B × ω`, normalised: the tangent direction at `x_B` across the segment.
    pub fn across(&self) -> glam::Vec3 {
        let w = self.omega();
        self.n_b
            .cross(w)
            .try_normalize()
            .unwrap_or_else(|| w.any_orthonormal_vector())
    }

    /// `t_B = |x_S x_B| / |x_S x_D|`, where `x_B` sits on the segment (0 if `x_S = x_D`).
    pub fn t_b(&self) -> f32 {
        let sd = self.x_s.distance(self.x_d);
        if sd > 0.0 {
            self.x_s.distance(self.x_b) / sd
        } else {
            0.0
        }
    }

    /// `sin θ_D`: the angle at `x_D` between the segment and the discontinuity curve (supplemental eq. 14).
    pub fn sin_theta_d(&self) -> f32 {
        sin_to_section(self.n_d, self.omega(), self.across())
    }

    /// `sin θ_S` of supplemental eq. 20: the angle at `x_S` between the segment and the section of `x_S`'s
    /// surface by `M`'s tangent plane at `x_B`.
    pub fn sin_theta_s(&self) -> f32 {
        sin_to_section(self.n_s, self.omega(), self.across())
    }

    /// `sin θ^B` of supplemental eqs. 17–19: the angle **at `x_S`** between the segment and the section of
    /// `x_S`'s surface by the plane spanned by `ω` and `n_B`.
    pub fn sin_theta_b(&self) -> f32 {
        sin_to_section(self.n_s, self.omega(), self.n_b)
    }

    /// `|n_S·ω|`, the cosine that turns the area across the line at `x_S` into `dA(x_S)`.
    pub fn cos_s(&self) -> f32 {
        self.n_s.dot(self.omega()).abs()
    }

    /// The change of measure `dA(x_S) dℓ(x_D) / (dA(x_B) dθ_B)`, eq. (A) of the module notes:
    /// `|x_S x_B| |x_S x_D| κ_n / (|n_S·ω| sin θ_D)`. 0 for a rejected (measure-zero) configuration.
    pub fn jacobian(&self) -> f32 {
        if !convex(self.kappa_n) {
            return 0.0;
        }
        let num = self.x_s.distance(self.x_b) * self.x_s.distance(self.x_d) * self.kappa_n;
        guarded_ratio(num, self.cos_s() * self.sin_theta_d())
    }

    /// The supplemental's eq. 23 (docs/theory.md (5.4)) taken literally: `|x_S x_D| κ_n |x_S x_B| / (sin θ_D sin θ^B sin θ_S)`, the
    /// change to the oblique measure `dℓ_t(x_S) dℓ_n(x_S) dℓ(x_D)`. Equals [`Self::jacobian`] divided
    /// by `sin∠(c_t, c_n)`; kept for comparison and for the tests, not for estimators.
    pub fn seed_jacobian(&self) -> f32 {
        if !convex(self.kappa_n) {
            return 0.0;
        }
        let num = self.x_s.distance(self.x_b) * self.x_s.distance(self.x_d) * self.kappa_n;
        guarded_ratio(
            num,
            self.sin_theta_d() * self.sin_theta_b() * self.sin_theta_s(),
        )
    }

    /// The change of measure when `x_D` is at infinity: `dA(x_S) dψ / (dA(x_B) dθ_B) =
    /// |x_S x_B| κ_n / |n_S·ω|`, `ψ` the angle swept by the direction from `x_S` (`x_d` is not used).
    pub fn jacobian_directional(&self) -> f32 {
        if !convex(self.kappa_n) {
            return 0.0;
        }
        guarded_ratio(self.x_s.distance(self.x_b) * self.kappa_n, self.cos_s())
    }

    /// The unit curve normal `n_∂` at `x_D` (tangent to `x_D`'s surface, across the discontinuity
    /// curve, towards the side where the segment clears `M`); `None` where the segment grazes `x_D`'s
    /// surface (no curve direction).
    pub fn curve_normal(&self) -> Option<glam::Vec3> {
        curve_normal_towards(self.n_d, self.omega(), self.across(), self.n_b)
    }
}

/// `dA(x_S) dℓ(x_D) / (dA(x_B) dθ_B)` for the segment (see [`BoundarySegment::jacobian`]); 0 for a
/// rejected configuration.
pub fn boundary_jacobian(seg: &BoundarySegment) -> f32 {
    seg.jacobian()
}

/// The primary boundary's change of measure from the silhouette's arc length at `x_b` to the arc length
/// of its image curve at `x_d` seen from `c` (supplemental eq. 15 with the obliquity of the silhouette):
/// `|c x_D| sin α_B / (|c x_B| sin θ_D)`, `α_B` the angle between `tangent_b` (the unit silhouette
/// tangent, [`silhouette_tangent`]) and the view ray, `θ_D` the angle at `x_D` between the ray and the
/// image curve (normal `n_d`). 0 where the ray grazes `x_D`'s surface or the result is not finite.
pub fn primary_measure_change(
    c: glam::Vec3,
    x_b: glam::Vec3,
    n_b: glam::Vec3,
    tangent_b: glam::Vec3,
    x_d: glam::Vec3,
    n_d: glam::Vec3,
) -> f32 {
    let Some(w) = (x_b - c).try_normalize() else {
        return 0.0;
    };
    let e = n_b
        .cross(w)
        .try_normalize()
        .unwrap_or_else(|| w.any_orthonormal_vector());
    let sin_alpha = tangent_b.cross(w).length();
    guarded_ratio(
        c.distance(x_d) * sin_alpha,
        c.distance(x_b) * sin_to_section(n_d, w, e),
    )
}

/// The normal velocity `V_∂` of the discontinuity curve at `x_D` along [`BoundarySegment::curve_normal`]
/// (module notes): `−∂πh / (t_B ∇φ(x_B)·n_∂)`, `h = φ_M(x_S + t_B (x_D − x_S))` evaluated with the
/// attached `x_s`, `x_d` and `shape`'s lifted parameters. Generic over the scalar type (forward or
/// reverse mode; camera, emitter and shape parameters alike); the primal is exactly 0. Zero where the
/// curve normal is undefined or the rate vanishes.
pub fn boundary_velocity<S: Scalar>(
    shape: &Shape,
    seg: &BoundarySegment,
    x_s: Vec3<S>,
    x_d: Vec3<S>,
) -> S {
    let Some(n_curve) = seg.curve_normal() else {
        return S::zero();
    };
    let t_b = seg.t_b();
    let rate = t_b * seg.grad_b.dot(n_curve);
    if !(rate > 0.0 && rate.is_finite()) {
        return S::zero();
    }
    let x = x_s + (x_d - x_s) * S::constant(t_b);
    let h = shape.eval(x);
    -(h - h.detach()) / rate
}

/// The unit normal at `x_D` (surface normal `n_d`) of the discontinuity curve whose tangent lies in
/// `span(w, e)` (`w` the segment's direction, `e` across it), within `x_D`'s tangent plane and oriented
/// so that its dot product with `clear` is positive (the side where the segment clears the occluder);
/// `None` where the segment grazes `x_D`'s surface or the orientation is undecided.
pub(crate) fn curve_normal_towards(
    n_d: glam::Vec3,
    w: glam::Vec3,
    e: glam::Vec3,
    clear: glam::Vec3,
) -> Option<glam::Vec3> {
    // The curve's tangent: the direction in span(w, e) tangent to x_D's surface.
    let c = (w * n_d.dot(e) - e * n_d.dot(w)).try_normalize()?;
    let m = n_d.cross(c).try_normalize()?;
    let s = m.dot(clear);
    if s == 0.0 || !s.is_finite() {
        return None;
    }
    Some(if s > 0.0 { m } else { -m })
}

/// Sine of the angle between the line direction `w` and the section of a surface (unit normal `n`) by
/// the plane spanned by `w` and `v` (unit, `v ⊥ w`): `|n·w| / √((n·w)² + (n·v)²)`. 0 when the plane is
/// the surface's tangent plane (no section direction).
pub(crate) fn sin_to_section(n: glam::Vec3, w: glam::Vec3, v: glam::Vec3) -> f32 {
    let (a, b) = (n.dot(w), n.dot(v));
    let r = a.hypot(b);
    if r > 0.0 { a.abs() / r } else { 0.0 }
}

/// `num / den`, or 0 when `den` is 0 or the result is not finite (a measure-zero configuration).
pub(crate) fn guarded_ratio(num: f32, den: f32) -> f32 {
    if den == 0.0 {
        return 0.0;
    }
    let r = num / den;
    if r.is_finite() { r } else { 0.0 }
}
