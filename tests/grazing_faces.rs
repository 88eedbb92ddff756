//! A face of a sharp box seen nearly edge-on, from in front of its plane (the face visible as a sliver)
//! and from behind it (the face turned away, its edges a silhouette), at 10°, 3°, 1° and 0.3°: the
//! complete derivative with respect to every parameter of the box and of the transform that turns and
//! places it.
//!
//! A face seen at 1° projects to a sliver a few hundredths of a pixel wide. The primary term along its
//! edges used to take each side's radiance from a camera ray passing the edge's image at a fiftieth of
//! a pixel: on the sliver's side that ray crossed it and saw what lies beyond (another face, the
//! background), on both edges bounding the sliver, which counted the jump between those twice (the
//! derivative's sum 2.3 times the finite differences' at 0.2°). Each side now looks at its own face
//! when the eye sees it (docs/theory.md §7.2).
//!
//! The reference is a closed form: in a constant environment a convex diffuse box has radiance `ρL` on
//! every face, so the image is `ρL` inside the convex hull of the projected corners and `L` outside,
//! and its derivative is `∮ w_j (ρ − 1) L v dℓ` along the hull, `v` the outward normal velocity of the
//! hull's edges, from the corners' positions as functions of the eleven parameters (no rendering, no
//! finite-difference noise: at 0.3° a finite difference must step by less than the grazing angle, and
//! two seeds of one at 20×20 pixels and 192 spp differed by 0.2–0.9 in blurred relative L2). The closed
//! form itself is checked against finite differences where they resolve it.

mod common;

use common::deriv::*;
use glam::{DQuat, DVec2, DVec3};
use implicit_psdr::scene::Scene;

/// Image size (pixels), estimator budgets (camera samples per pixel, primary boundary samples).
const SIZE: u32 = 24;
const SPP: u32 = 64;
const PRIMARY: u64 = 60_000;

/// The box's albedo; the sky's radiance is 1.
const RHO: f64 = 0.5;

/// The parameters: the transform's translation, rotation axis and angle (degrees), scale; the box's
/// centre and half size.
#[derive(Copy, Clone, Debug)]
struct Placement {
    translate: DVec3,
    axis: DVec3,
    angle: f64,
    scale: f64,
    center: DVec3,
    half: DVec3,
}

impl Placement {
    fn new() -> Self {
        Self {
            translate: DVec3::new(0.1, 0.05, -0.1),
            axis: DVec3::new(0.3, 1.0, 0.2).normalize(),
            angle: 25.0,
            scale: 1.1,
            center: DVec3::ZERO,
            half: DVec3::new(0.5, 0.4, 0.5),
        }
    }

    /// World position of the box point `p` (box coordinates).
    fn world(&self, p: DVec3) -> DVec3 {
        self.translate + DQuat::from_axis_angle(self.axis, self.angle.to_radians()) * p * self.scale
    }

    /// The eight corners, in world coordinates.
    fn corners(&self) -> [DVec3; 8] {
        std::array::from_fn(|i| {
            let s = |bit: usize| if i & bit == 0 { -1.0 } else { 1.0 };
            self.world(self.center + DVec3::new(s(1), s(2), s(4)) * self.half)
        })
    }

    /// This placement with parameter `k` of [`PARAMS`] moved by `h`.
    fn moved(mut self, k: usize, h: f64) -> Self {
        match k {
            0..=2 => self.translate[k] += h,
            3 => self.angle += h,
            4 => self.scale += h,
            5..=7 => self.center[k - 5] += h,
            _ => self.half[k - 8] += h,
        }
        self
    }
}

/// The parameters' names, in [`Placement::moved`]'s order.
const PARAMS: [&str; 11] = [
    "b.sdf.translate.x",
    "b.sdf.translate.y",
    "b.sdf.translate.z",
    "b.sdf.angle",
    "b.sdf.scale",
    "b.sdf.child.center.x",
    "b.sdf.child.center.y",
    "b.sdf.child.center.z",
    "b.sdf.child.half_size.x",
    "b.sdf.child.half_size.y",
    "b.sdf.child.half_size.z",
];

/// The grazing angles (degrees), from in front of the face's plane and from behind it.
const ANGLES: [f64; 8] = [10.0, 3.0, 1.0, 0.3, -0.3, -1.0, -3.0, -10.0];

