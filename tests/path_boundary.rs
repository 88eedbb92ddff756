//! The boundary terms of the `path` integrator: the complete derivative (interior + primary +
//! secondary) against central finite differences with common random numbers on a scene whose indirect
//! shadows matter; `max_depth = 1` is the `direct` estimator exactly; finite and deterministic.

mod common;

use common::deriv::{blurred_rel_l2, gray};
use implicit_psdr::bsdf::Bsdf;
use implicit_psdr::camera::Camera;
use implicit_psdr::emitter::Emitter;
use implicit_psdr::film::Filter;
use implicit_psdr::integrator::boundary::primary::render_primary;
use implicit_psdr::integrator::boundary::secondary::render_secondary;
use implicit_psdr::integrator::fd::finite_difference;
use implicit_psdr::integrator::{DiffOptions, render_derivatives_with_boundary};
use implicit_psdr::integrator::{IntegratorKind, RenderOptions};
use implicit_psdr::math::Ray;
use implicit_psdr::scene::{Intersection, NamedEmitter, Scene, Shape, Surface};
use implicit_psdr::sdf::Sdf;
use implicit_psdr::{Param, Param3};

const SIZE: u32 = 32;

fn diffuse(a: [f32; 3]) -> Bsdf {
    Bsdf::Diffuse {
        albedo: Param3::new(a),
    }
}

/// A ball over a floor next to a wall, under a rectangle light the camera does not see: the floor near
/// the wall is lit mostly by the wall, so the ball's shadows on the light reflected by the wall (segments
/// floor → wall grazing the ball) are boundaries of paths with two scattering vertices.
fn wall_scene(integrator: IntegratorKind) -> Scene {
    let camera = Camera::new(
        glam::Vec3::new(0.8, 1.7, 3.0),
        glam::Vec3::new(-0.5, 0.45, 0.0),
        glam::Vec3::Y,
        45.0,
        SIZE,
        SIZE,
        Filter::Tent,
    );
    let floor = Shape::new("floor", Sdf::plane(glam::Vec3::Y, 0.0), diffuse([0.7; 3]));
    let wall = Shape::new("wall", Sdf::plane(glam::Vec3::X, -1.2), diffuse([0.8; 3]));
    let ball = Shape::new(
        "ball",
        Sdf::sphere([-0.5, 0.45, 0.2], 0.35),
        diffuse([0.6; 3]),
    );
    let light = NamedEmitter {
        name: "light".into(),
        emitter: Emitter::Rectangle {
            center: Param3::new([0.3, 2.2, 0.2]),
            normal: -glam::Vec3::Y,
            u: glam::Vec3::X,
            size: [Param::new(0.6), Param::new(0.6)],
            radiance: Param3::new([10.0; 3]),
        },
    };
    Scene::new(camera, integrator, 1, vec![floor, wall, ball], vec![light])
}

/// Relative L2 error of `a` against `b` after a 5×5 blur.
fn rel_l2(a: &[f64], b: &[f64]) -> f64 {
    let n = SIZE as usize;
    blurred_rel_l2(a, b, n, n, None)
}

/// Per pixel: which shape the camera sees at its centre (`None`: an emitter or nothing).
fn first_hits(scene: &Scene) -> Vec<Option<usize>> {
    let frame = scene.camera.frame::<f32>();
    (0..SIZE * SIZE)
        .map(|i| {
            let film = glam::Vec2::new((i % SIZE) as f32 + 0.5, (i / SIZE) as f32 + 0.5);
            let ray: Ray = frame.generate_ray(film);
            match scene.intersect(&ray, f32::INFINITY) {
                Intersection::Hit(h) => match h.surface {
                    Surface::Shape(s) => Some(s),
                    Surface::Emitter(_) => None,
                },
                _ => None,
            }
        })
        .collect()
}

fn sum_where(a: &[f64], hits: &[Option<usize>], shape: usize) -> f64 {
    a.iter()
        .zip(hits)
        .filter(|(_, h)| **h == Some(shape))
        .map(|(v, _)| v)
        .sum()
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

fn add(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x + y).collect()
}

/// The complete derivative's terms and finite differences (gray per pixel) for one parameter of the
/// `max_depth = 2` wall scene: `[interior, primary, secondary, fd]`.
fn terms(name: &str, h: f32, seed: u64, fd_seed: u64) -> [Vec<f64>; 4] {
    let path = IntegratorKind::Path { max_depth: 2 };
    let scene = wall_scene(path);
    let selection = scene.select(&[name]).unwrap();
    let pixels = (SIZE * SIZE) as u64;
    let budgets = (16 * pixels, 192 * pixels);
    let out = render_derivatives_with_boundary(
        &scene,
        &selection,
        &options(64, seed),
        budgets.0,
        budgets.1,
    )
    .unwrap();
    for image in out.total().iter().chain(&out.primary).chain(&out.secondary) {
        assert!(image.rgb.iter().all(|v| v.is_finite()), "{name}: NaN/Inf");
    }
    let fd = finite_difference(
        &wall_scene(path),
        name,
        h,
        &RenderOptions {
            spp: 384,
            seed: fd_seed,
            progress: Default::default(),
        },
    )
    .unwrap();
    [
        gray(&out.interior[0]),
        gray(&out.primary[0]),
        gray(&out.secondary[0]),
        gray(&fd),
    ]
}

