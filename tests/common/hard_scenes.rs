//! The hard configurations of the derivative, one `direct` scene each at `size × size` pixels (tent
//! filter): `tests/hard_cases.rs` checks the complete derivative on them against finite differences,
//! `tests/gradient.rs` checks that reverse mode's gradient stays finite on some of them.

use super::deriv::{json_point, scene_json};
use implicit_psdr::scene::Scene;

/// A `direct` scene of `size × size` pixels (tent filter) from JSON fragments: the camera's `origin`,
/// `target` and `fov_y`, the shapes and the emitters.
fn scene(size: u32, camera: &str, shapes: &str, emitters: &str) -> Scene {
    scene_json(&format!(
        r#"{{"camera": {{{camera}, "up": [0, 1, 0], "width": {size}, "height": {size}, "filter": "tent"}},
            "integrator": {{"type": "direct"}}, "shapes": [{shapes}], "emitters": [{emitters}]}}"#
    ))
}

const LIGHT: &str = r#"{"name": "light", "type": "rectangle", "center": [1.5, 4, 1], "normal": [0, -1, 0],
    "u": [1, 0, 0], "size": [1, 1], "radiance": [30, 30, 30]}"#;

const SKY: &str = r#"{"name": "sky", "type": "constant", "radiance": [0.3, 0.3, 0.3]}"#;

/// A shape's `"bsdf"` member: diffuse, grey albedo `a`.
pub fn diffuse(a: f32) -> String {
    format!(r#""bsdf": {{"type": "diffuse", "albedo": [{a}, {a}, {a}]}}"#)
}

/// A finite floor slab (top at `y = 0`, slightly rounded so it has no crease). Not an infinite plane:
/// under an environment, rays leaving the floor at shallow angles march along an unbounded plane for
/// hundreds of steps (measured: a 32×32 image at 1024 spp, 12.4 s with a plane and a sky, 1.6 s with the
/// plane alone, 0.6 s with this slab).
fn slab() -> String {
    format!(
        r#"{{"name": "floor", "sdf": {{"type": "box", "center": [0, -0.1, 0], "half_size": [2.5, 0.1, 2.5],
            "rounding": 0.02}}, {}}}"#,
        diffuse(0.5)
    )
}

/// A torus seen nearly edge-on (its axis tilted 8° from the image plane): the silhouette's ends are
/// cusps where its tangent runs almost along the view ray (`|P'T| → 0`).
pub fn grazing_silhouette(size: u32) -> Scene {
    scene(
        size,
        r#""origin": [0, 0.3, 3], "target": [0, 0, 0], "fov_y": 40"#,
        &format!(
            r#"{{"name": "donut", "sdf": {{"type": "torus", "center": [0, 0, 0], "axis": [0, 1, -0.14],
                "major_radius": 0.7, "minor_radius": 0.2}}, {}}}"#,
            diffuse(0.7)
        ),
        &format!("{LIGHT}, {SKY}"),
    )
}

/// A ball seen by a camera almost level with the floor: the floor and the ball's shadow on it are seen
/// at a grazing angle (3–7°: the floor's film Jacobian is small, its pixels cover long strips).
pub fn shadow_on_grazing_surface(size: u32) -> Scene {
    scene(
        size,
        r#""origin": [0, 0.35, 5], "target": [0, 0.2, 0], "fov_y": 35"#,
        &format!(
            r#"{}, {{"name": "ball", "sdf": {{"type": "sphere", "center": [0, 0.6, 0], "radius": 0.4}}, {}}}"#,
            slab(),
            diffuse(0.7)
        ),
        LIGHT,
    )
}

/// A large box with little rounding above the floor: its flat faces (κ = 0: every tangent line is
/// rejected) are seen and cast the shadow; only the thin rounded edges are silhouettes.
pub fn flat_faces(size: u32) -> Scene {
    scene(
        size,
        r#""origin": [0, 3, 4], "target": [0, 0.3, 0], "fov_y": 45"#,
        &format!(
            r#"{}, {{"name": "slab", "sdf": {{"type": "box", "center": [0, 0.6, 0], "half_size": [0.8, 0.2, 0.6],
                "rounding": 0.05}}, {}}}"#,
            slab(),
            diffuse(0.7)
        ),
        LIGHT,
    )
}

