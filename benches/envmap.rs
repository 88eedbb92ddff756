//! The variance reduction of the environment map's importance sampling (luminance × sin θ) against
//! uniform sphere sampling, at equal sample counts, under the example map `scenes/sky.exr` (a sky with
//! a bright sun-like spot): the irradiance `E = ∫ L(ω) max(n·ω, 0) dω` at surface points of several
//! orientations, estimated from one direction per sample by each strategy (next-event estimation
//! alone, no multiple importance sampling). The per-sample variances are measured over many samples
//! and their ratio printed per orientation; both estimators are checked to agree on `E`.
//!
//! `cargo bench --bench envmap [-- SAMPLES]`.

use implicit_psdr::emitter::{Emitter, EnvMap};
use implicit_psdr::math::Vec3;
use implicit_psdr::math::sampling::{UNIFORM_SPHERE_PDF, uniform_sphere};
use implicit_psdr::scalar::Param;
use std::path::Path;
use std::sync::Arc;

/// Mean and variance of `f` over `n` samples of a low-discrepancy-free hash sequence.
fn moments(n: usize, mut f: impl FnMut(glam::Vec2) -> f64) -> (f64, f64) {
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = || {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        ((state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40) as f32) / (1u64 << 24) as f32
    };
    let (mut s, mut s2) = (0.0, 0.0);
    for _ in 0..n {
        let u = glam::Vec2::new(next(), next());
        let v = f(u);
        s += v;
        s2 += v * v;
    }
    let mean = s / n as f64;
    (mean, (s2 / n as f64 - mean * mean).max(0.0))
}

fn main() {
    let n: usize = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(2_000_000);
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/sky.exr");
    let map = EnvMap::read(&path).expect("scenes/sky.exr (cargo run --example make_envmap)");
    let env = Emitter::Envmap {
        map: Arc::new(map),
        scale: Param::new(1.0),
        axis: glam::Vec3::Y,
        angle: Param::new(0.0),
    };
    let radiance = |w: glam::Vec3| -> f64 {
        let back = Vec3::<f32>::constant(-w);
        let l: glam::Vec3 = env.emitted::<f32>(Vec3::zero(), back, back).into();
        (0.2126 * l.x + 0.7152 * l.y + 0.0722 * l.z) as f64
    };
    println!("irradiance (luminance) under scenes/sky.exr, {n} samples per strategy");
    println!("normal              E (importance)  E (uniform)  variance ratio uniform/importance");
    let mut ratios = Vec::new();
    for normal in [
        glam::Vec3::Y,
        glam::Vec3::new(1.0, 1.0, 0.0).normalize(),
        glam::Vec3::new(-1.0, 0.3, 0.5).normalize(),
        glam::Vec3::Z,
    ] {
        let (e_is, v_is) = moments(n, |u| match env.sample_li(glam::Vec3::ZERO, u) {
            Some(s) => radiance(s.wi) * normal.dot(s.wi).max(0.0) as f64 / s.pdf as f64,
            None => 0.0,
        });
        let (e_un, v_un) = moments(n, |u| {
            let w = uniform_sphere(u);
            radiance(w) * normal.dot(w).max(0.0) as f64 / UNIFORM_SPHERE_PDF as f64
        });
        let ratio = v_un / v_is;
        ratios.push(ratio);
        println!(
            "{:<19} {e_is:>15.4} {e_un:>12.4} {ratio:>10.1}",
            format!("{:.2?}", normal.to_array())
        );
        let tol = 5.0 * (v_un / n as f64).sqrt() + 5.0 * (v_is / n as f64).sqrt();
        assert!(
            (e_is - e_un).abs() <= tol,
            "the two estimators disagree: {e_is} vs {e_un}"
        );
    }
    ratios.sort_by(f64::total_cmp);
    println!(
        "variance reduction: {:.1}x to {:.1}x (median {:.1}x)",
        ratios[0],
        ratios[ratios.len() - 1],
        ratios[ratios.len() / 2]
    );
}
