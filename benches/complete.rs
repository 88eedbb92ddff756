//! The complete derivative (interior + primary + secondary boundary terms) on the default scene
//! (`scenes/sphere_floor.json`, 64×64, direct), measured in one run:
//!
//! 1. **Cost**: complete-derivative time / primal time at the same spp (the scene's 64) with `diff`'s
//!    default boundary budgets (`BoundaryBudget`: 2 silhouette and 8 shadow samples per pixel at
//!    64 spp), one parameter; also with 4× those budgets. Goal ≤ 3.
//! 2. **Time to 5% error** of the complete derivative and of central finite differences for
//!    `ball.radius`, `ball.center.x` and `light.center.x`: the protocol of the `report` command
//!    (`implicit_psdr::report`, every estimator, its default budget and references), so that the
//!    table of docs/performance.md and `implicit-psdr report` are one measurement. Prints the table's
//!    rows.
//!
//! The machine is shared: medians and ratios, never one absolute time. `cargo bench --bench complete
//! [-- REPS]`.

use implicit_psdr::film::Image;
use implicit_psdr::integrator::{
    BoundaryBudget, DiffOptions, render_derivatives_with_boundary, render_interior,
};
use implicit_psdr::integrator::{RenderOptions, render};
use implicit_psdr::report::{self, DEFAULT_BUDGET, Estimator, summary};
use implicit_psdr::scene::{Scene, Selection, load};
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

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
fn complete(scene: &Scene, selection: &Selection, spp: u32, seed: u64, boost: u64) -> Image {
    let pixels = (scene.camera.width * scene.camera.height) as u64;
    let (p, s) = BoundaryBudget::default().resolve(spp);
    let (primary, secondary) = (boost * p as u64 * pixels, boost * s as u64 * pixels);
    let options = options(spp, seed);
    let out = render_derivatives_with_boundary(scene, selection, &options, primary, secondary)
        .expect("the default scene supports every term");
    out.total().remove(0)
}

fn main() {
    let reps: usize = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(5);
    let plain = default_scene();
    let one = plain
        .select(&["ball.radius"])
        .expect("the default scene has a ball");
    let spp = 64;
    let render_options = options(spp, 0).render;
    black_box(render(&plain, &render_options));
    let (mut tp, mut ti, mut tc, mut t4) = (vec![], vec![], vec![], vec![]);
    for _ in 0..reps {
        let t = Instant::now();
        black_box(render(&plain, &render_options));
        tp.push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        black_box(render_interior(&plain, &one, &options(spp, 0)).unwrap());
        ti.push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        black_box(complete(&plain, &one, spp, 0, 1));
        tc.push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        black_box(complete(&plain, &one, spp, 0, 4));
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
        4.0 * bp,
        4.0 * bs,
        c4 * 1e3,
        c4 / p
    );

    time_to_five_percent();
}

/// Part 2: the `report` protocol on the default scene, and the rows of docs/performance.md from it.
fn time_to_five_percent() {
    let params: Vec<String> = ["ball.radius", "ball.center.x", "light.center.x"]
        .map(String::from)
        .to_vec();
    let scene = default_scene();
    let plan = report::plan(&scene, &params, &Estimator::ALL, DEFAULT_BUDGET, true)
        .expect("the default scene supports every estimator");
    for s in &plan.skipped {
        println!("  skipped {}: {}", s.estimator.name(), s.reason);
    }
    let result = report::run(&plan, None, &mut |_| {}).expect("the report runs");
    println!(
        "time to a 5% relative L2 error after a 5x5 blur (report protocol, {} s budget, references \
         at {} spp):",
        plan.budget, plan.reference_spp
    );
    println!(
        "| parameter | complete derivative | `fd` (common random numbers) | `fd` / complete |"
    );
    println!("|---|---|---|---|");
    for section in result.sections.iter().filter(|s| s.parameter.is_some()) {
        let time = |e| summary::time_to(&summary::points(section, e), 0.05);
        let show = |t: Option<(f64, u32)>| match t {
            Some((s, spp)) => format!("{} ({spp} spp)", summary::seconds(s)),
            None => "not reached".into(),
        };
        let (c, f) = (time(Estimator::Complete), time(Estimator::Fd));
        let ratio = match (c, f) {
            (Some((c, _)), Some((f, _))) => format!("{:.1}", f / c),
            _ => "–".into(),
        };
        println!(
            "| `{}` | {} | {} | {ratio} |",
            summary::section_name(section.parameter.as_deref()),
            show(c),
            show(f)
        );
        println!("    reference: {}", summary::describe_reference(section));
    }
}
