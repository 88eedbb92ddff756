//! The learning-rate schedule of an optimisation (decay over the run, and grid steps scaled with the
//! grid's resolution) and the exponential moving average of the parameters that a run reports and
//! saves.

/// How the learning rate decays over the iterations.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Decay {
    /// A constant rate.
    None,
    /// Half a cosine from the rate at iteration 0 down to `final_fraction` of it at the last
    /// iteration: `f + (1 − f) · (1 + cos(π t / (T − 1))) / 2`.
    Cosine {
        /// The fraction `f` of the rate left at the last iteration.
        final_fraction: f32,
    },
    /// Geometric from the rate at iteration 0 down to `final_fraction` of it at the last iteration:
    /// `f^(t / (T − 1))`.
    Exponential {
        /// The fraction `f` of the rate left at the last iteration.
        final_fraction: f32,
    },
}

impl Decay {
    /// The factor of the learning rate at iteration `index` (0-based) of `iterations`: 1 at the first,
    /// the final fraction at the last (1 throughout for a run of one iteration).
    pub fn factor(self, index: u32, iterations: u32) -> f32 {
        if iterations <= 1 {
            return 1.0;
        }
        let s = (index.min(iterations - 1) as f64) / (iterations - 1) as f64;
        match self {
            Decay::None => 1.0,
            Decay::Cosine { final_fraction } => {
                let f = final_fraction as f64;
                (f + (1.0 - f) * 0.5 * (1.0 + (std::f64::consts::PI * s).cos())) as f32
            }
            Decay::Exponential { final_fraction } => (final_fraction as f64).powf(s) as f32,
        }
    }
}

/// The factor of the learning rate at iteration `index` for the warm-up after a refinement: with the
/// last refinement at `u ≤ index` (of `upsample_at`), `min(1, (index − u + 1) / iterations)`; 1
/// before the first refinement or with `iterations` 0.
///
/// A refinement restarts Adam, whose first steps are then about the full rate for every entry with
/// a gradient, whatever its sign's noise (a step is `m / √v`, ±1 when `m` and `v` hold one gradient):
/// on a shape already close to its target, a full-rate step of every lattice value near the surface
/// undoes several iterations of progress. The ramp lets Adam's moments gather a few gradients first.
pub fn warmup(index: u32, upsample_at: &[u32], iterations: u32) -> f32 {
    match upsample_at.iter().filter(|&&u| u <= index).max() {
        Some(&u) if iterations > 0 => ((index - u + 1) as f32 / iterations as f32).min(1.0),
        _ => 1.0,
    }
}

/// How a grid's learning rate follows its lattice spacing as `upsample_at` refines it: each
/// refinement `n → n'` points along the longest axis multiplies the grid's rate by
/// `((n − 1) / (n' − 1))ᵖ` (a half per power for the usual `n' = 2n − 1`).
///
/// With `p` = 1 a step stays the same fraction of a cell at every stage. A larger `p` makes it a
/// smaller fraction, which suits a shape the coarser stage has already found (a finer value is seen
/// by fewer pixels, so its gradient is noisier relative to its signal, and Adam moves a
/// noise-dominated value by about the rate) and slows one whose detail still has far to move;
/// docs/inverse-rendering.md has both measurements.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum ResolutionPower {
    /// The same power `p ≥ 0` at every refinement (0: the rate ignores the resolution).
    Fixed(f32),
    /// At each refinement, 2 if the stage that ends had converged and 1 if its shape was still
    /// moving ([`auto_power`]).
    Auto,
}

/// [`ResolutionPower::Auto`] judges a stage converged when Adam's signal ratio over the grid's values
/// at its last step ([`super::Adam::signal_ratio`]) is at most this multiple of what zero-mean noise
/// gives ([`super::Adam::noise_ratio`]).
///
/// On the race and the scanned bunny of docs/inverse-rendering.md, stages that had converged ended
/// at 0.76–1.00 times the noise's ratio and stages whose shape still moved at 1.47–1.83 times it;
/// 1.2 is near the geometric middle of the gap.
pub const AUTO_CONVERGED_RATIO: f64 = 1.2;

