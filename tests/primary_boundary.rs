//! The primary boundary term (silhouettes seen from the camera) of the `direct` integrator: a diffuse
//! sphere in a constant environment against the closed form of its radius derivative, interior +
//! primary against central finite differences, finiteness and determinism across thread counts.

mod common;

use common::deriv::{gray, rel_l2 as rel_l2_masked};
use implicit_psdr::bsdf::Bsdf;
use implicit_psdr::camera::Camera;
use implicit_psdr::emitter::Emitter;
use implicit_psdr::film::Filter;
use implicit_psdr::integrator::boundary::primary::render_primary;
use implicit_psdr::integrator::fd::finite_difference;
use implicit_psdr::integrator::{
    DiffOptions, Normalization, render_derivatives_with_boundary, render_interior,
};
use implicit_psdr::integrator::{IntegratorKind, RenderOptions};
use implicit_psdr::scene::{NamedEmitter, Scene, Selection, Shape};
use implicit_psdr::sdf::Sdf;
use implicit_psdr::{Param, Param3};

const SIZE: u32 = 32;
const DIST: f32 = 4.0;
const FOV: f32 = 40.0;
const RHO: f32 = 0.5;
const ENV: f32 = 1.0;

/// A diffuse ball of radius `r` at the origin in a constant environment, seen from `DIST` on +z.
fn ball_scene(r: f32) -> Scene {
    let camera = Camera::new(
        glam::Vec3::new(0.0, 0.0, DIST),
        glam::Vec3::ZERO,
        glam::Vec3::Y,
        FOV,
        SIZE,
        SIZE,
        Filter::Tent,
    );
    let ball = Shape::new(
        "ball",
        Sdf::sphere([0.0, 0.0, 0.0], Param::new(r)),
        Bsdf::Diffuse {
            albedo: Param3::new([RHO; 3]),
        },
    );
    let env = NamedEmitter {
        name: "env".into(),
        emitter: Emitter::Constant {
            radiance: Param3::new([ENV; 3]),
        },
    };
    Scene::new(camera, IntegratorKind::Direct, 1, vec![ball], vec![env])
}

fn diff_options(spp: u32, seed: u64) -> DiffOptions {
    DiffOptions {
        render: RenderOptions {
            spp,
            seed,
            progress: Default::default(),
        },
        // The terms are computed separately here: `render_primary` is the `fixed` normalisation's.
        normalization: Normalization::Fixed,
        ..Default::default()
    }
}

/// The ball scene and the selection of its radius.
fn selected(r: f32) -> (Scene, Selection) {
    let scene = ball_scene(r);
    let radius = scene.select(&["ball.radius"]).unwrap();
    (scene, radius)
}

fn tent(x: f64) -> f64 {
    (1.0 - x.abs()).max(0.0)
}

/// Closed form per pixel (one channel) of `jump · dR/dr ∮ tent(u − c_j) dℓ`: the projected silhouette is
/// a circle of radius `R = f tan α`, `sin α = r/D`, centred on the film; it moves outward at
/// `dR/dr = f / (D cos³α)`. With `jump = −(1−ρ)L` it is d/dr of the image (the disk ρL replaces the
/// background L); with `jump = −L` it is the primary term alone (the occluder's side `+ρL` is the
/// interior term's: its first vertex is attached and its projection moves with the surface).
fn closed_form(r: f32, jump: f64) -> Vec<f64> {
    let focal = (0.5 * SIZE as f64) / (FOV as f64 * std::f64::consts::PI / 360.0).tan();
    let sin_a = r as f64 / DIST as f64;
    let cos_a = (1.0 - sin_a * sin_a).sqrt();
    let big_r = focal * sin_a / cos_a;
    let d_r = focal / (DIST as f64 * cos_a.powi(3));
    let c = 0.5 * SIZE as f64;
    let n = 200_000;
    let dl = 2.0 * std::f64::consts::PI * big_r / n as f64;
    let mut out = vec![0.0; (SIZE * SIZE) as usize];
    for i in 0..n {
        let t = 2.0 * std::f64::consts::PI * (i as f64 + 0.5) / n as f64;
        let (ux, uy) = (c + big_r * t.cos(), c + big_r * t.sin());
        let (x0, y0) = (ux.floor() as i64, uy.floor() as i64);
        for y in y0 - 1..=y0 + 1 {
            for x in x0 - 1..=x0 + 1 {
                if x < 0 || y < 0 || x >= SIZE as i64 || y >= SIZE as i64 {
                    continue;
                }
                let w = tent(ux - (x as f64 + 0.5)) * tent(uy - (y as f64 + 0.5));
                out[(y * SIZE as i64 + x) as usize] += w * dl;
            }
        }
    }
    let k = jump * d_r;
    out.iter().map(|v| v * k).collect()
}

