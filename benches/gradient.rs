//! Reverse mode on a grid scene (`scenes/grid.json` with its grid replaced by a 32³ bake of two
//! blended spheres over a cube, moved clear of the ball, 96×72, direct, 64 spp): the whole `grad` (loss pass + adjoint pass with
//! all three terms, default boundary budgets) for all 32,768 grid values plus 8 named parameters,
//! against a primal render of the same scene at the same spp, in one run (median of interleaved
//! repetitions; the machine is shared, so ratios, never one absolute time). Goal ≤ 5.
//!
//! Also: the same with the interior term alone (boundary budgets 0), and the process's peak resident
//! memory (`VmHWM`) after the primal renders and after the gradients.
//!
//! `cargo bench --bench gradient [-- REPS]`.

use implicit_psdr::integrator::{
    BoundaryBudget, DiffOptions, GradientLayout, Loss, RenderOptions, loss_gradient, render,
};
use implicit_psdr::scene::{Scene, load};
use implicit_psdr::sdf::{Sdf, bake, write_npy};
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

/// Named parameters differentiated with the grid's values.
const PARAMS: [&str; 8] = [
    "ball.radius",
    "ball.center.x",
    "ball.center.y",
    "key.center.x",
    "baked_blob.albedo.r",
    "baked_blob.sdf.translate.x",
    "baked_blob.sdf.angle",
    "baked_blob.sdf.child.level",
];

/// The grid node of `scenes/grid.json`.
const GRID: &str = "baked_blob.sdf.child";

/// `scenes/grid.json` with its grid file replaced by a 32³ bake over `[-1, 1]³` (written to a
/// temporary folder).
fn scene_with_32_cubed_grid() -> Scene {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = std::env::temp_dir().join(format!("psdr-bench-gradient-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let blob = Sdf::smooth_union(
        vec![
            Sdf::sphere([-0.25, 0.0, 0.0], 0.55),
            Sdf::sphere([0.35, 0.15, 0.1], 0.4),
        ],
        0.3,
    );
    let (lo, hi) = (glam::Vec3::splat(-1.0), glam::Vec3::splat(1.0));
    let grid = bake(&blob, lo, hi, 32);
    assert_eq!(grid.dims, [32, 32, 32]);
    write_npy(&dir.join("blob32.npy"), &grid).unwrap();
    let text = std::fs::read_to_string(root.join("scenes/grid.json")).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json["shapes"][0]["sdf"]["translate"] = serde_json::json!([-0.5, -0.2, 0]);
    let node = &mut json["shapes"][0]["sdf"]["child"];
    node["file"] = "blob32.npy".into();
    node["bbox_min"] = serde_json::json!([-1, -1, -1]);
    node["bbox_max"] = serde_json::json!([1, 1, 1]);
    let path = dir.join("grid32.json");
    std::fs::write(&path, json.to_string()).unwrap();
    let scene = load(&path).expect("the bench scene parses");
    let _ = std::fs::remove_dir_all(&dir);
    scene
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Peak resident memory of this process so far, in MiB (Linux; 0 elsewhere).
fn peak_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(0.0, |kb| kb / 1024.0)
}

fn main() {
    let reps: usize = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(5);
    let scene = scene_with_32_cubed_grid();
    let spp = scene.spp;
    let params: Vec<String> = PARAMS.iter().map(|s| s.to_string()).collect();
    let layout =
        GradientLayout::select(&scene, &params, &[GRID.to_string()]).expect("the parameters exist");
    let options = |seed: u64, boundary: BoundaryBudget| DiffOptions {
        render: RenderOptions {
            spp,
            seed,
            ..RenderOptions::default()
        },
        boundary,
        ..DiffOptions::default()
    };
    // A target that differs where the shapes are: the ball a little larger.
    let target_scene = scene.with_parameter("ball.radius", 0.65).unwrap();
    let (target, _) = render(
        &target_scene,
        &options(99, BoundaryBudget::default()).render,
    );
    println!(
        "grid scene {}x{}, {spp} spp, {} gradient entries ({} named + {} grid values)",
        scene.camera.width,
        scene.camera.height,
        layout.entries,
        params.len(),
        layout.entries - params.len()
    );
    let (mut primal, mut complete, mut interior) = (Vec::new(), Vec::new(), Vec::new());
    // The whole gradient's parts, seconds: loss pass, interior, primary, secondary.
    let mut parts = Vec::new();
    let mut peak_primal = 0.0;
    for rep in 0..reps {
        let seed = rep as u64;
        let t = Instant::now();
        black_box(render(
            &scene,
            &options(seed, BoundaryBudget::default()).render,
        ));
        primal.push(t.elapsed().as_secs_f64());
        peak_primal = peak_mib();
        let t = Instant::now();
        let g = loss_gradient(
            &scene,
            &layout,
            &target,
            Loss::L2,
            &options(seed, BoundaryBudget::default()),
        )
        .unwrap();
        complete.push(t.elapsed().as_secs_f64());
        assert_eq!(g.gradient.stats.invalid_derivatives, 0);
        let [i, p, s] = g.gradient.term_seconds;
        parts.push([g.loss_seconds, i, p, s]);
        black_box(g);
        let t = Instant::now();
        black_box(
            loss_gradient(
                &scene,
                &layout,
                &target,
                Loss::L2,
                &options(seed, BoundaryBudget::NONE),
            )
            .unwrap(),
        );
        interior.push(t.elapsed().as_secs_f64());
    }
    let p = median(primal.clone());
    println!("primal render: median {p:.3} s");
    println!(
        "grad (loss pass + adjoint pass, interior + primary + secondary) / primal: {:.2} (goal <= 5)",
        median(complete.iter().zip(&primal).map(|(c, p)| c / p).collect())
    );
    let part = |k: usize| median(parts.iter().zip(&primal).map(|(s, p)| s[k] / p).collect());
    println!(
        "  its parts / primal: loss pass {:.2}, interior {:.2}, primary {:.2}, secondary {:.2}",
        part(0),
        part(1),
        part(2),
        part(3)
    );
    println!(
        "grad, interior term only / primal: {:.2}",
        median(interior.iter().zip(&primal).map(|(c, p)| c / p).collect())
    );
    println!(
        "peak resident memory: {peak_primal:.0} MiB after the primal renders, {:.0} MiB after the \
         gradients ({} threads)",
        peak_mib(),
        rayon::current_num_threads()
    );
}
