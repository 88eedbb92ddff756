//! The interior term's samples next to sharp edges: camera rays aimed within 1e-7 .. 1e-3 of the
//! crease edges of sharp boxes, cylinders and hard CSG, each sample's derivative (its contribution's,
//! its area factor's and its film motion's) finite and within a constant of what the same edge's
//! faces give a little farther away (2e-2 .. 6e-2), for translations, rotations, scales and size
//! parameters, direct and path.
//!
//! A hit within the tracer's tolerance of an edge may lie outside the solid by a tiny `φ`, where the
//! exact distance's level set rounds the edge with radius `φ`: its curvature `1/φ` in `∂πJ = κV` and
//! its normal turning across the edge made such samples up to `10⁶` times a face's (a firefly of 40
//! times the whole derivative in a 48×48 image at 1024 spp). A point of a face has its face's
//! geometry on either side of the tolerance (docs/theory.md §7.1, "surface points next to an edge").

mod common;

use common::Rng;
use common::deriv::scene_json;
use implicit_psdr::integrator::VelocityField;
use implicit_psdr::integrator::attach::SceneAttach;
use implicit_psdr::integrator::path::{PathRecord, TraceCounters, contribution_parts, trace_path};
use implicit_psdr::math::Ray;
use implicit_psdr::sampler::Sampler;
use implicit_psdr::scalar::Dual32;
use implicit_psdr::scene::Scene;
use implicit_psdr::sdf::{CreaseEdge, Face, Sdf};

/// One shape named `s` (its sdf `sdf`) on a floor, lit by a small sphere and a sky, seen obliquely.
fn scene(sdf: &str, integrator: &str) -> Scene {
    scene_json(&format!(
        r#"{{
  "camera": {{"origin": [-2.3, 1.7, 3.1], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 35,
             "width": 48, "height": 48, "filter": "tent"}},
  "integrator": {integrator},
  "shapes": [
    {{"name": "s", "sdf": {sdf}, "bsdf": {{"type": "diffuse", "albedo": [0.7, 0.6, 0.4]}}}},
    {{"name": "floor", "sdf": {{"type": "plane", "normal": [0, 1, 0], "offset": -1.2}},
     "bsdf": {{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}}}
  ],
  "emitters": [
    {{"name": "sky", "type": "constant", "radiance": [0.5, 0.5, 0.5]}},
    {{"name": "lamp", "type": "sphere", "center": [1.5, 3, 2], "radius": 0.3, "radiance": [30, 30, 30]}}
  ]
}}"#
    ))
}

const ROTATED_BOX: &str = r#"{"type": "transform", "translate": [0.1, 0, 0], "rotate": {"axis": [0.2, 1, -0.4], "angle": 40},
    "scale": 1.2, "child": {"type": "box", "center": [0, 0, 0], "half_size": [0.5, 0.35, 0.7]}}"#;
const CYLINDER: &str = r#"{"type": "cylinder", "center": [0, 0.1, 0], "axis": [0.3, 1, 0.2], "radius": 0.6,
    "half_height": 0.45, "rounding": 0}"#;
const CSG: &str = r#"{"type": "difference", "children": [
    {"name": "k", "type": "box", "center": [0, 0, 0], "half_size": [0.6, 0.45, 0.55], "rounding": 0},
    {"name": "c", "type": "sphere", "center": [0.5, 0.45, 0.5], "radius": 0.4}]}"#;

