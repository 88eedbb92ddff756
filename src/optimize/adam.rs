//! Adam (Kingma and Ba, "Adam: A Method for Stochastic Optimization", ICLR 2015), with a learning rate
//! per entry, configurable `β₁`, `β₂`, `ε` (the paper's defaults `0.9`, `0.999`, `1e-8`) and an optional
//! per-entry clamp of the gradient relative to Adam's own running scale of that entry.

/// Adam's hyper-parameters.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct AdamOptions {
    /// First-moment decay `β₁ ∈ [0, 1)`.
    pub beta1: f64,
    /// Second-moment decay `β₂ ∈ [0, 1)`.
    pub beta2: f64,
    /// Denominator guard `ε > 0`, in the gradient's units.
    pub epsilon: f64,
    /// Per-entry gradient clamp `k`: from the second step on, entry `i` of the gradient is clamped to
    /// `± k · √v̂ᵢ`, `v̂ᵢ` the bias-corrected second moment before this step (the entry's running RMS);
    /// entries with no history yet (`v̂ᵢ = 0`) are left as they are. `None`: no clamp.
    pub clamp: Option<f64>,
}

impl Default for AdamOptions {
    /// The paper's `β₁ = 0.9`, `β₂ = 0.999`, `ε = 1e-8`, no clamp.
    fn default() -> Self {
        Self {
            beta1: 0.9,
            beta2: 0.999,
            epsilon: 1e-8,
            clamp: None,
        }
    }
}

/// Adam's moment estimates for a vector of parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Adam {
    m: Vec<f64>,
    v: Vec<f64>,
    t: i32,
    options: AdamOptions,
}

impl Adam {
    /// Zero moments for `n` parameters, the paper's hyper-parameters.
    pub fn new(n: usize) -> Self {
        Self::with_options(n, AdamOptions::default())
    }

    /// Zero moments for `n` parameters and the given hyper-parameters.
    pub fn with_options(n: usize, options: AdamOptions) -> Self {
        Self {
            m: vec![0.0; n],
            v: vec![0.0; n],
            t: 0,
            options,
        }
    }

    /// The values after one step from `values` along the gradient `gradient`, entry `i` with step size
    /// `rates[i]`: `x − rate · m̂ / (√v̂ + ε)` with bias-corrected moments. A step moves each entry by
    /// about its rate at most. Non-finite gradient entries count as 0.
    pub fn step(&mut self, values: &[f32], gradient: &[f64], rates: &[f32]) -> Vec<f32> {
        let AdamOptions {
            beta1,
            beta2,
            epsilon,
            clamp,
        } = self.options;
        // The bias correction of the second moment as it stands before this step.
        let previous = 1.0 - beta2.powi(self.t);
        self.t += 1;
        let (c1, c2) = self.bias_corrections();
        values
            .iter()
            .zip(gradient)
            .zip(rates)
            .enumerate()
            .map(|(i, ((&x, &g), &rate))| {
                let mut g = if g.is_finite() { g } else { 0.0 };
                if let Some(k) = clamp
                    && self.v[i] > 0.0
                {
                    let bound = k * (self.v[i] / previous).sqrt();
                    g = g.clamp(-bound, bound);
                }
                self.m[i] = beta1 * self.m[i] + (1.0 - beta1) * g;
                self.v[i] = beta2 * self.v[i] + (1.0 - beta2) * g * g;
                let (m, v) = (self.m[i] / c1, self.v[i] / c2);
                (x as f64 - rate as f64 * m / (v.sqrt() + epsilon)) as f32
            })
            .collect()
    }

    /// How much of the recent gradients of the entries `range` is signal rather than noise:
    /// `Σ |m̂ᵢ| / Σ √v̂ᵢ` over the entries with a history, in `[0, 1]`: about 1 while each entry's
    /// gradients keep their sign, about [`Adam::noise_ratio`] when they are zero-mean noise. `None`
    /// before the first step or when no entry of `range` has had a gradient.
    pub fn signal_ratio(&self, range: std::ops::Range<usize>) -> Option<f64> {
        if self.t == 0 {
            return None;
        }
        let (c1, c2) = self.bias_corrections();
        let (mut m, mut v) = (0.0, 0.0);
        for i in range {
            if self.v[i] > 0.0 {
                m += (self.m[i] / c1).abs();
                v += (self.v[i] / c2).sqrt();
            }
        }
        (v > 0.0).then(|| m / v)
    }

