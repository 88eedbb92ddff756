use crate::scalar::Scalar;
use std::sync::OnceLock;

/// Pixel reconstruction filter, centred on the pixel centre, in pixel units. Each is normalised
/// (integrates to 1) and sampled exactly, so a sample's filter weight divided by its density is 1.
///
/// All three are separable: `eval(dx, dy) = f(dx) f(dy)` with a 1D filter `f` of integral 1, and
/// [`Filter::sample`] inverts the 1D CDF on each axis.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Default)]
pub enum Filter {
    /// Box of half-width 0.5 (discontinuous: derivatives through it need pixel-edge terms). Its
    /// [`Filter::eval`] is a constant 1 on `[-0.5, 0.5]²` (edges included) and 0 outside, with a zero
    /// derivative everywhere: the jump at the pixel edges is not in it.
    Box,
    /// Tent of radius 1 pixel (the default): `f(x) = max(0, 1 − |x|)`. Continuous, so moving film
    /// positions need no pixel-edge terms.
    #[default]
    Tent,
    /// Gaussian, σ = 0.5 pixel, truncated at radius 1.5 and renormalised. The truncation value is
    /// subtracted first (as in pbrt), `f(x) ∝ exp(−x²/2σ²) − exp(−r²/2σ²)` for `|x| < r = 1.5`, so the
    /// filter is continuous at its edge: a plain truncation would jump by 1.1 % of the peak there, and that
    /// jump would need pixel-edge boundary terms in derivative images.
    Gaussian,
}

/// Gaussian filter width (pixels).
const SIGMA: f64 = 0.5;
/// Gaussian filter truncation radius (pixels).
const GAUSS_RADIUS: f64 = 1.5;

/// `erf(x)` in f64 by its Maclaurin series, accurate to about 1e-15 for the `|x| ≤ 2.2` used here
/// (Abramowitz & Stegun 7.1.5: `erf x = 2/√π Σ (−1)ⁿ x^{2n+1} / (n! (2n+1))`).
fn erf(x: f64) -> f64 {
    debug_assert!(x.abs() <= 3.0);
    let x2 = x * x;
    let mut power = x; // (−1)ⁿ x^{2n+1} / n!
    let mut sum = x;
    for n in 1..120 {
        power *= -x2 / n as f64;
        let term = power / (2 * n + 1) as f64;
        sum += term;
        if term.abs() < 1e-17 * sum.abs() {
            break;
        }
    }
    sum * std::f64::consts::FRAC_2_SQRT_PI
}

/// Constants and a coarse inverse-CDF table of the 1D Gaussian filter.
struct Gauss {
    /// `exp(−r²/2σ²)`, subtracted to make the filter continuous.
    edge: f64,
    /// `∫_{−r}^{r} (exp(−x²/2σ²) − edge) dx`.
    norm: f64,
    /// `1 / norm` in f32, for [`Filter::eval`].
    inv_norm_f32: f32,
    /// `edge` in f32.
    edge_f32: f32,
    /// Inverse CDF at `u = k / (len − 1)`: starting points for Newton's method.
    table: Vec<f64>,
}

