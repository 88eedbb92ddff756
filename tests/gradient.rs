//! Reverse mode ([`render_gradient`], [`loss_gradient`]) checked five ways.
//!
//! 1. **Dot products against forward mode** (same seed, same samples): for a pixel adjoint `g`, the
//!    reverse gradient of `Σ g·I` equals, entry by entry and term by term (interior, primary,
//!    secondary), `Σ g · ∂I` from forward mode's derivative images. Named parameters on a `direct`
//!    scene; a rotated grid's values along a direction; and on a `path` scene with a grid and analytic
//!    shapes, a random direction `u` over *all* selected entries at once (named parameters and grid
//!    values), `⟨∇, u⟩` against forward mode's directional derivative `Σ_k u_k ∂_k I + ∂_u(values) I`,
//!    with both pixel normalisations. Exact in exact arithmetic: the tolerance is float rounding.
//! 2. **Level identity**: a grid node is `spline − level` and the B-spline's weights sum to 1, so the
//!    gradient summed over the grid's values is minus the gradient of `<node>.level`, per term, in one
//!    run that selects both. Float rounding again.
//! 3. **Finite differences of the loss**: on a small grid scene, the L2 loss against a target rendered
//!    from a different scene; `⟨∇L, u⟩` from [`loss_gradient`] for a smooth random direction `u` of the
//!    grid's values and for named parameters (a radius, a light position, an albedo) against central
//!    differences of the loss (common random numbers: both sides of a difference rendered with the same
//!    seeds). Both are Monte Carlo estimates: over twelve seeds, their paired differences must have a
//!    mean within 4 standard errors of 0, and that error must be small (see [`loss_gradient_matches_finite_differences`] for why the
//!    difference is taken of `mean((I_s − T)(I_{s+1} − T))`, and the measured numbers).
//! 4. **Determinism**: the gradient is bit for bit the same with 1, 2 and 3 threads.
//! 5. **Hard cases** (scenes of `tests/hard_cases.rs`, shared in [`common::hard_scenes`], and a camera
//!    inside a closed grid shape): with every parameter of the scene selected, no gradient entry is NaN
//!    or infinite and no sample's gradient was dropped as non-finite.
//!
//! Images are 16–24 px with a few samples per pixel: the whole file runs in about 10 s (release, two
//! cores), most of it the finite differences.

mod common;

use common::Rng;
use common::hard_scenes;
use implicit_psdr::film::{Image, Normalization};
use implicit_psdr::integrator::gradient::adjoint_seed;
use implicit_psdr::integrator::{
    self, BoundaryBudget, DiffOptions, Gradient, GradientLayout, Loss, RenderOptions,
    loss_gradient, render, render_gradient,
};
use implicit_psdr::scene::{self, GridBlock, GridDirection, Scene, Shape};
use implicit_psdr::sdf::{Sdf, bake_padded, write_npy};
use std::path::Path;
use std::sync::Arc;

// ---------------------------------------------------------------------------------------------------
// Helpers

/// The scene file `path` at `size × size` pixels.
fn small(path: &str, size: u32) -> Scene {
    let mut s = scene::load(Path::new(path)).unwrap();
    s.camera.width = size;
    s.camera.height = size;
    s
}

/// A deterministic pseudo-random adjoint image in [-1, 1].
fn adjoint(w: u32, h: u32, seed: u64) -> Image {
    let mut img = Image::new(w, h);
    let mut x = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    for v in &mut img.rgb {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        *v = (x >> 40) as f32 / (1u64 << 23) as f32 * 2.0 - 1.0;
    }
    img
}

/// `n` values uniform in [-1, 1].
fn direction(n: usize, seed: u64) -> Vec<f32> {
    let mut rng = Rng::new(seed);
    (0..n).map(|_| rng.f32() * 2.0 - 1.0).collect()
}

/// `Σ a·b` over every channel of every pixel, in `f64`.
fn dot(a: &Image, b: &Image) -> f64 {
    a.rgb
        .iter()
        .zip(&b.rgb)
        .map(|(x, y)| *x as f64 * *y as f64)
        .sum()
}

/// `spp` camera samples with `seed`, the given boundary budgets (samples per pixel) and normalisation.
fn options(spp: u32, seed: u64, primary: u32, secondary: u32, norm: Normalization) -> DiffOptions {
    DiffOptions {
        render: RenderOptions {
            spp,
            seed,
            ..RenderOptions::default()
        },
        normalization: norm,
        boundary: BoundaryBudget {
            primary_spp: Some(primary as f32),
            secondary_spp: Some(secondary as f32),
        },
        ..Default::default()
    }
}

