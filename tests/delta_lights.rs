//! Point and directional (sun) lights: closed forms of their irradiance on a plane, derivatives of
//! their parameters and of shapes moving under them (the hard shadow edge, whose secondary term
//! [`implicit_psdr::integrator::boundary::delta_shadows`] is essential) against central finite
//! differences with common random numbers ([`common::deriv::check_against_fd`]), reverse mode against
//! forward mode, hard cases and bad input.

mod common;

use common::deriv::*;
use implicit_psdr::integrator::IntegratorKind;
use implicit_psdr::scene::Scene;

/// A ball over a floor slab (rounded box, 0.2 above it) lit by `light` (emitter JSON), seen at
/// `size × size`, with `integrator`.
fn ball_on_floor(size: u32, light: &str, integrator: &str) -> Scene {
    scene_json(&format!(
        r#"{{"camera": {{"origin": [0, 3.2, 3.6], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 45,
                "width": {size}, "height": {size}, "filter": "tent"}},
            "integrator": {integrator}, "spp": 1,
            "shapes": [
              {{"name": "ball", "sdf": {{"type": "sphere", "center": [0, 0.5, 0], "radius": 0.5}},
               "bsdf": {{"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}}}},
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
        spp: 16,
        primary: 40_000,
        secondary: 40_000,
        fd_spp: 64,
    }
}

#[test]
fn point_light_moving_ball_direct() {
    let scene = ball_on_floor(32, BULB, DIRECT);
    check_against_fd(
        "point_direct",
        &scene,
        &[
            Check { name: "ball.center.x", h: 0.02, l2: 0.1, sum: 0.05 },
            Check { name: "bulb.position.x", h: 0.02, l2: 0.1, sum: 0.05 },
            Check { name: "bulb.position.y", h: 0.02, l2: 0.1, sum: 0.05 },
        ],
        budget(),
        1,
    );
}

#[test]
fn sun_moving_ball_direct() {
    let scene = ball_on_floor(32, SUN, DIRECT);
    check_against_fd(
        "sun_direct",
        &scene,
        &[
            Check { name: "ball.center.x", h: 0.02, l2: 0.1, sum: 0.05 },
            Check { name: "sun.direction.x", h: 0.02, l2: 0.1, sum: 0.05 },
        ],
        budget(),
        2,
    );
}

#[test]
fn point_light_moving_ball_path() {
    let scene = ball_on_floor(32, BULB, PATH);
    check_against_fd(
        "point_path",
        &scene,
        &[
            Check { name: "ball.center.x", h: 0.02, l2: 0.1, sum: 0.05 },
            Check { name: "bulb.position.x", h: 0.02, l2: 0.1, sum: 0.05 },
        ],
        budget(),
        3,
    );
}

#[test]
fn sun_moving_ball_path() {
    let scene = ball_on_floor(32, SUN, PATH);
    check_against_fd(
        "sun_path",
        &scene,
        &[
            Check { name: "ball.center.x", h: 0.02, l2: 0.1, sum: 0.05 },
            Check { name: "sun.direction.z", h: 0.02, l2: 0.1, sum: 0.05 },
        ],
        budget(),
        4,
    );
}