/// The size of sample `ray`'s derivative in the interior term: `|∂L|` plus `|L|` times the relative
/// change of what multiplies it when the film point moves (the first vertex's area factor, its film
/// position in pixels, the film area per unit area). Panics on a non-finite value.
///
/// `None` where the camera sees the first vertex at a grazing angle (`|cos| < 0.05`): there the film
/// area per unit area, `∝ |n·(x − o)|`, changes relative to itself like `1/cos` on any face, next to
/// an edge or not (the heavy tail of a smooth silhouette, the primary term's side of the boundary).
fn derivative_size(scene: &Scene, attach: &SceneAttach, ray: Ray, k: u64) -> Option<f64> {
    let frame = scene.camera.frame::<Dual32>();
    let spread = scene.camera.frame::<f32>().spread(ray.d);
    let mut sampler = Sampler::new(7, 0, k, 0);
    let (mut record, mut counters) = (PathRecord::default(), TraceCounters::default());
    let depth = scene.integrator.max_scatter();
    trace_path(
        scene,
        ray,
        spread,
        depth,
        &mut sampler,
        &mut record,
        &mut counters,
    );
    let (l, first) = contribution_parts::<Dual32, _>(scene, &record, attach);
    let mut size = (l.x.eps.abs() + l.y.eps.abs() + l.z.eps.abs()) as f64;
    let radiance = (l.x.re.abs() + l.y.re.abs() + l.z.re.abs()) as f64;
    if let Some(a) = first {
        if a.n.primal().dot(ray.d).abs() < GRAZING {
            return None;
        }
        let jacobian = frame.film_area_jacobian(a.x, a.n);
        let moves = match frame.project(a.x) {
            Some((px, py)) => px.eps.abs() + py.eps.abs(),
            None => 0.0,
        };
        let relative = a.j.eps.abs() + moves + jacobian.eps.abs() / jacobian.re.max(1e-30);
        size += radiance * relative as f64;
    }
    assert!(size.is_finite(), "non-finite derivative along {ray:?}");
    Some(size)
}

/// `|cos|` between the camera ray and the first vertex's normal below which a sample is not compared.
const GRAZING: f32 = 0.05;

/// Rays from the camera through points of every crease edge of shape 0 moved off it (perpendicular to
/// it, in a random direction) by a distance drawn log-uniformly in `[lo, hi]`.
fn edge_rays(scene: &Scene, lo: f32, hi: f32, count: usize, seed: u64) -> Vec<Ray> {
    let shape = &scene.shapes[0];
    let edges = shape.sdf.crease_edges();
    assert!(!edges.is_empty());
    let eye = scene.camera.origin.value();
    let mut rng = Rng::new(seed);
    (0..count)
        .filter_map(|k| {
            let edge = &edges[k % edges.len()];
            let (p, t, _) = shape.sdf.crease_point(edge, rng.f32())?;
            let v = glam::Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - glam::Vec3::ONE;
            let v = (v - t * v.dot(t)).normalize_or_zero();
            let distance = lo * (hi / lo).powf(rng.f32());
            let target = p + shape.translate.value() + v * distance;
            Some(Ray::new(eye, (target - eye).normalize()))
        })
        .collect()
}

/// For each parameter of `names`: the largest derivative among rays aimed within 1e-7 .. 1e-3 of the
/// edges is at most `ratio` times the largest among rays aimed at the faces 2e-2 .. 6e-2 from them.
fn check(label: &str, sdf: &str, names: &[&str], ratio: f64) {
    for integrator in [
        r#"{"type": "direct"}"#,
        r#"{"type": "path", "max_depth": 3}"#,
    ] {
        for (i, name) in names.iter().enumerate() {
            let plain = scene(sdf, integrator);
            let scene = plain.select(&[name]).unwrap().apply(&plain).unwrap();
            let attach = SceneAttach::new(&scene, VelocityField::Auto);
            let largest = |rays: Vec<Ray>| {
                (rays.into_iter().enumerate())
                    .filter_map(|(k, ray)| derivative_size(&scene, &attach, ray, k as u64))
                    .fold(0.0f64, f64::max)
            };
            let seed = 11 * i as u64;
            let near = largest(edge_rays(&scene, 1e-7, 1e-3, 3000, seed));
            let faces = largest(edge_rays(&scene, 2e-2, 6e-2, 1000, seed + 1));
            println!("{label} {integrator} {name}: near edges {near:.4}, on faces {faces:.4}");
            assert!(faces > 0.0, "{label} {name}: the faces must move");
            assert!(
                near <= ratio * faces,
                "{label} {integrator} {name}: a sample next to an edge {near} > {ratio} × the faces' {faces}"
            );
        }
    }
}

