//! Velocity fields (docs/theory.md §8): a thin shape moved by its known motion (rigid for a
//! translation, radial for a torus's major radius) instead of along its normal gives the same
//! derivative with far less variance, because the normal field's area factor `∂πJ = κV` is
//! heavy-tailed where the curvature radius is far below a pixel.
//!
//! Measured on image sums (the derivative of the image's total, where the per-pixel noise averages out
//! and a heavy tail shows as seed-to-seed spread): the `auto` field (carried here) against finite
//! differences with common random numbers and against the normal field at the same budget.

mod common;

use common::deriv::{derivative_terms_with, fd, scene_json};
use implicit_psdr::integrator::VelocityField;
use implicit_psdr::scene::Scene;

/// A torus of major radius 1 and minor radius `minor`, tilted, under a sky and a rectangle light,
/// seen from 4 units on a 32×32 film (a pixel is about 0.09 units wide at the torus).
fn thin_torus(minor: f32) -> Scene {
    scene_json(&format!(
        r#"{{"camera": {{"origin": [0, 2, 3.5], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 40,
              "width": 32, "height": 32, "filter": "tent"}},
            "integrator": {{"type": "direct"}}, "spp": 64,
            "shapes": [{{"name": "ring",
              "sdf": {{"type": "torus", "center": [0, 0, 0], "axis": [0.2, 1, 0.1], "major_radius": 1,
                       "minor_radius": {minor}}},
              "bsdf": {{"type": "diffuse", "albedo": [0.2, 0.2, 0.2]}}}}],
            "emitters": [
              {{"name": "light", "type": "rectangle", "center": [1, 3, 1], "normal": [-0.3, -1, -0.3],
                "u": [1, 0, 0], "size": [1, 1], "radiance": [10, 10, 10]}},
              {{"name": "sky", "type": "constant", "radiance": [1, 1, 1]}}]}}"#
    ))
}

