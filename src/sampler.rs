//! Deterministic random numbers: a sample's numbers are a pure function of (seed, pixel, sample index,
//! dimension), so a pixel renders the same whatever the thread count, the primal and derivative passes see
//! the same samples, and one pixel can be re-rendered alone. The dimension is the draw order.
//!
//! **Stratified film positions.** [`stratified_2d`] gives the samples `0, 1, …` of one pixel the
//! points of a scrambled Sobol (0, 2)-sequence: the first `2^k` of them fall one in each elementary
//! interval of area `2^-k` of the unit square, so a pixel's estimate of a silhouette's coverage, or of
//! the shading across it, has far less variance than with independent points, and every point is still
//! uniform. The scramble is Laine and Karras's hash with a seed per (seed, stream, pixel), as in
//! pbrt-v4's Sobol samplers: a nested scramble whose top 16 output bits are uniform for a uniform seed
//! (each step maps the low bits of its input to the low bits of its output bijectively, and the seed
//! is added to the low 16 bits); the 8 bits below them are the sample's own random bits, so each
//! coordinate is uniform on the 24-bit grid of [`Sampler::next_1d`]. Only the film position is
//! stratified: the other draws of a sample stay independent ([`Sampler`]), since stratifying them
//! each with the same sample index couples the draws of a pixel's samples (measured: the finite
//! differences of a soft shadow's derivative, taken with common random numbers, became several times
//! noisier), while the film position alone carries nearly all of the variance reduction in the
//! inverse-rendering images (docs/inverse-rendering.md, "Stratified film positions").

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

/// Direction numbers of the second dimension of the Sobol sequence (primitive polynomial `x + 1`),
/// bit-reversed: `v_0 = 1`, `v_k = v_(k−1) ^ (v_(k−1) << 1)` (the columns of Pascal's triangle mod 2).
const SOBOL_1_REVERSED: [u32; 32] = {
    let mut v = [0u32; 32];
    v[0] = 1;
    let mut k = 1;
    while k < 32 {
        v[k] = v[k - 1] ^ (v[k - 1] << 1);
        k += 1;
    }
    v
};

/// The second Sobol coordinate of point `index`, bit-reversed (its most significant fraction bit in
/// bit 0).
#[inline]
fn sobol_1_reversed(index: u32) -> u32 {
    let mut bits = index;
    let mut v = 0;
    let mut k = 0;
    while bits != 0 {
        if bits & 1 != 0 {
            v ^= SOBOL_1_REVERSED[k];
        }
        bits >>= 1;
        k += 1;
    }
    v
}

/// Laine and Karras's nested scramble of a bit-reversed coordinate `v` (its most significant fraction
/// bit in bit 0) with `seed`, returned as a fraction in the usual bit order. Each step maps the low
/// `k` bits of its input to the low `k` bits of its output bijectively, so the points of one
/// elementary interval stay together.
#[inline]
fn scramble(mut v: u32, seed: u32) -> u32 {
    v ^= v.wrapping_mul(0x3d20_adea);
    v = v.wrapping_add(seed);
    v = v.wrapping_mul((seed >> 16) | 1);
    v ^= v.wrapping_mul(0x0552_6c56);
    v ^= v.wrapping_mul(0x53a2_2864);
    v.reverse_bits()
}

/// Separates the stratified points' keys from the independent streams' states.
const STRATA_SALT: u64 = 0x57A7_1F1E_D5A3_9B01;

/// Point `sample` of pixel `pixel`'s scrambled Sobol (0, 2)-sequence in `[0, 1)²` under `seed` and
/// `stream` (module docs): the pixel's first `2^k` points are stratified, each is uniform on the 24-bit
/// grid of [`Sampler::next_1d`].
#[inline]
pub fn stratified_2d(seed: u64, stream: u64, pixel: u64, sample: u64) -> Vec2 {
    let key = mix(mix(seed ^ mix(stream ^ STRATA_SALT)) ^ pixel.rotate_left(32));
    let low = mix(key ^ sample);
    let index = sample as u32;
    // The first Sobol coordinate is the index's bit reversal: bit-reversed, the index itself.
    let x = scramble(index, key as u32);
    let y = scramble(sobol_1_reversed(index), (key >> 32) as u32);
    // The scramble's top 16 bits and 8 of the sample's own.
    let fraction = |s: u32, low: u64| ((s >> 16) << 8 | (low as u32 & 0xff)) as f32 / 16_777_216.0;
    Vec2::new(fraction(x, low), fraction(y, low >> 8))
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

    /// The first 16 points of a pixel put one point in every elementary interval of area 1/16 (a
    /// (0, 4, 2)-net), and the first 64 one in every interval of area 1/64.
    #[test]
    fn stratified_points_form_nets() {
        for pixel in [0, 1, 77, 1 << 40] {
            for m in [4u32, 6] {
                let n = 1usize << m;
                let points: Vec<Vec2> = (0..n as u64)
                    .map(|s| stratified_2d(3, 5, pixel, s))
                    .collect();
                for i in 0..=m {
                    let (nx, ny) = (1usize << i, 1usize << (m - i));
                    let mut seen = vec![false; n];
                    for p in &points {
                        let cell = (p.x * nx as f32) as usize * ny + (p.y * ny as f32) as usize;
                        assert!(!seen[cell], "pixel {pixel}: two points in a {nx}x{ny} cell");
                        seen[cell] = true;
                    }
                }
            }
        }
    }

    /// Over many pixels, each point of the sequence is uniform: chi-square over 16 x 16 cells for
    /// points 0 (the scramble's image of the origin), 1, 5 and 13.
    #[test]
    fn stratified_points_are_uniform() {
        let n = 100_000u64;
        for sample in [0, 1, 5, 13] {
            let mut cells = vec![0u32; 256];
            for pixel in 0..n {
                let p = stratified_2d(9, 2, pixel, sample);
                cells[(p.x * 16.0) as usize * 16 + (p.y * 16.0) as usize] += 1;
            }
            let e = n as f64 / 256.0;
            let chi2: f64 = cells.iter().map(|&c| (c as f64 - e).powi(2) / e).sum();
            // 255 degrees of freedom: mean 255, standard deviation 22.6; 370 is 5 deviations up.
            assert!(chi2 < 370.0, "point {sample}: chi-square {chi2}");
        }
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
