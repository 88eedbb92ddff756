//! Chi-square goodness-of-fit of a direction sampler against its own density, as in Mitsuba 3's test
//! suite (`mitsuba.chi2`): samples are binned on a grid over `(cos θ, φ)` (equal solid angle per bin
//! area, `dω = d cos θ dφ`), the expected count of each bin is the density integrated over the bin
//! (midpoint rule on a sub-grid), bins expecting fewer than 5 samples are pooled, and the statistic's
//! p-value from the χ² distribution must exceed a significance threshold. A sample where the density
//! is zero fails outright, and so does a density whose integral disagrees with the fraction of samples
//! the routine returned.

use super::Rng;
use glam::{Vec2, Vec3};
use std::f64::consts::PI;

/// One goodness-of-fit run.
pub struct Chi2 {
    /// Bins along `cos θ ∈ [−1, 1]`.
    pub theta_bins: usize,
    /// Bins along `φ ∈ [0, 2π)`.
    pub phi_bins: usize,
    /// Midpoint sub-grid per bin side for the expected counts.
    pub sub: usize,
    /// Samples drawn.
    pub samples: usize,
    /// Seed of the random numbers.
    pub seed: u64,
}

impl Default for Chi2 {
    fn default() -> Self {
        Self {
            theta_bins: 10,
            phi_bins: 20,
            sub: 24,
            samples: 400_000,
            seed: 1,
        }
    }
}

/// The outcome of [`Chi2::run`].
#[derive(Debug)]
pub struct Outcome {
    /// The χ² p-value (1 when nothing could be tested).
    pub p_value: f64,
    /// Degrees of freedom after pooling.
    pub dof: usize,
    /// Fraction of draws that produced a direction.
    pub returned: f64,
    /// The density integrated over the sphere.
    pub integral: f64,
    /// Samples whose own density is zero or not finite.
    pub zero_pdf: usize,
}