impl Gauss {
    fn get() -> &'static Gauss {
        static G: OnceLock<Gauss> = OnceLock::new();
        G.get_or_init(|| {
            let edge = (-GAUSS_RADIUS * GAUSS_RADIUS / (2.0 * SIGMA * SIGMA)).exp();
            let norm = Self::unnormalised_cdf(GAUSS_RADIUS, edge);
            let mut g = Gauss {
                edge,
                norm,
                inv_norm_f32: (1.0 / norm) as f32,
                edge_f32: edge as f32,
                table: Vec::new(),
            };
            // Bisection is slow but exact; the table is built once.
            const N: usize = 257;
            g.table = (0..N)
                .map(|k| {
                    let u = k as f64 / (N - 1) as f64;
                    let (mut lo, mut hi) = (-GAUSS_RADIUS, GAUSS_RADIUS);
                    for _ in 0..60 {
                        let mid = 0.5 * (lo + hi);
                        if g.cdf(mid) < u {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    0.5 * (lo + hi)
                })
                .collect();
            g
        })
    }

    /// `∫_{−r}^{x} (exp(−s²/2σ²) − edge) ds`.
    fn unnormalised_cdf(x: f64, edge: f64) -> f64 {
        let k = SIGMA * std::f64::consts::SQRT_2;
        let half = 0.5 * std::f64::consts::PI.sqrt() * k;
        half * (erf(x / k) + erf(GAUSS_RADIUS / k)) - edge * (x + GAUSS_RADIUS)
    }

    fn cdf(&self, x: f64) -> f64 {
        Self::unnormalised_cdf(x, self.edge) / self.norm
    }

    fn pdf(&self, x: f64) -> f64 {
        if x.abs() >= GAUSS_RADIUS {
            0.0
        } else {
            ((-x * x / (2.0 * SIGMA * SIGMA)).exp() - self.edge) / self.norm
        }
    }

    /// The `x` with `cdf(x) = u`, by Newton's method from the table, safeguarded by bisection (the density
    /// vanishes at the edges). Converges to f64 round-off in a few steps; returned in f32.
    fn inverse_cdf(&self, u: f64) -> f64 {
        let u = u.clamp(0.0, 1.0);
        let n = self.table.len() - 1;
        let pos = u * n as f64;
        let k = (pos as usize).min(n - 1);
        // The table brackets the root: the CDF is increasing.
        let (mut lo, mut hi) = (self.table[k], self.table[k + 1]);
        let mut x = lo + (hi - lo) * (pos - k as f64);
        for _ in 0..50 {
            let f = self.cdf(x) - u;
            if f < 0.0 {
                lo = x;
            } else {
                hi = x;
            }
            let d = self.pdf(x);
            let mut next = if d > 0.0 { x - f / d } else { f64::NAN };
            if !(next > lo && next < hi) {
                next = 0.5 * (lo + hi);
            }
            if (next - x).abs() <= 1e-13 || hi - lo <= 1e-13 {
                return next;
            }
            x = next;
        }
        x
    }
}

/// The pixels whose filter covers a film point: [`Filter::footprint`].
#[derive(Clone, Debug)]
pub struct Footprint {
    p: glam::Vec2,
    r: f32,
    x_lo: i64,
    x_hi: i64,
    x: i64,
    y: i64,
    y_hi: i64,
}

impl Iterator for Footprint {
    type Item = (u32, u32);

    #[inline]
    fn next(&mut self) -> Option<(u32, u32)> {
        while self.y <= self.y_hi {
            if (self.p.y - (self.y as f32 + 0.5)).abs() < self.r {
                while self.x <= self.x_hi {
                    let x = self.x;
                    self.x += 1;
                    if (self.p.x - (x as f32 + 0.5)).abs() < self.r {
                        return Some((x as u32, self.y as u32));
                    }
                }
            }
            self.y += 1;
            self.x = self.x_lo;
        }
        None
    }
}

/// Tent inverse CDF on one axis: `F(x) = (1 + x)²/2` on `[−1, 0]`, `1 − (1 − x)²/2` on `[0, 1]`.
#[inline]
fn tent_sample(u: f32) -> f32 {
    if u < 0.5 {
        (2.0 * u).sqrt() - 1.0
    } else {
        1.0 - (2.0 - 2.0 * u).max(0.0).sqrt()
    }
}

impl Filter {
    /// Support half-width in pixels.
    pub fn radius(&self) -> f32 {
        match self {
            Filter::Box => 0.5,
            Filter::Tent => 1.0,
            Filter::Gaussian => GAUSS_RADIUS as f32,
        }
    }

    /// True if the filter is continuous, so film positions may move without pixel-edge boundary terms
    /// (docs/theory.md §2.5: derivatives through a discontinuous filter need them).
    pub fn is_continuous(&self) -> bool {
        !matches!(self, Filter::Box)
    }