/// The power of the lattice spacing for a refinement under [`ResolutionPower::Auto`]: 2 when the
/// stage that ends had converged (`signal ≤` [`AUTO_CONVERGED_RATIO`]` · noise`), else 1 (also when
/// the stage took no step: `signal` is `None`).
pub fn auto_power(signal: Option<f64>, noise: f64) -> f32 {
    match signal {
        Some(s) if s <= AUTO_CONVERGED_RATIO * noise => 2.0,
        _ => 1.0,
    }
}

/// The factor of a grid's learning rate for one refinement from `before` to `after` points per axis,
/// with the spacing's power `power`: `((n − 1) / (n' − 1))ᵖ` along the longest axis.
pub fn refinement_scale(before: [usize; 3], after: [usize; 3], power: f32) -> f32 {
    let longest = |d: [usize; 3]| d.iter().copied().max().unwrap_or(2).max(2) - 1;
    (longest(before) as f32 / longest(after) as f32).powf(power)
}

/// The exponential moving average of a parameter vector, with a weight on the past that grows from 0
/// to `β` as values come in: the first value is the average, then the `t`-th value (`t ≥ 1` values
/// before it) enters as `a ← βₜ a + (1 − βₜ) x`, `βₜ = min(β, (1 + t) / (10 + t))` (the warm-up of
/// TensorFlow's `ExponentialMovingAverage` with `num_updates`). Early on, while the values move fast,
/// the average follows them closely; later it averages about `1 / (1 − β)` of them.
#[derive(Clone, Debug, PartialEq)]
pub struct Ema {
    beta: f64,
    average: Vec<f64>,
    /// Values averaged so far.
    count: u64,
}

impl Ema {
    /// An empty average of `n` values with weight at most `beta ∈ [0, 1)` on the past.
    pub fn new(n: usize, beta: f64) -> Self {
        Self {
            beta,
            average: vec![0.0; n],
            count: 0,
        }
    }

    /// The weight on the past when the next value comes in: `min(β, (1 + t) / (10 + t))` for `t ≥ 1`
    /// values so far, 0 for the first.
    pub fn weight(&self) -> f64 {
        if self.count == 0 {
            return 0.0;
        }
        let t = self.count as f64;
        self.beta.min((1.0 + t) / (10.0 + t))
    }

    /// Adds the values `x` (of the average's length).
    pub fn push(&mut self, x: &[f32]) {
        let w = self.weight();
        for (a, &x) in self.average.iter_mut().zip(x) {
            *a = w * *a + (1.0 - w) * x as f64;
        }
        self.count += 1;
    }

    /// The average (`None` before the first value).
    pub fn value(&self) -> Option<Vec<f32>> {
        (self.count > 0).then(|| self.average.iter().map(|&a| a as f32).collect())
    }

