//! Reverse mode against forward mode: for a pixel adjoint `g`, the gradient of `Σ g·I` equals, entry by
//! entry and term by term, `Σ g · ∂I` from the derivative images of the same samples (dot-product test).

use implicit_psdr::film::Image;
use implicit_psdr::integrator::{
    self, BoundaryBudget, DiffOptions, GradientLayout, RenderOptions, render_gradient,
};
use implicit_psdr::scene::{self, Scene};
use std::path::Path;

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

fn dot(a: &Image, b: &Image) -> f64 {
    a.rgb
        .iter()
        .zip(&b.rgb)
        .map(|(x, y)| *x as f64 * *y as f64)
        .sum()
}

#[test]
fn named_parameters_match_forward_mode_term_by_term() {
    let mut scene = small("scenes/sphere_floor.json", 24);
    let params: Vec<String> = [
        "ball.radius",
        "light.center.x",
        "ball.albedo.r",
        "ball.center.y",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let layout = GradientLayout::select(&mut scene, &params, &[]).unwrap();
    let options = DiffOptions {
        render: RenderOptions {
            spp: 4,
            seed: 7,
            ..RenderOptions::default()
        },
        boundary: BoundaryBudget {
            primary_spp: Some(2),
            secondary_spp: Some(4),
        },
        ..DiffOptions::default()
    };
    let g = adjoint(24, 24, 3);
    let forward = integrator::render_derivatives(&scene, params.len(), &options).unwrap();
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

#[test]
fn grid_values_match_a_forward_direction() {
    use implicit_psdr::scalar::GridValues;
    use std::sync::Arc;
    let mut scene = small("scenes/grid.json", 24);
    let node = "baked_blob.sdf.child".to_string();
    let params = vec!["ball.radius".to_string()];
    let options = DiffOptions {
        render: RenderOptions {
            spp: 4,
            seed: 5,
            ..RenderOptions::default()
        },
        boundary: BoundaryBudget {
            primary_spp: Some(2),
            secondary_spp: Some(4),
        },
        ..DiffOptions::default()
    };
    let g = adjoint(24, 24, 11);
    let mut reverse_scene = scene.clone();
    let layout =
        GradientLayout::select(&mut reverse_scene, &params, std::slice::from_ref(&node)).unwrap();
    let reverse = render_gradient(&reverse_scene, &layout, &g, &options).unwrap();
    let (block, first) = &layout.grids[0];
    let u = adjoint(block.len() as u32, 1, 99).rgb[..block.len()].to_vec();
    scene.select_parameters(&params).unwrap();
    scene
        .select_grids(&[(
            node.clone(),
            GridValues::Direction {
                slot: 1,
                u: Arc::new(u.clone()),
            },
        )])
        .unwrap();
    let forward = integrator::render_derivatives(&scene, 2, &options).unwrap();
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
