//! How noisy one inverse-rendering step is: over SEEDS independent loss + adjoint passes at 16
//! samples per pixel (the race's budgets: `secondary` 0.25 boundary samples per pixel), the image's
//! squared error per pixel and channel against a 1024-spp render, and the gradient of GRID's values'
//! squared deviation from the seeds' element-wise median. Both printed sorted (take the median).
//!
//! `cargo run --release --example adjoint_noise -- SCENE.json TARGET.exr GRID [SEEDS]`, e.g. with
//! the `result.json` and `targets/view_0.exr` of an `optimize` run on
//! `scenes/inverse/race/opt.json` (its camera is view 0's) and GRID `shape`; SEEDS defaults to 12.
use implicit_psdr::integrator::{
    BoundaryBudget, DiffOptions, GradientLayout, Loss, RenderOptions, render, render_gradient,
};
use implicit_psdr::io::read_exr_rgb;
use implicit_psdr::scene::load;
use std::path::Path;

fn sorted(mut v: Vec<f64>) -> Vec<String> {
    v.sort_by(|a, b| a.total_cmp(b));
    v.iter().map(|m| format!("{m:.3e}")).collect()
}

fn main() -> implicit_psdr::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if !(3..=4).contains(&args.len()) {
        eprintln!("usage: adjoint_noise SCENE.json TARGET.exr GRID [SEEDS]");
        std::process::exit(2);
    }
    let scene = load(Path::new(&args[0]))?;
    let target = read_exr_rgb(Path::new(&args[1]))?;
    let seeds = args.get(3).map_or(Some(12), |s| s.parse::<u64>().ok());
    let Some(seeds) = seeds.filter(|&n| n > 0) else {
        eprintln!("SEEDS: expected a whole number > 0, got {}", args[3]);
        std::process::exit(2);
    };
    let layout = GradientLayout::select(&scene, &[], &[args[2].clone()])?;
    let options = |seed: u64, spp: u32| DiffOptions {
        render: RenderOptions {
            spp,
            seed,
            ..RenderOptions::default()
        },
        boundary: BoundaryBudget {
            primary_spp: None,
            secondary_spp: Some(0.25),
        },
        ..DiffOptions::default()
    };
    let reference = render(&scene, &options(12345, 1024).render).0;
    let mut mse = Vec::new();
    let mut grads = Vec::new();
    for seed in 0..seeds {
        let image = render(&scene, &options(2 * seed, 16).render).0;
        let n = image.rgb.len() as f64;
        mse.push(
            (image.rgb.iter().zip(&reference.rgb))
                .map(|(a, b)| ((a - b) as f64).powi(2))
                .sum::<f64>()
                / n,
        );
        let (_, adjoint) = Loss::L2.evaluate(&image, &target, "target")?;
        grads.push(render_gradient(&scene, &layout, &adjoint, &options(2 * seed + 1, 16))?.total());
    }
    let median: Vec<f64> = (0..grads[0].len())
        .map(|e| {
            let mut v: Vec<f64> = grads.iter().map(|g| g[e]).collect();
            v.sort_by(|a, b| a.total_cmp(b));
            v[v.len() / 2]
        })
        .collect();
    let deviation = grads
        .iter()
        .map(|g| g.iter().zip(&median).map(|(a, m)| (a - m).powi(2)).sum())
        .collect();
    println!("image squared error (sorted) {:?}", sorted(mse));
    println!(
        "gradient squared deviation from the median (sorted) {:?}",
        sorted(deviation)
    );
    Ok(())
}