/// The three terms of a gradient with their names.
fn terms(g: &Gradient) -> [(&'static str, &Vec<f64>); 3] {
    [
        ("interior", &g.interior),
        ("primary", &g.primary),
        ("secondary", &g.secondary),
    ]
}

/// The forward-mode direction `u` of the values of grid `block`.
fn along(block: &GridBlock, u: Arc<Vec<f32>>) -> GridDirection {
    GridDirection {
        node: block.node.clone(),
        shape: block.shape.clone(),
        values: u,
        source: "u".into(),
    }
}

/// Owned names.
fn names(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

/// The grid shape of the grid scenes: a smooth union of a sphere and a rounded box, baked at `res`
/// samples along its longest edge (a padded box, [`bake_padded`]).
fn baked_blob(res: usize) -> implicit_psdr::sdf::Baked {
    let shape = Sdf::smooth_union(
        vec![
            Sdf::sphere([0.0, 0.1, 0.0], 0.4),
            Sdf::cuboid([0.0, -0.15, 0.0], [0.35, 0.2, 0.3], 0.08),
        ],
        0.15,
    );
    bake_padded(&shape, res, "blob").unwrap()
}

/// A scene with a grid shape `blob` (baked at `res`³, written to a test folder), a ball, a floor
/// slab, a rectangular light `light` and, with `sky`, a constant environment `sky`; `size × size`
/// pixels, tent filter, `integrator` as JSON. Its grid node is `blob`.
fn grid_scene(label: &str, integrator: &str, size: u32, res: usize, sky: bool) -> Scene {
    let dir = common::workdir("gradient", label);
    let baked = baked_blob(res);
    write_npy(&dir.join("blob.npy"), &baked.grid).unwrap();
    let sky = if sky {
        r#", {"name": "sky", "type": "constant", "radiance": [0.2, 0.22, 0.25]}"#
    } else {
        ""
    };
    let json = format!(
        r#"{{"camera": {{"origin": [0, 1.6, 3.2], "target": [0, 0.3, 0], "up": [0, 1, 0], "fov_y": 40,
                "width": {size}, "height": {size}, "filter": "tent"}},
            "integrator": {integrator},
            "shapes": [
              {{"name": "blob", "translate": [-0.5, 0.45, 0], "sdf": {node},
                "bsdf": {{"type": "diffuse", "albedo": [0.8, 0.35, 0.25]}}}},
              {{"name": "ball", "sdf": {{"type": "sphere", "center": [0.6, 0.35, 0.2], "radius": 0.35}},
                "bsdf": {{"type": "diffuse", "albedo": [0.6, 0.7, 0.8]}}}},
              {{"name": "floor", "sdf": {{"type": "box", "center": [0, -0.1, 0], "half_size": [2.5, 0.1, 2.5],
                "rounding": 0.02}}, "bsdf": {{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}}}],
            "emitters": [
              {{"name": "light", "type": "rectangle", "center": [1.0, 3.0, 1.5], "normal": [0, -1, 0],
                "u": [1, 0, 0], "size": [1, 1], "radiance": [25, 25, 25]}}{sky}]}}"#,
        node = baked.scene_node("blob.npy"),
    );
    scene::parse(&json, &dir).unwrap()
}

/// `scene` with a second grid shape `twin`: `blob`'s grid and material, behind the others.
fn with_twin(scene: &Scene) -> Scene {
    let blob = scene.shape_named("blob").unwrap().clone();
    let mut shapes = scene.shapes.clone();
    let at = glam::Vec3::new(0.2, 0.45, -0.9);
    shapes.push(Shape::translated("twin", blob.sdf, blob.bsdf, at.into()));
    Scene::new(
        scene.camera.clone(),
        scene.integrator,
        scene.spp,
        shapes,
        scene.emitters.clone(),
    )
}

const PATH: &str = r#"{"type": "path", "max_depth": 3}"#;
const DIRECT: &str = r#"{"type": "direct"}"#;

// ---------------------------------------------------------------------------------------------------
// 1. Dot products against forward mode

#[test]
fn named_parameters_match_forward_mode_term_by_term() {
    let scene = small("scenes/sphere_floor.json", 24);
    let params = names(&[
        "ball.radius",
        "light.center.x",
        "ball.albedo.r",
        "ball.center.y",
    ]);
    let layout = GradientLayout::select(&scene, &params, &[]).unwrap();
    let options = options(4, 7, 2, 4, Normalization::default());
    let g = adjoint(24, 24, 3);
    let forward =
        integrator::render_derivatives(&scene, &scene.select(&params).unwrap(), &options).unwrap();
    let reverse = render_gradient(&scene, &layout, &g, &options).unwrap();
    for (k, name) in params.iter().enumerate() {
        for (term, f, r) in [
            ("interior", &forward.interior, &reverse.interior),
            ("primary", &forward.primary, &reverse.primary),
            ("secondary", &forward.secondary, &reverse.secondary),
        ] {
            let want = dot(&g, &f[k]);
            let got = r[k];
            println!("{name} {term}: forward {want:.6e} reverse {got:.6e}");
            assert!(
                (got - want).abs() <= 1e-4 * want.abs().max(1e-3),
                "{name} {term}: reverse {got} vs forward {want}"
            );
        }
    }
}

/// A sparse adjoint (zero outside a 6×6 window of a 24×24 image, as where an inverse rendering's image
/// and target agree): reverse mode skips the camera samples that can reach no pixel of non-zero adjoint
/// and must still equal the forward mode's contraction term by term. The samples of the pixels just
/// outside the window splat into it through the moving pixel filter; skipping them would show as an
/// error of the order of that share (measured: rounding, as for a dense adjoint).
#[test]
fn sparse_adjoint_matches_forward_mode() {
    let scene = small("scenes/sphere_floor.json", 24);
    let params = names(&[
        "ball.radius",
        "ball.center.y",
        "ball.center.x",
        "camera.fov_y",
    ]);
    let layout = GradientLayout::select(&scene, &params, &[]).unwrap();
    let options = options(4, 9, 2, 4, Normalization::default());
    let mut g = adjoint(24, 24, 5);
    for y in 0..24 {
        for x in 0..24 {
            if !(9..15).contains(&x) || !(9..15).contains(&y) {
                g.rgb[3 * (y * 24 + x)..3 * (y * 24 + x) + 3].fill(0.0);
            }
        }
    }
    let forward =
        integrator::render_derivatives(&scene, &scene.select(&params).unwrap(), &options).unwrap();
    let reverse = render_gradient(&scene, &layout, &g, &options).unwrap();
    for (k, name) in params.iter().enumerate() {
        for (term, f, r) in [
            ("interior", &forward.interior, &reverse.interior),
            ("primary", &forward.primary, &reverse.primary),
            ("secondary", &forward.secondary, &reverse.secondary),
        ] {
            let want = dot(&g, &f[k]);
            let got = r[k];
            println!("{name} {term}: forward {want:.6e} reverse {got:.6e}");
            assert!(
                (got - want).abs() <= 1e-4 * want.abs().max(1e-3),
                "{name} {term}: reverse {got} vs forward {want}"
            );
        }
    }
}

