//! What a pixel's shared camera culling (`scene::frustum`) costs and saves on the camera rays alone:
//! every pixel's camera rays at 1, 2, 4, 8 and 16 samples per pixel traced through the scene's
//! hierarchy one by one, then with the pixel's shapes gathered first (whatever the samples per pixel),
//! on one thread; prints both times, their ratio, and whether the hits were the same.
//!
//! `cargo run --release --example camera_culling -- SCENE.json` (a scene of more than four shapes,
//! e.g. `cargo run --release --example many_balls -- 1000 balls.json`).

use implicit_psdr::camera::CameraFrame;
use implicit_psdr::scene::frustum::PixelShapes;
use implicit_psdr::scene::shape_list::ShapeList;
use implicit_psdr::scene::{Intersection, Scene, load};
use std::path::Path;
use std::time::Instant;

/// Traces the camera ray of every sample of every pixel with `trace` (given the pixel and the ray);
/// returns the seconds taken and the sum of the hits' distances.
fn camera_rays(
    scene: &Scene,
    frame: &CameraFrame<f32>,
    spp: u32,
    mut trace: impl FnMut(u32, u32, &implicit_psdr::math::Ray) -> Intersection,
) -> (f64, f64) {
    let start = Instant::now();
    let mut sum = 0.0f64;
    for y in 0..scene.camera.height {
        for x in 0..scene.camera.width {
            for s in 0..spp {
                // Film offsets spread over the pixel's box filter square, the same for both queries.
                let offset = glam::Vec2::new(
                    (s as f32 * 0.618_034).fract() - 0.5,
                    (s as f32 * 0.754_878).fract() - 0.5,
                );
                let centre = glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let ray = frame.generate_ray(centre + offset);
                if let Intersection::Hit(h) = trace(x, y, &ray) {
                    sum += h.t as f64;
                }
            }
        }
    }
    (start.elapsed().as_secs_f64(), sum)
}

fn main() {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: camera_culling SCENE.json");
        std::process::exit(2);
    };
    let scene = match load(Path::new(&path)) {
        Ok(scene) => scene,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let frame = scene.camera.frame::<f32>();
    let mut gathered = PixelShapes::default();
    let mut shapes = ShapeList::default();
    let mut pixel = None;
    println!("spp   walk s   gathered s   ratio   same hits");
    for spp in [1, 2, 4, 8, 16] {
        let (walk, a) = camera_rays(&scene, &frame, spp, |_, _, ray| {
            scene.intersect_resolving(ray, f32::INFINITY, frame.spread(ray.d))
        });
        let (among, b) = camera_rays(&scene, &frame, spp, |x, y, ray| {
            if pixel != Some((x, y)) {
                // Gathered as for a render with enough samples to use it.
                let Some(found) = gathered.gather(&scene, &frame, x, y, u32::MAX) else {
                    eprintln!("error: the scene has no hierarchy (five shapes or more needed)");
                    std::process::exit(1);
                };
                shapes.clone_from(found);
                pixel = Some((x, y));
            }
            scene.intersect_among(ray, f32::INFINITY, frame.spread(ray.d), &shapes)
        });
        pixel = None;
        println!(
            "{spp:3}   {walk:6.3}   {among:10.3}   {:5.2}   {}",
            among / walk,
            a == b
        );
    }
}
