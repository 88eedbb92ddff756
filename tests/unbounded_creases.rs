//! The boundary terms along creases where two unbounded children of hard CSG cross (two planes), which
//! no box of the children holds: a wedge of two planes cut by a ball (the ball's box bounds the
//! planes' crease), a ridge of two planes crossing under the whole view (bounded only by the scene's
//! crease region, which the view's part of the line lies inside), and a plane cutting a sharp box. Each
//! against central finite differences with common random numbers ([`common::deriv::check_against_fd`]:
//! blurred relative L2, region sums, the interior alone failing). Bounds are twice the larger of two
//! seeds' errors (`PSDR_TEST_SEED` unset and `=1`), quoted next to each.

mod common;

use common::deriv::*;

/// A rectangle light above and to the right, and a dim sky: the two faces of each crease are lit
/// differently.
const LIGHTS: &str = r#"[
    {"name": "light", "type": "rectangle", "center": [2, 3, 2], "normal": [-0.5, -1, -0.5],
     "u": [1, 0, 0], "size": [1, 1], "radiance": [20, 20, 20]},
    {"name": "sky", "type": "constant", "radiance": [0.3, 0.3, 0.3]}
  ]"#;

const BUDGET: Budget = Budget {
    spp: 128,
    primary: 200_000,
    secondary: 100_000,
    fd_spp: 1024,
};

fn scene_with(camera: &str, sdf: &str) -> implicit_psdr::scene::Scene {
    scene_json(&format!(
        r#"{{
  "camera": {camera},
  "integrator": {{"type": "direct"}},
  "shapes": [{{"name": "solid", "sdf": {sdf}, "bsdf": {{"type": "diffuse", "albedo": [0.8, 0.6, 0.4]}}}}],
  "emitters": {LIGHTS}
}}"#
    ))
}

const CAMERA: &str = r#"{"origin": [0.6, 1.2, 3.2], "target": [0, 0, 0], "up": [0, 1, 0],
    "fov_y": 40.0, "width": 32, "height": 32, "filter": "tent"}"#;

/// A roof of two planes meeting along the z axis, cut by a ball of radius 0.8.
#[test]
fn wedge_cut_by_a_ball() {
    let scene = scene_with(
        CAMERA,
        r#"{"type": "intersection", "children": [
            {"name": "left", "type": "plane", "normal": [0.7071, 0.7071, 0], "offset": 0.2},
            {"name": "right", "type": "plane", "normal": [-0.7071, 0.7071, 0], "offset": 0.2},
            {"name": "ball", "type": "sphere", "center": [0, 0, 0], "radius": 0.8}]}"#,
    );
    assert!(scene.unsampled_creases().is_empty());
    check_against_fd(
        "wedge cut by a ball",
        &scene,
        &[
            Check {
                name: "left.offset",
                h: 0.02,
                // Seeds 0 and 1: L2 (0.125, 0.099), sums ≤ (0.119, 0.088); interior alone 0.59.
                // (At four times the budget: L2 0.061, sums ≤ 0.010.)
                l2: 0.25,
                sum: 0.24,
            },
            Check {
                name: "solid.translate.x",
                h: 0.02,
                // Seeds 0 and 1: L2 (0.079, 0.069), sums ≤ (0.032, 0.040); interior alone 0.48.
                l2: 0.16,
                sum: 0.08,
            },
        ],
        BUDGET,
        41,
    );
}

/// A ridge of two unbounded planes along z seen from above, the line leaving the image at both ends
/// well inside the scene's crease region.
#[test]
fn ridge_of_two_planes() {
    let camera = r#"{"origin": [0.4, 3.0, 1.2], "target": [0, 0, 0], "up": [0, 1, 0],
        "fov_y": 40.0, "width": 32, "height": 32, "filter": "tent"}"#;
    let scene = scene_with(
        camera,
        r#"{"type": "union", "children": [
            {"name": "left", "type": "plane", "normal": [0.4472, 0.8944, 0], "offset": 0.0},
            {"name": "right", "type": "plane", "normal": [-0.4472, 0.8944, 0], "offset": 0.0}]}"#,
    );
    let named = scene.unsampled_creases();
    assert!(
        named.len() == 1 && named[0].1.contains("sampled only within"),
        "{named:?}"
    );
    check_against_fd(
        "ridge of two planes",
        &scene,
        &[Check {
            name: "left.offset",
            h: 0.02,
            // Seeds 0 and 1: L2 (0.088, 0.092), sums ≤ (0.008, 0.047); interior alone 0.69.
            l2: 0.19,
            sum: 0.1,
        }],
        BUDGET,
        42,
    );
}

/// A sharp box with a corner cut off by a plane: its creases with three faces, which the box's
/// bounds hold.
#[test]
fn plane_cutting_a_box() {
    let scene = scene_with(
        CAMERA,
        r#"{"type": "intersection", "children": [
            {"type": "box", "center": [0, 0, 0], "half_size": [0.6, 0.5, 0.5], "rounding": 0},
            {"name": "cut", "type": "plane", "normal": [0.577, 0.577, 0.577], "offset": 0.6}]}"#,
    );
    assert!(scene.unsampled_creases().is_empty());
    check_against_fd(
        "plane cutting a box",
        &scene,
        &[Check {
            name: "cut.offset",
            h: 0.02,
            // Seeds 0 and 1: L2 (0.058, 0.062), sums ≤ (0.045, 0.044); interior alone 0.94.
            l2: 0.13,
            sum: 0.09,
        }],
        BUDGET,
        43,
    );
}