/// The primary term for d/dr matches the closed form `−L dR/dr ∮ tent dℓ`: zero off the ring, the
/// ring's sum within 1%, every pixel within a noise-justified bound.
///
/// Noise: the per-pixel standard deviation of the estimate at 200k samples, measured over seeds, is
/// reported in the assertion message; the bound is 5 σ plus 1% of the ring's peak.
#[test]
fn ball_radius_matches_closed_form() {
    let (scene, radius) = selected(1.0);
    let expected = closed_form(1.0, -(ENV as f64));
    let seeds = [1u64, 2, 3, 4];
    let runs: Vec<Vec<f64>> = seeds
        .iter()
        .map(|&s| {
            let img = render_primary(&scene, &radius, &diff_options(1, s), 200_000).unwrap();
            gray(&img[0]).iter().map(|v| v / 3.0).collect()
        })
        .collect();
    let n = expected.len();
    let mean: Vec<f64> = (0..n)
        .map(|i| runs.iter().map(|r| r[i]).sum::<f64>() / runs.len() as f64)
        .collect();
    let sd: Vec<f64> = (0..n)
        .map(|i| {
            let v = runs.iter().map(|r| (r[i] - mean[i]).powi(2)).sum::<f64>()
                / (runs.len() - 1) as f64;
            v.sqrt()
        })
        .collect();
    let (sum_e, sum_m): (f64, f64) = (expected.iter().sum(), runs[0].iter().sum());
    let rel = (sum_m - sum_e).abs() / sum_e.abs();
    let peak = expected.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let max_sd = sd.iter().cloned().fold(0.0, f64::max);
    let mut worst = 0.0f64;
    for i in 0..n {
        let err = (runs[0][i] - expected[i]).abs();
        worst = worst.max(err / (5.0 * max_sd + 0.01 * peak));
        if expected[i] == 0.0 {
            assert_eq!(runs[0][i], 0.0, "pixel {i} off the ring is nonzero");
        }
    }
    eprintln!(
        "ring sum: estimate {sum_m:.5}, closed form {sum_e:.5}, rel {rel:.2e}; peak {peak:.4}, \
         max per-pixel sd {max_sd:.2e}, worst err/bound {worst:.3}"
    );
    assert!(rel < 0.01, "ring sum off by {rel}");
    assert!(
        worst <= 1.0,
        "a pixel exceeds 5 sd + 1% of the peak ({worst})"
    );
}

/// Interior + primary against the closed form `−(1−ρ)L dR/dr ∮ tent dℓ` and against central finite
/// differences with common random numbers; the interior alone (`+ρL …`) must fail.
#[test]
fn interior_plus_primary_matches_finite_differences() {
    let (scene, radius) = selected(1.0);
    let opts = diff_options(512, 5);
    let interior = gray(&render_interior(&scene, &radius, &opts).unwrap().interior[0]);
    let primary = gray(&render_primary(&scene, &radius, &opts, 200_000).unwrap()[0]);
    let fd = gray(
        &finite_difference(
            &ball_scene(1.0),
            "ball.radius",
            0.02,
            &RenderOptions {
                spp: 256,
                seed: 11,
                progress: Default::default(),
            },
        )
        .unwrap(),
    );
    let total: Vec<f64> = interior.iter().zip(&primary).map(|(a, b)| a + b).collect();
    let (st, sf, si): (f64, f64, f64) = (
        total.iter().sum(),
        fd.iter().sum(),
        interior.iter().sum::<f64>(),
    );
    let (mut num, mut den) = (0.0, 0.0);
    for i in 0..fd.len() {
        num += (total[i] - fd[i]).powi(2);
        den += fd[i].powi(2);
    }
    let l2 = (num / den).sqrt();
    let sc: f64 = 3.0
        * closed_form(1.0, -((1.0 - RHO) * ENV) as f64)
            .iter()
            .sum::<f64>();
    let (mut num_c, mut den_c) = (0.0, 0.0);
    let cf = closed_form(1.0, -((1.0 - RHO) * ENV) as f64);
    for i in 0..fd.len() {
        num_c += (total[i] - 3.0 * cf[i]).powi(2);
        den_c += (3.0 * cf[i]).powi(2);
    }
    let l2c = (num_c / den_c).sqrt();
    eprintln!(
        "sums: interior {si:.4}, interior+primary {st:.4}, fd {sf:.4}, closed form {sc:.4}; \
         relative L2 vs fd {l2:.3}, vs closed form {l2c:.3}"
    );
    assert!((st - sf).abs() < 0.03 * sf.abs(), "sum {st} vs fd {sf}");
    assert!(
        (st - sc).abs() < 0.02 * sc.abs(),
        "sum {st} vs closed form {sc}"
    );
    assert!(
        (si - sf).abs() > 0.5 * sf.abs(),
        "the interior alone should miss the boundary"
    );
    assert!(l2 < 0.25, "relative L2 {l2}");
}

