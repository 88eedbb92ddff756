//! The parameter registry: names, selection (checked by lifting with dual numbers), setting values
//! (checked against finite differences and by re-rendering).

use implicit_psdr::integrator::{RenderOptions, render};
use implicit_psdr::scalar::{Dual32, DualN};
use implicit_psdr::scene::{self, Scene};
use implicit_psdr::sdf::Sdf;
use implicit_psdr::{Scalar, Vec3};
use std::collections::HashSet;
use std::path::{Path, PathBuf};

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

fn example(name: &str) -> Scene {
    scene::load(&scenes_dir().join(format!("{name}.json"))).unwrap()
}

fn parse(json: &serde_json::Value) -> implicit_psdr::Result<Scene> {
    scene::parse(&json.to_string(), Path::new("."))
}

fn names(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

/// A copy of `scene` with the parameters `wanted` selected (what the estimators render).
fn selected(scene: &Scene, wanted: &[&str]) -> Scene {
    scene.select(wanted).unwrap().apply(scene).unwrap()
}

/// Slot of every parameter, by name.
fn slots(scene: &Scene) -> Vec<(String, Option<u32>)> {
    let mut out = Vec::new();
    scene.visit_params(&mut |n, p| out.push((n.to_string(), p.slot)));
    out
}

fn dual_point(p: glam::Vec3) -> Vec3<Dual32> {
    Vec3::new(
        Dual32::from_re(p.x),
        Dual32::from_re(p.y),
        Dual32::from_re(p.z),
    )
}

#[test]
fn every_example_scene_lists_unique_shell_friendly_parameters() {
    let mut count = 0;
    for entry in std::fs::read_dir(scenes_dir()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("json") {
            continue;
        }
        count += 1;
        let scene = scene::load(&path).unwrap();
        let params = scene.parameters();
        // At least the camera's 10 and, per shape, translate (3) and albedo (3).
        assert!(
            params.len() >= 10 + 6 * scene.shapes.len(),
            "{}: {params:?}",
            path.display()
        );
        let mut seen = HashSet::new();
        for (name, value) in &params {
            assert!(
                seen.insert(name.clone()),
                "{}: {name} twice",
                path.display()
            );
            assert!(
                name.chars()
                    .all(|c| c.is_ascii_alphanumeric() || "_-.".contains(c)),
                "{name}"
            );
            assert!(value.is_finite(), "{name} = {value}");
            assert_eq!(scene.parameter(name).unwrap(), *value, "{name}");
        }
        // Every shape has its rigid translation, zero unless the file gives one.
        for s in &scene.shapes {
            for c in ["x", "y", "z"] {
                assert!(seen.contains(&format!("{}.translate.{c}", s.name)));
            }
        }
    }
    assert!(count >= 4, "found {count} example scenes");
}

#[test]
fn issue_names_exist_with_their_values() {
    let scene = example("sphere_floor");
    for (name, value) in [
        ("ball.radius", 1.0),
        ("ball.center.x", 0.0),
        ("light.center.y", 4.0),
        ("light.size.x", 1.0),
        ("light.radiance.r", 40.0),
        ("ball.albedo.r", 0.8),
        ("camera.origin.x", 0.0),
        ("camera.origin.y", 3.0),
        ("camera.fov_y", 45.0),
        ("ball.translate.x", 0.0),
        ("floor.translate.y", 0.0),
        ("floor.half_size.x", 50.0),
        ("floor.rounding", 0.25),
    ] {
        assert_eq!(scene.parameter(name).unwrap(), value, "{name}");
    }
    // The camera comes first, in a fixed order.
    let first: Vec<String> = scene.parameters()[..4]
        .iter()
        .map(|(n, _)| n.clone())
        .collect();
    assert_eq!(
        first,
        names(&[
            "camera.origin.x",
            "camera.origin.y",
            "camera.origin.z",
            "camera.target.x"
        ])
    );

    let env = example("environment");
    assert_eq!(env.parameter("sky.radiance.g").unwrap(), 1.0);
    assert_eq!(env.parameter("donut.major_radius").unwrap(), 0.7);
    assert_eq!(env.parameter("donut.minor_radius").unwrap(), 0.3);

    let csg = example("csg");
    for (name, value) in [
        ("blob.k", 0.4),
        // Named children use their own names.
        ("blob_sphere.radius", 0.7),
        ("blob_box.rounding", 0.15),
        ("blob_box.half_size.y", 0.5),
        // An unnamed root transform lives under `.sdf`, its child under `.child`.
        ("ring.sdf.translate.y", 0.1),
        ("ring.sdf.angle", 60.0),
        ("ring.sdf.scale", 1.0),
        ("ring.sdf.child.major_radius", 0.8),
        ("ring.translate.y", 0.0),
        // Unnamed children are numbered.
        ("bitten.children.0.rounding", 0.2),
        ("bitten.children.1.radius", 0.6),
        ("bitten.children.1.center.x", 2.5),
        ("sky.radiance.g", 0.22),
        ("key.size.y", 2.0),
    ] {
        assert_eq!(csg.parameter(name).unwrap(), value, "{name}");
    }
    // Directions are not parameters.
    assert!(csg.parameter("ring.sdf.child.axis.x").is_err());
    assert!(csg.parameter("key.normal.x").is_err());
    let grid = example("grid");
    assert_eq!(grid.parameter("baked_blob.sdf.translate.x").unwrap(), 1.3);
    // A grid node's one parameter is its iso-level; its samples are not parameters.
    let child: Vec<String> = grid
        .parameters()
        .into_iter()
        .filter(|(n, _)| n.starts_with("baked_blob.sdf.child"))
        .map(|(n, _)| n)
        .collect();
    assert_eq!(child, names(&["baked_blob.sdf.child.level"]));
    assert_eq!(grid.parameter("baked_blob.sdf.child.level").unwrap(), 0.0);
}

#[test]
fn named_nodes_keep_their_names_and_behave_as_their_child() {
    let v = serde_json::json!({
        "camera": {"origin": [0, 3, 4], "target": [0, 0, 0], "up": [0, 1, 0],
                   "fov_y": 45.0, "width": 8, "height": 8},
        "shapes": [
            {"name": "thing", "translate": [0.5, -0.25, 2],
             "sdf": {"type": "union", "children": [
                {"type": "torus", "name": "ring", "center": [0, 0, 0], "axis": [0, 1, 0],
                 "major_radius": 1, "minor_radius": 0.2},
                {"type": "transform", "translate": [1, 0, 0], "scale": 2,
                 "child": {"type": "sphere", "center": [0, 0, 0], "radius": 0.3}}
             ]},
             "bsdf": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}
        ]
    });
    let scene = parse(&v).unwrap();
    assert_eq!(scene.parameter("ring.major_radius").unwrap(), 1.0);
    assert_eq!(scene.parameter("thing.children.1.scale").unwrap(), 2.0);
    assert_eq!(
        scene.parameter("thing.children.1.child.radius").unwrap(),
        0.3
    );
    assert_eq!(scene.parameter("thing.translate.z").unwrap(), 2.0);
    assert!(scene.parameter("thing.children.0.major_radius").is_err());

    // The shape's translation is applied: bounds and values move with it.
    let shape = &scene.shapes[0];
    let Sdf::Union(children) = &shape.sdf else {
        panic!("{:?}", shape.sdf)
    };
    let Sdf::Named { name, child } = &children[0] else {
        panic!("{:?}", children[0])
    };
    assert_eq!(name, "ring");
    assert_eq!(children[0].unnamed(), &**child);
    let t = glam::Vec3::new(0.5, -0.25, 2.0);
    assert_eq!(shape.translate.value(), t);
    assert_eq!(shape.bounds.min, shape.sdf.bounds().min + t);
    // The wrapper delegates everything.
    assert_eq!(children[0].bounds(), child.bounds());
    assert_eq!(children[0].lipschitz(), child.lipschitz());
    for p in [
        glam::Vec3::new(1.1, 0.1, 0.0),
        glam::Vec3::new(-0.3, 0.5, 0.9),
        glam::Vec3::new(0.0, -1.0, 0.2),
    ] {
        assert_eq!(children[0].eval_f32(p), child.eval_f32(p));
        assert_eq!(children[0].gradient(p), child.gradient(p));
        assert_eq!(children[0].curvature(p), child.curvature(p));
        assert_eq!(shape.eval_f32(p + t), shape.sdf.eval_f32(p));
    }
}

#[test]
fn camera_is_a_reserved_name() {
    let v = serde_json::json!({
        "camera": {"origin": [0, 3, 4], "target": [0, 0, 0], "up": [0, 1, 0],
                   "fov_y": 45.0, "width": 8, "height": 8},
        "emitters": [{"name": "camera", "type": "constant", "radiance": [1, 1, 1]}]
    });
    let e = parse(&v).unwrap_err().to_string();
    assert!(e.starts_with("emitters[0].name: "), "{e}");
    assert!(e.contains("reserved"), "{e}");
}

#[test]
fn a_selection_sets_exactly_the_requested_slots() {
    let scene = example("csg");
    let wanted = ["ring.sdf.angle", "blob.k", "camera.fov_y", "sky.radiance.g"];
    let selection = scene.select(&wanted).unwrap();
    assert_eq!(selection.names(), wanted);
    for (name, slot) in slots(&selection.apply(&scene).unwrap()) {
        let expected = wanted.iter().position(|w| *w == name).map(|k| k as u32);
        assert_eq!(slot, expected, "{name}");
    }
    // The scene itself carries no selection; applying another one replaces the first, and an empty
    // one selects nothing.
    assert!(slots(&scene).iter().all(|(_, s)| s.is_none()));
    let twice = selected(&selection.apply(&scene).unwrap(), &["floor.translate.y"]);
    let chosen: Vec<_> = slots(&twice)
        .into_iter()
        .filter(|(_, s)| s.is_some())
        .collect();
    assert_eq!(chosen, vec![("floor.translate.y".to_string(), Some(0))]);
    assert!(
        slots(&selected(&twice, &[]))
            .iter()
            .all(|(_, s)| s.is_none())
    );
}

#[test]
fn selected_parameters_lift_to_the_expected_derivatives() {
    let base = example("sphere_floor");
    let p = glam::Vec3::new(0.3, 1.2, -0.5);
    let n = p.normalize();

    // φ = |p − c − t| − r: ∂φ/∂r = −1, ∂φ/∂t_x = −n_x, ∂φ/∂c_y = −n_y.
    for (name, expected) in [
        ("ball.radius", -1.0),
        ("ball.translate.x", -n.x),
        ("ball.center.y", -n.y),
        ("floor.translate.y", 0.0),
    ] {
        let scene = selected(&base, &[name]);
        let d = scene.shapes[0].eval(dual_point(p));
        assert!((d.re - (p.length() - 1.0)).abs() < 1e-6);
        assert!((d.eps - expected).abs() < 1e-6, "{name}: {d:?}");
    }
    // The floor's top face is y = −1.5 (box centre −2, half size 0.5) moved by translate.y.
    let scene = selected(&base, &["floor.translate.y"]);
    assert!((scene.shapes[1].eval(dual_point(p)).eps + 1.0).abs() < 1e-6);

    // Several directions in one pass: the same numbers, in the requested slots.
    let scene = selected(
        &base,
        &["ball.translate.x", "floor.translate.y", "ball.radius"],
    );
    let q = Vec3::new(
        DualN::<3>::constant(p.x),
        DualN::constant(p.y),
        DualN::constant(p.z),
    );
    let close = |a: [f32; 3], b: [f32; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6);
    let ball = scene.shapes[0].eval(q).eps;
    assert!(close(ball, [-n.x, 0.0, -1.0]), "{ball:?}");
    let floor = scene.shapes[1].eval(q).eps;
    assert!(close(floor, [0.0, -1.0, 0.0]), "{floor:?}");
}

#[test]
fn every_derivative_matches_a_finite_difference_of_the_value() {
    // For every parameter of two scenes (camera, emitters and materials included, whose derivative of φ
    // must be zero), the lifted derivative of each shape's φ at fixed points agrees with the central
    // difference of φ between `with_parameter(v ± h)`: names, slots and setters address the same number.
    let cases: [(&str, &[[f32; 3]]); 2] = [
        (
            "environment",
            &[
                [1.0, 0.6, 0.2],
                [-0.9, 0.5, 0.1],
                [0.3, -0.6, 0.4],
                [-1.8, 0.2, -0.7],
            ],
        ),
        (
            "csg",
            &[
                [-2.0, 1.0, 0.3],
                [-1.2, -0.3, 0.5],
                [0.9, 0.5, 0.3],
                [2.0, 0.5, -0.3],
                [1.2, -0.4, 0.8],
                [0.5, -0.8, 1.5],
            ],
        ),
    ];
    let h = 1e-2;
    for (scene_name, points) in cases {
        let base = example(scene_name);
        let mut checked = 0;
        for (name, value) in base.parameters() {
            let lifted = selected(&base, &[name.as_str()]);
            let (Ok(plus), Ok(minus)) = (
                base.with_parameter(&name, value + h),
                base.with_parameter(&name, value - h),
            ) else {
                // Values at the edge of their range (a rounding of 0) cannot be stepped both ways.
                continue;
            };
            for (i, shape) in lifted.shapes.iter().enumerate() {
                for &p in points {
                    let p = glam::Vec3::from(p);
                    let ad = shape.eval(dual_point(p)).eps;
                    let fd = (plus.shapes[i].eval_f32(p) - minus.shapes[i].eval_f32(p)) / (2.0 * h);
                    assert!(
                        (ad - fd).abs() < 2e-3 * (1.0 + fd.abs()),
                        "{scene_name}: d {} / d {name} at {p}: AD {ad}, FD {fd}",
                        shape.name
                    );
                }
            }
            checked += 1;
        }
        assert!(checked > 30, "{scene_name}: only {checked} parameters");
    }
}

#[test]
fn unknown_and_repeated_names_are_clear_errors() {
    let scene = example("sphere_floor");
    let e = scene
        .select(&["light.center.y", "ball.radus"])
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("params: no parameter \"ball.radus\"; did you mean ball.radius?"),
        "{e}"
    );
    // The library names its own registry, not a front end's option or command.
    assert!(!e.contains("--") && !e.contains("implicit-psdr"), "{e}");
    assert!(!e.contains('\n'), "{e}");

    // Up to three near matches, nearest first.
    let e = scene.select(&["ball.center.w"]).unwrap_err().to_string();
    assert!(
        e.contains("did you mean ball.center.x, ball.center.y, ball.center.z?"),
        "{e}"
    );
    // Nothing near: names of the same object, else just the hint.
    let e = scene.parameter("light.colour").unwrap_err().to_string();
    assert!(e.contains("did you mean light.center.x"), "{e}");
    let e = scene.parameter("nothing").unwrap_err().to_string();
    assert_eq!(e, "params: no parameter \"nothing\"");

    let e = scene
        .select(&["ball.radius", "light.center.y", "ball.radius"])
        .unwrap_err()
        .to_string();
    assert!(e.contains("\"ball.radius\" is given twice"), "{e}");

    let e = scene.with_parameter("ligth.center.y", 3.0).unwrap_err();
    assert!(e.to_string().contains("did you mean light.center.y"), "{e}");
}