    /// What [`Adam::signal_ratio`] is, after the steps taken so far, for gradients that are zero-mean
    /// Gaussian noise of one scale `σ`: `E|m̂| / E√v̂ = √(2/π) · √(Σₖ wₖ²) / c`, `wₖ` the weights of
    /// the `t` gradients in `m̂` (`(1 − β₁) β₁^(t−k) / (1 − β₁ᵗ)`) and `c = E[χₜ]/√t` the mean of `√v̂`
    /// over `σ` (`v̂` taken as the mean of the `t` squares, as it nearly is for `t ≪ 1/(1 − β₂)`). 1
    /// before any step and after the first; `√(2/π) · √((1 − β₁)/(1 + β₁))` (0.183 at `β₁ = 0.9`)
    /// after many. Heavier-tailed noise gives less.
    pub fn noise_ratio(&self) -> f64 {
        if self.t == 0 {
            return 1.0;
        }
        let b = self.options.beta1;
        let bt = b.powi(self.t);
        let sum_w2 =
            (1.0 - b) * (1.0 - b) * (1.0 - bt * bt) / ((1.0 - b * b) * (1.0 - bt) * (1.0 - bt));
        // E[χ₁] = √(2/π) and E[χₖ] E[χₖ₊₁] = k; past a few hundred steps c is 1 to 10⁻³.
        let steps = self.t.min(1000);
        let mut mean_chi = (2.0 / std::f64::consts::PI).sqrt();
        for k in 1..steps {
            mean_chi = k as f64 / mean_chi;
        }
        let c = mean_chi / (steps as f64).sqrt();
        (2.0 / std::f64::consts::PI).sqrt() * sum_w2.sqrt() / c
    }

    /// The bias corrections `(1 − β₁ᵗ, 1 − β₂ᵗ)` of the moments after `t` steps.
    fn bias_corrections(&self) -> (f64, f64) {
        (
            1.0 - self.options.beta1.powi(self.t),
            1.0 - self.options.beta2.powi(self.t),
        )
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

    /// The clamp: after a step with gradient 1 (`v̂ = 1`), a spike of 100 enters as `k = 2`, so the
    /// moments and the step are those of an unclamped Adam fed 1 then 2; the first step and an entry
    /// without history are not clamped.
    #[test]
    fn clamp_bounds_spikes_by_the_running_scale() {
        let options = AdamOptions {
            clamp: Some(2.0),
            ..AdamOptions::default()
        };
        let mut clamped = Adam::with_options(2, options);
        let mut plain = Adam::new(2);
        let rates = [0.1, 0.1];
        let a = clamped.step(&[0.0, 0.0], &[1.0, 0.0], &rates);
        let b = plain.step(&[0.0, 0.0], &[1.0, 0.0], &rates);
        assert_eq!(a, b);
        // Entry 1 had gradient 0 so far (v = 0): its 50 is not clamped.
        let a = clamped.step(&a, &[100.0, 50.0], &rates);
        let b = plain.step(&b, &[2.0, 50.0], &rates);
        assert_eq!(a, b);
        assert_eq!(clamped.m, plain.m);
        assert_eq!(clamped.v, plain.v);
    }

    /// `β₂` and `ε` are used as given: with `β₁ = 0`, `β₂ = 0`, the step is `rate · g / (|g| + ε)`.
    #[test]
    fn betas_and_epsilon_are_used() {
        let options = AdamOptions {
            beta1: 0.0,
            beta2: 0.0,
            epsilon: 1.0,
            clamp: None,
        };
        let mut adam = Adam::with_options(1, options);
        let x = adam.step(&[0.0], &[1.0], &[0.1]);
        assert!((x[0] + 0.05).abs() < 1e-7, "{x:?}");
        let x = adam.step(&x, &[-3.0], &[0.1]);
        assert!((x[0] - (-0.05 + 0.075)).abs() < 1e-7, "{x:?}");
    }

    /// Deterministic standard Gaussian noise: Box–Muller on two uniforms from SplitMix64 of `k`.
    fn noise(k: u64) -> f64 {
        let uniform = |x: u64| {
            let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        };
        let (u1, u2) = (1.0 - uniform(2 * k), uniform(2 * k + 1));
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// The signal ratio is 1 for gradients that keep their signs, and close to the noise ratio for
    /// zero-mean Gaussian noise at every step count.
    #[test]
    fn signal_ratio_tells_signal_from_noise() {
        let n = 20_000;
        let mut steady = Adam::new(n);
        let mut noisy = Adam::new(n);
        assert_eq!(steady.signal_ratio(0..n), None);
        assert_eq!(noisy.noise_ratio(), 1.0);
        let x = vec![0.0f32; n];
        let rates = vec![0.0f32; n];
        for t in 1..=60u64 {
            let g: Vec<f64> = (0..n)
                .map(|i| if i % 2 == 0 { 1.0 } else { -3.0 })
                .collect();
            steady.step(&x, &g, &rates);
            let g: Vec<f64> = (0..n as u64).map(|i| noise(t * n as u64 + i)).collect();
            noisy.step(&x, &g, &rates);
            let s = steady.signal_ratio(0..n).unwrap();
            assert!((s - 1.0).abs() < 1e-9, "steady gradients: {s} at step {t}");
            let (r, expected) = (noisy.signal_ratio(0..n).unwrap(), noisy.noise_ratio());
            // Sampling error of 20,000 entries: about 1%; β₂ < 1 (v̂ is not quite the plain mean of
            // the squares) a little more.
            let tolerance = 0.04;
            assert!(
                (r / expected - 1.0).abs() < tolerance,
                "noise: {r} against {expected} at step {t}"
            );
        }
        // Entries without a gradient do not count.
        assert_eq!(Adam::new(3).signal_ratio(0..3), None);
        let mut idle = Adam::new(2);
        idle.step(&[0.0; 2], &[0.0, 0.0], &[0.1, 0.1]);
        assert_eq!(idle.signal_ratio(0..2), None);
    }
}
