//! Writes the example environment map `scenes/sky.exr`: a 128 × 64 latitude–longitude sky (the
//! `envmap` emitter's mapping: row 0 looks straight up, `u = atan2(x, −z)/2π`) with a blue zenith, a
//! pale horizon, a dim brown ground and a bright sun-like spot 40° above the horizon.
//!
//! ```sh
//! cargo run --release --example make_envmap            # writes scenes/sky.exr
//! cargo run --release --example make_envmap -- out.exr
//! ```

use implicit_psdr::emitter::EnvMap;
use std::path::PathBuf;

/// Image size (columns, rows).
const SIZE: (usize, usize) = (128, 64);
/// Direction towards the sun's centre (normalised below).
const SUN: [f32; 3] = [0.55, 0.70, 0.45];
/// Peak radiance of the sun (per channel, a warm white).
const SUN_RADIANCE: [f32; 3] = [900.0, 820.0, 700.0];
/// Angular radius (standard deviation of the Gaussian falloff), degrees.
const SUN_SIGMA_DEGREES: f32 = 2.5;

fn main() {
    let out = std::env::args()
        .nth(1)
        .map_or_else(|| PathBuf::from("scenes/sky.exr"), PathBuf::from);
    let (w, h) = SIZE;
    let sun = glam::Vec3::from(SUN).normalize();
    let sigma = SUN_SIGMA_DEGREES.to_radians();
    let mut planes = [
        vec![0.0f32; w * h],
        vec![0.0f32; w * h],
        vec![0.0f32; w * h],
    ];
    for i in 0..h {
        for j in 0..w {
            let (u, v) = ((j as f32 + 0.5) / w as f32, (i as f32 + 0.5) / h as f32);
            let d = EnvMap::direction(u, v);
            let rgb = sky(d) + sun_spot(d, sun, sigma);
            for (c, plane) in planes.iter_mut().enumerate() {
                plane[i * w + j] = rgb[c];
            }
        }
    }
    let channels: Vec<(String, Vec<f32>)> = ["R", "G", "B"]
        .iter()
        .zip(planes)
        .map(|(n, p)| (n.to_string(), p))
        .collect();
    if let Err(e) = implicit_psdr::io::write_exr(&out, w as u32, h as u32, &channels) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
    println!("wrote {} ({w}x{h})", out.display());
}

/// The sky without the sun: zenith blue to a pale horizon above, a dim brown ground below.
fn sky(d: glam::Vec3) -> glam::Vec3 {
    let zenith = glam::Vec3::new(0.25, 0.45, 0.95);
    let horizon = glam::Vec3::new(0.9, 0.92, 0.95);
    let ground = glam::Vec3::new(0.22, 0.18, 0.14);
    if d.y >= 0.0 {
        let t = d.y.powf(0.6);
        horizon.lerp(zenith, t)
    } else {
        let t = (-d.y * 6.0).min(1.0);
        horizon.lerp(ground, t)
    }
}

/// A Gaussian spot of angular standard deviation `sigma` (radians) around `sun`.
fn sun_spot(d: glam::Vec3, sun: glam::Vec3, sigma: f32) -> glam::Vec3 {
    let angle = d.dot(sun).clamp(-1.0, 1.0).acos();
    glam::Vec3::from(SUN_RADIANCE) * (-0.5 * (angle / sigma).powi(2)).exp()
}