/// The crease edges' terms (a turned sharp box with a ball bitten out of its corner, a crease where
/// CSG children cross, and a sharp cylinder over a floor: seen by the camera, their shadows, and on
/// `path` their tear after a bounce) in reverse mode equal the forward mode's contraction with the
/// adjoint.
#[test]
fn crease_edges_match_forward_mode() {
    for integrator in [
        r#"{"type": "direct"}"#,
        r#"{"type": "path", "max_depth": 3}"#,
    ] {
        crease_edges_case(integrator);
    }
}

fn crease_edges_case(integrator: &str) {
    let scene = scene::parse(
        &r#"{
  "camera": {"origin": [0, 1.6, 4], "target": [0, 0, 0], "up": [0, 1, 0],
             "fov_y": 40.0, "width": 20, "height": 20, "filter": "tent"},
  "integrator": INTEGRATOR,
  "shapes": [
    {"name": "block",
     "sdf": {"type": "transform", "translate": [-0.5, 0, 0],
             "rotate": {"axis": [0.2, 1, 0.1], "angle": 30}, "scale": 1.0,
             "child": {"type": "difference", "children": [
                {"type": "box", "center": [0, 0, 0], "half_size": [0.4, 0.5, 0.4], "rounding": 0},
                {"name": "bite", "type": "sphere", "center": [0.2, 0.5, 0.3], "radius": 0.35}]}},
     "bsdf": {"type": "diffuse", "albedo": [0.8, 0.6, 0.4]}},
    {"name": "can",
     "sdf": {"type": "cylinder", "center": [0.7, 0, 0], "axis": [0.3, 1, 0.2],
             "radius": 0.4, "half_height": 0.5, "rounding": 0},
     "bsdf": {"type": "diffuse", "albedo": [0.4, 0.7, 0.8]}},
    {"name": "floor", "sdf": {"type": "plane", "normal": [0, 1, 0], "offset": -0.5},
     "bsdf": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}
  ],
  "emitters": [
    {"name": "light", "type": "rectangle", "center": [2, 3, 2], "normal": [-0.5, -1, -0.5],
     "u": [1, 0, 0], "size": [1, 1], "radiance": [20, 20, 20]},
    {"name": "sky", "type": "constant", "radiance": [0.3, 0.3, 0.3]}
  ]
}"#
        .replace("INTEGRATOR", integrator),
        Path::new("."),
    )
    .unwrap();
    let params = names(&[
        "block.sdf.translate.x",
        "block.sdf.angle",
        "can.radius",
        "bite.radius",
        "camera.origin.y",
    ]);
    let layout = GradientLayout::select(&scene, &params, &[]).unwrap();
    let options = options(4, 7, 2, 4, Normalization::default());
    let g = adjoint(20, 20, 5);
    let forward =
        integrator::render_derivatives(&scene, &scene.select(&params).unwrap(), &options).unwrap();
    let reverse = render_gradient(&scene, &layout, &g, &options).unwrap();
    for (k, name) in params.iter().enumerate() {
        for (term, f, r) in [
            ("primary", &forward.primary, &reverse.primary),
            ("secondary", &forward.secondary, &reverse.secondary),
        ] {
            let want = dot(&g, &f[k]);
            let got = r[k];
            println!("{integrator} {name} {term}: forward {want:.6e} reverse {got:.6e}");
            assert!(
                (got - want).abs() <= 1e-4 * want.abs().max(1e-3),
                "{integrator} {name} {term}: reverse {got} vs forward {want}"
            );
        }
        let primary = dot(&g, &forward.primary[k]);
        assert!(
            primary.abs() > 1e-3,
            "{name}: the primary term should not vanish"
        );
    }
}

#[test]
fn grid_values_match_a_forward_direction() {
    let scene = small("scenes/grid.json", 24);
    let node = "baked_blob.sdf.child".to_string();
    let params = names(&["ball.radius"]);
    let options = options(4, 5, 2, 4, Normalization::default());
    let g = adjoint(24, 24, 11);
    let layout = GradientLayout::select(&scene, &params, std::slice::from_ref(&node)).unwrap();
    let reverse = render_gradient(&scene, &layout, &g, &options).unwrap();
    let (block, first) = &layout.grids[0];
    let u = adjoint(block.len() as u32, 1, 99).rgb[..block.len()].to_vec();
    let along = along(block, Arc::new(u.clone()));
    let selection = (scene.select_with_grid_directions(&params, &[along])).unwrap();
    let forward = integrator::render_derivatives(&scene, &selection, &options).unwrap();
    for (term, f, r) in [
        ("interior", &forward.interior, &reverse.interior),
        ("primary", &forward.primary, &reverse.primary),
        ("secondary", &forward.secondary, &reverse.secondary),
    ] {
        let want = dot(&g, &f[1]);
        let got: f64 = (0..block.len()).map(|i| r[first + i] * u[i] as f64).sum();
        println!("grid {term}: forward {want:.6e} reverse {got:.6e}");
        assert!(
            (got - want).abs() <= 1e-4 * want.abs().max(1e-3),
            "{term}: reverse {got} vs forward {want}"
        );
    }
}