/// Finite everywhere and identical bit for bit with 1 and 2 threads; accepts the path integrator.
/// (`camera.origin.x`, not `camera.target.x`: a pure rotation moves the silhouette and the environment's
/// directions alike on the film, so its primary term in front of the environment is exactly 0.)
#[test]
fn finite_and_deterministic() {
    let scene = ball_scene(1.0);
    let three = (scene.select(&["ball.radius", "camera.origin.x", "ball.center.y"])).unwrap();
    let opts = diff_options(1, 9);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| render_primary(&scene, &three, &opts, 20_000).unwrap())
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.len(), 3);
    assert_eq!(a, b);
    for img in &a {
        assert!(img.rgb.iter().all(|v| v.is_finite()));
        assert!(img.rgb.iter().any(|v| *v != 0.0));
    }
    // The path integrator is supported (its background radiance is its own estimator's).
    let mut path = ball_scene(1.0);
    path.integrator = IntegratorKind::Path { max_depth: 2 };
    let radius = path.select(&["ball.radius"]).unwrap();
    assert!(render_primary(&path, &radius, &opts, 10).is_ok());
}

/// A black ball (albedo 0, so only its silhouette matters) in front of a large emitting rectangle (a
/// finite background `x_D` whose points are attached), no other light.
fn backdrop_scene() -> Scene {
    let camera = Camera::new(
        glam::Vec3::new(0.0, 0.0, DIST),
        glam::Vec3::ZERO,
        glam::Vec3::Y,
        FOV,
        SIZE,
        SIZE,
        Filter::Tent,
    );
    let ball = Shape::new(
        "ball",
        Sdf::sphere([0.1, -0.05, 0.0], Param::new(0.6)),
        Bsdf::Diffuse {
            albedo: Param3::new([0.0; 3]),
        },
    );
    let wall = NamedEmitter {
        name: "wall".into(),
        emitter: Emitter::Rectangle {
            center: Param3::new([0.0, 0.0, -2.0]),
            normal: glam::Vec3::Z,
            u: glam::Vec3::X,
            size: [Param::new(12.0), Param::new(12.0)],
            radiance: Param3::new([1.0, 2.0, 3.0]),
        },
    };
    Scene::new(camera, IntegratorKind::Direct, 1, vec![ball], vec![wall])
}

/// Relative L2 of `a` against `b`.
fn rel_l2(a: &[f64], b: &[f64]) -> f64 {
    rel_l2_masked(a, b, None)
}