/// Image sums of the complete derivative of `name` at `spp` over `seeds`, with `field`.
fn sums(scene: &Scene, name: &str, field: VelocityField, spp: u32, seeds: &[u64]) -> Vec<f64> {
    let pixels = (scene.camera.width * scene.camera.height) as u64;
    let budget = (pixels * 8, pixels * 32);
    seeds
        .iter()
        .map(|&seed| {
            let t = derivative_terms_with(scene, &[name], spp, budget, seed, field);
            t[0].total().iter().sum()
        })
        .collect()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// Sample standard deviation.
fn spread(v: &[f64]) -> f64 {
    let m = mean(v);
    (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}

/// The image sum of central differences of `name` (step `h`) over `seeds` at `spp`: mean and
/// standard error.
fn fd_sum(scene: &Scene, name: &str, h: f32, spp: u32, seeds: &[u64]) -> (f64, f64) {
    let s: Vec<f64> = seeds
        .iter()
        .map(|&seed| fd(scene, name, h, spp, seed).iter().sum())
        .collect();
    (mean(&s), spread(&s) / (s.len() as f64).sqrt())
}

/// What [`measure`] found for one parameter.
struct Found {
    /// The auto field's image sums (one per seed) and the normal field's.
    auto: Vec<f64>,
    normal: Vec<f64>,
    /// Finite differences: mean image sum and its standard error.
    fd: (f64, f64),
}

/// The complete derivative's image sum of `name` on the thin torus of minor radius `minor` at 256 spp
/// over six seeds with the auto and the normal field, and finite differences of step `h` at 4096 spp
/// over `fd_seeds`.
fn measure(minor: f32, name: &str, h: f32, fd_seeds: &[u64]) -> Found {
    let scene = thin_torus(minor);
    let seeds: Vec<u64> = (1..=6).collect();
    let found = Found {
        auto: sums(&scene, name, VelocityField::Auto, 256, &seeds),
        normal: sums(&scene, name, VelocityField::Normal, 256, &seeds),
        fd: fd_sum(&scene, name, h, 4096, fd_seeds),
    };
    eprintln!(
        "minor {minor} {name}: fd {:.4} ± {:.4}; auto {:.4} ± {:.4} {:.3?}; normal {:.4} ± {:.4} {:.3?}; \
         spread normal / auto {:.1}",
        found.fd.0,
        found.fd.1,
        mean(&found.auto),
        spread(&found.auto),
        found.auto,
        mean(&found.normal),
        spread(&found.normal),
        found.normal,
        spread(&found.normal) / spread(&found.auto)
    );
    found
}

/// [`check_with`] against finite differences at step 0.05 over four seeds.
fn check(minor: f32, name: &str, gain: f64) {
    check_with(minor, name, gain, 0.05, &[11, 12, 13, 14]);
}

/// The auto field's mean image sum agrees with finite differences (step `h`, over `fd_seeds`) within
/// three standard errors of their difference, and its seed-to-seed spread is at least `gain` times
/// smaller than the normal field's.
fn check_with(minor: f32, name: &str, gain: f64, h: f32, fd_seeds: &[u64]) {
    let f = measure(minor, name, h, fd_seeds);
    let error = (spread(&f.auto).powi(2) / f.auto.len() as f64 + f.fd.1.powi(2)).sqrt();
    assert!(
        (mean(&f.auto) - f.fd.0).abs() < 3.0 * error,
        "minor {minor} {name}: auto {} vs fd {} (3σ = {})",
        mean(&f.auto),
        f.fd.0,
        3.0 * error
    );
    let ratio = spread(&f.normal) / spread(&f.auto);
    assert!(
        ratio >= gain,
        "minor {minor} {name}: spread ratio {ratio} < {gain}"
    );
}

// Measured (six seeds; fd at step 0.05, 4 × 4096 spp): minor radius 1e-3, major_radius: fd −3.37 ±
// 0.14, auto −3.65 (spread 0.53), normal 129 (spread 307): 576× smaller; translate.x, whose image sum
// is nearly 0, against finite differences at step 0.2 (two pixels; steps 0.2, 0.1 and 0.05 agree
// within their noise, and four seeds' spread at step 0.05 understated its standard error by half)
// over eight seeds: fd 0.088 ± 0.028, auto −0.02 (spread 0.18), normal −32 (spread 82): 470×.
#[test]
fn thin_torus_of_minor_radius_1e_3() {
    check(1e-3, "ring.major_radius", 100.0);
    let fd_seeds = [11, 12, 13, 14, 15, 16, 17, 18];
    check_with(1e-3, "ring.translate.x", 100.0, 0.2, &fd_seeds);
}

// Measured: minor radius 1e-2, major_radius: fd −35.9 ± 0.2, auto −32.9 (spread 5.9), normal −4.7
// (spread 64): 10.8×; translate.x: fd 1.15 ± 0.25, auto −3.1 (spread 4.5), normal −12 (spread 41):
// 9.1×. What is left of the auto field's spread is the primary term's (−8 to +5 per seed), which both
// fields share; six seeds estimate a spread to about ±30%, hence the bound of 5.
#[test]
fn thin_torus_of_minor_radius_1e_2() {
    check(1e-2, "ring.major_radius", 5.0);
    check(1e-2, "ring.translate.x", 5.0);
}

/// [`thin_torus`]'s scene with a ball of radius 0.8 and `albedo` in place of the torus (named `ring`).
fn ball(albedo: f32) -> Scene {
    let mut scene = thin_torus(0.1);
    scene.shapes[0] = scene_json(&format!(
        r#"{{"camera": {{"origin": [0, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 40,
              "width": 8, "height": 8}},
            "integrator": {{"type": "direct"}}, "spp": 1,
            "shapes": [{{"name": "ring", "sdf": {{"type": "sphere", "center": [0, 0, 0], "radius": 0.8}},
              "bsdf": {{"type": "diffuse", "albedo": [{albedo}, {albedo}, {albedo}]}}}}],
            "emitters": []}}"#
    ))
    .shapes[0]
        .clone();
    scene
}

