//! Adam (Kingma and Ba, "Adam: A Method for Stochastic Optimization", ICLR 2015), with the paper's
//! defaults `β₁ = 0.9`, `β₂ = 0.999`, `ε = 1e-8` and a learning rate per entry.

/// Adam's moment estimates for a vector of parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Adam {
    m: Vec<f64>,
    v: Vec<f64>,
    t: i32,
}

impl Adam {
    /// First-moment decay.
    pub const BETA1: f64 = 0.9;
    /// Second-moment decay.
    pub const BETA2: f64 = 0.999;
    /// Denominator guard.
    pub const EPS: f64 = 1e-8;

    /// Zero moments for `n` parameters.
    pub fn new(n: usize) -> Self {
        Self {
            m: vec![0.0; n],
            v: vec![0.0; n],
            t: 0,
        }
    }

    /// The values after one step from `values` along the gradient `gradient`, entry `i` with step size
    /// `rates[i]`: `x − rate · m̂ / (√v̂ + ε)` with bias-corrected moments. A step moves each entry by
    /// about its rate at most.
    pub fn step(&mut self, values: &[f32], gradient: &[f64], rates: &[f32]) -> Vec<f32> {
        self.t += 1;
        let (c1, c2) = (
            1.0 - Self::BETA1.powi(self.t),
            1.0 - Self::BETA2.powi(self.t),
        );
        values
            .iter()
            .zip(gradient)
            .zip(rates)
            .enumerate()
            .map(|(i, ((&x, &g), &rate))| {
                let g = if g.is_finite() { g } else { 0.0 };
                self.m[i] = Self::BETA1 * self.m[i] + (1.0 - Self::BETA1) * g;
                self.v[i] = Self::BETA2 * self.v[i] + (1.0 - Self::BETA2) * g * g;
                let (m, v) = (self.m[i] / c1, self.v[i] / c2);
                (x as f64 - rate as f64 * m / (v.sqrt() + Self::EPS)) as f32
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On `f(x) = Σ (x_i − c_i)²` Adam reaches the minimum, each entry at its own rate.
    #[test]
    fn minimises_a_quadratic() {
        let c = [1.5f32, -2.0, 0.25];
        let mut x = vec![0.0f32; 3];
        let mut adam = Adam::new(3);
        for _ in 0..2000 {
            let g: Vec<f64> = x.iter().zip(c).map(|(x, c)| 2.0 * (x - c) as f64).collect();
            x = adam.step(&x, &g, &[0.05, 0.05, 0.01]);
        }
        for (x, c) in x.iter().zip(c) {
            assert!((x - c).abs() < 1e-2, "{x} vs {c}");
        }
    }

    /// The first step moves every entry by its rate whatever the gradient's size (the bias-corrected
    /// `m̂/√v̂` is ±1, up to `ε/|g|`: 1e-5 of the rate for `|g| = 1e-3`).
    #[test]
    fn first_step_is_the_rate() {
        let mut adam = Adam::new(2);
        let x = adam.step(&[1.0, 1.0], &[3.0, -1e-3], &[0.1, 0.2]);
        assert!((x[0] - 0.9).abs() < 1e-6, "{x:?}");
        assert!((x[1] - 1.2).abs() < 0.2 * 1e-5 + 1e-6, "{x:?}");
    }
}
