//! Cost against the number of shapes: primal throughput of the default scene with its ball replaced by
//! 1, 10, 100 and 1,000 random balls (`benches/scenes/many_balls.rs`; 256×256, 16 spp, `direct`), with
//! the scene's bounding volume hierarchy and without it (every shape's bounds tested on every ray), in
//! one run; then `diff` (the complete derivative of `ball0.radius`, default boundary budgets) against
//! `render` at 1,000 balls.
//!
//! Then the same 1,000 balls as the children of ONE union shape, hard and smooth (blend 0.1: a ball's
//! radius), with the union's own hierarchy over its children and evaluating every child at every step
//! (that at 1 spp), beside the 1,000 separate shapes and one ball.
//!
//! Then Mitsuba 3 on the same scenes at 1 and 1,000 balls, when its Python package imports
//! (`benches/mitsuba_balls.py` through `$MITSUBA_PYTHON`, else `python3`; Dr.Jit's LLVM backend may
//! need `DRJIT_LIBLLVM_PATH`); skipped with a line saying so otherwise.
//!
//! The machine is shared: medians and ratios. `cargo bench --bench bvh [-- REPS]` (default 3).

#[path = "scenes/many_balls.rs"]
mod many_balls;

use implicit_psdr::integrator::{DiffOptions, RenderOptions, render, render_derivatives};
use implicit_psdr::scene::{Scene, parse};
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

fn scene(n: usize) -> Scene {
    parse(&many_balls::many_balls(n, 1), Path::new(".")).expect("the generated scene parses")
}

/// The scene of `n` balls with the balls made the children of one union shape named `balls` (a smooth
/// union with blend `k` when given).
fn union_scene(n: usize, culled: bool, k: Option<f64>) -> Scene {
    let mut doc: serde_json::Value =
        serde_json::from_str(&many_balls::many_balls(n, 1)).expect("the generated scene is JSON");
    let shapes = doc["shapes"].as_array_mut().expect("shapes");
    let children: Vec<serde_json::Value> = shapes.drain(..n).map(|s| s["sdf"].clone()).collect();
    let sdf = match k {
        Some(k) => serde_json::json!({"type": "smooth_union", "k": k, "children": children}),
        None => serde_json::json!({"type": "union", "children": children}),
    };
    shapes.insert(
        0,
        serde_json::json!({
            "name": "balls",
            "sdf": sdf,
            "bsdf": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}
        }),
    );
    let mut scene = parse(&doc.to_string(), Path::new(".")).expect("the union scene parses");
    if !culled {
        for shape in &mut scene.shapes {
            shape.sdf.set_culling(false);
        }
    }
    scene
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Median seconds of `reps` calls of `f` (after one untimed call).
fn time(reps: usize, mut f: impl FnMut()) -> f64 {
    f();
    median(
        (0..reps)
            .map(|_| {
                let t = Instant::now();
                f();
                t.elapsed().as_secs_f64()
            })
            .collect(),
    )
}

