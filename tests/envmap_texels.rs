//! An environment map's texels as a parameter block (`<name>.values`, shape `[H, W, 3]`): reverse-mode
//! texel gradients against central finite differences of the loss with common random numbers,
//! forward mode along a direction against reverse mode dotted with it (`direct` and `path`), finite
//! derivatives on maps with black texels, and the block on the command line.
//!
//! Finite differences with common random numbers are exact here (to rounding) only along directions
//! that leave the map's importance-sampling tables unchanged, since the tables are rebuilt from the
//! perturbed texels and move the samples: a change of colour at constant luminance (the tables are
//! built from the luminance) and a common scaling of every texel (the tables are normalised).
//! Along those the image is linear in the texels, so the difference quotient is the derivative.

mod common;

use common::{assert_failure, assert_success, npy_bytes, run};
use implicit_psdr::film::Image;
use implicit_psdr::integrator::{
    self, DiffOptions, GradientLayout, Normalization, RenderOptions, render_gradient,
};
use implicit_psdr::scene::{self, GridDirection, Scene};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Image size of the test scenes.
const SIZE: u32 = 16;
/// Map size (columns, rows): a small map, so that every texel covers a visible solid angle.
const MAP: (usize, usize) = (8, 4);
/// Values in the block: `H · W · 3`.
const N: usize = MAP.0 * MAP.1 * 3;
/// Rec. 709 luminance weights, as the map's sampling tables use them.
const LUMINANCE: [f32; 3] = [0.2126, 0.7152, 0.0722];

fn workdir(name: &str) -> PathBuf {
    common::workdir("envmap-texels", name)
}

/// Distinct texel values in `[0.4, 1.6]` (a bright one at index 3·13 + 1).
fn texels() -> Vec<f32> {
    (0..N)
        .map(|i| 0.4 + 1.2 * ((i * 7919) % 97) as f32 / 96.0)
        .collect()
}

/// Writes `values` (block layout `[H, W, 3]`) as `sky.exr` in `dir`.
fn write_map(dir: &Path, values: &[f32]) {
    let (w, h) = MAP;
    let channels: Vec<(String, Vec<f32>)> = (["R", "G", "B"].iter().enumerate())
        .map(|(c, n)| {
            (
                n.to_string(),
                values.iter().skip(c).step_by(3).copied().collect(),
            )
        })
        .collect();
    implicit_psdr::io::write_exr(&dir.join("sky.exr"), w as u32, h as u32, &channels).unwrap();
}

/// A diffuse ball and a glossy metal ball over a floor slab under `sky.exr` (scale 0.8, turned 20°
/// about `+y`), seen from above with the sky behind them.
fn scene_json(integrator: &str) -> String {
    format!(
        r#"{{"camera": {{"origin": [0, 1.6, 4], "target": [0, 0.2, 0], "up": [0, 1, 0], "fov_y": 50,
                "width": {SIZE}, "height": {SIZE}, "filter": "tent"}},
            "integrator": {integrator}, "spp": 1,
            "shapes": [
              {{"name": "ball", "sdf": {{"type": "sphere", "center": [-0.6, 0.4, 0], "radius": 0.5}},
               "bsdf": {{"type": "diffuse", "albedo": [0.8, 0.7, 0.6]}}}},
              {{"name": "metal", "sdf": {{"type": "sphere", "center": [0.6, 0.4, 0], "radius": 0.5}},
               "bsdf": {{"type": "roughconductor", "alpha": 0.15}}}},
              {{"name": "floor", "sdf": {{"type": "box", "center": [0, -0.6, 0], "half_size": [3, 0.5, 3],
                "rounding": 0.1}}, "bsdf": {{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}}}
            ],
            "emitters": [
              {{"name": "sky", "type": "envmap", "file": "sky.exr", "scale": 0.8,
               "rotate": {{"axis": [0, 1, 0], "angle": 20}}}}
            ]}}"#
    )
}

const DIRECT: &str = r#"{"type": "direct"}"#;
const PATH: &str = r#"{"type": "path", "max_depth": 3}"#;

