//! The "Boundary sample budgets" measurement of docs/derivatives.md: for several pairs of boundary
//! budgets (primary + secondary samples per pixel) at the scene's own spp, the noise of `diff`'s complete
//! derivative times its time, the figure of merit of a Monte Carlo estimator (lower is better).
//!
//! The noise is measured without a reference: two renders with different seeds differ by twice the
//! estimator's variance in expectation, so the relative variance of one render is
//! `Σ(a−b)² / 2 / Σ((a+b)/2)²` over all pixels and channels, averaged over the parameters and over
//! `PAIRS` pairs of seeds. The time is the mean of all renders'.
//!
//! `cargo run --release --example boundary_budgets -- [SCENE.json] [PARAM ...]`
//! (defaults: `scenes/sphere_floor.json`, `ball.radius ball.center.x light.center.x`, all in one pass).

use implicit_psdr::integrator::{BoundaryBudget, DiffOptions, RenderOptions, render_derivatives};
use implicit_psdr::scene;
use std::path::Path;
use std::time::Instant;

/// Pairs of seeds per budget.
const PAIRS: u64 = 3;

/// The budget pairs measured: proportional ones around the default and a few lopsided ones.
const BUDGETS: [(u32, u32); 9] = [
    (1, 4),
    (2, 8),
    (4, 16),
    (8, 32),
    (16, 64),
    (2, 2),
    (2, 32),
    (8, 8),
    (1, 16),
];

fn main() -> implicit_psdr::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = args
        .first()
        .map_or("scenes/sphere_floor.json", String::as_str);
    let params: Vec<String> = if args.len() > 1 {
        args[1..].to_vec()
    } else {
        ["ball.radius", "ball.center.x", "light.center.x"]
            .map(String::from)
            .to_vec()
    };
    let scene = scene::load(Path::new(path))?;
    let selection = scene.select(&params)?;
    let spp = scene.spp;
    println!(
        "{path}: {spp} spp, {}; default budgets {:?} per pixel\n",
        params.join(", "),
        BoundaryBudget::default().resolve(spp)
    );
    println!(
        "| primary + secondary per pixel | relative variance | seconds | variance × seconds |"
    );
    println!("|---|---|---|---|");
    for (primary, secondary) in BUDGETS {
        let boundary = BoundaryBudget {
            primary_spp: Some(primary as f32),
            secondary_spp: Some(secondary as f32),
        };
        let (mut variance, mut seconds) = (0.0, 0.0);
        for pair in 0..PAIRS {
            let mut renders = Vec::new();
            for seed in [2 * pair, 2 * pair + 1] {
                let options = DiffOptions {
                    render: RenderOptions {
                        spp,
                        seed,
                        ..RenderOptions::default()
                    },
                    boundary,
                    ..DiffOptions::default()
                };
                let start = Instant::now();
                renders.push(render_derivatives(&scene, &selection, &options)?.total());
                seconds += start.elapsed().as_secs_f64() / (2 * PAIRS) as f64;
            }
            variance += renders[0]
                .iter()
                .zip(&renders[1])
                .map(|(a, b)| {
                    let (mut diff, mut mean) = (0.0, 0.0);
                    for (x, y) in a.rgb.iter().zip(&b.rgb) {
                        let (x, y) = (*x as f64, *y as f64);
                        diff += (x - y).powi(2) / 2.0;
                        mean += ((x + y) / 2.0).powi(2);
                    }
                    diff / mean
                })
                .sum::<f64>()
                / (params.len() as u64 * PAIRS) as f64;
        }
        println!(
            "| {primary} + {secondary} | {variance:.4} | {seconds:.3} | {:.5} |",
            variance * seconds
        );
    }
    Ok(())
}