/// The named parameters of the path-scene checks: geometry (a radius, a position, the grid's level
/// and translation), the camera (a position and the field of view), the light (a position and a
/// radiance), the environment, albedos. Twelve of them and the grid's direction: forward mode takes
/// two passes of eight directions (the grid's in the second), reverse mode one.
const PATH_PARAMS: [&str; 12] = [
    "ball.radius",
    "ball.center.x",
    "light.center.x",
    "blob.albedo.r",
    "blob.level",
    "blob.translate.y",
    "floor.albedo.g",
    "camera.origin.y",
    "camera.fov_y",
    "light.radiance.r",
    "sky.radiance.b",
    "ball.albedo.b",
];

/// On a `path` scene (grid, sphere, floor, rectangle light and sky; three bounces), for a random
/// adjoint `g` and a random direction `u` over every selected entry ([`PATH_PARAMS`] and the grid's
/// 10³ values), `⟨∇, u⟩` from reverse mode equals `Σ_j g_j D_u I_j` from forward mode with the
/// same seed, where `D_u I = Σ_k u_k ∂_k I + ∂I/∂values · u_values` (the named parameters' derivative
/// images combined with `u`'s components, plus the grid's direction in the last slot), term by term,
/// with the fixed and the differentiable normalisation.
///
/// Tolerance: both sides sum the same per-sample products in `f32`, in different orders and groupings
/// (forward: per pixel, then the images; reverse: per sample's tape, per work item, then `f64`); the
/// error is rounding, relative to the sum of the magnitudes involved, `Σ_j |g_j| Σ_k |u_k ∂_k I_j|`.
/// Each named parameter's entry is also compared with its own image, relative to `Σ_j |g_j ∂_k I_j|`.
/// Measured: at most 3.3e-8 of that scale (interior, primary, secondary: fixed 1.6e-8, 3.3e-8, 5.5e-9;
/// differentiable 2.5e-8, 1.6e-8, 5.5e-9); the bound is 1e-5. A wrong partial or a dropped sample
/// shows as an error of the order of the term itself.
#[test]
fn path_scene_every_entry_matches_forward_direction() {
    let size = 24;
    let base = grid_scene("dot", PATH, size, 10, true);
    let params = names(&PATH_PARAMS);
    let node = "blob".to_string();
    let g = adjoint(size, size, 21);
    for norm in [Normalization::Fixed, Normalization::Differentiable] {
        let options = options(4, 31, 2, 4, norm);
        let layout = GradientLayout::select(&base, &params, std::slice::from_ref(&node)).unwrap();
        let first = layout.grids[0].1;
        assert_eq!(first, params.len());
        let u = direction(layout.entries, 5);
        let u_values = Arc::new(u[first..].to_vec());
        let reverse = render_gradient(&base, &layout, &g, &options).unwrap();
        let along = along(&layout.grids[0].0, u_values.clone());
        let selection = (base.select_with_grid_directions(&params, &[along])).unwrap();
        let forward = integrator::render_derivatives(&base, &selection, &options).unwrap();
        assert_eq!(forward.stats.invalid_derivatives, 0);
        assert_eq!(reverse.stats.invalid_derivatives, 0);
        for (term, f, r) in [
            ("interior", &forward.interior, &reverse.interior),
            ("primary", &forward.primary, &reverse.primary),
            ("secondary", &forward.secondary, &reverse.secondary),
        ] {
            // Forward: Σ_j g_j (Σ_k u_k ∂_k I_j + ∂_values I_j).
            let weights: Vec<f64> = (0..params.len())
                .map(|k| u[k] as f64)
                .chain([1.0])
                .collect();
            let mut want = 0.0;
            let mut scale = 0.0;
            for j in 0..g.rgb.len() {
                let parts = f
                    .iter()
                    .zip(&weights)
                    .map(|(image, w)| w * image.rgb[j] as f64);
                let gj = g.rgb[j] as f64;
                for p in parts {
                    want += gj * p;
                    scale += (gj * p).abs();
                }
            }
            let got: f64 = (0..layout.entries).map(|i| r[i] * u[i] as f64).sum();
            let err = (got - want).abs() / scale.max(1e-30);
            println!(
                "{norm:?} {term}: forward {want:.6e} reverse {got:.6e} (scale {scale:.3e}, \
                 error {err:.1e} of it)"
            );
            assert!(scale > 0.0, "{norm:?} {term}: nothing to compare");
            assert!(
                err <= 1e-5,
                "{norm:?} {term}: reverse {got} vs forward {want} (scale {scale})"
            );
            // And each named parameter on its own (a wrong entry could hide in the sum).
            for (k, name) in params.iter().enumerate() {
                let want = dot(&g, &f[k]);
                let scale: f64 = g
                    .rgb
                    .iter()
                    .zip(&f[k].rgb)
                    .map(|(a, b)| (a * b).abs() as f64)
                    .sum();
                assert!(
                    (r[k] - want).abs() <= 1e-5 * scale,
                    "{norm:?} {term} {name}: reverse {} vs forward {want} (scale {scale})",
                    r[k]
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------------
// 2. Level identity

/// `φ = spline(values) − level` with B-spline weights summing to 1: every sample's partials satisfy
/// `Σ_i ∂/∂c_i = −∂/∂level`, so the gradient summed over a grid's values is minus its level's, per
/// term. One run selects both (the levels as named parameters, the values as blocks), on the path
/// scene with a second grid shape `twin` (selected first, so that its block precedes `blob`'s: a
/// misplaced block would pair one grid's values with the other's level).
///
/// Tolerance: a sample reports its 64 value partials per lattice sum and its level partial separately,
/// each rounded in `f32` and summed per work item; the two sides differ by that rounding, relative to
/// `Σ_i |∂/∂c_i|`. Measured: at most 1.2e-7 of that scale (see the printout); the bound is 1e-5.
#[test]
fn grid_values_sum_to_minus_the_level() {
    let size = 24;
    let scene = with_twin(&grid_scene("level", PATH, size, 10, true));
    let params = names(&["blob.level", "ball.radius", "twin.level"]);
    let grids = names(&["twin", "blob"]);
    let layout = GradientLayout::select(&scene, &params, &grids).unwrap();
    assert_eq!(layout.grids.len(), 2);
    for (seed, norm) in [
        (3, Normalization::Differentiable),
        (4, Normalization::Fixed),
    ] {
        let g = adjoint(size, size, seed);
        let options = options(4, seed, 2, 4, norm);
        let gradient = render_gradient(&scene, &layout, &g, &options).unwrap();
        for (term, r) in terms(&gradient) {
            for (block, first) in &layout.grids {
                let level_name = format!("{}.level", block.node);
                let level = r[params.iter().position(|p| *p == level_name).unwrap()];
                let values = &r[*first..first + block.len()];
                let sum: f64 = values.iter().sum();
                let scale: f64 = values.iter().map(|v| v.abs()).sum();
                let err = (sum + level).abs() / scale.max(1e-30);
                println!(
                    "{norm:?} {term} {}: Σ values {sum:.6e}, level {level:.6e} (scale {scale:.3e}, \
                     error {err:.1e} of it)",
                    block.node
                );
                assert!(
                    scale > 0.0 && level != 0.0,
                    "{norm:?} {term} {}: nothing to compare",
                    block.node
                );
                assert!(
                    err <= 1e-5,
                    "{norm:?} {term} {}: Σ values {sum} vs −level {}",
                    block.node,
                    -level
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------------
// 3. Finite differences of the loss

/// Mean and standard error of the mean.
fn mean_se(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// The image of `scene` with `spp` samples and `seed`.
fn image(scene: &Scene, spp: u32, seed: u64) -> Image {
    let options = RenderOptions {
        spp,
        seed,
        ..RenderOptions::default()
    };
    render(scene, &options).0
}

/// The two losses of [`loss_gradient_matches_finite_differences`] for one seed `s`: the L2 loss of the image of seed `s`, and the
/// unbiased estimate of the loss of the expected image, `mean((I_s − T)(I_{s+1} − T))`.
fn losses(scene: &Scene, target: &Image, spp: u32, seed: u64) -> (f64, f64) {
    let a = image(scene, spp, seed);
    let b = image(scene, spp, adjoint_seed(seed));
    let loss = Loss::L2.evaluate(&a, target, "target").unwrap().0;
    let cross = a
        .rgb
        .iter()
        .zip(&b.rgb)
        .zip(&target.rgb)
        .map(|((a, b), t)| (*a as f64 - *t as f64) * (*b as f64 - *t as f64))
        .sum::<f64>()
        / a.rgb.len() as f64;
    (loss, cross)
}

/// A smooth random direction of a grid's values (shape `[nz, ny, nx]`): four random plane waves of at
/// most about one period across the grid, scaled to a largest magnitude of 1. A smooth perturbation moves
/// the surface coherently (an uncorrelated one mostly cancels in the image and leaves FD with noise).
fn smooth_direction(shape: [usize; 3], seed: u64) -> Vec<f32> {
    let [nz, ny, nx] = shape;
    let mut rng = Rng::new(seed);
    let waves: Vec<([f32; 3], f32, f32)> = (0..4)
        .map(|_| {
            let k = [rng.f32(), rng.f32(), rng.f32()].map(|v| (v * 2.0 - 1.0) * 6.0);
            (k, rng.f32() * std::f32::consts::TAU, rng.f32() * 2.0 - 1.0)
        })
        .collect();
    let mut u = Vec::with_capacity(nx * ny * nz);
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let p = [
                    x as f32 / nx as f32,
                    y as f32 / ny as f32,
                    z as f32 / nz as f32,
                ];
                let v: f32 = waves
                    .iter()
                    .map(|(k, phase, a)| {
                        a * (k[0] * p[0] + k[1] * p[1] + k[2] * p[2] + phase).cos()
                    })
                    .sum();
                u.push(v);
            }
        }
    }
    let max = u.iter().fold(0.0f32, |m, v| m.max(v.abs()));
    u.iter().map(|v| v / max).collect()
}

/// `⟨∇L, u⟩` from [`loss_gradient`] against central differences of the loss, over several seeds.
///
/// The scene: the grid scene with a `direct` integrator, 24 px, 16 spp, the grid baked at 12³. The target: the same scene with the grid's level raised by 0.04 (the blob
/// dilated), the ball's radius, the light's position and the blob's albedo changed, rendered at 256 spp.
/// The directions: a smooth random direction of the grid's values ([`smooth_direction`]), and the named
/// parameters `ball.radius`, `light.center.x`, `blob.albedo.g`.
///
/// Per seed `s` (twelve of them): the gradient estimate `⟨∇L, u⟩` of [`loss_gradient`] (loss pass
/// seed `s`, adjoint pass `s + 1`), and central differences `(X(θ + hu) − X(θ − hu)) / 2h` with common
/// random numbers (every image of a difference rendered with the same seeds) of two losses `X`:
///
/// - `L_cross = mean((I_s − T)(I_{s+1} − T))`, whose expectation is the loss of the *expected* image,
///   `L(E I)`: what the two-seed gradient estimates (its expectation is `2 mean((E I − T) E ∂I)` since
///   the adjoint is linear in `I_s`, independent of the adjoint pass). **Asserted**: the mean over seeds
///   of `gradient − FD` is within 4 standard errors of 0 (the SE from the spread of the paired
///   differences; a Student t with 11 degrees of freedom exceeds 4 with probability 0.2%), and that SE
///   is below 10% of the derivative, so that an error of the gradient of that size cannot hide. FD at
///   `h/2` must agree with FD at `h` the same way (truncation error below the noise), up to 1e-5 of the
///   derivative for the rounding of the `f32` images (the albedo's losses are exactly quadratic: its two
///   FDs differ by rounding only, 3e-7 relative, with a near-zero spread).
///
/// Measured (see the printout; gradient − FD in standard errors, that SE in % of the derivative):
/// grid values −0.45 SE (4.5%), `ball.radius` −0.70 (3.8%), `light.center.x` −1.63 (1.5%),
/// `blob.albedo.g` −1.00 (1.6%); FD(h/2) − FD(h) within 1.4 SE.
/// - `L = mean((I_s − T)²)`, the loss itself (printed only): its expectation is `L(E I) + mean Var(I)`,
///   so its FD also holds the derivative of the pixel variance, a bias of order `1/spp` which the
///   two-seed gradient deliberately does not estimate (module docs of `integrator::gradient`). Measured
///   (gradient − FD of `L`): grid −2.8%, `ball.radius` −3.8%, `light.center.x` +2.1%, `blob.albedo.g`
///   −4.1% of the derivative; for the albedo that is 2.3 combined standard errors (its `L` is linear in
///   the pixel variance, which grows with the albedo), where `L_cross` agrees within 1.0.
#[test]
fn loss_gradient_matches_finite_differences() {
    let size = 24;
    let spp = 16;
    let scene = grid_scene("fd", DIRECT, size, 12, false);
    let node = "blob".to_string();
    let values = scene.grid_values(&node).unwrap().values.clone();
    let target_scene = scene
        .with_parameter("blob.level", 0.04)
        .unwrap()
        .with_parameter("ball.radius", 0.38)
        .unwrap()
        .with_parameter("light.center.x", 1.2)
        .unwrap()
        .with_parameter("blob.albedo.g", 0.45)
        .unwrap();
    let target = image(&target_scene, 256, 999);
    let params = names(&["ball.radius", "light.center.x", "blob.albedo.g"]);
    let layout = GradientLayout::select(&scene, &params, std::slice::from_ref(&node)).unwrap();
    let (block, first) = layout.grids[0].clone();
    let u = smooth_direction(block.shape.clone().try_into().unwrap(), 77);
    let seeds: Vec<u64> = (0..12).map(|s| 100 + 2 * s).collect();
    let options = options(spp, 0, 4, 8, Normalization::default());
    let gradients: Vec<Vec<f64>> = seeds
        .iter()
        .map(|&seed| {
            let mut o = options.clone();
            o.render.seed = seed;
            let lg = loss_gradient(&scene, &layout, &target, Loss::L2, &o).unwrap();
            assert_eq!(lg.gradient.stats.invalid_derivatives, 0);
            lg.gradient.total()
        })
        .collect();
    // (label, step, the scene moved by t along the direction, the gradient along the direction)
    type Moved<'a> = Box<dyn Fn(f32) -> Scene + 'a>;
    type Along = Box<dyn Fn(&[f64]) -> f64>;
    let mut cases: Vec<(String, f32, Moved, Along)> = Vec::new();
    {
        let (scene, node, values, u) = (&scene, &node, &values, u.clone());
        let u2 = u.clone();
        cases.push((
            "grid values along u".into(),
            // At most 0.02 on a value: the surface moves at most ~0.2 px.
            0.02,
            Box::new(move |t: f32| {
                let mut s = scene.clone();
                let v = values.iter().zip(&u).map(|(v, u)| v + t * u).collect();
                s.set_grid_values(node, v).unwrap();
                s
            }),
            Box::new(move |g: &[f64]| (0..block.len()).map(|i| g[first + i] * u2[i] as f64).sum()),
        ));
    }
    // Steps (the image spans about 0.1 scene units per pixel): the ball's edge moves 0.1 px, the light
    // by 5% of its size, the albedo 0.35 by 0.05 (its losses are quadratic: FD exact). Smaller steps
    // make the FD noisier (fewer samples see an edge cross), larger ones are checked by h/2.
    for (k, (name, h)) in params.iter().zip([0.01f32, 0.05, 0.05]).enumerate() {
        let scene = &scene;
        let v = scene.parameter(name).unwrap();
        cases.push((
            name.clone(),
            h,
            Box::new(move |t: f32| scene.with_parameter(name, v + t).unwrap()),
            Box::new(move |g: &[f64]| g[k]),
        ));
    }
    for (label, h, moved, along) in &cases {
        let estimates: Vec<f64> = gradients.iter().map(|g| along(g)).collect();
        // Per seed: FD of (L, L_cross) at h and h/2.
        let fd = |h: f32, seed: u64| {
            let (lp, cp) = losses(&moved(h), &target, spp, seed);
            let (lm, cm) = losses(&moved(-h), &target, spp, seed);
            let d = 2.0 * h as f64;
            ((lp - lm) / d, (cp - cm) / d)
        };
        let at_h: Vec<(f64, f64)> = seeds.iter().map(|&s| fd(*h, s)).collect();
        let at_half: Vec<(f64, f64)> = seeds.iter().map(|&s| fd(*h / 2.0, s)).collect();
        let cross: Vec<f64> = at_h.iter().map(|v| v.1).collect();
        let plain: Vec<f64> = at_h.iter().map(|v| v.0).collect();
        let diff: Vec<f64> = estimates.iter().zip(&cross).map(|(g, f)| g - f).collect();
        let trunc: Vec<f64> = at_half.iter().zip(&cross).map(|(a, b)| a.1 - b).collect();
        let (gm, gse) = mean_se(&estimates);
        let (fm, fse) = mean_se(&cross);
        let (pm, pse) = mean_se(&plain);
        let (dm, dse) = mean_se(&diff);
        let (tm, tse) = mean_se(&trunc);
        println!(
            "{label} (h {h}): gradient {gm:.4e} ± {gse:.1e}, FD of L_cross {fm:.4e} ± {fse:.1e}; \
             gradient − FD {dm:.2e} ± {dse:.1e} ({:.2} SE, SE {:.1}% of FD); FD(h/2) − FD(h) \
             {tm:.2e} ± {tse:.1e} ({:.2} SE); FD of L {pm:.4e} ± {pse:.1e} (gradient − it: {:.2e}, \
             {:.1}%)",
            dm / dse,
            100.0 * dse / fm.abs(),
            tm / tse,
            gm - pm,
            100.0 * (gm - pm) / pm.abs(),
        );
        assert!(
            dse <= 0.1 * fm.abs(),
            "{label}: too noisy to check (SE {dse} of the difference, FD {fm})"
        );
        assert!(
            dm.abs() <= 4.0 * dse,
            "{label}: gradient {gm} ± {gse} vs FD {fm} ± {fse} (difference {dm} ± {dse})"
        );
        assert!(
            tm.abs() <= 4.0 * tse + 1e-5 * fm.abs(),
            "{label}: FD(h/2) − FD(h) = {tm} ± {tse}: truncation error"
        );
    }
}

// ---------------------------------------------------------------------------------------------------
// 4. Determinism

/// `work`'s result on a pool of `threads` threads (unwrapped).
fn with_threads<T: Send>(
    threads: usize,
    work: impl FnOnce() -> implicit_psdr::error::Result<T> + Send,
) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(work)
        .unwrap()
}

/// Asserts that every term of `other` (run on `threads` threads) is bit for bit `one`'s (1 thread).
fn assert_same_bits(one: &Gradient, other: &Gradient, threads: usize) {
    for ((term, a), (_, b)) in terms(one).into_iter().zip(terms(other)) {
        let a: Vec<u64> = a.iter().map(|v| v.to_bits()).collect();
        let b: Vec<u64> = b.iter().map(|v| v.to_bits()).collect();
        assert_eq!(a, b, "{term}: 1 thread vs {threads}");
    }
}

/// Work items are merged in item order whatever the thread that ran them, so the gradient (every term,
/// every entry) is bit for bit the same with 1, 2 and 3 threads (3 changes the merge waves too).
#[test]
fn gradient_is_identical_across_thread_counts() {
    let size = 16;
    let scene = grid_scene("threads", PATH, size, 10, true);
    let layout =
        GradientLayout::select(&scene, &names(&PATH_PARAMS), &["blob".to_string()]).unwrap();
    let g = adjoint(size, size, 8);
    let options = options(2, 9, 2, 4, Normalization::default());
    let run = |threads| with_threads(threads, || render_gradient(&scene, &layout, &g, &options));
    let one = run(1);
    assert!(one.total().iter().any(|v| *v != 0.0));
    for threads in [2, 3] {
        let other = run(threads);
        assert_same_bits(&one, &other, threads);
        assert_eq!(
            one.stats.invalid_derivatives,
            other.stats.invalid_derivatives
        );
    }
}

/// [`loss_gradient`] (its loss pass, then the adjoint pass) is just as deterministic: the loss and
/// the gradient bit for bit the same with 1, 2 and 3 threads, and its image bit for bit the image
/// [`render`] makes with the same seed.
#[test]
fn loss_gradient_is_identical_across_thread_counts() {
    let size = 16;
    let scene = grid_scene("threads-loss", PATH, size, 10, true);
    let target = image(&scene.with_parameter("blob.level", 0.03).unwrap(), 16, 5);
    let layout =
        GradientLayout::select(&scene, &names(&PATH_PARAMS), &["blob".to_string()]).unwrap();
    let options = options(4, 9, 2, 4, Normalization::default());
    let run = |threads| {
        with_threads(threads, || {
            loss_gradient(&scene, &layout, &target, Loss::L2, &options)
        })
    };
    let one = run(1);
    assert!(one.gradient.interior.iter().any(|v| *v != 0.0));
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&one.image.rgb), bits(&image(&scene, 4, 9).rgb));
    for threads in [2, 3] {
        let other = run(threads);
        assert_same_bits(&one.gradient, &other.gradient, threads);
        assert_eq!(one.loss.to_bits(), other.loss.to_bits());
    }
}

// ---------------------------------------------------------------------------------------------------
// 5. Hard cases

/// Every parameter of `scene` (and every grid's values) selected; the gradient of a random adjoint has
/// finite entries only and no sample was dropped as non-finite.
fn assert_finite_gradient(label: &str, scene: Scene) {
    let params: Vec<String> = scene.parameters().into_iter().map(|(n, _)| n).collect();
    let grids: Vec<String> = scene.grid_blocks().into_iter().map(|b| b.node).collect();
    let layout = GradientLayout::select(&scene, &params, &grids).unwrap();
    let (w, h) = (scene.camera.width, scene.camera.height);
    let g = adjoint(w, h, 17);
    let options = options(4, 23, 4, 8, Normalization::default());
    let gradient = render_gradient(&scene, &layout, &g, &options).unwrap();
    for (term, r) in terms(&gradient) {
        if let Some(i) = r.iter().position(|v| !v.is_finite()) {
            let name = params.get(i).map_or("a grid value", String::as_str);
            panic!("{label}: {term} gradient of {name} (entry {i}) is {}", r[i]);
        }
    }
    let nonzero = gradient.total().iter().filter(|v| **v != 0.0).count();
    println!(
        "{label}: {} entries ({} parameters), {nonzero} non-zero, {:.2} s",
        layout.entries,
        params.len(),
        gradient.stats.seconds
    );
    assert_eq!(
        gradient.stats.invalid_derivatives, 0,
        "{label}: {:?}",
        gradient.stats.first_invalid
    );
    assert!(nonzero > 0, "{label}: the gradient is zero");
}

// The scenes of `tests/hard_cases.rs` (`common::hard_scenes`), all at 24 px; 4 spp, 4 primary and 8
// secondary boundary samples per pixel.

/// [`hard_scenes::grazing_silhouette`]: a torus nearly edge-on (cusps of the silhouette).
#[test]
fn hard_case_grazing_silhouette_is_finite() {
    assert_finite_gradient("grazing_silhouette", hard_scenes::grazing_silhouette(24));
}

/// [`hard_scenes::shadow_on_grazing_surface`]: the floor and a shadow seen at 3–7°.
#[test]
fn hard_case_shadow_on_grazing_surface_is_finite() {
    assert_finite_gradient(
        "shadow_on_grazing_surface",
        hard_scenes::shadow_on_grazing_surface(24),
    );
}

/// [`hard_scenes::two_silhouettes_on_a_camera_ray`]: one line of sight tangent to two spheres.
#[test]
fn hard_case_tangent_camera_ray_is_finite() {
    assert_finite_gradient(
        "two_silhouettes_on_a_camera_ray",
        hard_scenes::two_silhouettes_on_a_camera_ray(24),
    );
}

/// [`hard_scenes::two_silhouettes_on_a_light_ray`]: one shadow ray tangent to two spheres.
#[test]
fn hard_case_tangent_light_ray_is_finite() {
    assert_finite_gradient(
        "two_silhouettes_on_a_light_ray",
        hard_scenes::two_silhouettes_on_a_light_ray(24),
    );
}

/// [`hard_scenes::camera_close_to_a_surface`]: the camera 0.1 from a ball.
#[test]
fn hard_case_camera_close_to_a_surface_is_finite() {
    assert_finite_gradient(
        "camera_close_to_a_surface",
        hard_scenes::camera_close_to_a_surface(24),
    );
}

/// [`hard_scenes::light_touching_an_occluder`]: a sphere light touching the ball (`G ∝ 1/d²`).
#[test]
fn hard_case_light_touching_an_occluder_is_finite() {
    assert_finite_gradient(
        "light_touching_an_occluder",
        hard_scenes::light_touching_an_occluder(24),
    );
}

/// The camera inside a closed grid shape: a rounded box with a spherical cavity (baked at 14³), lit by
/// a sphere light inside, with a ball; `path` integrator. Every camera ray starts inside the grid's box,
/// the walls are seen from inside (concave), shadows and silhouettes fall on them; grid values and all
/// named parameters selected.
#[test]
fn hard_case_camera_inside_a_grid_room_is_finite() {
    let dir = common::workdir("gradient", "room");
    let room = Sdf::difference(vec![
        Sdf::cuboid([0.0; 3], [1.5, 1.5, 1.5], 0.3),
        Sdf::sphere([0.0; 3], 1.15),
    ]);
    let baked = bake_padded(&room, 14, "room").unwrap();
    write_npy(&dir.join("room.npy"), &baked.grid).unwrap();
    let json = format!(
        r#"{{"camera": {{"origin": [0.2, 0.1, 0.8], "target": [0, -0.4, -0.4], "up": [0, 1, 0],
                "fov_y": 60, "width": 16, "height": 16, "filter": "tent"}},
            "integrator": {PATH},
            "shapes": [
              {{"name": "room", "sdf": {node}, "bsdf": {{"type": "diffuse", "albedo": [0.7, 0.7, 0.6]}}}},
              {{"name": "ball", "sdf": {{"type": "sphere", "center": [0.3, -0.6, -0.3], "radius": 0.3}},
                "bsdf": {{"type": "diffuse", "albedo": [0.6, 0.3, 0.3]}}}}],
            "emitters": [{{"name": "light", "type": "sphere", "center": [-0.4, 0.5, -0.2], "radius": 0.15,
                "radiance": [20, 20, 20]}}]}}"#,
        node = baked.scene_node("room.npy"),
    );
    let s = scene::parse(&json, &dir).unwrap();
    let eye = glam::Vec3::new(0.2, 0.1, 0.8);
    let room = s.shape_named("room").unwrap();
    assert!(room.bounds.contains(eye) && room.eval_f32(eye) > 0.0);
    assert_finite_gradient("camera_inside_a_grid_room", s);
}
