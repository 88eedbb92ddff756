//! The hard shadow edges that sharp occluders' crease edges cast from point and directional lights
//! ([`implicit_psdr::integrator::boundary::delta_creases`]): a sharp box (axis-aligned and rotated) and
//! a hard CSG intersection moving under a point light and under the sun, their derivatives against
//! central finite differences with common random numbers ([`common::deriv::check_against_fd`]),
//! direct and path; reverse mode against forward mode; hard cases finite.

mod common;

use common::deriv::*;
use implicit_psdr::scene::Scene;

/// An axis-aligned sharp box hovering 0.2 over the floor slab.
const BOX: &str =
    r#"{"type": "box", "center": [0, 0.35, 0], "half_size": [0.35, 0.35, 0.4], "rounding": 0}"#;
/// The same box turned about a slanted axis.
const ROTATED: &str = r#"{"type": "transform", "translate": [0, 0.5, 0],
    "rotate": {"axis": [0.3, 1, 0.2], "angle": 35},
    "child": {"type": "box", "center": [0, 0, 0], "half_size": [0.35, 0.3, 0.4], "rounding": 0}}"#;
/// A cube cut by a ball (hard intersection): the crossing creases, the cube's remaining edges and the
/// ball's silhouette all cast the shadow.
const CUT: &str = r#"{"type": "intersection", "children": [
    {"type": "box", "center": [0, 0.45, 0], "half_size": [0.4, 0.4, 0.4], "rounding": 0},
    {"type": "sphere", "center": [0, 0.45, 0], "radius": 0.62}]}"#;