/// Interior + primary + secondary against finite differences (384 spp, common random numbers) on the
/// `max_depth = 2` wall scene, as relative L2 after a 5×5 blur over the whole image and as sums over the
/// floor and the wall pixels; without the secondary term the error must be large.
///
/// Noise, measured with six seed pairs (estimator, FD) on `ball.center.x` (32 or 64 spp interior, 128 to
/// 256 boundary samples per pixel, FD 256 or 512 spp): blurred relative L2 0.068–0.129, without the
/// secondary term 0.74–0.81; total − FD over the floor −1.9…+1.5 (FD ≈ −9.8), over the wall −1.5…+3.5
/// (FD ≈ 9.9), dominated by the interior term's noise (its wall sum ranges over −9.5…−4.3); without the
/// secondary term the floor sum has the wrong sign. On `light.center.x` (four seed pairs, these budgets):
/// relative L2 0.016–0.019 (0.166–0.173 without the secondary term), floor sums within 1.3–1.9% and wall
/// sums within 0.16–0.5% (without the secondary term about 9% and 3% off).
#[test]
fn path_derivatives_match_finite_differences() {
    let hits = first_hits(&wall_scene(IntegratorKind::Path { max_depth: 2 }));
    // (name, h, blurred rel L2 bound, lower bound without the secondary term, floor and wall sum
    // tolerances)
    for (name, h, l2, l2_without, sum_tol) in [
        ("ball.center.x", 0.04f32, 0.2, 0.5, [0.3, 0.35]),
        ("light.center.x", 0.05, 0.05, 0.12, [0.05, 0.015]),
    ] {
        let [i, p, s, f] = terms(name, h, 7, 11);
        let total = add(&add(&i, &p), &s);
        let without = add(&i, &p);
        let (lt, lw) = (rel_l2(&total, &f), rel_l2(&without, &f));
        println!("{name}: rel L2 (5x5) total {lt:.3}, without secondary {lw:.3}");
        for (shape, label) in [(0, "floor"), (1, "wall")] {
            let (st, sf) = (sum_where(&total, &hits, shape), sum_where(&f, &hits, shape));
            println!(
                "  {label}: total {st:.4} (interior {:.4} primary {:.4} secondary {:.4}) fd {sf:.4}",
                sum_where(&i, &hits, shape),
                sum_where(&p, &hits, shape),
                sum_where(&s, &hits, shape),
            );
            assert!(sf.abs() > 1.0, "{name}: the {label} must respond ({sf})");
            let tol = sum_tol[shape];
            assert!(
                (st - sf).abs() <= tol * sf.abs(),
                "{name}: {label} sum {st} vs FD {sf} (tolerance {tol})"
            );
        }
        assert!(lt < l2, "{name}: relative L2 {lt} (bound {l2})");
        assert!(
            lw > l2_without,
            "{name}: without the secondary term the relative L2 {lw} should exceed {l2_without}"
        );
    }
}

/// `max_depth = 1` is the `direct` estimator: both boundary terms bit for bit.
#[test]
fn path_depth_one_is_direct() {
    let names = ["ball.center.x".to_string(), "light.center.x".to_string()];
    let run = |integrator| {
        let scene = wall_scene(integrator);
        let two = scene.select(&names).unwrap();
        let opts = options(1, 3);
        (
            render_secondary(&scene, &two, &opts, 20_000).unwrap(),
            render_primary(&scene, &two, &opts, 5_000).unwrap(),
        )
    };
    let (direct, path) = (
        run(IntegratorKind::Direct),
        run(IntegratorKind::Path { max_depth: 1 }),
    );
    assert_eq!(direct, path);
    assert!(direct.0[0].rgb.iter().any(|&v| v != 0.0));
}

/// Deeper paths: finite everywhere, nonzero, different from `direct` (indirect segments count), and
/// identical bit for bit with 1 and 2 threads.
#[test]
fn path_secondary_is_finite_and_deterministic() {
    let names: Vec<String> = ["ball.center.x", "ball.radius", "light.center.x"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let scene = wall_scene(IntegratorKind::Path { max_depth: 3 });
    let three = scene.select(&names).unwrap();
    let opts = options(1, 5);
    let run = |scene: &Scene, threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| render_secondary(scene, &three, &opts, 20_000).unwrap())
    };
    let (one, two) = (run(&scene, 1), run(&scene, 2));
    assert_eq!(one, two);
    let mut direct = scene.clone();
    direct.integrator = IntegratorKind::Direct;
    let direct = run(&direct, 2);
    for (image, d) in one.iter().zip(&direct) {
        assert!(image.rgb.iter().all(|v| v.is_finite()));
        assert!(image.rgb.iter().any(|&v| v != 0.0));
        assert_ne!(image, d);
    }
}