/// The box placed by [`Placement::new`] in a constant sky, the camera looking at its centre from 3.3
/// box units away at `alpha` degrees from the plane of its `+x` face at the face's centre (negative:
/// from behind that plane), its up the box's `y`.
fn grazing_scene(alpha: f64) -> Scene {
    let place = Placement::new();
    let rotation = DQuat::from_axis_angle(place.axis, place.angle.to_radians());
    let along = DVec3::new(0.0, 1.5, 3.0).normalize();
    let a = alpha.to_radians();
    let eye = place.world(DVec3::new(0.5, 0.0, 0.0) + (along * a.cos() + DVec3::X * a.sin()) * 3.3);
    let v = |p: DVec3| format!("[{}, {}, {}]", p.x, p.y, p.z);
    scene_json(&format!(
        r#"{{
  "camera": {{"origin": {}, "target": {}, "up": {}, "fov_y": 40, "width": {SIZE}, "height": {SIZE},
             "filter": "tent"}},
  "integrator": {{"type": "direct"}},
  "shapes": [{{"name": "b",
    "sdf": {{"type": "transform", "translate": {}, "rotate": {{"axis": {}, "angle": {}}}, "scale": {},
            "child": {{"type": "box", "center": {}, "half_size": {}}}}},
    "bsdf": {{"type": "diffuse", "albedo": [{RHO}, {RHO}, {RHO}]}}}}],
  "emitters": [{{"name": "sky", "type": "constant", "radiance": [1, 1, 1]}}]
}}"#,
        v(eye),
        v(place.translate),
        v(rotation * DVec3::Y),
        v(place.translate),
        v(place.axis),
        place.angle,
        place.scale,
        v(place.center),
        v(place.half),
    ))
}

/// The closed form of the derivative of `scene`'s grey image (three channels summed) with respect to
/// parameter `k`: `∮ w_j 3 (ρ − 1) v dℓ` along the convex hull of the projected corners, `v` the
/// outward normal velocity of each hull edge's image (from the corners moved by `±1e-5`, in `f64`).
fn closed_form(scene: &Scene, k: usize) -> Vec<f64> {
    let frame = scene.camera.frame::<f32>();
    let v = |a: implicit_psdr::math::Vec3<f32>| glam::Vec3::from(a).as_dvec3();
    let (o, r, up, fwd) = (
        v(frame.origin),
        v(frame.right),
        v(frame.up),
        v(frame.forward),
    );
    let (f, (cx, cy)) = (frame.focal as f64, frame.center);
    let project = |x: DVec3| {
        let q = x - o;
        let z = q.dot(fwd);
        DVec2::new(cx as f64 + f * q.dot(r) / z, cy as f64 - f * q.dot(up) / z)
    };
    let step = 1e-5;
    let place = Placement::new();
    let (corners, plus, minus) = (
        place.corners(),
        place.moved(k, step).corners(),
        place.moved(k, -step).corners(),
    );
    let image = corners.map(project);
    // The convex hull of the projected corners (gift wrapping).
    let start = (0..8)
        .min_by(|&a, &b| image[a].x.total_cmp(&image[b].x))
        .unwrap();
    let mut hull = vec![start];
    loop {
        let last = *hull.last().unwrap();
        let mut next = (last + 1) % 8;
        for c in 0..8 {
            if (image[next] - image[last]).perp_dot(image[c] - image[last]) < 0.0 {
                next = c;
            }
        }
        if next == start {
            break;
        }
        hull.push(next);
    }
    let centroid = hull.iter().map(|&i| image[i]).sum::<DVec2>() / hull.len() as f64;
    let (w, h) = (scene.camera.width as i64, scene.camera.height as i64);
    let mut out = vec![0.0; (w * h) as usize];
    let tent = |x: f64| (1.0 - x.abs()).max(0.0);
    let n = 4000;
    for e in 0..hull.len() {
        let (a, b) = (hull[e], hull[(e + 1) % hull.len()]);
        let mut normal = (image[b] - image[a]).perp().normalize();
        if normal.dot(image[a] - centroid) < 0.0 {
            normal = -normal;
        }
        for i in 0..n {
            let s = (i as f64 + 0.5) / n as f64;
            let at = |c: &[DVec3; 8], s: f64| project(c[a] + (c[b] - c[a]) * s);
            let u = at(&corners, s);
            let velocity = (at(&plus, s) - at(&minus, s)) / (2.0 * step);
            // The image's length per unit of `s` (perspective: not uniform along the edge).
            let du_ds = (at(&corners, s + step) - at(&corners, s - step)).length() / (2.0 * step);
            let weight = 3.0 * (RHO - 1.0) * velocity.dot(normal) * du_ds / n as f64;
            let (x0, y0) = (u.x.floor() as i64, u.y.floor() as i64);
            for py in y0 - 1..=y0 + 1 {
                for px in x0 - 1..=x0 + 1 {
                    if px >= 0 && py >= 0 && px < w && py < h {
                        let wj = tent(u.x - (px as f64 + 0.5)) * tent(u.y - (py as f64 + 0.5));
                        out[(py * w + px) as usize] += wj * weight;
                    }
                }
            }
        }
    }
    out
}