/// `sdf` (the occluder, named `crate`) over a floor slab (rounded box, no crease) lit by `light`
/// (emitter JSON), seen at `size × size`, with `integrator`.
fn crate_on_floor(size: u32, sdf: &str, light: &str, integrator: &str) -> Scene {
    scene_json(&format!(
        r#"{{"camera": {{"origin": [0, 3.2, 3.6], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 45,
                "width": {size}, "height": {size}, "filter": "tent"}},
            "integrator": {integrator}, "spp": 1,
            "shapes": [
              {{"name": "crate", "sdf": {sdf}, "bsdf": {{"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}}}},
              {{"name": "floor", "sdf": {{"type": "box", "center": [0, -0.5, 0], "half_size": [4, 0.3, 4], "rounding": 0.1}},
               "bsdf": {{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}}}],
            "emitters": [{light}]}}"#
    ))
}

const BULB: &str =
    r#"{"name": "bulb", "type": "point", "position": [0.8, 2.2, 0.6], "intensity": [8, 8, 8]}"#;
const SUN: &str = r#"{"name": "sun", "type": "directional", "direction": [-0.5, -1, -0.3], "irradiance": [2, 2, 2]}"#;
const DIRECT: &str = r#"{"type": "direct"}"#;
const PATH: &str = r#"{"type": "path", "max_depth": 2}"#;

fn budget() -> Budget {
    Budget {
        spp: 32,
        primary: 60_000,
        secondary: 120_000,
        fd_spp: 1024,
    }
}

/// [`check_against_fd`] on `sdf` over the floor under `light`, then for each of the parameters that
/// move the occluder (and so its hard shadow) the secondary term is essential: the interior and
/// primary terms alone miss the bound by at least twice. Under delta lights alone the only secondary
/// samples that reach a light are the shadow edges', so this is the crease shadow term's test.
fn moving_under(
    label: &str,
    sdf: &str,
    light: &str,
    integrator: &str,
    checks: &[Check],
    seed: u64,
) {
    let scene = crate_on_floor(32, sdf, light, integrator);
    let measured = check_against_fd(label, &scene, checks, budget(), seed);
    for (c, m) in checks.iter().zip(&measured) {
        if !c.name.starts_with("crate.") {
            continue;
        }
        let without: Vec<f64> = (m.terms.interior.iter().zip(&m.terms.primary))
            .map(|(i, p)| i + p)
            .collect();
        let l2 = blurred_rel_l2(&without, &m.fd, 32, 32, None);
        println!("{label} {}: without the secondary term {l2:.4}", c.name);
        assert!(
            l2 > 2.0 * c.l2,
            "{label} {}: interior + primary alone ({l2}) should miss the bound {} by twice",
            c.name,
            c.l2
        );
    }
}

/// A check of parameter `name` with FD step 0.02, bounds `l2` and `sum`.
///
/// The bounds below come from two runs with independent seeds (`PSDR_TEST_SEED` unset and `=1`),
/// quoted as `(seed 0, seed 1)`, with the finite differences' own noise (`PSDR_CHECK_H=1`: FD against
/// FD with another seed, and at `h/2` against `h`), which dominates: at four times every budget the
/// box's and the hard CSG's errors fall to 0.01–0.02 (point light) and 0.04 (sun, where FD against FD
/// is 0.06).
const fn check(name: &'static str, l2: f64, sum: f64) -> Check {
    Check {
        name,
        h: 0.02,
        l2,
        sum,
    }
}

#[test]
fn point_light_and_moving_box_direct() {
    moving_under(
        "box_point_direct",
        BOX,
        BULB,
        DIRECT,
        &[
            // L2 (0.035, 0.053), sums ≤ 0.020, FD vs FD 0.035–0.039; without the secondary term 0.30.
            check("crate.center.x", 0.08, 0.05),
            // L2 (0.040, 0.049), sums ≤ 0.003, FD vs FD 0.043–0.045; without the secondary term 0.21.
            check("crate.half_size.y", 0.08, 0.05),
            // L2 (0.018, 0.016), sums ≤ 0.005, FD vs FD 0.010–0.013.
            check("bulb.position.x", 0.04, 0.05),
        ],
        1,
    );
}

#[test]
fn sun_and_moving_box_direct() {
    moving_under(
        "box_sun_direct",
        BOX,
        SUN,
        DIRECT,
        &[
            // L2 (0.039, 0.063), sums ≤ 0.052, FD vs FD 0.059–0.093; without the secondary term 0.73.
            check("crate.center.z", 0.1, 0.08),
            // L2 (0.014, 0.019), sums ≤ 0.004, FD vs FD 0.028.
            check("sun.direction.x", 0.04, 0.05),
        ],
        2,
    );
}

#[test]
fn point_light_and_rotated_box_direct() {
    moving_under(
        "rotated_point_direct",
        ROTATED,
        BULB,
        DIRECT,
        &[
            // L2 (0.047, 0.034), sums ≤ 0.013, FD vs FD 0.044–0.058; without the secondary term 0.29.
            check("crate.sdf.translate.x", 0.08, 0.05),
        ],
        3,
    );
}

#[test]
fn sun_and_rotated_box_path() {
    moving_under(
        "rotated_sun_path",
        ROTATED,
        SUN,
        PATH,
        // L2 (0.067, 0.067), sums ≤ 0.055, FD vs FD 0.054–0.059; without the secondary term 0.75.
        &[check("crate.sdf.translate.z", 0.12, 0.08)],
        4,
    );
}

#[test]
fn point_light_and_hard_csg_path() {
    moving_under(
        "csg_point_path",
        CUT,
        BULB,
        PATH,
        // L2 (0.037, 0.034), sums ≤ 0.015, FD vs FD 0.028–0.046; without the secondary term 0.25.
        &[check("crate.translate.x", 0.07, 0.05)],
        5,
    );
}

#[test]
fn sun_and_hard_csg_direct() {
    moving_under(
        "csg_sun_direct",
        CUT,
        SUN,
        DIRECT,
        // L2 (0.042, 0.065), sums ≤ 0.038, FD vs FD 0.038–0.049; without the secondary term 0.77.
        &[check("crate.translate.z", 0.1, 0.06)],
        6,
    );
}

/// Reverse mode equals the forward mode's contraction with an adjoint image, term by term, for the
/// lights' parameters and the sharp occluders moving under them (direct and path); the crease shadow
/// edges' secondary term does not vanish.
#[test]
fn reverse_mode_equals_forward_mode() {
    use implicit_psdr::integrator::{self, GradientLayout, render_gradient};
    let two_lights = format!("{BULB}, {SUN}");
    for (sdf, shape_param) in [
        (BOX, "crate.center.x"),
        (ROTATED, "crate.sdf.translate.x"),
        (CUT, "crate.translate.x"),
    ] {
        for integrator in [DIRECT, PATH] {
            let scene = crate_on_floor(16, sdf, &two_lights, integrator);
            let params: Vec<String> = [shape_param, "bulb.position.y", "sun.direction.x"]
                .iter()
                .map(|s| s.to_string())
                .collect();
            let layout = GradientLayout::select(&scene, &params, &[]).unwrap();
            let mut options = diff_options(4, 7);
            options.boundary.primary_spp = Some(2.0);
            options.boundary.secondary_spp = Some(8.0);
            let mut adjoint = implicit_psdr::film::Image::new(16, 16);
            for (i, v) in adjoint.rgb.iter_mut().enumerate() {
                *v = ((i * 7919) % 13) as f32 / 6.0 - 1.0;
            }
            let selection = scene.select(&params).unwrap();
            let forward = integrator::render_derivatives(&scene, &selection, &options).unwrap();
            let reverse = render_gradient(&scene, &layout, &adjoint, &options).unwrap();
            let dot = |a: &implicit_psdr::film::Image| -> f64 {
                (a.rgb.iter().zip(&adjoint.rgb))
                    .map(|(x, y)| *x as f64 * *y as f64)
                    .sum()
            };
            for (k, name) in params.iter().enumerate() {
                for (term, f, r) in [
                    ("interior", &forward.interior, &reverse.interior),
                    ("primary", &forward.primary, &reverse.primary),
                    ("secondary", &forward.secondary, &reverse.secondary),
                ] {
                    let (want, got) = (dot(&f[k]), r[k]);
                    println!("{integrator} {name} {term}: forward {want:.6e} reverse {got:.6e}");
                    assert!(
                        (got - want).abs() <= 1e-4 * want.abs().max(1e-3),
                        "{integrator} {name} {term}: reverse {got} vs forward {want}"
                    );
                }
            }
            assert!(
                dot(&forward.secondary[0]).abs() > 1e-2,
                "{shape_param} {integrator}: no shadow-edge term"
            );
        }
    }
}

/// Hard cases are finite in every term (direct and path): a point light on the box's top face, on
/// its edge, at its corner and inside it; the sun grazing the box's top face and along its vertical
/// edges.
#[test]
fn hard_cases_are_finite() {
    let cases = [
        r#"{"name": "bulb", "type": "point", "position": [0.1, 0.7, 0.1], "intensity": [8, 8, 8]}"#,
        r#"{"name": "bulb", "type": "point", "position": [0.35, 0.7, 0], "intensity": [8, 8, 8]}"#,
        r#"{"name": "bulb", "type": "point", "position": [0.35, 0.7, 0.4], "intensity": [8, 8, 8]}"#,
        r#"{"name": "bulb", "type": "point", "position": [0.1, 0.3, 0.1], "intensity": [8, 8, 8]}"#,
        r#"{"name": "sun", "type": "directional", "direction": [1, 0, 0.2], "irradiance": [2, 2, 2]}"#,
        r#"{"name": "sun", "type": "directional", "direction": [0, -1, 0], "irradiance": [2, 2, 2]}"#,
    ];
    for integrator in [DIRECT, PATH] {
        for light in cases {
            let scene = crate_on_floor(16, BOX, light, integrator);
            let names: &[&str] = if light.contains("point") {
                &[
                    "crate.center.x",
                    "crate.half_size.y",
                    "bulb.position.x",
                    "bulb.position.y",
                ]
            } else {
                &[
                    "crate.center.x",
                    "crate.half_size.y",
                    "sun.direction.x",
                    "sun.direction.z",
                ]
            };
            // derivative_terms asserts that every term of every pixel is finite.
            let t = derivative_terms(&scene, names, 4, 4_000, 8_000, 11);
            assert!(t.iter().all(|t| t.total().iter().all(|v| v.is_finite())));
        }
    }
}