/// A ball under the same lights, translated: its curvature radius is far above a pixel, so `auto` is
/// the normal field; its image sum agrees with finite differences. Measured: fd 4.80 ± 1.11 (4 × 4096
/// spp), auto 5.50 (spread 2.9 over six seeds); the carried (rigid) field 6.10 (spread 1.56): for a
/// ball most of the spread is the silhouette term's (2 to 11 per seed), which no field removes.
#[test]
fn translated_ball_agrees_with_fd() {
    let scene = ball(0.2);
    let seeds: Vec<u64> = (1..=6).collect();
    let auto = sums(&scene, "ring.center.x", VelocityField::Auto, 256, &seeds);
    let (reference, reference_error) =
        fd_sum(&scene, "ring.center.x", 0.05, 4096, &[11, 12, 13, 14]);
    let error = (spread(&auto).powi(2) / auto.len() as f64 + reference_error.powi(2)).sqrt();
    eprintln!(
        "ball center.x: auto {} ± {}, fd {reference} ± {reference_error}",
        mean(&auto),
        spread(&auto)
    );
    assert!(
        (mean(&auto) - reference).abs() < 3.0 * error,
        "auto {} vs fd {reference} (3σ = {})",
        mean(&auto),
        3.0 * error
    );
}

/// Shapes whose curvature radius is not below a pixel keep the normal field under `auto`: a ball's
/// derivative images are those of the normal field, bit for bit.
#[test]
fn auto_keeps_the_normal_field_for_a_ball() {
    let scene = ball(0.5);
    let auto = sums(&scene, "ring.center.x", VelocityField::Auto, 16, &[3]);
    let normal = sums(&scene, "ring.center.x", VelocityField::Normal, 16, &[3]);
    let carried = sums(&scene, "ring.center.x", VelocityField::Carried, 16, &[3]);
    assert_eq!(auto, normal);
    assert_ne!(auto, carried, "the carried field must change the estimate");
}

/// Two balls blended by a smooth union of radius `k` under a sky and a rectangle light (32×32).
fn blended_balls(k: f32) -> Scene {
    scene_json(&format!(
        r#"{{"camera": {{"origin": [0.3, 1.5, 4], "target": [0.4, 0, 0], "up": [0, 1, 0], "fov_y": 45,
              "width": 32, "height": 32, "filter": "tent"}},
            "integrator": {{"type": "direct"}}, "spp": 64,
            "shapes": [{{"name": "blob",
              "sdf": {{"type": "smooth_union", "k": {k}, "children": [
                {{"name": "a", "type": "sphere", "center": [0, 0, 0], "radius": 1}},
                {{"name": "b", "type": "sphere", "center": [1.2, 0.3, 0.2], "radius": 0.7}}]}},
              "bsdf": {{"type": "diffuse", "albedo": [0.6, 0.6, 0.6]}}}}],
            "emitters": [
              {{"name": "light", "type": "rectangle", "center": [1, 3, 2], "normal": [-0.3, -1, -0.6],
                "u": [1, 0, 0], "size": [1, 1], "radiance": [8, 8, 8]}},
              {{"name": "sky", "type": "constant", "radiance": [0.5, 0.5, 0.5]}}]}}"#
    ))
}

/// Blurred relative L2 of the complete derivative of `b.center.x` on [`blended_balls`] against finite
/// differences (step 0.01, 4096 spp), with `field` at 256 spp and the default boundary budgets.
fn blend_error(k: f32, field: VelocityField, seed: u64) -> f64 {
    let scene = blended_balls(k);
    let f = fd(&scene, "b.center.x", 0.01, 4096, 77);
    let pixels = 32 * 32;
    let budget = (pixels * 8, pixels * 32);
    let t = derivative_terms_with(&scene, &["b.center.x"], 256, budget, seed, field);
    common::deriv::errors(&format!("k {k} {field:?} seed {seed}"), &t[0], &f, 32, 32).l2
}

// Measured (seeds 1 and 2): auto 0.079/0.071, 0.079/0.068, 0.075/0.070, 0.078/0.069 for k = 1e-1 ..
// 1e-4 (at k = 1e-1 the blend is not far below the balls' radii and auto is the normal field); the
// normal field 0.079/0.071, 0.13/0.14, 0.24/0.32, 0.20/0.83: it grows as k shrinks.
#[test]
fn smooth_union_error_does_not_grow_as_k_shrinks() {
    const BOUND: f64 = 0.12;
    for k in [1e-1f32, 1e-2, 1e-3, 1e-4] {
        let e = blend_error(k, VelocityField::Auto, 1);
        assert!(e < BOUND, "k {k}: blurred rel L2 {e} ≥ {BOUND}");
    }
    // The normal field fails the same bound where the blend is far below a pixel.
    let e = blend_error(1e-3, VelocityField::Normal, 1);
    assert!(
        e > BOUND,
        "k 1e-3, normal field: {e} (the test cannot tell the fields apart)"
    );
}