/// Blurred relative L2 and `|Σ a − Σ b| / Σ|b|` of `a` against `b`.
fn errors(a: &[f64], b: &[f64]) -> (f64, f64) {
    let (w, h) = (SIZE as usize, SIZE as usize);
    let abs: f64 = b.iter().map(|v| v.abs()).sum();
    let sum = (a.iter().sum::<f64>() - b.iter().sum::<f64>()).abs() / abs;
    (blurred_rel_l2(a, b, w, h, None), sum)
}

/// Bounds on the blurred relative L2 and the sum error against the closed form: twice the largest over
/// all grazing angles and two seeds (`PSDR_TEST_SEED` unset and `=1`). Translations, scale, centre and
/// half sizes: L2 ≤ (0.046, 0.046), sums ≤ (0.025, 0.027); before each side looked at its own face,
/// 0.21 at 0.3° (x translations and half size), 0.07 at 1°. The rotation's error is the interior
/// term's noise on the sliver (a turning face's film area per unit area changes like `1/cos` of the
/// grazing angle): L2 (0.26, 0.17) at 0.3°, ≤ 0.14 at 1° and beyond, falling to 0.11 at 0.3° with 8×
/// the budget; sums ≤ (0.032, 0.029); before, L2 0.72 and sum 0.23 at 0.3°, sum 0.09 at 1°.
const L2: f64 = 0.1;
const SUM: f64 = 0.06;
const L2_ANGLE: f64 = 0.53;
const SUM_ANGLE: f64 = 0.07;

#[test]
fn faces_seen_edge_on() {
    let start = std::time::Instant::now();
    println!("angle  parameter                 L2     sum");
    for (i, alpha) in ANGLES.into_iter().enumerate() {
        let scene = grazing_scene(alpha);
        // Measuring only: PSDR_BUDGET_SCALE multiplies the budget.
        let scale: f64 = std::env::var("PSDR_BUDGET_SCALE")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(1.0);
        let (spp, primary) = ((SPP as f64 * scale) as u32, (PRIMARY as f64 * scale) as u64);
        let terms = derivative_terms(&scene, &PARAMS, spp, primary, 0, seed(100 * i as u64));
        for (k, t) in terms.iter().enumerate() {
            let (l2, sum) = errors(&t.total(), &closed_form(&scene, k));
            let name = PARAMS[k];
            println!("{alpha:>5}° {name:<24} {l2:.4} {sum:.4}");
            let (l2_bound, sum_bound) = if name == "b.sdf.angle" {
                (L2_ANGLE, SUM_ANGLE)
            } else {
                (L2, SUM)
            };
            if std::env::var("PSDR_MEASURE").is_err() {
                assert!(
                    l2 <= l2_bound,
                    "{alpha}° {name}: blurred rel L2 {l2} > {l2_bound}"
                );
                assert!(
                    sum <= sum_bound,
                    "{alpha}° {name}: sum error {sum} > {sum_bound}"
                );
            }
        }
    }
    println!("{:.1} s", start.elapsed().as_secs_f64());
}

/// The closed form against central finite differences (`h` = 0.01, 1024 spp), from both sides of the
/// face's plane, where a step of 0.01 stays far from the grazing angle. Bounds: twice the largest of
/// the FD's distances to it over two seeds, L2 (0.048, 0.051), sums ≤ (0.013, 0.012); two FD seeds
/// differ by 0.039–0.081 (L2), `h/2` against `h` by 0.028–0.048.
#[test]
fn closed_form_matches_finite_differences() {
    for (alpha, k) in [(3.0, 0), (-3.0, 8)] {
        let scene = grazing_scene(alpha);
        let exact = closed_form(&scene, k);
        let f = fd(&scene, PARAMS[k], 0.01, 1024, seed(7));
        let (l2, sum) = errors(&f, &exact);
        println!(
            "{alpha}° {}: FD vs closed form L2 {l2:.4}, sum {sum:.4}",
            PARAMS[k]
        );
        if std::env::var("PSDR_CHECK_H").is_ok() {
            let g = fd(&scene, PARAMS[k], 0.01, 1024, seed(8));
            let half = fd(&scene, PARAMS[k], 0.005, 1024, seed(7));
            println!(
                "  FD seeds {:?}, h/2 {:?}",
                errors(&g, &f),
                errors(&half, &f)
            );
        }
        assert!(
            l2 <= FD_L2,
            "{alpha}° {}: FD vs closed form {l2}",
            PARAMS[k]
        );
        assert!(
            sum <= FD_SUM,
            "{alpha}° {}: FD vs closed form sum {sum}",
            PARAMS[k]
        );
    }
}

const FD_L2: f64 = 0.11;
const FD_SUM: f64 = 0.03;
