//! One iteration of the race setup (`scenes/inverse/race/opt.json`: 6 of its 12 views, 128×128,
//! 16 spp, `optimize`'s default boundary budgets), term by term, against a primal render of the same
//! views at the same spp, in one run (medians of interleaved repetitions; the machine is shared, so ratios, never
//! one absolute time).
//!
//! The optimised grid is the target's shape (the smooth union of `target.json`) baked over the
//! grid's box at `N³` (`--grid N`, default 16; the race refines 16 → 31 → 61), so that the silhouette
//! and the tracing cost are those of a shape near the end of each stage; or, with `--state
//! result.json`, the grid and level of a scene `optimize` wrote (a shape the race itself reached, not
//! an exact distance). Targets: the target scene at 64 spp (`--targets-spp`). The loss is the race's
//! (its image pyramid included).
//!
//! The loss and gradient are `optimize`'s own (`Optimization::views_gradient`: the views run as many
//! at a time as there are threads, at the image scale `optimize` takes for the grid, half size at
//! 16³). Prints per iteration the seconds of the primal renders (one view after the other, at the same
//! image size), of the loss and gradient and of its loss passes, interior, primary and secondary
//! terms (their shares of its wall time), and each as a ratio to the primal.
//!
//! `cargo bench --bench race_iteration [-- --grid 61 | --state DIR/result.json] [-- REPS]`.
//!
//! To profile the iteration alone (`perf record` on the bench's executable), `--targets-spp 1` renders
//! the targets at 1 spp and `--no-primal` skips the primal renders (the table then has no ratios):
//! almost all of the process's samples are then the six views' loss passes and gradients.

use implicit_psdr::integrator::{RenderOptions, render};
use implicit_psdr::optimize::Optimization;
use implicit_psdr::optimize::config::{OptimizeConfig, Target};
use implicit_psdr::sdf::bake;
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

/// Views per iteration, as in the race.
const VIEWS: usize = 6;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let grid: usize = (args.iter().position(|a| a == "--grid"))
        .and_then(|i| args.get(i + 1)?.parse().ok())
        .unwrap_or(16);
    let targets_spp: u32 = (args.iter().position(|a| a == "--targets-spp"))
        .and_then(|i| args.get(i + 1)?.parse().ok())
        .unwrap_or(64);
    let state = (args.iter().position(|a| a == "--state")).and_then(|i| args.get(i + 1));
    let primal = !args.iter().any(|a| a == "--no-primal");
    let reps: usize = (args.iter().enumerate())
        .filter(|(i, _)| {
            *i == 0 || !matches!(args[i - 1].as_str(), "--grid" | "--targets-spp" | "--state")
        })
        .find_map(|(_, a)| a.parse().ok())
        .unwrap_or(3);
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let cfg = OptimizeConfig::load(&root.join("scenes/inverse/race/opt.json"))
        .expect("the race's opt.json loads");
    let Target::Scene { scene: target, .. } = &cfg.target else {
        panic!("the race's target is a scene");
    };
    let node = cfg.settings.grids[0].clone();
    let mut scene = cfg.scene.clone();
    let level = format!("{node}.level");
    let scene = match state {
        Some(path) => {
            let reached = implicit_psdr::scene::load(Path::new(path)).expect("--state loads");
            let data = reached
                .grid_values(&node)
                .expect("--state has the race's grid");
            scene.set_grid(&node, (*data).clone()).unwrap();
            let level_value = reached.parameter(&level).unwrap();
            scene.with_parameter(&level, level_value).unwrap()
        }
        None => {
            let [lo, hi] = scene.grid_box(&node).unwrap();
            let baked = bake(&target.shapes[0].sdf, lo, hi, grid);
            scene.set_grid(&node, baked).unwrap();
            scene.with_parameter(&level, 0.0).unwrap()
        }
    };
    let spp = cfg.settings.spp;
    let targets: Vec<_> = (cfg.views.iter().enumerate())
        .map(|(k, v)| {
            let options = RenderOptions {
                spp: targets_spp,
                seed: 1000 + k as u64,
                ..RenderOptions::default()
            };
            render(&v.apply(target).unwrap(), &options).0
        })
        .collect();
    let mut settings = cfg.settings.clone();
    settings.upsample_at.clear();
    let opt = Optimization::new(scene, cfg.views.clone(), targets, settings).unwrap();
    let views = opt.views_of(0);
    assert_eq!(views.len(), VIEWS);
    println!(
        "race iteration: {VIEWS} views {}x{}, {spp} spp, grid {:?} ({} values), {reps} repetitions",
        opt.scene.camera.width,
        opt.scene.camera.height,
        opt.scene.grid_values(&node).unwrap().dims,
        opt.scene.grid_values(&node).unwrap().values.len()
    );
    // Per repetition: primal, loss pass, interior, primary, secondary, whole gradient call.
    let mut rows: Vec<[f64; 6]> = Vec::new();
    for rep in 0..reps {
        let mut row = [0.0; 6];
        if primal {
            for &v in &views {
                let divisor = opt.divisor_at(rep as u32);
                let scene = opt.views[v].apply_reduced(&opt.scene, divisor).unwrap();
                let options = RenderOptions {
                    spp,
                    seed: (rep * 100 + 2 * v) as u64,
                    ..RenderOptions::default()
                };
                let t = Instant::now();
                black_box(render(&scene, &options));
                row[0] += t.elapsed().as_secs_f64();
            }
        }
        // What `optimize` runs for an iteration's views (several at once), at iteration `rep`'s seeds.
        let t = Instant::now();
        let g = opt.views_gradient(rep as u32, &views).unwrap();
        row[5] = t.elapsed().as_secs_f64();
        let s = g.stage_seconds;
        row[1..5].copy_from_slice(&[s.loss_pass, s.interior, s.primary, s.secondary]);
        black_box(g);
        rows.push(row);
    }
    let names = [
        "primal (6 renders)",
        "loss pass",
        "interior term",
        "primary term",
        "secondary term",
        "loss + gradient",
    ];
    let ratio_column = if primal { "/ primal" } else { "" };
    println!(
        "{:<20} {:>10} {:>10}",
        "per iteration", "median s", ratio_column
    );
    for (k, name) in names.iter().enumerate() {
        let seconds = median(rows.iter().map(|r| r[k]).collect());
        if primal {
            let ratio = median(rows.iter().map(|r| r[k] / r[0]).collect());
            println!("{name:<20} {seconds:>10.3} {ratio:>10.2}");
        } else if k > 0 {
            println!("{name:<20} {seconds:>10.3}");
        }
    }
}
