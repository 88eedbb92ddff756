//! Velocity fields other than the normal field (docs/theory.md §8): how the points of a shape's surface
//! move with the selected parameters when that choice lowers the variance of the interior term.
//!
//! Any field `u` that moves the surface onto itself in the normal direction (`u·n = V`) gives the same
//! derivative; the normal field `u = V n` has the area factor `∂πJ = κV`, heavy-tailed where the
//! curvature `κ` is huge. A field with a tangential part `d_T` has the area factor of its surface
//! divergence, and moves every attached position and normal with it. Written for any motion `u` with
//! spatial Jacobian `∂u/∂p` (both from [`Grad`] arithmetic), `u` corrected along `n` so that its normal
//! part is the surface's exactly:
//!
//! ```text
//!   x = p + d + (V − n·d) n,   J = 1 + ∇_Γ·d + κ (V − n·d),   ∇_Γ·d = tr ∂d/∂p − nᵀ(∂d/∂p)n
//! ```
//!
//! Two motions are known:
//! - **carried** ([`crate::sdf::Sdf::carried`]): translations, rotations and scales of transforms, a
//!   torus's centre and major radius, the centres and radii of spheres and capsules, the centres of
//!   boxes and cylinders: bounded divergence (0 for rigid motions, `1/ρ` for a torus's major radius);
//! - **along a smooth union's crease**: a smooth union of two children whose blend `k` is far below
//!   their own curvature radius `ℓ` is a crease smoothed over a width of order `k`, where `κ ~ 1/k`.
//!   Near it, the field that keeps both children's values, the least-norm `u_C` with
//!   `∇φ_a·u_C = −∂πφ_a` and `∇φ_b·u_C = −∂πφ_b`, moves the blend with the crease like a rigid body
//!   (it keeps `smin(φ_a, φ_b)`, so `u_C·n = V` in the blend and `κ` never multiplies anything), and
//!   its divergence is of the order of the children's curvature. Away from the crease the normal
//!   field takes over: `u = w u_C + (1 − w) V n`, the weight `w` going from 1 (where the children
//!   differ by less than `k`) to 0 (by more than `k + ℓ`) as a smooth step, and to 0 where the
//!   children's normals are nearly parallel (their crease is ill-conditioned there). `∇w` enters the
//!   divergence through the Jacobian, of order `1/ℓ`, not `1/k`.

use crate::integrator::options::VelocityField;
use crate::math::Vec3;
use crate::scalar::{Grad, Scalar};
use crate::scene::{Scene, Shape};
use crate::sdf::Sdf;

/// `sin²` of the angle between the children's normals below which a crease's field fades out (about
/// 18°), and below which it is not evaluated at all (the weight is then below `1e-9`).
const FULL_CREASE_SIN2: f32 = 0.1;
const LEAST_CREASE_SIN2: f32 = 1e-6;

/// The field that moves a shape's points instead of the normal field, decided once per shape.
#[derive(Clone, Debug)]
pub enum Field<'a> {
    /// The shape's known motion ([`Sdf::carried`]).
    Carried,
    /// The crease-following field of a smooth union of two children.
    Crease(SmoothPair<'a>),
}

impl<'a> Field<'a> {
    /// The field of `shape` in `scene` under the choice `velocity`; `None` for the normal field.
    /// With [`VelocityField::Auto`]: a shape without creases with a known field, whose curvature
    /// radius can be below the width of a pixel where the camera sees it (the normal field's `κV` is
    /// heavy-tailed there). Near the eye the normal field stays: a tangential motion there moves the
    /// image fast, and the moving pixel filter's term (theory §2.5) grows with it.
    pub fn of(scene: &Scene, shape: &'a Shape, velocity: VelocityField) -> Option<Self> {
        if velocity == VelocityField::Normal || shape.creased {
            return None;
        }
        let known = if (shape.sdf)
            .carried(Vec3::<f32>::constant(glam::Vec3::ZERO))
            .is_some()
        {
            Field::Carried
        } else {
            Field::Crease(SmoothPair::of(&shape.sdf)?)
        };
        if velocity == VelocityField::Carried {
            return Some(known);
        }
        let camera = &scene.camera;
        let eye = camera.origin.value();
        let nearest = (eye.clamp(shape.bounds.min, shape.bounds.max) - eye).length();
        let pixel =
            2.0 * (0.5 * camera.fov_y.value.to_radians()).tan() / camera.height.max(1) as f32;
        (shape.sdf.curvature_bound() * nearest * pixel > 1.0).then_some(known)
    }