/// A finite background: interior + primary against finite differences for the ball's position and
/// radius and the camera's position (the camera moving the attached background points: the interior
/// and the primary term then nearly cancel, the image hardly changes).
#[test]
fn finite_background_matches_finite_differences() {
    for (name, h) in [
        ("ball.center.x", 0.02f32),
        ("ball.radius", 0.02),
        ("camera.origin.x", 0.05),
    ] {
        let scene = backdrop_scene();
        let selection = scene.select(&[name]).unwrap();
        // The camera's interior term is noisy per pixel (moving projections through the filter).
        let spp = if name.starts_with("camera") {
            8192
        } else {
            128
        };
        let opts = diff_options(spp, 5);
        let interior = gray(&render_interior(&scene, &selection, &opts).unwrap().interior[0]);
        let primary = gray(&render_primary(&scene, &selection, &opts, 200_000).unwrap()[0]);
        let fd = gray(
            &finite_difference(
                &backdrop_scene(),
                name,
                h,
                &RenderOptions {
                    spp: 256,
                    seed: 11,
                    progress: Default::default(),
                },
            )
            .unwrap(),
        );
        let total: Vec<f64> = interior.iter().zip(&primary).map(|(a, b)| a + b).collect();
        let abs = |v: &[f64]| v.iter().map(|x| x.abs()).sum::<f64>();
        let (st, sf) = (total.iter().sum::<f64>(), fd.iter().sum::<f64>());
        let diff: Vec<f64> = total.iter().zip(&fd).map(|(a, b)| a - b).collect();
        eprintln!(
            "{name}: sum total {st:.3} fd {sf:.3}; |interior| {:.3} |primary| {:.3} |fd| {:.3} \
             |total − fd| {:.3}; rel L2 {:.3}",
            abs(&interior),
            abs(&primary),
            abs(&fd),
            abs(&diff),
            rel_l2(&total, &fd)
        );
        if name.starts_with("camera") {
            // FD ≈ 0 (the ball stays centred, the wall is uniform): the primary term must cancel the
            // interior's moving hole; without it the error is |interior|, with the film-fixed velocity
            // (not relative to the attached wall) it is about |interior| too. The rest is interior
            // noise: |total − fd| fell 1749 → 666 → 244 at 128 → 1024 → 8192 spp (measured).
            assert!(abs(&diff) < 0.4 * abs(&interior).min(abs(&primary)));
            assert!(abs(&primary) > 0.5 * abs(&interior));
        } else {
            // Measured: rel L2 0.13 (center.x), 0.12 (radius); |total − fd| / |fd| 0.13, 0.11.
            assert!(rel_l2(&total, &fd) < 0.2, "{name}: rel L2");
            assert!(abs(&diff) < 0.2 * abs(&fd), "{name}: |total − fd|");
            assert!(
                (st - sf).abs() < 0.03 * abs(&fd),
                "{name}: sums {st} vs {sf}"
            );
        }
    }
}

/// `--normalization differentiable` (supplemental §3): the complete derivative `∂F − I ∂W`, with `W`'s own
/// primary term (`PrimaryTerm::coverage`), matches the same closed form as the fixed normalisation; without
/// `W`'s primary term it is biased by `+I ∮ w v dℓ` (measured: 2.5 times the true ring sum; with it the
/// sum is within 0.3% and the relative L2 0.055).
#[test]
fn differentiable_normalization_matches_closed_form() {
    let (scene, radius) = selected(1.0);
    let mut opts = diff_options(256, 5);
    opts.normalization = Normalization::Differentiable;
    let out = render_derivatives_with_boundary(&scene, &radius, &opts, 200_000, 0).unwrap();
    let total = gray(&out.total()[0]);
    let without_w: Vec<f64> = gray(&out.interior[0])
        .iter()
        .zip(gray(
            &render_primary(&scene, &radius, &opts, 200_000).unwrap()[0],
        ))
        .map(|(a, b)| a + b)
        .collect();
    let cf: Vec<f64> = closed_form(1.0, -((1.0 - RHO) * ENV) as f64)
        .iter()
        .map(|v| 3.0 * v)
        .collect();
    let (st, sw, sc): (f64, f64, f64) =
        (total.iter().sum(), without_w.iter().sum(), cf.iter().sum());
    let l2 = |a: &[f64]| {
        let num: f64 = a.iter().zip(&cf).map(|(x, c)| (x - c).powi(2)).sum();
        (num / cf.iter().map(|c| c * c).sum::<f64>()).sqrt()
    };
    let (l2t, l2w) = (l2(&total), l2(&without_w));
    eprintln!(
        "sums: complete {st:.4}, without W's primary term {sw:.4}, closed form {sc:.4}; relative L2 \
         vs closed form {l2t:.3} (without W's term {l2w:.3})"
    );
    assert!(total.iter().all(|v| v.is_finite()));
    assert!(
        (st - sc).abs() < 0.02 * sc.abs(),
        "sum {st} vs closed form {sc}"
    );
    assert!(l2t < 0.25, "relative L2 {l2t}");
    assert!(
        (sw - sc).abs() > 0.5 * sc.abs(),
        "without W's primary term the sum should be biased: {sw} vs {sc}"
    );
}