/// Concave tangent directions: a torus lying on its side above the floor, the light shining through its
/// hole (its inner side is saddle-shaped), and a smooth union of two spheres (a saddle at the neck).
pub fn concave_tangent_directions(size: u32) -> Scene {
    scene(
        size,
        r#""origin": [0, 3.2, 3], "target": [0, 0.3, 0], "fov_y": 45"#,
        &format!(
            r#"{}, {{"name": "donut", "sdf": {{"type": "torus", "center": [-0.6, 0.5, 0], "axis": [0, 1, 0],
                "major_radius": 0.5, "minor_radius": 0.15}}, {}}},
               {{"name": "blob", "sdf": {{"type": "smooth_union", "k": 0.3, "children": [
                   {{"type": "sphere", "center": [0.7, 0.4, 0], "radius": 0.3}},
                   {{"type": "sphere", "center": [0.7, 0.95, 0], "radius": 0.25}}]}}, {}}}"#,
            slab(),
            diffuse(0.7),
            diffuse(0.7)
        ),
        LIGHT,
    )
}

/// Two silhouettes on one camera ray: a far sphere partly behind a near one, its image circle centred on
/// the near one's, so that the two circles cross; at each crossing one line of sight grazes both
/// spheres (the background of the near silhouette jumps there from the far sphere to the sky).
pub fn two_silhouettes_on_a_camera_ray(size: u32) -> Scene {
    // The far centre's direction is offset by the near sphere's angular radius.
    let offset = (0.2f32 / 3.0).asin();
    let (x, z) = (6.0 * offset.sin(), 3.0 - 6.0 * offset.cos());
    scene(
        size,
        r#""origin": [0, 0, 3], "target": [0, 0, 0], "fov_y": 20"#,
        &format!(
            r#"{{"name": "near", "sdf": {{"type": "sphere", "center": [0, 0, 0], "radius": 0.2}}, {}}},
               {{"name": "far", "sdf": {{"type": "sphere", "center": [{x}, 0, {z}], "radius": 0.5}}, {}}}"#,
            diffuse(0.8),
            diffuse(0.3)
        ),
        &format!("{LIGHT}, {SKY}"),
    )
}

/// Two spheres whose shadow boundaries coincide: on one vertical line under a small light, radii
/// proportional to the distance from it, so one tangent line from the floor touches both.
pub fn two_silhouettes_on_a_light_ray(size: u32) -> Scene {
    scene(
        size,
        r#""origin": [0, 3, 3], "target": [0, 0.5, 0], "fov_y": 45"#,
        &format!(
            r#"{}, {{"name": "upper", "sdf": {{"type": "sphere", "center": [0, 2.5, 0], "radius": 0.15}}, {}}},
               {{"name": "lower", "sdf": {{"type": "sphere", "center": [0, 1.5, 0], "radius": 0.25}}, {}}}"#,
            slab(),
            diffuse(0.7),
            diffuse(0.7)
        ),
        r#"{"name": "light", "type": "rectangle", "center": [0, 4, 0], "normal": [0, -1, 0],
            "u": [1, 0, 0], "size": [0.2, 0.2], "radiance": [300, 300, 300]}"#,
    )
}

/// A thin rod (a capsule 0.03 thick, about one pixel wide at 32 px) above the floor, and its thin
/// shadow.
pub fn thin_feature(size: u32) -> Scene {
    scene(
        size,
        r#""origin": [0, 3, 3], "target": [0, 0.3, 0], "fov_y": 45"#,
        &format!(
            r#"{}, {{"name": "rod", "sdf": {{"type": "capsule", "a": [-0.9, 0.6, 0.3], "b": [0.9, 0.7, -0.3],
                "radius": 0.015}}, {}}}"#,
            slab(),
            diffuse(0.9)
        ),
        &format!("{LIGHT}, {SKY}"),
    )
}

/// A ball under two pixels across at 24 px (radius 0.9 px) above the floor, and its shadow.
pub fn tiny_object(size: u32) -> Scene {
    scene(
        size,
        r#""origin": [0, 3, 3], "target": [0, 0.3, 0], "fov_y": 45"#,
        &format!(
            r#"{}, {{"name": "dot", "sdf": {{"type": "sphere", "center": [0.2, 0.5, 0], "radius": 0.1}}, {}}}"#,
            slab(),
            diffuse(0.9)
        ),
        &format!("{LIGHT}, {SKY}"),
    )
}