#[test]
fn with_parameter_sets_the_value_and_recomputes_derived_data() {
    let scene = selected(&example("sphere_floor"), &["ball.radius"]);
    let big = scene.with_parameter("ball.radius", 1.5).unwrap();
    assert_eq!(big.parameter("ball.radius").unwrap(), 1.5);
    assert_eq!(big.shapes[0].bounds.max, glam::Vec3::splat(1.5));
    assert_eq!(big.shapes[0].bounds.min, glam::Vec3::splat(-1.5));
    assert!((big.shapes[0].eval_f32(glam::Vec3::new(0.0, 1.5, 0.0))).abs() < 1e-6);
    // Slots survive; nothing else changed.
    assert_eq!(slots(&big), slots(&scene));
    for ((n, a), (_, b)) in scene.parameters().iter().zip(big.parameters()) {
        if n != "ball.radius" {
            assert_eq!(*a, b, "{n}");
        }
    }

    let moved = scene.with_parameter("ball.translate.x", 0.5).unwrap();
    assert_eq!(moved.shapes[0].bounds.min.x, -0.5);
    assert_eq!(moved.shapes[0].bounds.max.x, 1.5);
    assert_eq!(
        moved.shapes[0].eval_f32(glam::Vec3::new(1.5, 0.0, 0.0)),
        0.0
    );

    // The tracer's tolerance floor follows the smallest shape, never the scene's extent: a floor 400
    // wide leaves it as it was, a smaller ball lowers it.
    let wide = scene.with_parameter("floor.half_size.x", 200.0).unwrap();
    assert_eq!(wide.trace.eps, scene.trace.eps);
    let small = scene.with_parameter("ball.radius", 0.01).unwrap();
    assert!(
        small.trace.eps < 0.1 * scene.trace.eps,
        "{} vs {}",
        small.trace.eps,
        scene.trace.eps
    );

    // Emitter and camera values reach the rendering types.
    let lit = scene.with_parameter("light.center.y", 5.0).unwrap();
    assert_eq!(lit.emitters[0].emitter.bounds().unwrap().min.y, 5.0);
    let cam = scene.with_parameter("camera.origin.x", 1.0).unwrap();
    assert_eq!(cam.camera.origin.value().x, 1.0);
}

