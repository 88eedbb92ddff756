//! Derivative time / primal time on the default scene (`scenes/sphere_floor.json`, 64×64, direct), same
//! spp and seed, measured in one run: one parameter (`ball.radius`) and eight at once. Goals: ≤ 1.5 and
//! ≤ 4. The runs are interleaved and the medians of several repetitions compared (the machine is shared:
//! ratios, not absolute times, are the figures to quote).
//!
//! `cargo bench --bench derivative [-- REPS]`.

use implicit_psdr::integrator::{DiffOptions, Normalization, render_interior};
use implicit_psdr::integrator::{RenderOptions, render};
use implicit_psdr::scene::{Scene, load};
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

fn default_scene() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/sphere_floor.json");
    load(&path).expect("the default scene parses")
}

/// The eight parameters of the eight-direction pass; the one-direction pass takes the first.
const EIGHT: [&str; 8] = [
    "ball.radius",
    "ball.center.x",
    "ball.center.y",
    "ball.albedo.r",
    "floor.translate.y",
    "light.center.y",
    "light.radiance.r",
    "camera.origin.x",
];

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let reps: usize = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(7);
    let spp = 16;
    let render_options = RenderOptions {
        spp,
        seed: 0,
        progress: Default::default(),
    };
    let options = DiffOptions {
        render: render_options.clone(),
        normalization: Normalization::Fixed,
        ..Default::default()
    };
    let plain = default_scene();
    let one = plain.select(&EIGHT[..1]).expect("the parameters exist");
    let eight = plain.select(&EIGHT).expect("the parameters exist");
    // Warm-up (thread pool, caches).
    black_box(render(&plain, &render_options));
    let (mut tp, mut t1, mut t8, mut t8d) = (vec![], vec![], vec![], vec![]);
    for _ in 0..reps {
        let t = Instant::now();
        black_box(render(&plain, &render_options));
        tp.push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        black_box(render_interior(&plain, &one, &options).unwrap());
        t1.push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        black_box(render_interior(&plain, &eight, &options).unwrap());
        t8.push(t.elapsed().as_secs_f64());
        let o = DiffOptions {
            normalization: Normalization::Differentiable,
            ..options.clone()
        };
        let t = Instant::now();
        black_box(render_interior(&plain, &eight, &o).unwrap());
        t8d.push(t.elapsed().as_secs_f64());
    }
    let (p, d1, d8, d8d) = (median(tp), median(t1), median(t8), median(t8d));
    println!("default scene 64x64, {spp} spp, direct, median of {reps}:");
    println!("  primal                      {:8.1} ms", p * 1e3);
    println!(
        "  1 parameter  (DualN<1>)     {:8.1} ms  ratio {:.2} (goal <= 1.5)",
        d1 * 1e3,
        d1 / p
    );
    println!(
        "  8 parameters (DualN<8>)     {:8.1} ms  ratio {:.2} (goal <= 4)",
        d8 * 1e3,
        d8 / p
    );
    println!(
        "  8 parameters, differentiable normalisation {:8.1} ms  ratio {:.2}",
        d8d * 1e3,
        d8d / p
    );
}