#[test]
fn rotated_box() {
    check(
        "rotated box",
        ROTATED_BOX,
        &[
            "s.translate.x",
            "s.sdf.translate.y",
            "s.sdf.angle",
            "s.sdf.scale",
            "s.sdf.child.half_size.y",
            "s.sdf.child.center.x",
        ],
        RATIO,
    );
}

#[test]
fn cylinder() {
    check(
        "cylinder",
        CYLINDER,
        &["s.translate.z", "s.radius", "s.half_height", "s.center.y"],
        RATIO,
    );
}

#[test]
fn box_minus_sphere() {
    check(
        "box minus sphere",
        CSG,
        &["k.half_size.x", "k.center.y", "c.radius", "c.center.x"],
        RATIO,
    );
}

/// Near an edge the sample's derivative is the face's; the spread of the faces' own values (lighting
/// and the film motion across a few hundredths of a unit) is what the margin covers.
const RATIO: f64 = 4.0;

/// The field of the faces (`Sdf::eval_faces`) is the exact distance inside and wherever one face is
/// nearest, a lower bound of it outside next to edges, with the same sign everywhere (the same
/// surface); its gradient (analytic for a box) is AD's, and its level sets next to a box's edges and
/// corners are flat (`κ = 0`) where the exact distance's are cylinders and spheres of radius `φ`.
#[test]
fn face_field_keeps_the_surface_and_flattens_the_edges() {
    let node = |json: &str| scene(json, r#"{"type": "direct"}"#).shapes[0].sdf.clone();
    let mut rng = Rng::new(5);
    for json in [
        ROTATED_BOX,
        CYLINDER,
        CSG,
        r#"{"type": "box", "center": [0.1, 0, 0], "half_size": [0.5, 0.4, 0.6]}"#,
    ] {
        let sdf = node(json);
        let b = sdf.bounds();
        let mut flattened = 0;
        for _ in 0..4000 {
            let p = rng.in_box(b.min - 0.2, b.max + 0.2);
            let (exact, faces) = (sdf.eval_f32(p), sdf.eval_faces::<f32>(p.into()));
            assert_eq!(
                exact > 0.0,
                faces > 0.0,
                "{json} at {p}: {exact} vs {faces}"
            );
            if exact <= 0.0 {
                assert_eq!(exact, faces, "{json} at {p}");
            } else {
                assert!(faces <= exact + 1e-6, "{json} at {p}: {faces} > {exact}");
            }
            let ad = sdf.ad_gradient(p);
            let analytic = sdf.gradient_faces(p);
            let by_ad = Sdf::named("f", sdf.clone()).gradient_faces(p);
            assert!((analytic - by_ad).length() < 1e-5, "{json} at {p}");
            assert!((analytic.length() - 1.0).abs() < 1e-4 || ad == glam::Vec3::ZERO);
        }
        // Points just outside an edge, where the exact distance's level set is a cylinder of radius φ.
        let shape = &scene(json, r#"{"type": "direct"}"#).shapes[0];
        let primitive = |e: &&CreaseEdge| !e.inverted && !matches!(e.faces[0], Face::Child { .. });
        for edge in sdf.crease_edges().iter().filter(primitive) {
            let Some((p, _, _)) = sdf.crease_point(edge, rng.f32()) else {
                continue;
            };
            let [a, c] = edge
                .faces
                .map(|f| sdf.face_gradient(&edge.path, f, p).normalize());
            let out = p + (a + c).normalize() * 1e-5;
            // Only where the edge is the surface's (not cut away by another child).
            if (shape.sdf.eval_f32(out) - 1e-5).abs() > 1e-6 {
                continue;
            }
            let exact = shape.sdf.curvature(out);
            let (_, g, h) = sdf.hessian_faces(out);
            let faces = (h.x_axis.x + h.y_axis.y + h.z_axis.z - g.dot(h * g) / g.length_squared())
                / g.length();
            assert!(
                exact > 1e4,
                "{json}: the exact distance rounds the edge ({exact})"
            );
            assert!(
                faces.abs() < 3.0,
                "{json}: the faces' curvature {faces} at an edge"
            );
            flattened += 1;
        }
        assert!(flattened > 0, "{json}: no edge point tried");
    }
}