/// A ball cut by the image's left border, its shadow too.
pub fn partly_outside_the_image(size: u32) -> Scene {
    scene(
        size,
        r#""origin": [0, 3, 3], "target": [0, 0.3, 0], "fov_y": 45"#,
        &format!(
            r#"{}, {{"name": "ball", "sdf": {{"type": "sphere", "center": [-1.4, 0.6, 0], "radius": 0.5}}, {}}}"#,
            slab(),
            diffuse(0.7)
        ),
        r#"{"name": "light", "type": "rectangle", "center": [0, 4, 1], "normal": [0, -1, 0],
            "u": [1, 0, 0], "size": [1, 1], "radiance": [30, 30, 30]}"#,
    )
}

/// The camera 0.1 from a ball's surface, looking past it at the floor: the silhouette is close and
/// large, seen through a wide perspective.
pub fn camera_close_to_a_surface(size: u32) -> Scene {
    scene(
        size,
        r#""origin": [0.6, 1.1, 1.5], "target": [0, 0, 0], "fov_y": 60"#,
        &format!(
            r#"{}, {{"name": "ball", "sdf": {{"type": "sphere", "center": [0.6, 1.1, 0.7], "radius": 0.7}}, {}}}"#,
            slab(),
            diffuse(0.7)
        ),
        &format!("{LIGHT}, {SKY}"),
    )
}

/// A sphere light touching the ball that shadows the floor: the shadow segments `x_B x_D` become
/// arbitrarily short near the contact, and the geometry term `G ∝ 1/d²` is singular there.
pub fn light_touching_an_occluder(size: u32) -> Scene {
    scene(
        size,
        r#""origin": [0, 3, 3.5], "target": [0, 0.5, 0], "fov_y": 45"#,
        &format!(
            r#"{}, {{"name": "ball", "sdf": {{"type": "sphere", "center": [0, 0.8, 0], "radius": 0.5}}, {}}}"#,
            slab(),
            diffuse(0.7)
        ),
        r#"{"name": "light", "type": "sphere", "center": [0.7, 0.8, 0], "radius": 0.2, "radiance": [20, 20, 20]}"#,
    )
}

/// The ground under [`ball_over_ground`].
#[derive(Copy, Clone, Debug)]
pub enum Ground {
    /// A box 10,000 units wide (half size 5,000 × 0.5 × 5,000, its top at `y = 0`, edges rounded by
    /// 0.02): the scene's extent is that of the floor, the ball's a ten-thousandth of it.
    Huge,
    /// The unbounded plane `y = 0`.
    Plane,
}

/// A ball resting 0.2 above a ground under the rectangle light and the sky, the whole scene moved by
/// `offset`: tolerances must follow the float resolution where the rays are, not the floor's size
/// (a huge box, a plane) nor the distance to the origin, and rays skimming the ground towards the
/// horizon must finish.
pub fn ball_over_ground(size: u32, ground: Ground, offset: [f32; 3]) -> Scene {
    let at = |p: [f32; 3]| json_point(p, offset);
    let ground = match ground {
        Ground::Huge => format!(
            r#"{{"type": "box", "center": {}, "half_size": [5000, 0.5, 5000], "rounding": 0.02}}"#,
            at([0.0, -0.5, 0.0])
        ),
        Ground::Plane => format!(
            r#"{{"type": "plane", "normal": [0, 1, 0], "offset": {}}}"#,
            offset[1]
        ),
    };
    scene(
        size,
        &format!(
            r#""origin": {}, "target": {}, "fov_y": 40"#,
            at([0.0, 1.2, 3.5]),
            at([0.0, 0.4, 0.0])
        ),
        &format!(
            r#"{{"name": "floor", "sdf": {ground}, {}}},
               {{"name": "ball", "sdf": {{"type": "sphere", "center": {}, "radius": 0.4}}, {}}}"#,
            diffuse(0.5),
            at([0.0, 0.6, 0.0]),
            diffuse(0.7)
        ),
        &format!(
            r#"{{"name": "light", "type": "rectangle", "center": {}, "normal": [0, -1, 0],
                "u": [1, 0, 0], "size": [1, 1], "radiance": [30, 30, 30]}}, {SKY}"#,
            at([1.5, 4.0, 1.0])
        ),
    )
}