/// The lights of the hard cases: a rectangle light above and a sky.
const HARD_CASE_LIGHTS: &str = r#"[
    {"name": "light", "type": "rectangle", "center": [1, 3, 2], "normal": [-0.3, -1, -0.6],
     "u": [1, 0, 0], "size": [1, 1], "radiance": [8, 8, 8]},
    {"name": "sky", "type": "constant", "radiance": [0.5, 0.5, 0.5]}]"#;

/// Hard cases of the crease-following field: children that barely overlap (their normals nearly
/// parallel along the crease), one ball almost inside the other, a blend seen edge-on, and a tiny blend
/// around the eye: every term finite (checked by `derivative_terms`).
#[test]
fn smooth_union_hard_cases_are_finite() {
    for (a, b, eye) in [
        (
            "[0, 0, 0], \"radius\": 1",
            "[1.699, 0, 0], \"radius\": 0.7",
            "[0.3, 1.5, 4]",
        ),
        (
            "[0, 0, 0], \"radius\": 1",
            "[0.29, 0.05, 0], \"radius\": 0.7",
            "[0.3, 1.5, 4]",
        ),
        (
            "[0, 0, 0], \"radius\": 1",
            "[1.2, 0, 0], \"radius\": 0.7",
            "[0.85, 0, 4]",
        ),
        (
            "[0, 0, 0], \"radius\": 1",
            "[1.2, 0, 0], \"radius\": 0.7",
            "[0.86, 0.6, 0.3]",
        ),
    ] {
        let scene = scene_json(&format!(
            r#"{{"camera": {{"origin": {eye}, "target": [0.4, 0, 0], "up": [0, 1, 0], "fov_y": 45,
                  "width": 16, "height": 16, "filter": "tent"}},
                "integrator": {{"type": "path", "max_depth": 3}}, "spp": 16,
                "shapes": [{{"name": "blob",
                  "sdf": {{"type": "smooth_union", "k": 1e-4, "children": [
                    {{"name": "a", "type": "sphere", "center": {a}}},
                    {{"name": "b", "type": "sphere", "center": {b}}}]}},
                  "bsdf": {{"type": "diffuse", "albedo": [0.6, 0.6, 0.6]}}}}],
                "emitters": {HARD_CASE_LIGHTS}}}"#
        ));
        for field in [VelocityField::Auto, VelocityField::Carried] {
            derivative_terms_with(
                &scene,
                &["b.center.x", "a.radius", "blob.translate.y"],
                16,
                (2048, 8192),
                5,
                field,
            );
        }
    }
}

/// `∫ ∂πJ dA` over the surface of shape 0 with the velocity field `field`, and the area itself,
/// estimated on `lines` area-sampling lines (a low-discrepancy sequence, the same for every scene).
fn area_and_its_derivative(scene: &Scene, lines: usize, field: VelocityField) -> (f64, f64) {
    use implicit_psdr::integrator::attach::SceneAttach;
    use implicit_psdr::integrator::surface_sampling::sample_surface;
    use implicit_psdr::scalar::Dual32;
    let attach = SceneAttach::new(scene, field);
    let shape = &scene.shapes[0];
    let mut hits = Vec::new();
    let (mut area, mut derivative) = (0.0f64, 0.0f64);
    // The R3 sequence (Roberts 2018): fractional parts of i·(1/g, 1/g², 1/g³), g³ = g + 1.
    let g = 1.220_744_084_605_759_5f64;
    let alpha = [1.0 / g, 1.0 / (g * g), 1.0 / (g * g * g)];
    for i in 0..lines {
        let u = alpha.map(|a| ((0.5 + a * i as f64) % 1.0) as f32);
        sample_surface(
            shape,
            &scene.trace,
            u[0],
            glam::Vec2::new(u[1], u[2]),
            &mut hits,
        )
        .unwrap();
        for h in &hits {
            area += 1.0 / h.pdf as f64;
            derivative += attach.shape_vertex::<Dual32>(0, h.p, h.n).j.eps as f64 / h.pdf as f64;
        }
    }
    (area / lines as f64, derivative / lines as f64)
}