/// The test scene in `dir` (its map written from `values`).
fn scene_in(dir: &Path, values: &[f32], integrator: &str) -> Scene {
    write_map(dir, values);
    std::fs::write(dir.join("scene.json"), scene_json(integrator)).unwrap();
    scene::load(&dir.join("scene.json")).unwrap()
}

fn render_options(spp: u32, seed: u64) -> RenderOptions {
    RenderOptions {
        spp,
        seed,
        ..RenderOptions::default()
    }
}

/// Fixed normalisation: the gradient is then exactly that of `Σ g · I` for the image `I` of the
/// same samples.
fn diff_options(spp: u32, seed: u64) -> DiffOptions {
    DiffOptions {
        render: render_options(spp, seed),
        normalization: Normalization::Fixed,
        ..DiffOptions::default()
    }
}

/// A fixed pixel adjoint (a ramp of both signs, positive on average).
fn adjoint() -> Image {
    let n = (SIZE * SIZE * 3) as usize;
    Image {
        width: SIZE,
        height: SIZE,
        rgb: (0..n).map(|i| ((i * 31) % 17) as f32 / 8.0 - 0.5).collect(),
    }
}

fn dot(g: &Image, image: &Image) -> f64 {
    (g.rgb.iter().zip(&image.rgb))
        .map(|(a, b)| *a as f64 * *b as f64)
        .sum()
}

/// `Σ g · I` with the texels `values`, seed `seed`.
fn weighted(scene: &Scene, values: Vec<f32>, spp: u32, seed: u64) -> f64 {
    let mut s = scene.clone();
    s.set_block_values("sky", values).unwrap();
    dot(
        &adjoint(),
        &integrator::render(&s, &render_options(spp, seed)).0,
    )
}

/// The reverse-mode gradient of `Σ g · I` with respect to the texels.
fn texel_gradient(scene: &Scene, spp: u32, seed: u64) -> Vec<f64> {
    let layout = GradientLayout::select(scene, &[], &["sky".to_string()]).unwrap();
    assert_eq!(layout.entries, N);
    let g = render_gradient(scene, &layout, &adjoint(), &diff_options(spp, seed)).unwrap();
    // Texels move nothing: the boundary terms are zero.
    assert!(g.primary.iter().chain(&g.secondary).all(|v| *v == 0.0));
    g.total()
}

/// Reverse mode against central differences of the loss, per texel along a colour change of zero
/// luminance, and along a common scaling of every texel; `direct` and `path`.
#[test]
fn texel_gradients_match_finite_differences_of_the_loss() {
    for (name, integrator) in [("direct", DIRECT), ("path", PATH)] {
        let dir = workdir(&format!("fd-{name}"));
        let values = texels();
        let scene = scene_in(&dir, &values, integrator);
        let (spp, seed) = (4, 11);
        let g = texel_gradient(&scene, spp, seed);
        assert!(g.iter().all(|v| v.is_finite()), "{name}: {g:?}");
        // Zero luminance: R up, G down.
        let delta = [LUMINANCE[1], -LUMINANCE[0], 0.0];
        let h = 0.05;
        let mut seen = 0;
        for k in [0, 5, 9, 12, 14, 18, 21, 26, 30] {
            let shifted = |sign: f32| {
                let mut v = values.clone();
                for c in 0..3 {
                    v[3 * k + c] += sign * h * delta[c];
                }
                weighted(&scene, v, spp, seed)
            };
            let fd = (shifted(1.0) - shifted(-1.0)) / (2.0 * h as f64);
            let reverse: f64 = (0..3).map(|c| g[3 * k + c] * delta[c] as f64).sum();
            assert!(
                (reverse - fd).abs() <= 1e-3 * fd.abs().max(1e-2),
                "{name}: texel {k}: reverse {reverse} vs fd {fd}"
            );
            seen += (fd.abs() > 1e-2) as usize;
        }
        assert!(seen >= 6, "{name}: only {seen} texels are seen");
        // Every texel scaled by 1 ± h: the derivative is g · values.
        let scaled = |f: f32| weighted(&scene, values.iter().map(|v| v * f).collect(), spp, seed);
        let fd = (scaled(1.0 + h) - scaled(1.0 - h)) / (2.0 * h as f64);
        let reverse: f64 = g.iter().zip(&values).map(|(a, b)| a * *b as f64).sum();
        assert!(fd.abs() > 1.0, "{name}: {fd}");
        assert!(
            (reverse - fd).abs() <= 1e-3 * fd.abs(),
            "{name}: scaling: reverse {reverse} vs fd {fd}"
        );
    }
}

