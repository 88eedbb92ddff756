//! The complete derivative (interior + primary + secondary boundary terms) on the default scene
//! (`scenes/sphere_floor.json`, 64×64, direct), measured in one run:
//!
//! 1. **Cost**: complete-derivative time / primal time at the same spp (the scene's 64) with `diff`'s
//!    default boundary budgets (`BoundaryBudget`: 2 silhouette and 8 shadow samples per pixel at
//!    64 spp), one parameter; also with 4× those budgets. Goal ≤ 3.
//! 2. **Time to 5% error**, this estimator against central finite differences (common random numbers,
//!    `h = 0.01`), for `ball.radius`, `ball.center.x` and `light.center.x`: each method's budget is doubled
//!    until the relative L2 error after a 5×5 box blur (all three channels) against a reference falls below
//!    5%. The reference is `fd` at `REF_SPP` with other seeds; its own error (half the distance between
//!    two such references, in quadrature) is printed too. The reference shares `fd`'s step, so `fd`'s
//!    `O(h²)` bias does not count against it: the comparison favours `fd`.
//!
//! The machine is shared: medians and ratios, never one absolute time. `cargo bench --bench complete
//! [-- REPS]`.

use implicit_psdr::film::Image;
use implicit_psdr::integrator::fd::finite_difference;
use implicit_psdr::integrator::{
    BoundaryBudget, DiffOptions, render_derivatives_with_boundary, render_interior,
};
use implicit_psdr::integrator::{RenderOptions, render};
use implicit_psdr::report::blurred_error;
use implicit_psdr::scene::{Scene, load};
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

/// Samples per pixel of each finite-difference reference.
const REF_SPP: u32 = 4096;
/// The finite-difference step.
const H: f32 = 0.01;
/// The error to reach.
const TARGET: f64 = 0.05;

fn default_scene() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/sphere_floor.json");
    load(&path).expect("the default scene parses")
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn options(spp: u32, seed: u64) -> DiffOptions {
    DiffOptions {
        render: RenderOptions {
            spp,
            seed,
            progress: Default::default(),
        },
        ..DiffOptions::default()
    }
}

/// The complete derivative with `spp` camera samples and `boost` times `diff`'s default boundary budgets.
fn complete(scene: &Scene, spp: u32, seed: u64, boost: u64) -> Image {
    let pixels = (scene.camera.width * scene.camera.height) as u64;
    let (p, s) = BoundaryBudget::default().resolve(spp);
    let (primary, secondary) = (boost * p as u64 * pixels, boost * s as u64 * pixels);
    let out = render_derivatives_with_boundary(scene, 1, &options(spp, seed), primary, secondary)
        .expect("the default scene supports every term");
    out.total().remove(0)
}

/// Doubles the budget from 1 spp until `run` is within [`TARGET`] of `reference` (or `max_spp` is passed);
/// returns the seconds and the spp of the first run below the target, and the last error.
fn time_to_target(
    reference: &Image,
    max_spp: u32,
    mut run: impl FnMut(u32) -> Image,
) -> (Option<(f64, u32)>, f64) {
    let mut spp = 1;
    let mut last = f64::INFINITY;
    while spp <= max_spp {
        let t = Instant::now();
        let image = run(spp);
        let seconds = t.elapsed().as_secs_f64();
        last = blurred_error(&image, reference);
        if last < TARGET {
            return (Some((seconds, spp)), last);
        }
        spp *= 2;
    }
    (None, last)
}

fn main() {
    let reps: usize = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(5);
    let plain = default_scene();
    let mut one = default_scene();
    one.select_parameters(&["ball.radius".to_string()]).unwrap();
    let spp = 64;
    let render_options = options(spp, 0).render;
    black_box(render(&plain, &render_options));
    let (mut tp, mut ti, mut tc, mut t4) = (vec![], vec![], vec![], vec![]);
    for _ in 0..reps {
        let t = Instant::now();
        black_box(render(&plain, &render_options));
        tp.push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        black_box(render_interior(&one, 1, &options(spp, 0)).unwrap());
        ti.push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        black_box(complete(&one, spp, 0, 1));
        tc.push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        black_box(complete(&one, spp, 0, 4));
        t4.push(t.elapsed().as_secs_f64());
    }
    let (p, i, c, c4) = (median(tp), median(ti), median(tc), median(t4));
    println!("default scene 64x64, {spp} spp, direct, ball.radius, median of {reps}:");
    println!("  primal                 {:8.1} ms", p * 1e3);
    println!(
        "  interior only          {:8.1} ms  ratio {:.2}",
        i * 1e3,
        i / p
    );
    let (bp, bs) = BoundaryBudget::default().resolve(spp);
    println!(
        "  complete ({bp}+{bs} boundary samples per pixel) {:8.1} ms  ratio {:.2} (goal <= 3)",
        c * 1e3,
        c / p
    );
    println!(
        "  complete ({}+{} boundary samples per pixel) {:8.1} ms  ratio {:.2}",
        4 * bp,
        4 * bs,
        c4 * 1e3,
        c4 / p
    );

    println!(
        "time to a {:.0}% relative L2 error after a 5x5 blur:",
        TARGET * 100.0
    );
    for name in ["ball.radius", "ball.center.x", "light.center.x"] {
        let fd_options = |spp: u32, seed: u64| RenderOptions {
            spp,
            seed,
            progress: Default::default(),
        };
        let reference = finite_difference(&plain, name, H, &fd_options(REF_SPP, 1000)).unwrap();
        let second = finite_difference(&plain, name, H, &fd_options(REF_SPP, 2000)).unwrap();
        let own = blurred_error(&second, &reference) / std::f64::consts::SQRT_2;
        let mut scene = default_scene();
        scene.select_parameters(&[name.to_string()]).unwrap();
        let (ours, ours_err) = time_to_target(&reference, 1024, |spp| complete(&scene, spp, 7, 1));
        let (fd, fd_err) = time_to_target(&reference, REF_SPP / 2, |spp| {
            finite_difference(&plain, name, H, &fd_options(spp, 7)).unwrap()
        });
        let show = |r: Option<(f64, u32)>, err: f64| match r {
            Some((s, spp)) => format!("{:7.2} s ({spp} spp)", s),
            None => format!("not reached (error {err:.3} at the largest budget)"),
        };
        println!(
            "  {name:15} reference's own error {own:.3}; complete: {}; fd: {}{}",
            show(ours, ours_err),
            show(fd, fd_err),
            match (ours, fd) {
                (Some((a, _)), Some((b, _))) => format!("; fd / complete {:.1}", b / a),
                _ => String::new(),
            }
        );
    }
}