/// Every valid field changes the surface's total area at the same rate: `∫ ∂πJ dA = dA/dπ`, whatever
/// its tangential part (the divergence theorem on a closed surface). Checked for the crease-following
/// field of a smooth union (k = 0.05, far below the balls' radii) and for the normal field, against a
/// central difference of the area (step 0.02). Measured: b.center.x 4.771 and 4.756 against 4.755,
/// a.radius 19.30 and 19.36 against 19.18, b.center.y 1.191 and 1.174 against 1.204; with the
/// weight's spatial gradient dropped from the crease field, 2.30, 22.9 and 0.57.
#[test]
fn smooth_union_field_changes_the_area_as_the_surface_does() {
    let lines = 400_000;
    for name in ["b.center.x", "a.radius", "b.center.y"] {
        let h = 2e-2;
        let base = blended_balls(0.05);
        let value = base.parameter(name).unwrap();
        let plus = base.with_parameter(name, value + h).unwrap();
        let minus = base.with_parameter(name, value - h).unwrap();
        let area = |s: &Scene| area_and_its_derivative(s, lines, VelocityField::default()).0;
        let fd = (area(&plus) - area(&minus)) / (2.0 * h as f64);
        for field in [VelocityField::Carried, VelocityField::Normal] {
            let plain = blended_balls(0.05);
            let scene = plain.select(&[name]).unwrap().apply(&plain).unwrap();
            let (_, d) = area_and_its_derivative(&scene, lines, field);
            eprintln!("{name} {field:?}: ∫∂J dA {d:.5}, fd {fd:.5}");
            assert!(
                (d - fd).abs() < 0.03 * fd.abs().max(1.0),
                "{name} {field:?}: {d} vs {fd}"
            );
        }
    }
}

/// Hard cases of carried motions: a torus of minor radius 1e-4 seen edge-on from its own plane, the eye
/// in its hole, a ring whose hole closes (major radius just above the minor), the eye inside a thin
/// tube; every field forced: every term finite (checked by `derivative_terms`).
#[test]
fn carried_hard_cases_are_finite() {
    for (eye, major, minor) in [
        ("[0, 0, 4]", 1.0, 1e-4),
        ("[0, 0.01, 4]", 1.0, 1e-2),
        ("[0.1, 0.05, 0]", 1.0, 1e-3),
        ("[0, 2, 3]", 0.3001, 0.3),
        ("[1, 0, 0]", 1.0, 0.05),
    ] {
        let scene = scene_json(&format!(
            r#"{{"camera": {{"origin": {eye}, "target": [0, 0, 0.5], "up": [0, 1, 0], "fov_y": 60,
                  "width": 16, "height": 16, "filter": "tent"}},
                "integrator": {{"type": "path", "max_depth": 3}}, "spp": 16,
                "shapes": [
                  {{"name": "ring", "sdf": {{"type": "torus", "center": [0, 0, 0], "axis": [0, 1, 0],
                    "major_radius": {major}, "minor_radius": {minor}}},
                    "bsdf": {{"type": "diffuse", "albedo": [0.6, 0.6, 0.6]}}}},
                  {{"name": "floor", "sdf": {{"type": "plane", "normal": [0, 1, 0], "offset": -1}},
                    "bsdf": {{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}}}],
                "emitters": {HARD_CASE_LIGHTS}}}"#
        ));
        for field in [VelocityField::Auto, VelocityField::Carried] {
            derivative_terms_with(
                &scene,
                &[
                    "ring.major_radius",
                    "ring.translate.x",
                    "ring.minor_radius",
                    "floor.offset",
                ],
                16,
                (2048, 8192),
                5,
                field,
            );
        }
    }
}