/// Forward mode along a direction of the texels (`diff --grid-direction`) equals the reverse-mode
/// gradient dotted with it, to rounding; `direct` and `path`.
#[test]
fn forward_mode_equals_reverse_mode_along_a_direction() {
    for (name, integrator) in [("direct", DIRECT), ("path", PATH)] {
        let dir = workdir(&format!("forward-{name}"));
        let scene = scene_in(&dir, &texels(), integrator);
        let (spp, seed) = (4, 3);
        let g = texel_gradient(&scene, spp, seed);
        let u: Vec<f32> = (0..N).map(|i| ((i * 13) % 7) as f32 / 3.0 - 1.0).collect();
        let direction = GridDirection {
            node: "sky.values".into(),
            shape: vec![MAP.1, MAP.0, 3],
            values: Arc::new(u.clone()),
            source: "u".into(),
        };
        let selection = scene
            .select_with_grid_directions::<&str>(&[], &[direction])
            .unwrap();
        assert_eq!(selection.names(), ["sky.values"]);
        let forward =
            integrator::render_derivatives(&scene, &selection, &diff_options(spp, seed)).unwrap();
        let along = dot(&adjoint(), &forward.total()[0]);
        let predicted: f64 = g.iter().zip(&u).map(|(a, b)| a * *b as f64).sum();
        assert!(predicted.abs() > 1e-1, "{name}: {predicted}");
        assert!(
            (along - predicted).abs() <= 1e-4 * predicted.abs(),
            "{name}: forward {along} vs reverse · u {predicted}"
        );
        // Selected with a named parameter in the same pass, the texels' derivative is unchanged.
        let direction = GridDirection {
            node: "sky".into(),
            shape: vec![MAP.1, MAP.0, 3],
            values: Arc::new(u.clone()),
            source: "u".into(),
        };
        let both = scene
            .select_with_grid_directions(&["sky.scale"], &[direction])
            .unwrap();
        let out = integrator::render_derivatives(&scene, &both, &diff_options(spp, seed)).unwrap();
        let again = dot(&adjoint(), &out.total()[1]);
        assert!(
            (again - along).abs() <= 1e-5 * along.abs(),
            "{name}: {again} vs {along}"
        );
    }
}

/// A map with black texels, and one black everywhere (sampled by BSDF sampling alone): finite
/// gradients, and a black map's texels still have one (BSDF sampling reaches them).
#[test]
fn black_texels_have_finite_gradients() {
    let mut half = texels();
    for (i, v) in half.iter_mut().enumerate() {
        if (i / 3) % 2 == 0 {
            *v = 0.0;
        }
    }
    for (name, values) in [("black", vec![0.0; N]), ("half", half)] {
        for integrator in [DIRECT, PATH] {
            let dir = workdir(&format!("zero-{name}"));
            let scene = scene_in(&dir, &values, integrator);
            let g = texel_gradient(&scene, 4, 1);
            assert!(g.iter().all(|v| v.is_finite()), "{name}: {g:?}");
            let norm = g.iter().map(|v| v * v).sum::<f64>().sqrt();
            assert!(norm > 1e-2, "{name}: |g| = {norm}");
        }
    }
}

