//! How close a scene (an optimisation's start or its `result.json`) is to an `OPT.json`'s target
//! scene, in the run's views and in its optimised blocks:
//!
//! - image error: the relative L2 error `|I − T| / |T|` over every pixel of every view, both rendered
//!   at `SPP` samples per pixel with independent seeds (printed with the noise floor: the same
//!   measure between two renders of the target);
//! - per optimised environment map: the relative L2 error of its texels against the target's, over
//!   the texels the views see (those whose gradient of the views' summed images, at the target, is
//!   at least 1e-3 of the largest);
//! - per optimised volume texture: the mean absolute texel error;
//! - per optimised grid: IoU and Chamfer distance of its shape against the target's shape of the
//!   same name (as `optimize` reports them).
//!
//! `cargo run --release --example inverse_metrics -- OPT.json SCENE.json [SPP]` (default 256 spp)

use implicit_psdr::film::Image;
use implicit_psdr::integrator::{
    DiffOptions, GradientLayout, RenderOptions, render, render_gradient,
};
use implicit_psdr::optimize::config::{OptimizeConfig, Target};
use implicit_psdr::optimize::metrics::shape_quality;
use implicit_psdr::scene::{BlockKind, Scene, load};
use std::path::Path;

fn main() -> implicit_psdr::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (opt, scene, spp) = match args.as_slice() {
        [opt, scene] => (opt, scene, 256),
        [opt, scene, spp] => (opt, scene, spp.parse().unwrap_or(0)),
        _ => (&String::new(), &String::new(), 0),
    };
    if spp == 0 {
        eprintln!("usage: inverse_metrics OPT.json SCENE.json [SPP]");
        std::process::exit(2);
    }
    let cfg = OptimizeConfig::load(Path::new(opt))?;
    let Target::Scene { scene: target, .. } = &cfg.target else {
        eprintln!("error: {opt}: the target must be a scene");
        std::process::exit(2);
    };
    let scene = load(Path::new(scene))?;
    let images = |s: &Scene, seed: u64| -> implicit_psdr::Result<Vec<Image>> {
        (cfg.views.iter().enumerate())
            .map(|(k, v)| {
                let options = RenderOptions {
                    spp,
                    seed: seed + k as u64,
                    ..RenderOptions::default()
                };
                Ok(render(&v.apply(s)?, &options).0)
            })
            .collect()
    };
    let truth = images(target, 1000)?;
    let error = |a: &[Image]| {
        let (mut num, mut den) = (0.0f64, 0.0f64);
        for (x, t) in a.iter().zip(&truth) {
            for (p, q) in x.rgb.iter().zip(&t.rgb) {
                num += (*p as f64 - *q as f64).powi(2);
                den += (*q as f64).powi(2);
            }
        }
        (num / den).sqrt()
    };
    println!(
        "image error (relative L2, {} views, {spp} spp): {:.4} (noise floor {:.4})",
        cfg.views.len(),
        error(&images(&scene, 2000)?),
        error(&images(target, 3000)?)
    );
    let blocks = scene.blocks();
    for node in &cfg.settings.grids {
        let Some(block) = blocks.iter().find(|b| b.node == *node) else {
            continue;
        };
        match block.kind {
            BlockKind::Envmap => {
                let (a, b) = (scene.block_values(node)?, target.block_values(node)?);
                let seen = seen_texels(&cfg, target, node)?;
                let (mut num, mut den) = (0.0f64, 0.0f64);
                for (k, _) in seen.iter().enumerate().filter(|(_, s)| **s) {
                    for c in 0..3 {
                        num += (a[3 * k + c] as f64 - b[3 * k + c] as f64).powi(2);
                        den += (b[3 * k + c] as f64).powi(2);
                    }
                }
                println!(
                    "{node}: texel error (relative L2 over the {} of {} texels the views see): {:.4}",
                    seen.iter().filter(|s| **s).count(),
                    seen.len(),
                    (num / den).sqrt()
                );
            }
            BlockKind::Volume => {
                let (a, b) = (scene.block_values(node)?, target.block_values(node)?);
                let mean = a
                    .iter()
                    .zip(b.iter())
                    .map(|(x, y)| (x - y).abs())
                    .sum::<f32>()
                    / a.len() as f32;
                println!("{node}: mean absolute texel error {mean:.4}");
            }
            BlockKind::Grid => match shape_quality(&scene, target, &block.shape_name)? {
                Some((iou, chamfer)) => println!(
                    "{node} ({}): IoU {iou:.4}, Chamfer {chamfer:.5}",
                    block.shape_name
                ),
                None => println!("{node}: its shape is not in both scenes"),
            },
        }
    }
    Ok(())
}

/// Which texels of environment map `node` the views see: the gradient of the sum of each view's
/// image of `target` (64 spp), summed over the views and channels, is at least 1e-3 of the largest.
fn seen_texels(
    cfg: &OptimizeConfig,
    target: &Scene,
    node: &str,
) -> implicit_psdr::Result<Vec<bool>> {
    let mut weight: Vec<f64> = Vec::new();
    for (k, view) in cfg.views.iter().enumerate() {
        let s = view.apply(target)?;
        let layout = GradientLayout::select(&s, &[], &[node.to_string()])?;
        let ones = Image {
            width: s.camera.width,
            height: s.camera.height,
            rgb: vec![1.0; (s.camera.width * s.camera.height * 3) as usize],
        };
        let options = DiffOptions {
            render: RenderOptions {
                spp: 64,
                seed: 5000 + k as u64,
                ..RenderOptions::default()
            },
            ..DiffOptions::default()
        };
        let g = render_gradient(&s, &layout, &ones, &options)?.total();
        weight.resize(g.len() / 3, 0.0);
        for (w, t) in weight.iter_mut().zip(g.chunks_exact(3)) {
            *w += t.iter().map(|v| v.abs()).sum::<f64>();
        }
    }
    let max = weight.iter().copied().fold(0.0, f64::max);
    Ok(weight.iter().map(|w| *w >= 1e-3 * max).collect())
}