    /// How this field moves `shape`'s point `p` (normal `n`): the motion `d` (derivative parts only,
    /// primal zero) and its surface divergence `∇_Γ·d`, from which the attached vertex is built
    /// ([`crate::integrator::attach`], eq. 8.1); `None` where the motion is undefined.
    pub fn motion<S: Scalar>(
        &self,
        shape: &Shape,
        p: glam::Vec3,
        n: glam::Vec3,
    ) -> Option<(Vec3<S>, S)> {
        let u = match self {
            Field::Carried => {
                let seed = Grad::<S>::seed(p - shape.translate.value());
                shape.sdf.carried(seed)? + shape.translate.get::<Grad<S>>()
                    - seed
                    - shape.translate.value()
            }
            Field::Crease(pair) => pair.motion::<S>(shape, p)?,
        };
        // Only the derivative parts of the motion and its Jacobian: their primals are zero up to
        // rounding.
        let c = [u.x, u.y, u.z];
        let d = Vec3::new(c[0].v, c[1].v, c[2].v);
        let jac = |i: usize, j: usize| c[i].g[j] - c[i].g[j].detach();
        let nv = [n.x, n.y, n.z];
        let mut div = S::zero();
        for i in 0..3 {
            div += jac(i, i);
            for j in 0..3 {
                div -= jac(i, j) * (nv[i] * nv[j]);
            }
        }
        Some((d - d.detach(), div))
    }
}

/// A smooth union of two children whose blend is far below their curvature radius (see the
/// [module docs](self)).
#[derive(Clone, Debug)]
pub struct SmoothPair<'a> {
    a: &'a Sdf,
    b: &'a Sdf,
    /// The blend radius `k`.
    k: f32,
    /// The reach `ℓ` of the crease's field beyond the blend: the children's smallest curvature radius.
    reach: f32,
}

impl<'a> SmoothPair<'a> {
    /// The pair at the root of `sdf` (through names), with `k` not selected and `4k < ℓ`.
    fn of(sdf: &'a Sdf) -> Option<Self> {
        match sdf {
            Sdf::Named { child, .. } => Self::of(child),
            Sdf::SmoothUnion { children, k } if children.len() == 2 && k.slot.is_none() => {
                let (a, b) = (&children[0], &children[1]);
                let reach = 1.0 / a.curvature_bound().max(b.curvature_bound());
                (k.value > 0.0 && 4.0 * k.value < reach && reach.is_finite()).then_some(Self {
                    a,
                    b,
                    k: k.value,
                    reach,
                })
            }
            _ => None,
        }
    }

    /// The motion `u = w u_C + (1 − w) V n` at shape point `p`, with its spatial Jacobian.
    fn motion<S: Scalar>(&self, shape: &Shape, p: glam::Vec3) -> Option<Vec3<Grad<S>>> {
        let local = p - shape.translate.value();
        let at = Grad::<S>::seed(p) - shape.translate.get::<Grad<S>>();
        // Value, gradient (with its spatial derivatives, the Hessian) and the parameter derivative
        // (with its spatial gradient) of a function of the point.
        let field = |sdf: &Sdf| {
            let (value, g, h) = sdf.hessian(local);
            let r = sdf.eval::<Grad<S>>(at);
            let dpi = Grad {
                v: r.v - r.v.detach(),
                g: r.g.map(|x| x - x.detach()),
            };
            let cols = [h.x_axis, h.y_axis, h.z_axis];
            let grad = |i: usize| Grad {
                v: S::constant(g[i]),
                g: std::array::from_fn(|j| S::constant(cols[j][i])),
            };
            (value, g, Vec3::new(grad(0), grad(1), grad(2)), dpi)
        };
        let (phi_a, g_a, ga, sa) = field(self.a);
        let (phi_b, g_b, gb, sb) = field(self.b);
        let (_, _, g, s) = field(&shape.sdf);
        // The normal field of the union.
        let gl = g.length();
        if !(gl.primal() > 1e-12 && gl.primal().is_finite()) {
            return None;
        }
        let normal = g * (-s / (gl * gl));
        // How far from the crease: the children's difference beyond the blend, in units of ℓ.
        let diff = Grad {
            v: S::constant(phi_a - phi_b),
            g: std::array::from_fn(|j| S::constant(g_a[j] - g_b[j])),
        };
        let w_far = smooth_step((diff.abs() - self.k) / self.reach);
        let (aa, ab, bb) = (ga.dot(ga), ga.dot(gb), gb.dot(gb));
        let det = aa * bb - ab * ab;
        let sin2 = det / (aa * bb);
        // Far from the crease, or where it is ill-conditioned (also NaN), the normal field alone.
        let conditioned = sin2.primal() > LEAST_CREASE_SIN2;
        if !conditioned || w_far.primal() >= 1.0 {
            return Some(normal);
        }
        let w = (Grad::constant(1.0) - w_far) * smooth_step(sin2 / FULL_CREASE_SIN2);
        let alpha = (sb * ab - sa * bb) / det;
        let beta = (sa * ab - sb * aa) / det;
        let crease = ga * alpha + gb * beta;
        Some(crease * w + normal * (Grad::constant(1.0) - w))
    }
}

/// `3t² − 2t³` of `t` clamped to `[0, 1]`: 0 below, 1 above, C1.
fn smooth_step<S: Scalar>(t: S) -> S {
    let t = t.clamp(0.0, 1.0);
    t * t * (S::constant(3.0) - t * 2.0)
}