/// `params` lists the block after the emitter's parameters; `grad --grid` writes the gradient as a
/// `[H, W, 3]` `.npy`; `diff --grid-direction` takes a direction of that shape and names a file of
/// another; values below zero are refused.
#[test]
fn the_command_line_names_the_block() {
    let dir = workdir("cli");
    let mut scene = scene_in(&dir, &texels(), DIRECT);
    let listing = assert_success(&run(&dir, &["params", "scene.json"]));
    assert!(
        listing.contains(
            "sky.rotate.angle 20\nsky.values [4, 8, 3] (96 values; select with --grid sky"
        ),
        "{listing}"
    );
    let args = ["--out", "t.exr", "--png", "t.png", "--spp", "2"];
    assert_success(&run(&dir, &[&["render", "scene.json"][..], &args].concat()));
    let out = assert_success(&run(
        &dir,
        &[
            "grad",
            "scene.json",
            "--target",
            "t.exr",
            "--grid",
            "sky",
            "--spp",
            "2",
        ],
    ));
    assert!(out.contains("96 values of 1 environment map"), "{out}");
    let g = implicit_psdr::io::read_npy_array(&dir.join("grad.sky.values.npy")).unwrap();
    assert_eq!(g.shape, [4, 8, 3]);
    let npy = |shape: &[usize], v: f32| {
        let n: usize = shape.iter().product();
        let data: Vec<u8> = (0..n).flat_map(|_| v.to_le_bytes()).collect();
        npy_bytes("<f4", shape, &data)
    };
    std::fs::write(dir.join("u.npy"), npy(&[4, 8, 3], 1.0)).unwrap();
    let diff = ["diff", "scene.json", "--spp", "2", "--grid-direction"];
    assert_success(&run(&dir, &[&diff[..], &["sky=u.npy"]].concat()));
    std::fs::write(dir.join("bad.npy"), npy(&[8, 4, 3], 1.0)).unwrap();
    let out = run(&dir, &[&diff[..], &["sky=bad.npy"]].concat());
    assert_failure(&out, "bad.npy");
    let mut values = texels();
    values[7] = -0.1;
    let e = scene
        .set_block_values("sky", values)
        .unwrap_err()
        .to_string();
    assert!(e.contains("sky.values") && e.contains("-0.1"), "{e}");
}

/// The two examples that estimate lighting (`scenes/inverse/envmap_light/`: an environment map's
/// texels for a known ball; `shape_albedo_env/`: a grid shape and its albedo texture under a known
/// map) load, and a few iterations at 16 × 16 lower their loss (mean of the last three iterations
/// against the first) and raise the shape's IoU.
#[test]
fn the_lighting_examples_load_and_their_loss_falls() {
    use implicit_psdr::optimize::config::{OptimizeConfig, Target};
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/inverse");
    for (name, iterations, factor) in [("envmap_light", 12, 0.5), ("shape_albedo_env", 12, 0.8)] {
        let mut cfg = OptimizeConfig::load(&root.join(name).join("opt.json")).unwrap();
        let Target::Scene { scene: target, .. } = &mut cfg.target else {
            panic!("{name}: the target is a scene")
        };
        for camera in [&mut cfg.scene.camera, &mut target.camera] {
            camera.width = 16;
            camera.height = 16;
        }
        cfg.settings.iterations = iterations;
        cfg.settings.spp = 4;
        // Every view in every iteration: the losses of two iterations are then of the same views
        // (some see the sun, whose pixels are the noisiest).
        cfg.settings.views_per_iteration = None;
        cfg.target_spp = 32;
        let outcome = implicit_psdr::optimize::run(&cfg, None, &mut ()).unwrap();
        let losses: Vec<f64> = outcome.rows.iter().map(|r| r.loss).collect();
        assert_eq!(losses.len(), iterations as usize);
        assert!(losses.iter().all(|l| l.is_finite()), "{name}: {losses:?}");
        let last = losses[losses.len() - 3..].iter().sum::<f64>() / 3.0;
        assert!(
            last < factor * losses[0],
            "{name}: loss {} -> {last} ({losses:?})",
            losses[0]
        );
        if name == "shape_albedo_env" {
            let iou: Vec<f64> = (outcome.rows.iter()).map(|r| r.iou().unwrap()).collect();
            assert!(iou[iou.len() - 1] > iou[0] + 0.1, "{name}: IoU {iou:?}");
        }
    }
}
