//! The accuracy table of docs/derivatives.md: relative L2 error of `diff`'s derivative images against
//! central finite differences, per pixel and after a 5×5 box blur (the blur averages pixel noise away), at the
//! settings a user gets by default (the scene's spp, default boundary budgets), for both pixel
//! normalisations and for the interior term alone. Mean over three seeds.
//!
//! `cargo run --release --example accuracy_table -- [SCENE.json] [FD_SPP] [PARAM ...]`
//! (defaults: `scenes/sphere_floor.json`, 2048, `ball.radius ball.center.x light.center.x`; the
//! reference uses seeds not used by the derivatives and the default step `0.01 · max(|P|, 1)`).

use implicit_psdr::compare::{box_blur, relative_l2};
use implicit_psdr::film::Image;
use implicit_psdr::integrator::fd::{default_step, finite_difference, parameter_value};
use implicit_psdr::integrator::{
    BoundaryBudget, DiffOptions, Normalization, RenderOptions, render_derivatives,
};
use implicit_psdr::scene;
use std::path::Path;

/// Relative L2 errors of `a` against `b`: per pixel and after a 5×5 blur of each channel.
fn errors(a: &Image, b: &Image) -> (f64, f64) {
    let (w, h) = (a.width as usize, a.height as usize);
    let raw = relative_l2(&a.rgb, &b.rgb);
    let (mut num, mut den) = (0.0, 0.0);
    for c in 0..3 {
        let (ba, bb) = (
            box_blur(&a.channel(c), w, h, 2),
            box_blur(&b.channel(c), w, h, 2),
        );
        num += ba
            .iter()
            .zip(&bb)
            .map(|(x, y)| ((x - y) as f64).powi(2))
            .sum::<f64>();
        den += bb.iter().map(|y| (*y as f64).powi(2)).sum::<f64>();
    }
    (raw, (num / den).sqrt())
}

fn main() -> implicit_psdr::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = args
        .first()
        .map_or("scenes/sphere_floor.json", String::as_str);
    let fd_spp: u32 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(2048);
    let params: Vec<String> = if args.len() > 2 {
        args[2..].to_vec()
    } else {
        ["ball.radius", "ball.center.x", "light.center.x"]
            .map(String::from)
            .to_vec()
    };
    let base = scene::load(Path::new(path))?;
    let spp = base.spp;
    let selection = base.select(&params)?;
    let references: Vec<Image> = params
        .iter()
        .map(|p| {
            let h = default_step(parameter_value(&base, p)?);
            let options = RenderOptions {
                spp: fd_spp,
                seed: 1000,
                ..RenderOptions::default()
            };
            finite_difference(&base, p, h, &options)
        })
        .collect::<implicit_psdr::Result<_>>()?;
    let variants = [
        (
            "complete, differentiable",
            Normalization::Differentiable,
            BoundaryBudget::default(),
        ),
        (
            "complete, fixed",
            Normalization::Fixed,
            BoundaryBudget::default(),
        ),
        (
            "interior alone",
            Normalization::Differentiable,
            BoundaryBudget::NONE,
        ),
    ];
    println!(
        "{path}: {spp} spp, default boundary budgets {:?} per pixel; reference fd at {fd_spp} spp",
        BoundaryBudget::default().resolve(spp)
    );
    println!("relative L2 per pixel / after a 5x5 blur, mean of seeds 0, 1, 2\n");
    print!("| parameter |");
    for (name, _, _) in &variants {
        print!(" {name} |");
    }
    println!("\n|---|{}", "---|".repeat(variants.len()));
    let mut table = vec![vec![(0.0, 0.0); variants.len()]; params.len()];
    for (v, (_, normalization, boundary)) in variants.iter().enumerate() {
        for seed in 0..3 {
            let options = DiffOptions {
                render: RenderOptions {
                    spp,
                    seed,
                    ..RenderOptions::default()
                },
                normalization: *normalization,
                boundary: *boundary,
                ..Default::default()
            };
            let d = render_derivatives(&base, &selection, &options)?;
            for (k, total) in d.total().iter().enumerate() {
                let (raw, blurred) = errors(total, &references[k]);
                table[k][v].0 += raw / 3.0;
                table[k][v].1 += blurred / 3.0;
            }
        }
    }
    for (p, row) in params.iter().zip(&table) {
        print!("| `{p}` |");
        for (raw, blurred) in row {
            print!(" {raw:.3} / {blurred:.3} |");
        }
        println!();
    }
    Ok(())
}
