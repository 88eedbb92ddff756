//! How much of a grid gradient's noise each term carries, and what its samples cost: the numbers
//! behind `optimize`'s boundary budgets (docs/inverse-rendering.md, "Boundary samples in an
//! iteration").
//!
//! For `SEEDS` seeds, the L2 loss gradient of `SCENE` against `TARGET.exr` with respect to every value
//! of grid `NODE` (as `implicit-psdr grad --grid NODE` computes it, at the scene's spp unless
//! `--spp N` is given, and `grad`'s default boundary budgets unless `--spp-secondary R` is). Prints, per term (interior,
//! primary, secondary), its variance summed over the values as a share of the complete gradient's,
//! its seconds per sample, and the samples per pixel of each boundary term that would make the
//! variance least for the time (each term's samples in proportion to its per-sample standard
//! deviation over the square root of its per-sample cost, at the scene's camera spp). A term's
//! seconds include its fixed costs (the primary term's silhouette extraction), which its samples are
//! charged with.
//!
//! `cargo run --release --example term_variance -- SCENE.json TARGET.exr NODE [SEEDS] [--spp N]
//! [--spp-secondary R]`

use implicit_psdr::integrator::{
    BoundaryBudget, DiffOptions, GradientLayout, Loss, RenderOptions, loss_gradient,
};
use implicit_psdr::io::read_exr_rgb;
use implicit_psdr::scene::load;
use std::path::Path;

/// Summed over the entries, the variance across seeds (`runs[seed][entry]`, unbiased).
fn summed_variance(runs: &[Vec<f64>]) -> f64 {
    let n = runs.len() as f64;
    (0..runs[0].len())
        .map(|e| {
            let mean = runs.iter().map(|r| r[e]).sum::<f64>() / n;
            runs.iter().map(|r| (r[e] - mean).powi(2)).sum::<f64>() / (n - 1.0)
        })
        .sum()
}

fn main() -> implicit_psdr::Result<()> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    // `--flag VALUE`, removed from the arguments.
    let mut flag = |name: &str| -> Option<f32> {
        let i = args.iter().position(|a| a == name)?;
        let value = args.get(i + 1)?.parse().ok();
        args.drain(i..(i + 2).min(args.len()));
        value.filter(|v: &f32| v.is_finite() && *v >= 0.0)
    };
    let secondary = flag("--spp-secondary");
    let spp = flag("--spp").map(|s| s as u32);
    let (scene, target, node, seeds) = match args.as_slice() {
        [s, t, n] => (s, t, n, 8),
        [s, t, n, k] => (s, t, n, k.parse().unwrap_or(0)),
        _ => (&String::new(), &String::new(), &String::new(), 0),
    };
    if seeds < 2 {
        eprintln!(
            "usage: term_variance SCENE.json TARGET.exr NODE [SEEDS >= 2] [--spp N] [--spp-secondary R]"
        );
        std::process::exit(2);
    }
    let scene = load(Path::new(scene))?;
    let target = read_exr_rgb(Path::new(target))?;
    let layout = GradientLayout::select(&scene, &[], std::slice::from_ref(node))?;
    let boundary = BoundaryBudget {
        primary_spp: None,
        secondary_spp: secondary,
    };
    let spp = spp.filter(|&s| s >= 1).unwrap_or(scene.spp);
    let (budget_p, budget_s) = boundary.resolve(spp);
    // Per term, every seed's gradient and the seconds of its samples.
    let mut terms: [Vec<Vec<f64>>; 4] = Default::default();
    let mut seconds = [0.0; 3];
    for seed in 0..seeds {
        let options = DiffOptions {
            render: RenderOptions {
                spp,
                seed: 2 * seed,
                ..RenderOptions::default()
            },
            boundary,
            ..DiffOptions::default()
        };
        let g = loss_gradient(&scene, &layout, &target, Loss::L2, &options)?.gradient;
        terms[3].push(g.total());
        for (k, term) in [g.interior, g.primary, g.secondary].into_iter().enumerate() {
            terms[k].push(term);
            seconds[k] += g.term_seconds[k] / seeds as f64;
        }
    }
    let pixels = (scene.camera.width * scene.camera.height) as f64;
    let rates = [spp as f32, budget_p, budget_s];
    let total = summed_variance(&terms[3]);
    println!(
        "{seeds} seeds, {spp} spp; boundary samples per pixel {budget_p} (primary), {budget_s} (secondary)"
    );
    println!(
        "| term | samples per pixel | share of the variance | µs per sample | variance-optimal samples per pixel |"
    );
    println!("|---|---|---|---|---|");
    // Per-sample variance (times the samples per pixel) and cost of each term.
    let per_sample: Vec<(f64, f64)> = (0..3)
        .map(|k| {
            let samples = rates[k] as f64 * pixels;
            (
                summed_variance(&terms[k]) * rates[k] as f64,
                seconds[k] / samples.max(1.0),
            )
        })
        .collect();
    let merit = |(v, c): (f64, f64)| v.sqrt() / c.sqrt();
    for (k, name) in ["interior", "primary", "secondary"].iter().enumerate() {
        let share = summed_variance(&terms[k]) / total;
        let optimal = spp as f64 * merit(per_sample[k]) / merit(per_sample[0]);
        println!(
            "| {name} | {} | {:.3}% | {:.2} | {:.3} |",
            rates[k],
            100.0 * share,
            1e6 * per_sample[k].1,
            optimal
        );
    }
    Ok(())
}
