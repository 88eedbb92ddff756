//! Deterministic random numbers: a sample's numbers are a pure function of (seed, pixel, sample index,
//! dimension), so a pixel renders the same whatever the thread count, the primal and derivative passes see
//! the same samples, and one pixel can be re-rendered alone. The dimension is the draw order.

use glam::Vec2;
use rand_core::Rng;
use rand_pcg::Pcg32;

/// A stream of uniform numbers in `[0, 1)` for one (seed, pixel, sample).
#[derive(Clone, Debug)]
pub struct Sampler {
    rng: Pcg32,
}

/// SplitMix64 finaliser: decorrelates neighbouring keys before they seed the generator.
#[inline]
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl Sampler {
    /// The stream for `sample` of pixel index `pixel` (row-major, `y * width + x`) under `seed`.
    /// `stream` separates independent uses (camera paths, boundary samples, ...) of the same indices.
    #[inline]
    pub fn new(seed: u64, stream: u64, pixel: u64, sample: u64) -> Self {
        let state = mix(mix(seed ^ mix(stream)) ^ pixel.rotate_left(32) ^ sample);
        Self {
            rng: Pcg32::new(state, mix(state ^ stream)),
        }
    }
    /// Next number in `[0, 1)`.
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        // 24 random bits: every value is exactly representable and strictly below 1.
        (self.rng.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }
    /// Next two numbers in `[0, 1)²`.
    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        let x = self.next_1d();
        Vec2::new(x, self.next_1d())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_reproducible_and_distinct() {
        let a: Vec<f32> = {
            let mut s = Sampler::new(7, 0, 3, 4);
            (0..8).map(|_| s.next_1d()).collect()
        };
        let b: Vec<f32> = {
            let mut s = Sampler::new(7, 0, 3, 4);
            (0..8).map(|_| s.next_1d()).collect()
        };
        let c: Vec<f32> = {
            let mut s = Sampler::new(7, 0, 3, 5);
            (0..8).map(|_| s.next_1d()).collect()
        };
        assert_eq!(a, b);
        assert_ne!(a, c);
        assert!(a.iter().all(|&v| (0.0..1.0).contains(&v)));
    }

    #[test]
    fn mean_is_one_half() {
        let mut sum = 0.0f64;
        let n = 100_000;
        for i in 0..n {
            sum += Sampler::new(1, 0, i, 0).next_1d() as f64;
        }
        assert!((sum / n as f64 - 0.5).abs() < 0.005);
    }
}