#[test]
fn with_parameter_rejects_values_the_scene_file_would() {
    let scene = example("csg");
    for (name, value, expected) in [
        (
            "blob_sphere.radius",
            0.0,
            "blob_sphere.radius: must be > 0, got 0",
        ),
        ("blob.k", -0.1, "blob.k: must be > 0"),
        ("ring.sdf.scale", -1.0, "ring.sdf.scale: must be > 0"),
        (
            "ring.sdf.child.major_radius",
            0.2,
            "must be > minor_radius (0.25)",
        ),
        (
            "blob_box.rounding",
            0.7,
            "blob_box.rounding: must be in [0, 0.5]",
        ),
        (
            "bitten.children.0.half_size.y",
            0.1,
            "bitten.children.0.rounding",
        ),
        ("floor.albedo.g", 1.2, "floor.albedo.g: must be in [0, 1]"),
        ("key.radiance.b", -1.0, "key.radiance.b: must be >= 0"),
        ("key.size.x", 0.0, "key.size.x: must be > 0"),
        ("camera.fov_y", 180.0, "camera.fov_y"),
        ("ball.radius", 1.0, "params: no parameter"),
    ] {
        let e = scene.with_parameter(name, value).unwrap_err().to_string();
        assert!(e.contains(expected), "{name} = {value}: {e}");
    }
    for bad in [f32::NAN, f32::INFINITY] {
        let e = scene.with_parameter("blob.k", bad).unwrap_err().to_string();
        assert!(e.starts_with("blob.k: must be a finite number"), "{e}");
    }
    // The camera may not look from its target.
    let scene = example("sphere_floor");
    let at = scene
        .with_parameter("camera.origin.y", 0.0)
        .unwrap()
        .with_parameter("camera.origin.z", 0.0);
    assert!(at.unwrap_err().to_string().starts_with("camera.target"));
}