    /// The pixels `(x, y)` of a `width × height` image whose filter support holds film point `p`
    /// (pixels from the top-left corner): `|p − centre| < radius` on both axes, row by row. Empty for
    /// a non-finite point.
    pub fn footprint(&self, p: glam::Vec2, width: u32, height: u32) -> Footprint {
        let r = self.radius();
        // Centres i + 0.5 in (v − r, v + r); the bounds are widened by one and the test is exact.
        let lo = |v: f32| ((v - r - 0.5).floor() as i64).max(0);
        let hi = |v: f32, n: u32| ((v + r - 0.5).ceil() as i64).min(n as i64 - 1);
        let finite = p.is_finite();
        Footprint {
            p,
            r,
            x_lo: lo(p.x),
            x_hi: if finite { hi(p.x, width) } else { -1 },
            x: lo(p.x),
            y: lo(p.y),
            y_hi: if finite { hi(p.y, height) } else { -1 },
        }
    }

    /// A film offset from the pixel centre, distributed exactly as the filter, from `u ∈ [0,1)²`.
    pub fn sample(&self, u: glam::Vec2) -> glam::Vec2 {
        match self {
            Filter::Box => u - glam::Vec2::splat(0.5),
            Filter::Tent => glam::Vec2::new(tent_sample(u.x), tent_sample(u.y)),
            Filter::Gaussian => {
                let g = Gauss::get();
                glam::Vec2::new(
                    g.inverse_cdf(u.x as f64) as f32,
                    g.inverse_cdf(u.y as f64) as f32,
                )
            }
        }
    }

    /// Filter value at offset `(dx, dy)` from the pixel centre (generic: the offset may move). Equal to the
    /// density of [`Filter::sample`]. Branches on the primal offset only at the support's edge, where every
    /// filter but the box is zero with a continuous value.
    pub fn eval<S: Scalar>(&self, dx: S, dy: S) -> S {
        match self {
            Filter::Box => {
                if dx.primal().abs() <= 0.5 && dy.primal().abs() <= 0.5 {
                    S::one()
                } else {
                    S::zero()
                }
            }
            Filter::Tent => {
                let f = |x: S| {
                    if x.primal().abs() >= 1.0 {
                        S::zero()
                    } else {
                        -x.abs() + 1.0
                    }
                };
                f(dx) * f(dy)
            }
            Filter::Gaussian => {
                let g = Gauss::get();
                let c = (1.0 / (2.0 * SIGMA * SIGMA)) as f32;
                let f = |x: S| {
                    if x.primal().abs() >= GAUSS_RADIUS as f32 {
                        S::zero()
                    } else {
                        ((x * x * -c).exp() - g.edge_f32) * g.inv_norm_f32
                    }
                };
                f(dx) * f(dy)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn erf_matches_reference_values() {
        // Reference values (Abramowitz & Stegun table 7.1 / high-precision libraries).
        for (x, e) in [
            (0.0, 0.0),
            (0.5, 0.520_499_877_813_046_5),
            (1.0, 0.842_700_792_949_714_9),
            (2.0, 0.995_322_265_018_952_7),
            (2.121_320_343_559_642_6, 0.997_300_203_936_739_8),
        ] {
            assert!((erf(x) - e).abs() < 1e-14, "erf({x}) = {} vs {e}", erf(x));
            assert!((erf(-x) + e).abs() < 1e-14);
        }
    }

    #[test]
    fn gaussian_inverse_cdf_is_exact() {
        let g = Gauss::get();
        assert!((g.cdf(GAUSS_RADIUS) - 1.0).abs() < 1e-14 && g.cdf(-GAUSS_RADIUS).abs() < 1e-14);
        for k in 0..=1000 {
            let u = k as f64 / 1000.0;
            let x = g.inverse_cdf(u);
            assert!(
                (g.cdf(x) - u).abs() < 1e-9,
                "u = {u}: x = {x}, cdf = {}",
                g.cdf(x)
            );
        }
    }
}
