//! The secondary boundary term (shadows) of the `direct` integrator: interior + secondary against
//! central finite differences with common random numbers on a floor shadow; zero where no shadow
//! boundary is seen; determinism across thread counts.

use implicit_psdr::bsdf::Bsdf;
use implicit_psdr::camera::Camera;
use implicit_psdr::emitter::Emitter;
use implicit_psdr::film::{Filter, Image};
use implicit_psdr::integrator::boundary::secondary::render_secondary;
use implicit_psdr::integrator::derivative::{DiffOptions, render_derivatives};
use implicit_psdr::integrator::fd::finite_difference;
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

fn light(center: [f32; 3], size: f32) -> NamedEmitter {
    NamedEmitter {
        name: "light".into(),
        emitter: Emitter::Rectangle {
            center: Param3::new(center),
            normal: -glam::Vec3::Y,
            u: glam::Vec3::X,
            size: [Param::new(size), Param::new(size)],
            radiance: Param3::new([8.0, 8.0, 8.0]),
        },
    }
}

/// A ball above a floor under a small rectangle light; the camera looks at the floor shadow and does
/// not see the ball (so no primary silhouette enters).
fn shadow_scene() -> Scene {
    let camera = Camera::new(
        glam::Vec3::new(-1.2, 2.6, 2.2),
        glam::Vec3::new(-1.2, 0.0, 0.0),
        glam::Vec3::Y,
        40.0,
        SIZE,
        SIZE,
        Filter::Tent,
    );
    let floor = Shape::new("floor", Sdf::plane(glam::Vec3::Y, 0.0), diffuse([0.6; 3]));
    let ball = Shape::new("ball", Sdf::sphere([0.0, 0.9, 0.0], 0.4), diffuse([0.5; 3]));
    Scene::new(
        camera,
        IntegratorKind::Direct,
        1,
        vec![floor, ball],
        vec![light([2.0, 2.6, 0.0], 0.6)],
    )
}

/// Pixels whose whole filter footprint (±1.5 px) sees the floor.
fn floor_mask(scene: &Scene) -> Vec<bool> {
    let frame = scene.camera.frame::<f32>();
    let mut mask = vec![true; (SIZE * SIZE) as usize];
    for y in 0..SIZE {
        for x in 0..SIZE {
            for oy in [-1.5f32, 0.0, 1.5] {
                for ox in [-1.5f32, 0.0, 1.5] {
                    let film = glam::Vec2::new(x as f32 + 0.5 + ox, y as f32 + 0.5 + oy);
                    let ray: Ray = frame.generate_ray(film);
                    let floor = matches!(
                        scene.intersect(&ray, f32::INFINITY),
                        Intersection::Hit(h) if h.surface == Surface::Shape(0)
                    );
                    mask[(y * SIZE + x) as usize] &= floor;
                }
            }
        }
    }
    mask
}

/// Sum of the three channels per pixel.
fn gray(image: &Image) -> Vec<f64> {
    image
        .rgb
        .chunks(3)
        .map(|c| c.iter().map(|&v| v as f64).sum())
        .collect()
}

/// 3×3 box blur (within the image).
fn blur(v: &[f64]) -> Vec<f64> {
    let n = SIZE as i64;
    let mut out = vec![0.0; v.len()];
    for y in 0..n {
        for x in 0..n {
            let (mut s, mut c) = (0.0, 0.0);
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let (xx, yy) = (x + dx, y + dy);
                    if xx >= 0 && yy >= 0 && xx < n && yy < n {
                        s += v[(yy * n + xx) as usize];
                        c += 1.0;
                    }
                }
            }
            out[(y * n + x) as usize] = s / c;
        }
    }
    out
}

/// Relative L2 error of `a` against `b` over `mask` after a 3×3 blur.
fn rel_l2(a: &[f64], b: &[f64], mask: &[bool]) -> f64 {
    let (a, b) = (blur(a), blur(b));
    let (mut num, mut den) = (0.0, 0.0);
    for i in 0..a.len() {
        if mask[i] {
            num += (a[i] - b[i]).powi(2);
            den += b[i].powi(2);
        }
    }
    (num / den.max(1e-30)).sqrt()
}

fn masked_sum(a: &[f64], mask: &[bool]) -> f64 {
    a.iter()
        .zip(mask)
        .filter(|(_, m)| **m)
        .map(|(v, _)| v)
        .sum()
}

fn diff_options(spp: u32, seed: u64) -> DiffOptions {
    DiffOptions {
        render: RenderOptions {
            spp,
            seed,
            progress: false,
        },
        ..DiffOptions::default()
    }
}

/// Interior, secondary and finite differences for one parameter.
fn terms(name: &str, h: f32, spp: u32, boundary: u64, fd_spp: u32) -> [Vec<f64>; 3] {
    let mut scene = shadow_scene();
    scene.select_parameters(&[name.to_string()]).unwrap();
    let opts = diff_options(spp, 7);
    let interior = render_derivatives(&scene, 1, &opts).unwrap().interior[0].clone();
    let secondary = render_secondary(&scene, 1, &opts, boundary).unwrap()[0].clone();
    let fd = finite_difference(
        &shadow_scene(),
        name,
        h,
        &RenderOptions {
            spp: fd_spp,
            seed: 11,
            progress: false,
        },
    )
    .unwrap();
    [gray(&interior), gray(&secondary), gray(&fd)]
}

#[test]
#[ignore]
fn explore() {
    let scene = shadow_scene();
    let mask = floor_mask(&scene);
    println!("mask {}", mask.iter().filter(|m| **m).count());
    let (img, _) = implicit_psdr::integrator::render(
        &scene,
        &RenderOptions {
            spp: 64,
            seed: 1,
            progress: false,
        },
    );
    let g = gray(&img);
    for y in 0..SIZE {
        let row: String = (0..SIZE)
            .map(|x| {
                let i = (y * SIZE + x) as usize;
                if !mask[i] {
                    '#'
                } else {
                    b" .:-=+*%@"[((g[i] * 2.0).min(8.0)) as usize] as char
                }
            })
            .collect();
        println!("{row}");
    }
    for (name, h) in [
        ("ball.center.x", 0.02),
        ("ball.radius", 0.02),
        ("light.center.x", 0.05),
    ] {
        let t = std::time::Instant::now();
        let [i, s, f] = terms(name, h, 64, 200_000, 256);
        let total: Vec<f64> = i.iter().zip(&s).map(|(a, b)| a + b).collect();
        println!(
            "{name}: sums interior {:.4} secondary {:.4} total {:.4} fd {:.4}; relL2 total {:.3} interior {:.3} ({:?})",
            masked_sum(&i, &mask),
            masked_sum(&s, &mask),
            masked_sum(&total, &mask),
            masked_sum(&f, &mask),
            rel_l2(&total, &f, &mask),
            rel_l2(&i, &f, &mask),
            t.elapsed()
        );
    }
}