#[test]
fn with_parameter_and_the_parser_report_a_broken_rule_alike() {
    // The same value, set by name or written in the file, breaks the same rule with the same words;
    // only the field's naming differs (parameter name or JSON path).
    let text = std::fs::read_to_string(scenes_dir().join("csg.json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let scene = parse(&json).unwrap();
    for (name, pointer, path, value) in [
        (
            "blob_sphere.radius",
            "/shapes/0/sdf/children/0/radius",
            "shapes[0].sdf.children[0].radius",
            0.0,
        ),
        ("blob.k", "/shapes/0/sdf/k", "shapes[0].sdf.k", -0.1),
        (
            "ring.sdf.scale",
            "/shapes/1/sdf/scale",
            "shapes[1].sdf.scale",
            -1.0,
        ),
        (
            "ring.sdf.child.major_radius",
            "/shapes/1/sdf/child/major_radius",
            "shapes[1].sdf.child.major_radius",
            0.2,
        ),
        (
            "ring.sdf.child.minor_radius",
            "/shapes/1/sdf/child/minor_radius",
            "shapes[1].sdf.child.minor_radius",
            -0.1,
        ),
        (
            "blob_box.rounding",
            "/shapes/0/sdf/children/1/rounding",
            "shapes[0].sdf.children[1].rounding",
            0.7,
        ),
        (
            "bitten.children.0.half_size.y",
            "/shapes/2/sdf/children/0/half_size/1",
            "shapes[2].sdf.children[0].rounding",
            0.1,
        ),
        (
            "key.size.x",
            "/emitters/0/size/0",
            "emitters[0].size[0]",
            0.0,
        ),
    ] {
        let by_name = scene.with_parameter(name, value).unwrap_err().to_string();
        let mut edited = json.clone();
        *edited.pointer_mut(pointer).unwrap() = serde_json::json!(value);
        let in_file = parse(&edited).unwrap_err().to_string();
        let (field, rule) = in_file.split_once(": ").unwrap();
        assert_eq!(field, path, "{in_file}");
        assert_eq!(
            by_name.split_once(": ").unwrap().1,
            rule,
            "{name}: {by_name} vs {in_file}"
        );
    }
}

#[test]
fn with_parameter_at_the_current_value_changes_nothing() {
    for name in ["sphere_floor", "csg", "environment", "grid"] {
        let scene = example(name);
        for (param, value) in scene.parameters() {
            let same = scene.with_parameter(&param, value).unwrap();
            assert!(same == scene, "{name}: {param}");
        }
    }
    // And renders the same image, bit for bit.
    let scene = example("sphere_floor");
    let options = RenderOptions {
        spp: 2,
        ..Default::default()
    };
    let (reference, _) = render(&scene, &options);
    for param in ["ball.radius", "floor.translate.y", "light.center.y"] {
        let same = scene
            .with_parameter(param, scene.parameter(param).unwrap())
            .unwrap();
        let (image, _) = render(&same, &options);
        assert!(
            image
                .rgb
                .iter()
                .map(|v| v.to_bits())
                .eq(reference.rgb.iter().map(|v| v.to_bits())),
            "{param}"
        );
    }
    // A changed value does change the image (the test above can fail).
    let bigger = scene.with_parameter("ball.radius", 1.1).unwrap();
    assert_ne!(render(&bigger, &options).0.rgb, reference.rgb);
}
