//! The isotropic GGX (Trowbridge–Reitz) microfacet distribution: its normal distribution `D`, the
//! Smith masking function `G1`, and the sampling of visible normals.
//!
//! With `θ` the angle of a microfacet normal `m` to the macro normal `n` and roughness `α` (Walter et
//! al. 2007, *Microfacet Models for Refraction through Rough Surfaces*, eqs. 33–34; the forms of Mitsuba
//! 3's `MicrofacetDistribution`, whose local components `m.x² + m.y²` are `|n × m|²` here, so no
//! tangent frame is needed):
//!
//! ```text
//!   D(m)     = 1 / (π α² (sin²θ_m / α² + cos²θ_m)²)                 (zero where D cos θ_m ≤ 1e-20)
//!   G1(v, m) = 2 / (1 + √(1 + α² tan²θ_v))                           (1 at normal incidence, 0 when
//!                                                                    v sees m from its back)
//! ```
//!
//! `D` is normalised as `∫ D(m) cos θ_m dm = 1`. The distribution of normals visible from `v`
//! (Heitz 2014, *Understanding the Masking-Shadowing Function*, eq. 2) is
//! `D_v(m) = G1(v, m) max(0, v·m) D(m) / cos θ_v`, sampled exactly by [`sample_visible`] (Heitz 2018,
//! *Sampling the GGX Distribution of Visible Normals*, JCGT 7(4)): stretch `v` to the configuration of
//! roughness 1, sample a point on the projected hemisphere (a disk, one half of it warped), lift it onto
//! the hemisphere and unstretch.

use crate::scalar::Scalar;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// `D(m)` from `cos θ_m` and `sin²θ_m` (`|n × m|²`), roughness `alpha`.
#[inline]
pub fn d<S: Scalar>(alpha: S, cos_m: S, sin2_m: S) -> S {
    let a2 = alpha * alpha;
    let t = sin2_m / a2 + cos_m * cos_m;
    let d = (a2 * t * t * PI).recip();
    // Mitsuba's cut-off, which keeps the reflection's density finite where the half vector grazes.
    if d.primal() * cos_m.primal() > 1e-20 {
        d
    } else {
        S::zero()
    }
}

/// `G1(v, m)` from `cos θ_v`, `sin²θ_v` (`|n × v|²`) and the primal `v · m`.
///
/// The orientation test looks at primal values only: it is zero only where `v` and `m` lie on
/// different sides of each other's planes, a set the reflection never reaches from the front.
#[inline]
pub fn g1<S: Scalar>(alpha: S, cos_v: S, sin2_v: S, v_dot_m: f32) -> S {
    if v_dot_m * cos_v.primal() <= 0.0 {
        return S::zero();
    }
    let xy = alpha * alpha * sin2_v;
    if xy.primal() == 0.0 {
        // Normal incidence: no masking.
        return S::one();
    }
    let tan2 = xy / (cos_v * cos_v);
    S::constant(2.0) / ((tan2 + 1.0).sqrt() + 1.0)
}

/// A microfacet normal (local frame, `+z` the macro normal) drawn from `D_v` for the unit direction
/// `v` (local, `v.z > 0`), roughness `alpha`, from `u ∈ [0, 1)²`.
#[inline]
pub fn sample_visible(alpha: f32, v: Vec3, u: Vec2) -> Vec3 {
    // Stretch to roughness 1.
    let vh = Vec3::new(alpha * v.x, alpha * v.y, v.z).normalize();
    // An orthonormal basis around it (T1 horizontal).
    let lensq = vh.x * vh.x + vh.y * vh.y;
    let t1 = if lensq > 0.0 {
        Vec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt()
    } else {
        Vec3::X
    };
    let t2 = vh.cross(t1);
    // A uniform point on the disk, its half behind `vh` squeezed to the projected visible area.
    let r = u.x.sqrt();
    let phi = 2.0 * PI * u.y;
    let p1 = r * phi.cos();
    let p2 = r * phi.sin();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
    // Onto the hemisphere, then unstretch.
    let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    Vec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize_or_zero()
}

/// `D_v(m)` for unit local `v` and `m` (`+z` the macro normal), in `f32`.
#[inline]
pub fn visible_pdf(alpha: f32, v: Vec3, m: Vec3) -> f32 {
    if v.z <= 0.0 {
        return 0.0;
    }
    let sin2 = |w: Vec3| w.x * w.x + w.y * w.y;
    let vm = v.dot(m);
    g1(alpha, v.z, sin2(v), vm) * vm.max(0.0) * d(alpha, m.z, sin2(m)) / v.z
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `∫ D(m) cos θ_m dω = 1` (midpoint rule in `cos θ`, exact in φ by symmetry).
    #[test]
    fn d_projected_area_is_one() {
        for alpha in [0.05f32, 0.2, 0.5, 1.0] {
            let n = 200_000;
            let mut sum = 0.0f64;
            for i in 0..n {
                let c = (i as f64 + 0.5) / n as f64;
                let dv = d(alpha, c as f32, (1.0 - c * c) as f32) as f64;
                sum += dv * c * 2.0 * std::f64::consts::PI / n as f64;
            }
            assert!((sum - 1.0).abs() < 2e-3, "alpha {alpha}: {sum}");
        }
    }

    /// `∫ D_v(m) dω = 1` for a few incidences (the visible normals' density is normalised: Heitz
    /// 2014, eq. 2), on a grid in `(cos θ, φ)`.
    #[test]
    fn visible_density_is_normalised() {
        for alpha in [0.1f32, 0.4, 1.0] {
            for theta in [0.0f32, 0.7, 1.3, 1.5] {
                let v = Vec3::new(theta.sin(), 0.0, theta.cos());
                let (nc, np) = (2000, 256);
                let mut sum = 0.0f64;
                for i in 0..nc {
                    // Denser near cos θ = 1, where D peaks for small α: c = 1 − t².
                    let t = (i as f64 + 0.5) / nc as f64;
                    let c = 1.0 - t * t;
                    let dc = 2.0 * t / nc as f64;
                    let s = (1.0 - c * c).max(0.0).sqrt();
                    for j in 0..np {
                        let p = (j as f64 + 0.5) / np as f64 * 2.0 * std::f64::consts::PI;
                        let m = Vec3::new((s * p.cos()) as f32, (s * p.sin()) as f32, c as f32);
                        sum += visible_pdf(alpha, v, m) as f64 * dc * 2.0 * std::f64::consts::PI
                            / np as f64;
                    }
                }
                assert!(
                    (sum - 1.0).abs() < 5e-3,
                    "alpha {alpha} theta {theta}: {sum}"
                );
            }
        }
    }
}
