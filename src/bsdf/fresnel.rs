//! Fresnel reflectance of a conductor.
//!
//! For unpolarised light arriving at `cos θ` on a conductor of complex relative index `η + iκ`, the
//! reflectance is the mean of the s and p parts (Moeller, *Optics*, 1988; the form Mitsuba 3 uses in
//! `fresnel_conductor`, reproduced term by term so that images agree with it):
//!
//! ```text
//!   t₁ = η² − κ² − sin²θ,   a² + b² = √(t₁² + 4η²κ²),   a = √((a² + b² + t₁) / 2)
//!   R_s = (a² + b² + cos²θ − 2a cos θ) / (a² + b² + cos²θ + 2a cos θ)
//!   R_p = R_s (cos²θ (a² + b²) + sin⁴θ − 2a cos θ sin²θ) / (cos²θ (a² + b²) + sin⁴θ + 2a cos θ sin²θ)
//!   F   = (R_s + R_p) / 2
//! ```
//!
//! `η = 0, κ = 1` (the defaults) gives `a = 0`, so `R_s = R_p = 1` exactly: a perfect mirror's
//! Fresnel term.
//!
//! The square roots are the safe kind (zero derivative at zero): `a` is zero exactly when `η κ = 0`
//! and `t₁ ≤ 0`, where `a ~ |η κ|` has no derivative in `η` or `κ` (a kink at the edge of the valid
//! range), so the derivative there is one-sided at best; every other input is smooth.

use crate::scalar::Scalar;

/// Unpolarised Fresnel reflectance of a conductor of index `eta + i k` for light at `cos_i` (in
/// `[0, 1]`) to the microfacet normal.
#[inline]
pub fn conductor<S: Scalar>(cos_i: S, eta: S, k: S) -> S {
    let cos2 = cos_i * cos_i;
    let sin2 = S::one() - cos2;
    let sin4 = sin2 * sin2;
    let t1 = eta * eta - k * k - sin2;
    let a2b2 = (t1 * t1 + eta * eta * k * k * 4.0).safe_sqrt();
    let a = ((a2b2 + t1) * 0.5).safe_sqrt();
    let term1 = a2b2 + cos2;
    let term2 = cos_i * a * 2.0;
    let r_s = (term1 - term2) / (term1 + term2);
    let term3 = a2b2 * cos2 + sin4;
    let term4 = term2 * sin2;
    let r_p = r_s * (term3 - term4) / (term3 + term4);
    (r_s + r_p) * 0.5
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Normal incidence has the closed form `((η − 1)² + κ²) / ((η + 1)² + κ²)`.
    #[test]
    fn normal_incidence_closed_form() {
        for (eta, k) in [(0.2f32, 3.0f32), (1.5, 0.0), (0.05, 4.2), (2.0, 1.0)] {
            let want = ((eta - 1.0).powi(2) + k * k) / ((eta + 1.0).powi(2) + k * k);
            let got = conductor(1.0f32, eta, k);
            assert!((got - want).abs() < 1e-5, "{eta} {k}: {got} vs {want}");
        }
    }

    /// Grazing light is reflected entirely, and the defaults (η = 0, κ = 1) reflect everything.
    #[test]
    fn grazing_and_defaults() {
        assert!((conductor(0.0f32, 0.2, 3.0) - 1.0).abs() < 1e-6);
        for c in [0.0f32, 0.3, 0.7, 1.0] {
            assert_eq!(conductor(c, 0.0, 1.0), 1.0);
        }
    }

    /// Against the textbook form with complex arithmetic (s and p amplitudes from Snell's law), in f64.
    #[test]
    fn matches_complex_snell() {
        #[derive(Copy, Clone)]
        struct C(f64, f64);
        let mul = |a: C, b: C| C(a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
        let div = |a: C, b: C| {
            let d = b.0 * b.0 + b.1 * b.1;
            C((a.0 * b.0 + a.1 * b.1) / d, (a.1 * b.0 - a.0 * b.1) / d)
        };
        let sqrt = |a: C| {
            let r = (a.0 * a.0 + a.1 * a.1).sqrt();
            let re = ((r + a.0) / 2.0).sqrt();
            let im = ((r - a.0) / 2.0).sqrt().copysign(a.1);
            C(re, im)
        };
        let norm2 = |a: C| a.0 * a.0 + a.1 * a.1;
        for (eta, k) in [(0.2f64, 3.0f64), (1.1, 0.4), (0.05, 4.2)] {
            for c in [0.05f64, 0.3, 0.6, 0.95] {
                let n = C(eta, k);
                let s2 = 1.0 - c * c;
                // cos θ_t = sqrt(1 − sin²θ / n²)
                let ct = sqrt(C(1.0, 0.0).sub(div(C(s2, 0.0), mul(n, n))));
                let nct = mul(n, ct);
                let rs = div(C(c - nct.0, -nct.1), C(c + nct.0, nct.1));
                let nc = C(n.0 * c, n.1 * c);
                let rp = div(C(nc.0 - ct.0, nc.1 - ct.1), C(nc.0 + ct.0, nc.1 + ct.1));
                let want = 0.5 * (norm2(rs) + norm2(rp));
                let got = conductor(c as f32, eta as f32, k as f32) as f64;
                assert!((got - want).abs() < 1e-4, "{eta} {k} {c}: {got} vs {want}");
            }
        }
        trait Sub {
            fn sub(self, o: Self) -> Self;
        }
        impl Sub for C {
            fn sub(self, o: C) -> C {
                C(self.0 - o.0, self.1 - o.1)
            }
        }
    }
}