/// Mitsuba 3's M samples/s on the `n`-ball scene (median of `reps` renders after one that compiles its
/// kernels), or why it was not measured.
fn mitsuba_rate(n: usize, reps: usize) -> Result<f64, String> {
    let python = std::env::var("MITSUBA_PYTHON").unwrap_or_else(|_| "python3".into());
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = std::env::temp_dir().join(format!("psdr-bench-bvh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let path = dir.join(format!("balls{n}.json"));
    std::fs::write(&path, many_balls::many_balls(n, 1)).map_err(|e| e.to_string())?;
    let out = std::process::Command::new(&python)
        .arg(root.join("benches/mitsuba_balls.py"))
        .arg(&path)
        .arg(reps.to_string())
        .output();
    let _ = std::fs::remove_dir_all(&dir);
    let out = out.map_err(|e| format!("{python}: {e}"))?;
    let text = String::from_utf8_lossy(&out.stdout);
    (text.lines())
        .find_map(|l| l.strip_prefix("M samples/s: ")?.trim().parse().ok())
        .ok_or_else(|| {
            let err = String::from_utf8_lossy(&out.stderr);
            err.lines().last().unwrap_or("no output").to_string()
        })
}

fn main() {
    let reps: usize = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(3);
    let options = RenderOptions {
        spp: 16,
        seed: 0,
        progress: Default::default(),
    };
    println!("many balls, 256x256, 16 spp, direct, median of {reps} (M samples/s):");
    println!("  balls   with BVH   without   speed-up");
    let samples = (16 * 256 * 256) as f64;
    let (mut one, mut ours_1000) = (0.0, 0.0);
    for n in [1, 10, 100, 1000] {
        let with = scene(n);
        let mut without = with.clone();
        without.use_bvh = false;
        let t_with = time(reps, || {
            black_box(render(&with, &options));
        });
        // Without the hierarchy 1,000 balls take minutes: one timed render there.
        let t_without = time(if n >= 1000 { 1 } else { reps }, || {
            black_box(render(&without, &options));
        });
        let (a, b) = (samples / t_with / 1e6, samples / t_without / 1e6);
        if n == 1 {
            // Below five shapes both run the same code: both timings measure one ball.
            one = 0.5 * (a + b);
        }
        if n == 1000 {
            ours_1000 = a;
        }
        println!(
            "  {n:5}   {a:8.3}   {b:8.3}   {:6.1}x   (with BVH / 1 ball: {:.2})",
            a / b,
            a / one
        );
    }
    // Ours at 1,000 balls is the table's figure, from the same run.
    match (mitsuba_rate(1, reps), mitsuba_rate(1000, reps)) {
        (Ok(m1), Ok(m1000)) => {
            println!(
                "Mitsuba 3 (analytic spheres): 1 ball {m1:.3}, 1000 balls {m1000:.3} \
                 (1000 / 1: {:.2}); ours at 1000 balls {ours_1000:.3}, ours / Mitsuba {:.2}",
                m1000 / m1,
                ours_1000 / m1000
            );
        }
        (Err(e), _) | (_, Err(e)) => println!("Mitsuba 3: not measured ({e})"),
    }

    let balls = scene(1000);
    let selection = balls.select(&["ball0.radius"]).expect("ball0 exists");
    let diff = DiffOptions {
        render: options.clone(),
        ..DiffOptions::default()
    };
    let t_render = time(reps, || {
        black_box(render(&balls, &options));
    });
    let t_diff = time(reps, || {
        black_box(render_derivatives(&balls, &selection, &diff).expect("diff runs"));
    });
    println!(
        "1000 balls: render {:.1} ms, diff (ball0.radius, default budgets) {:.1} ms, ratio {:.2}",
        t_render * 1e3,
        t_diff * 1e3,
        t_diff / t_render
    );

    // One union of 1,000 balls against 1,000 shapes and one ball.
    let rate = |scene: &Scene, options: &RenderOptions, reps: usize| {
        let spp = options.spp as f64;
        samples / 16.0 * spp
            / time(reps, || {
                black_box(render(scene, options));
            })
            / 1e6
    };
    let r_one = rate(&scene(1), &options, reps);
    let r_shapes = rate(&scene(1000), &options, reps);
    let one_spp = RenderOptions {
        spp: 1,
        ..options.clone()
    };
    println!("1000 balls as one union shape (M samples/s, and / 1 ball):");
    println!("  1 ball                             {r_one:8.3}   1.00");
    println!(
        "  1000 shapes                        {r_shapes:8.3}   {:.2}",
        r_shapes / r_one
    );
    for (name, k) in [("union", None), ("smooth union, k 0.1", Some(0.1))] {
        let r_culled = rate(&union_scene(1000, true, k), &options, reps);
        let r_plain = rate(&union_scene(1000, false, k), &one_spp, 1);
        println!(
            "  {:<34} {r_culled:8.3}   {:.3}",
            format!("{name}, culled"),
            r_culled / r_one
        );
        println!(
            "  {:<34} {r_plain:8.3}   {:.4}   (1 spp, one render)",
            format!("{name}, every child"),
            r_plain / r_one
        );
    }
}
