//! The primary boundary term along crease edges (sharp boxes and cylinders): the complete derivative
//! against central finite differences with common random numbers ([`common::deriv::check_against_fd`]:
//! blurred relative L2, region sums, the primary term zero off the edge ring, the interior alone
//! failing). Bounds are twice the larger of two seeds' errors (`PSDR_TEST_SEED` unset and `=1`), quoted
//! next to each; at 8× the budget the errors fall to 0.03–0.06, the finite differences' own noise.

mod common;

use common::deriv::*;

/// A sharp box, turned so that three faces show, under a rectangle light and a dim sky: its edges
/// make both the silhouette (one face turned away) and the visible creases between lit faces.
fn sharp_box_scene(integrator: &str) -> implicit_psdr::scene::Scene {
    scene_json(&format!(
        r#"{{
  "camera": {{"origin": [0, 1.6, 4], "target": [0, 0, 0], "up": [0, 1, 0],
             "fov_y": 35.0, "width": 32, "height": 32, "filter": "tent"}},
  "integrator": {integrator},
  "shapes": [
    {{"name": "block",
     "sdf": {{"type": "transform", "translate": [0.1, 0, 0],
             "rotate": {{"axis": [0.2, 1, 0.1], "angle": 30}}, "scale": 1.0,
             "child": {{"type": "box", "center": [0, 0, 0], "half_size": [0.7, 0.5, 0.6], "rounding": 0}}}},
     "bsdf": {{"type": "diffuse", "albedo": [0.8, 0.6, 0.4]}}}}
  ],
  "emitters": [
    {{"name": "light", "type": "rectangle", "center": [2, 3, 2], "normal": [-0.5, -1, -0.5],
     "u": [1, 0, 0], "size": [1, 1], "radiance": [20, 20, 20]}},
    {{"name": "sky", "type": "constant", "radiance": [0.3, 0.3, 0.3]}}
  ]
}}"#
    ))
}

#[test]
fn sharp_box_direct() {
    let scene = sharp_box_scene(r#"{"type": "direct"}"#);
    let budget = Budget {
        spp: 128,
        primary: 200_000,
        secondary: 100_000,
        fd_spp: 1024,
    };
    check_against_fd(
        "sharp box (direct)",
        &scene,
        &[
            Check {
                name: "block.sdf.translate.x",
                h: 0.02,
                // Seeds 0 and 1: L2 (0.055, 0.047), sums ≤ (0.034, 0.016); interior alone 0.55.
                l2: 0.11,
                sum: 0.07,
            },
            Check {
                name: "block.sdf.child.half_size.y",
                h: 0.02,
                // Seeds 0 and 1: L2 (0.086, 0.137), sums ≤ (0.068, 0.024); interior alone 0.57.
                l2: 0.27,
                sum: 0.14,
            },
            Check {
                name: "block.sdf.angle",
                h: 1.0,
                // Seeds 0 and 1: L2 (0.074, 0.088), sums ≤ (0.023, 0.054); interior alone 0.52.
                l2: 0.18,
                sum: 0.11,
            },
        ],
        budget,
        11,
    );
}

/// A sharp cylinder, tilted towards the camera so both rims and a cap show, on the `path` integrator.
fn sharp_cylinder_scene() -> implicit_psdr::scene::Scene {
    scene_json(
        r#"{
  "camera": {"origin": [0, 1.2, 4], "target": [0, 0, 0], "up": [0, 1, 0],
             "fov_y": 35.0, "width": 32, "height": 32, "filter": "tent"},
  "integrator": {"type": "path", "max_depth": 2},
  "shapes": [
    {"name": "can",
     "sdf": {"type": "cylinder", "center": [0, 0, 0], "axis": [0.3, 1, 0.2],
             "radius": 0.6, "half_height": 0.7, "rounding": 0},
     "bsdf": {"type": "diffuse", "albedo": [0.4, 0.7, 0.8]}}
  ],
  "emitters": [
    {"name": "light", "type": "rectangle", "center": [-2, 3, 2], "normal": [0.5, -1, -0.5],
     "u": [1, 0, 0], "size": [1, 1], "radiance": [20, 20, 20]},
    {"name": "sky", "type": "constant", "radiance": [0.3, 0.3, 0.3]}
  ]
}"#,
    )
}

#[test]
fn sharp_cylinder_path() {
    let scene = sharp_cylinder_scene();
    let budget = Budget {
        spp: 128,
        primary: 200_000,
        secondary: 100_000,
        fd_spp: 1024,
    };
    check_against_fd(
        "sharp cylinder (path)",
        &scene,
        &[
            Check {
                name: "can.radius",
                h: 0.02,
                // Seeds 0 and 1: L2 (0.075, 0.083), sums ≤ (0.029, 0.058); interior alone 0.48.
                l2: 0.17,
                sum: 0.12,
            },
            Check {
                name: "can.half_height",
                h: 0.02,
                // Seeds 0 and 1: L2 (0.094, 0.100), sums ≤ (0.051, 0.040); interior alone 0.63.
                l2: 0.2,
                sum: 0.1,
            },
            Check {
                name: "can.translate.y",
                h: 0.02,
                // Seeds 0 and 1: L2 (0.080, 0.083), sums ≤ (0.030, 0.027); interior alone 0.57.
                l2: 0.17,
                sum: 0.06,
            },
        ],
        budget,
        12,
    );
}
