//! Writes the environment maps of the inverse-rendering examples `scenes/inverse/envmap_light/` and
//! `scenes/inverse/shape_albedo_env/`: a small (16 × 8) coloured sky with a bright sun, in the
//! `envmap` emitter's mapping (texel `(i, j)` looks along `u = (j + 0.5)/16`, `v = i/7`, row 0 up),
//! and a constant grey start map.
//!
//! ```sh
//! cargo run --release --example make_inverse_envmaps
//! ```

use implicit_psdr::emitter::EnvMap;
use std::path::Path;

/// Map size (columns, rows).
const SIZE: (usize, usize) = (16, 8);
/// The sun's texel (row, column): 38.6° above the horizon.
const SUN: (usize, usize) = (2, 5);
/// The sun's radiance, and what spills into its four neighbours.
const SUN_RADIANCE: [f32; 3] = [8.0, 7.0, 5.5];
const SUN_HALO: [f32; 3] = [1.6, 1.3, 0.9];
/// The start map's grey.
const START: f32 = 0.5;

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/inverse");
    let (w, h) = SIZE;
    let mut target = vec![[0.0f32; 3]; w * h];
    for i in 0..h {
        for j in 0..w {
            let d = EnvMap::direction((j as f32 + 0.5) / w as f32, i as f32 / (h - 1) as f32);
            target[i * w + j] = sky(d);
        }
    }
    let (si, sj) = SUN;
    for c in 0..3 {
        target[si * w + sj][c] += SUN_RADIANCE[c];
        for (i, j) in [(si - 1, sj), (si + 1, sj), (si, sj - 1), (si, sj + 1)] {
            target[i * w + j][c] += SUN_HALO[c];
        }
    }
    let start = vec![[START; 3]; w * h];
    for (folder, maps) in [
        (
            "envmap_light",
            vec![("target.exr", &target), ("start.exr", &start)],
        ),
        ("shape_albedo_env", vec![("sky.exr", &target)]),
    ] {
        for (name, texels) in maps {
            let path = root.join(folder).join(name);
            let channels: Vec<(String, Vec<f32>)> = (["R", "G", "B"].iter().enumerate())
                .map(|(c, n)| (n.to_string(), texels.iter().map(|t| t[c]).collect()))
                .collect();
            if let Err(e) = implicit_psdr::io::write_exr(&path, w as u32, h as u32, &channels) {
                eprintln!("error: {e}");
                std::process::exit(1);
            }
            println!("wrote {} ({w}x{h})", path.display());
        }
    }
}

/// A blue zenith, a warm horizon, a dim green-brown ground, and a red glow low in the `+x` sky.
fn sky(d: glam::Vec3) -> [f32; 3] {
    let zenith = glam::Vec3::new(0.2, 0.4, 1.0);
    let horizon = glam::Vec3::new(1.0, 0.85, 0.6);
    let ground = glam::Vec3::new(0.25, 0.3, 0.12);
    let base = if d.y >= 0.0 {
        horizon.lerp(zenith, d.y.powf(0.7))
    } else {
        horizon.lerp(ground, (-d.y * 3.0).min(1.0))
    };
    let glow = glam::Vec3::new(1.2, 0.25, 0.1) * (d.x.max(0.0) * (1.0 - d.y.abs())).powi(2);
    (base + glow).to_array()
}