impl Chi2 {
    /// Runs `sample` (directions in a local frame, `None` for no direction) against `pdf` (density per
    /// steradian of a local direction).
    pub fn run(
        &self,
        sample: impl Fn(Vec2) -> Option<(Vec3, f32)>,
        pdf: impl Fn(Vec3) -> f32,
    ) -> Outcome {
        let (nt, np) = (self.theta_bins, self.phi_bins);
        let bin = |d: Vec3| -> usize {
            let c = ((d.z as f64 + 1.0) * 0.5 * nt as f64).floor() as i64;
            let phi = (d.y as f64).atan2(d.x as f64).rem_euclid(2.0 * PI);
            let p = (phi / (2.0 * PI) * np as f64).floor() as i64;
            c.clamp(0, nt as i64 - 1) as usize * np + p.clamp(0, np as i64 - 1) as usize
        };
        let mut observed = vec![0.0f64; nt * np];
        let mut rng = Rng::new(self.seed);
        let (mut returned, mut zero_pdf) = (0usize, 0usize);
        for _ in 0..self.samples {
            let u = Vec2::new(rng.f32(), rng.f32());
            if let Some((d, p)) = sample(u) {
                returned += 1;
                let own = pdf(d);
                if !(own > 0.0 && own.is_finite() && p > 0.0 && p.is_finite()) {
                    zero_pdf += 1;
                    continue;
                }
                // The density the sampler reports is the one its callers use.
                assert!(
                    ((p - own) / own).abs() < 1e-3,
                    "reported density {p} vs pdf {own} at {d}"
                );
                observed[bin(d)] += 1.0;
            }
        }
        let (dc, dp) = (2.0 / nt as f64, 2.0 * PI / np as f64);
        // The density integrated over bin (t, q) on an s × s midpoint grid.
        let integrate = |t: usize, q: usize, s: usize| -> f64 {
            let mut sum = 0.0;
            for i in 0..s {
                let c = -1.0 + (t as f64 + (i as f64 + 0.5) / s as f64) * dc;
                let r = (1.0 - c * c).max(0.0).sqrt();
                for j in 0..s {
                    let phi = (q as f64 + (j as f64 + 0.5) / s as f64) * dp;
                    let d = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, c as f32);
                    sum += pdf(d) as f64;
                }
            }
            sum * dc * dp / (s * s) as f64
        };
        let mut expected = vec![0.0f64; nt * np];
        for t in 0..nt {
            for q in 0..np {
                // Refine a peaked bin until the midpoint rule settles (to well below the count noise).
                let mut s = self.sub;
                let mut value = integrate(t, q, s);
                while s < 16 * self.sub {
                    let finer = integrate(t, q, 2 * s);
                    let settled = (finer - value).abs() <= 1e-4 * finer + 1e-7;
                    (value, s) = (finer, 2 * s);
                    if settled {
                        break;
                    }
                }
                expected[t * np + q] = value;
            }
        }
        let integral: f64 = expected.iter().sum();
        for e in &mut expected {
            *e *= self.samples as f64;
        }
        // Pool the bins expecting fewer than 5 samples (Mitsuba's rule).
        let (mut chi2, mut dof) = (0.0, 0usize);
        let (mut pool_o, mut pool_e) = (0.0, 0.0);
        for (o, e) in observed.iter().zip(&expected) {
            if *e < 5.0 {
                pool_o += o;
                pool_e += e;
            } else {
                chi2 += (o - e) * (o - e) / e;
                dof += 1;
            }
        }
        if pool_e > 0.0 {
            if pool_e >= 5.0 {
                chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
                dof += 1;
            } else {
                assert!(
                    pool_o <= 5.0 + 10.0 * pool_e,
                    "{pool_o} samples where {pool_e} were expected"
                );
            }
        }
        // The samples not returned form one more cell: their count is fixed by the total.
        let missing_e = self.samples as f64 * (1.0 - integral);
        if missing_e >= 5.0 {
            let missing_o = (self.samples - returned) as f64;
            chi2 += (missing_o - missing_e) * (missing_o - missing_e) / missing_e;
            dof += 1;
        }
        let dof = dof.saturating_sub(1);
        let p_value = if dof == 0 {
            1.0
        } else {
            gamma_q(dof as f64 / 2.0, chi2 / 2.0)
        };
        Outcome {
            p_value,
            dof,
            returned: returned as f64 / self.samples as f64,
            integral,
            zero_pdf,
        }
    }
}

/// Asserts a passing [`Outcome`]: p-value above `1e-3`, no sample of zero density, and the density's
/// integral within `tol` of the fraction of directions returned.
#[track_caller]
pub fn assert_fits(label: &str, o: &Outcome, tol: f64) {
    println!("{label}: {o:?}");
    assert_eq!(o.zero_pdf, 0, "{label}: samples where the pdf is zero");
    assert!(
        (o.integral - o.returned).abs() <= tol,
        "{label}: pdf integrates to {} but {} of the draws returned a direction",
        o.integral,
        o.returned
    );
    assert!(
        o.p_value > 1e-3,
        "{label}: chi-square p-value {}",
        o.p_value
    );
}

/// The regularised upper incomplete gamma function `Q(a, x) = Γ(a, x) / Γ(a)`: the series for
/// `x < a + 1`, Lentz's continued fraction otherwise (Numerical Recipes, §6.2).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let ln_pre = a * x.ln() - x - ln_gamma(a);
    if x < a + 1.0 {
        let (mut term, mut sum, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * ln_pre.exp()
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-15 {
                break;
            }
        }
        ln_pre.exp() * h
    }
}

/// `ln Γ(x)` for `x > 0` (Lanczos, g = 7, n = 9).
pub fn ln_gamma(x: f64) -> f64 {
    const G: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = G[0];
    let t = x + 7.5;
    for (i, g) in G.iter().enumerate().skip(1) {
        a += g / (x + i as f64);
    }
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}
