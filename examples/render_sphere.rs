//! Builds the default scene in code (no JSON), renders it and writes `examples-out/sphere.exr` and
//! `examples-out/sphere.png`.
//!
//! `cargo run --release --example render_sphere`

use glam::Vec3;
use implicit_psdr::bsdf::Bsdf;
use implicit_psdr::camera::Camera;
use implicit_psdr::emitter::Emitter;
use implicit_psdr::film::{Filter, write_exr_and_png};
use implicit_psdr::integrator::{IntegratorKind, RenderOptions, render};
use implicit_psdr::scene::{NamedEmitter, Scene, Shape};
use implicit_psdr::sdf::Sdf;
use std::path::Path;

fn main() -> implicit_psdr::Result<()> {
    let camera = Camera::new(
        Vec3::new(0.0, 3.0, 4.0),
        Vec3::ZERO,
        Vec3::Y,
        45.0,
        128,
        128,
        Filter::Tent,
    );
    let ball = Shape::new(
        "ball",
        Sdf::sphere([0.0, 0.0, 0.0], 1.0),
        Bsdf::Diffuse {
            albedo: [0.8, 0.8, 0.8].into(),
        },
    );
    let floor = Shape::new(
        "floor",
        Sdf::cuboid([0.0, -2.0, 0.0], [50.0, 0.5, 50.0], 0.0),
        Bsdf::Diffuse {
            albedo: [0.5, 0.5, 0.5].into(),
        },
    );
    let light = NamedEmitter {
        name: "light".into(),
        emitter: Emitter::Rectangle {
            center: [1.5, 4.0, 2.0].into(),
            normal: Vec3::NEG_Y,
            u: Vec3::X,
            size: [1.0.into(), 1.0.into()],
            radiance: [40.0, 40.0, 40.0].into(),
        },
    };
    let scene = Scene::new(
        camera,
        IntegratorKind::Direct,
        64,
        vec![ball, floor],
        vec![light],
    );
    let (image, stats) = render(
        &scene,
        &RenderOptions {
            spp: 64,
            seed: 0,
            progress: Default::default(),
        },
    );
    println!("{} samples in {:.2} s", stats.samples, stats.seconds);
    let dir = Path::new("examples-out");
    std::fs::create_dir_all(dir).map_err(|e| implicit_psdr::Error::file(dir, e))?;
    let (exr, png) = (dir.join("sphere.exr"), dir.join("sphere.png"));
    let size = (image.width, image.height);
    write_exr_and_png(&exr, &png, size, &image.rgb_channels(""), &image)?;
    println!("wrote {} and {}", exr.display(), png.display());
    Ok(())
}
