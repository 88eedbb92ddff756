//! The cost of a rough conductor against a diffuse material: the default scene
//! (`scenes/sphere_floor.json`, 64×64) with both shapes diffuse, then both gold (`roughconductor`,
//! α = 0.2), rendered with the same spp and seed; the primal and the interior derivative with respect
//! to `ball.radius`, `direct` and `path` (depth 3). The runs are interleaved and the medians of several
//! repetitions compared (the machine is shared: the ratios are the figures to quote).
//!
//! `cargo bench --bench materials [-- REPS]`.

use implicit_psdr::bsdf::{Bsdf, RoughConductor};
use implicit_psdr::integrator::{
    DiffOptions, IntegratorKind, Normalization, RenderOptions, render, render_interior,
};
use implicit_psdr::scalar::{Param, Param3};
use implicit_psdr::scene::{Scene, load};
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

/// The default scene with `integrator`, both shapes made gold when `metal`.
fn scene(integrator: IntegratorKind, metal: bool) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/sphere_floor.json");
    let mut scene = load(&path).expect("the default scene parses");
    scene.integrator = integrator;
    if metal {
        for shape in &mut scene.shapes {
            shape.bsdf = Bsdf::RoughConductor(RoughConductor {
                alpha: Param::new(0.2),
                eta: Param3::new([0.143, 0.374, 1.442]),
                k: Param3::new([3.983, 2.385, 1.603]),
                specular_reflectance: Param3::new([1.0; 3]),
            });
        }
    }
    scene
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Seconds of `f`, median of `reps` runs interleaved with the others by the caller.
fn time(f: impl FnOnce()) -> f64 {
    let t = Instant::now();
    f();
    t.elapsed().as_secs_f64()
}

fn main() {
    let reps: usize = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(5);
    let spp = 16;
    let render_options = RenderOptions {
        spp,
        seed: 0,
        progress: Default::default(),
    };
    let options = DiffOptions {
        render: render_options.clone(),
        normalization: Normalization::Fixed,
        ..Default::default()
    };
    for integrator in [
        IntegratorKind::Direct,
        IntegratorKind::Path { max_depth: 3 },
    ] {
        let diffuse = scene(integrator, false);
        let metal = scene(integrator, true);
        let radius = diffuse
            .select(&["ball.radius"])
            .expect("the parameter exists");
        black_box(render(&diffuse, &render_options));
        let mut t = [vec![], vec![], vec![], vec![]];
        for _ in 0..reps {
            t[0].push(time(|| {
                black_box(render(&diffuse, &render_options));
            }));
            t[1].push(time(|| {
                black_box(render(&metal, &render_options));
            }));
            t[2].push(time(|| {
                black_box(render_interior(&diffuse, &radius, &options).unwrap());
            }));
            t[3].push(time(|| {
                black_box(render_interior(&metal, &radius, &options).unwrap());
            }));
        }
        let [pd, pm, dd, dm] = t.map(median);
        println!("default scene 64x64, {spp} spp, {integrator:?}, median of {reps}:");
        println!(
            "  primal: diffuse {:7.1} ms, rough conductor {:7.1} ms, ratio {:.2}",
            pd * 1e3,
            pm * 1e3,
            pm / pd
        );
        println!(
            "  diff (1 parameter): diffuse {:7.1} ms, rough conductor {:7.1} ms, ratio {:.2}",
            dd * 1e3,
            dm * 1e3,
            dm / dd
        );
    }
}