    /// Replaces the average by `map` of it, keeping the count: for a linear `map` (a grid's
    /// refinement) the result is the average of the mapped values. Does nothing before the first
    /// value.
    pub fn remap(&mut self, map: impl FnOnce(Vec<f32>) -> Vec<f32>) {
        if let Some(value) = self.value() {
            self.average = map(value).iter().map(|&v| v as f64).collect();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The warm-up ramps from 1/W at each refinement to 1 at its W-th iteration.
    #[test]
    fn warmup_ramps_after_each_refinement() {
        let at = [10, 20];
        let got: Vec<f32> = [0, 9, 10, 11, 12, 13, 14, 15, 19, 20, 24, 30]
            .iter()
            .map(|&i| warmup(i, &at, 5))
            .collect();
        assert_eq!(
            got,
            [1.0, 1.0, 0.2, 0.4, 0.6, 0.8, 1.0, 1.0, 1.0, 0.2, 1.0, 1.0]
        );
        assert_eq!(warmup(10, &at, 0), 1.0);
        assert_eq!(warmup(10, &[], 5), 1.0);
    }

    /// The cosine and exponential schedules against their closed forms at a few iterations.
    #[test]
    fn decay_values() {
        let cos = Decay::Cosine {
            final_fraction: 0.1,
        };
        let exp = Decay::Exponential {
            final_fraction: 0.01,
        };
        let close = |a: f32, b: f32| assert!((a - b).abs() < 1e-6, "{a} vs {b}");
        close(cos.factor(0, 101), 1.0);
        close(cos.factor(50, 101), 0.55);
        close(cos.factor(100, 101), 0.1);
        close(cos.factor(25, 101), 0.1 + 0.9 * 0.5 * (1.0 + 0.5f32.sqrt()));
        close(exp.factor(0, 101), 1.0);
        close(exp.factor(50, 101), 0.1);
        close(exp.factor(100, 101), 0.01);
        close(Decay::None.factor(70, 101), 1.0);
        close(cos.factor(0, 1), 1.0);
        // Past the end (never asked by a run) the last value holds.
        close(cos.factor(500, 101), 0.1);
    }

    /// Refinement halves the grid's spacing, the factor is its power; a non-cubic grid goes by its
    /// longest side.
    #[test]
    fn refinement_scales() {
        assert_eq!(refinement_scale([16; 3], [16; 3], 1.0), 1.0);
        assert_eq!(refinement_scale([16; 3], [31; 3], 1.0), 0.5);
        assert_eq!(refinement_scale([31; 3], [61; 3], 1.0), 0.5);
        assert_eq!(refinement_scale([9, 5, 3], [17, 9, 5], 1.0), 0.5);
        assert_eq!(refinement_scale([16; 3], [31; 3], 2.0), 0.25);
        assert_eq!(refinement_scale([16; 3], [31; 3], 0.0), 1.0);
    }

    /// The automatic power: 2 after a stage whose gradients were noise-like, 1 while they carried a
    /// signal or when there were none.
    #[test]
    fn auto_power_follows_the_signal() {
        let noise = 0.2;
        assert_eq!(auto_power(Some(0.15), noise), 2.0);
        assert_eq!(auto_power(Some(0.2), noise), 2.0);
        assert_eq!(auto_power(Some(AUTO_CONVERGED_RATIO * noise), noise), 2.0);
        assert_eq!(auto_power(Some(0.3), noise), 1.0);
        assert_eq!(auto_power(Some(1.0), noise), 1.0);
        assert_eq!(auto_power(None, noise), 1.0);
    }

    /// The average of a known sequence: the warm-up weights, then `β`; and its remapping.
    #[test]
    fn ema_of_a_known_sequence() {
        let mut ema = Ema::new(2, 0.5);
        assert_eq!(ema.value(), None);
        assert_eq!(ema.weight(), 0.0);
        ema.push(&[2.0, -4.0]);
        assert_eq!(ema.value().unwrap(), vec![2.0, -4.0]);
        // t = 1: weight 2/11.
        assert!((ema.weight() - 2.0 / 11.0).abs() < 1e-12);
        ema.push(&[13.0, 7.0]);
        let v = ema.value().unwrap();
        assert!(
            (v[0] - 11.0).abs() < 1e-5 && (v[1] - 5.0).abs() < 1e-5,
            "{v:?}"
        );
        // t = 2: weight 3/12; t = 8: min(0.5, 9/18) = 0.5; t = 20: 0.5 (β caps it).
        assert!((ema.weight() - 0.25).abs() < 1e-12);
        ema.push(&[3.0, 1.0]);
        let v = ema.value().unwrap();
        assert!(
            (v[0] - 5.0).abs() < 1e-5 && (v[1] - 2.0).abs() < 1e-5,
            "{v:?}"
        );
        // A linear map of the average is the average of the mapped values.
        ema.remap(|v| vec![v[0], v[0] + v[1], 2.0 * v[1]]);
        ema.push(&[1.0, 3.0, 0.0]);
        let mut direct = Ema::new(3, 0.5);
        for x in [
            [2.0f32, -2.0, -8.0],
            [13.0, 20.0, 14.0],
            [3.0, 4.0, 2.0],
            [1.0, 3.0, 0.0],
        ] {
            direct.push(&x);
        }
        let (a, b) = (ema.value().unwrap(), direct.value().unwrap());
        for (a, b) in a.iter().zip(&b) {
            assert!((a - b).abs() < 1e-5, "{a:?} vs {b:?}");
        }
        let mut long = Ema::new(1, 0.9);
        for _ in 0..8 {
            long.push(&[0.0]);
        }
        assert!((long.weight() - 9.0 / 18.0).abs() < 1e-12);
        for _ in 0..200 {
            long.push(&[0.0]);
        }
        assert_eq!(long.weight(), 0.9);
        // β = 0: the last value.
        let mut last = Ema::new(1, 0.0);
        last.push(&[3.0]);
        last.push(&[5.0]);
        assert_eq!(last.value().unwrap(), vec![5.0]);
    }
}
