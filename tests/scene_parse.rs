//! Scene parsing: the example scenes parse into the expected rendering types, and each class of bad
//! input gives an error naming the offending field (never a panic).

mod common;

use implicit_psdr::bsdf::Bsdf;
use implicit_psdr::emitter::Emitter;
use implicit_psdr::film::Filter;
use implicit_psdr::integrator::IntegratorKind;
use implicit_psdr::scene::{self, Scene};
use implicit_psdr::sdf::Sdf;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// A valid scene exercising every sdf type except grid, every emitter type and the camera.
fn base() -> Value {
    json!({
        "camera": {"origin": [0, 3, 4], "target": [0, 0, 0], "up": [0, 1, 0],
                   "fov_y": 45.0, "width": 16, "height": 12},
        "shapes": [
            {"name": "ball", "sdf": {"type": "sphere", "center": [0, 0, 0], "radius": 1.0},
             "bsdf": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}},
            {"name": "stuff", "sdf": {"type": "union", "children": [
                {"type": "box", "center": [0, 0, 0], "half_size": [1, 1, 1], "rounding": 0.1},
                {"type": "torus", "center": [0, 0, 0], "axis": [0, 1, 0], "major_radius": 1, "minor_radius": 0.2},
                {"type": "transform", "translate": [1, 0, 0], "rotate": {"axis": [0, 0, 1], "angle": 30},
                 "scale": 2, "child": {"type": "capsule", "a": [0, 0, 0], "b": [0, 1, 0], "radius": 0.1}},
                {"type": "smooth_union", "k": 0.1, "children": [
                    {"type": "cylinder", "center": [0, 0, 0], "axis": [0, 1, 0], "radius": 0.5, "half_height": 1}
                ]}
             ]},
             "bsdf": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}
        ],
        "emitters": [
            {"name": "light", "type": "rectangle", "center": [0, 4, 0], "normal": [0, -1, 0],
             "u": [1, 0, 0], "size": [1, 2], "radiance": [10, 10, 10]},
            {"name": "bulb", "type": "sphere", "center": [2, 2, 2], "radius": 0.1, "radiance": [5, 5, 5]},
            {"name": "sky", "type": "constant", "radiance": [1, 1, 1]}
        ]
    })
}

/// A valid scene without shapes: building it needs no SDF evaluation.
fn lights_only() -> Value {
    let mut v = base();
    v["shapes"] = json!([]);
    v
}

fn parse(v: &Value) -> implicit_psdr::Result<Scene> {
    scene::parse(&v.to_string(), Path::new("."))
}

/// Parses `v` after applying `edit`, expects an error and returns its message.
fn error_of(mut v: Value, edit: impl FnOnce(&mut Value)) -> String {
    edit(&mut v);
    match parse(&v) {
        Ok(_) => panic!("expected an error for {v}"),
        Err(e) => e.to_string(),
    }
}

#[track_caller]
fn assert_contains(message: &str, expected: &str) {
    assert!(
        message.contains(expected),
        "message {message:?} does not contain {expected:?}"
    );
    assert!(
        !message.contains('\n'),
        "message is not one line: {message:?}"
    );
}

/// An edit of the base scene and the text its error must contain.
type Case = (Box<dyn FnOnce(&mut Value)>, &'static str);

/// Removes a key that must exist.
fn del(v: &mut Value, key: &str) {
    v.as_object_mut().unwrap().remove(key).unwrap();
}

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

#[test]
fn example_scenes_parse() {
    let mut count = 0;
    for entry in std::fs::read_dir(scenes_dir()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "json") {
            let scene = scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert!(!scene.shapes.is_empty(), "{}", path.display());
            assert!(!scene.emitters.is_empty(), "{}", path.display());
            count += 1;
        }
    }
    assert!(
        count >= 4,
        "expected at least 4 example scenes, found {count}"
    );
}

#[test]
fn base_scene_maps_fields_and_defaults() {
    let scene = parse(&base()).unwrap();
    assert_eq!(scene.spp, 64);
    assert_eq!(scene.integrator, IntegratorKind::Direct);
    assert_eq!(scene.camera.filter, Filter::Tent);
    assert_eq!((scene.camera.width, scene.camera.height), (16, 12));
    assert_eq!(scene.camera.fov_y.value, 45.0);
    assert_eq!(scene.shapes[0].name, "ball");
    match &scene.shapes[0].sdf {
        Sdf::Sphere { radius, .. } => assert_eq!(radius.value, 1.0),
        other => panic!("expected a sphere, got {other:?}"),
    }
    match &scene.shapes[1].sdf {
        Sdf::Union(children) => {
            assert_eq!(children.len(), 4);
            match &children[2] {
                Sdf::Transform {
                    translate,
                    axis,
                    angle,
                    scale,
                    ..
                } => {
                    assert_eq!(translate.value(), glam::Vec3::X);
                    assert_eq!(*axis, glam::Vec3::Z);
                    assert_eq!((angle.value, scale.value), (30.0, 2.0));
                }
                other => panic!("expected a transform, got {other:?}"),
            }
            match &children[3] {
                Sdf::SmoothUnion { k, children } => {
                    assert_eq!(k.value, 0.1);
                    // Absent rounding defaults to a sharp cylinder.
                    assert!(
                        matches!(children[0], Sdf::Cylinder { rounding, .. } if rounding.value == 0.0)
                    );
                }
                other => panic!("expected a smooth union, got {other:?}"),
            }
        }
        other => panic!("expected a union, got {other:?}"),
    }
    assert_eq!(
        scene.shapes[1].bsdf,
        Bsdf::Diffuse {
            albedo: [0.5, 0.5, 0.5].into()
        }
    );
    assert_eq!(scene.environment, Some(2));
    assert_eq!(scene.finite_emitters, vec![0, 1]);
}

#[test]
fn scene_without_shapes_maps_emitters_and_options() {
    let mut v = lights_only();
    v["spp"] = json!(7);
    v["integrator"] = json!({"type": "path"});
    v["camera"]["filter"] = json!("gaussian");
    let scene = parse(&v).unwrap();
    assert_eq!(scene.spp, 7);
    assert_eq!(scene.integrator, IntegratorKind::Path { max_depth: 5 });
    assert_eq!(scene.camera.filter, Filter::Gaussian);
    v["integrator"] = json!({"type": "path", "max_depth": 2});
    v["camera"]["filter"] = json!("box");
    let scene = parse(&v).unwrap();
    assert_eq!(scene.integrator, IntegratorKind::Path { max_depth: 2 });
    assert_eq!(scene.camera.filter, Filter::Box);
    match &scene.emitters[0].emitter {
        Emitter::Rectangle {
            size, u, normal, ..
        } => {
            assert_eq!([size[0].value, size[1].value], [1.0, 2.0]);
            assert_eq!((*u, *normal), (glam::Vec3::X, glam::Vec3::NEG_Y));
        }
        other => panic!("expected a rectangle, got {other:?}"),
    }
    assert_eq!(scene.emitters[1].name, "bulb");
}

#[test]
fn rectangle_edge_is_orthonormalised() {
    let mut v = lights_only();
    v["emitters"][0]["normal"] = json!([0, -2, 0]);
    v["emitters"][0]["u"] = json!([2, 1, 0]);
    let scene = parse(&v).unwrap();
    match &scene.emitters[0].emitter {
        Emitter::Rectangle { normal, u, .. } => {
            assert!((*normal - glam::Vec3::NEG_Y).length() < 1e-6, "{normal}");
            assert!((*u - glam::Vec3::X).length() < 1e-6, "{u}");
        }
        other => panic!("expected a rectangle, got {other:?}"),
    }
}

#[test]
fn out_of_range_values_name_their_field() {
    let cases: Vec<Case> = vec![
        (
            Box::new(|v| v["shapes"][0]["sdf"]["radius"] = json!(-1)),
            "shapes[0].sdf.radius: must be > 0, got -1",
        ),
        (
            Box::new(|v| v["camera"]["width"] = json!(0)),
            "camera.width: must be >= 1, got 0",
        ),
        (
            Box::new(|v| v["camera"]["height"] = json!(-3)),
            "camera.height: must be >= 1, got -3",
        ),
        (
            Box::new(|v| v["camera"]["width"] = json!(2.5)),
            "camera.width: must be an integer, got 2.5",
        ),
        (
            Box::new(|v| v["camera"]["fov_y"] = json!(180)),
            "camera.fov_y: must be in (0, 180)",
        ),
        (
            Box::new(|v| v["camera"]["up"] = json!([0, -3, -4])),
            "camera.up: must not be parallel",
        ),
        (
            Box::new(|v| v["camera"]["target"] = json!([0, 3, 4])),
            "camera.target: must differ from origin",
        ),
        (
            Box::new(|v| v["spp"] = json!(0)),
            "spp: must be >= 1, got 0",
        ),
        (
            Box::new(|v| v["integrator"] = json!({"type": "path", "max_depth": 0})),
            "integrator.max_depth: must be >= 1",
        ),
        (
            Box::new(|v| v["shapes"][1]["sdf"]["children"][0]["rounding"] = json!(2)),
            "shapes[1].sdf.children[0].rounding: must be in [0, 1], got 2",
        ),
        (
            Box::new(|v| v["shapes"][1]["sdf"]["children"][0]["half_size"] = json!([1, 0, 1])),
            "shapes[1].sdf.children[0].half_size: every component must be > 0",
        ),
        (
            Box::new(|v| v["shapes"][1]["sdf"]["children"][1]["major_radius"] = json!(0.1)),
            "shapes[1].sdf.children[1].major_radius: must be > minor_radius",
        ),
        (
            Box::new(|v| v["shapes"][1]["sdf"]["children"][2]["child"]["radius"] = json!(0)),
            "shapes[1].sdf.children[2].child.radius: must be > 0, got 0",
        ),
        (
            Box::new(|v| v["shapes"][1]["sdf"]["children"][2]["scale"] = json!(-2)),
            "shapes[1].sdf.children[2].scale: must be > 0, got -2",
        ),
        (
            Box::new(|v| v["shapes"][1]["sdf"]["children"][3]["k"] = json!(0)),
            "shapes[1].sdf.children[3].k: must be > 0, got 0",
        ),
        (
            Box::new(|v| v["shapes"][1]["sdf"]["children"] = json!([])),
            "shapes[1].sdf.children: must hold at least one node",
        ),
        (
            Box::new(|v| v["shapes"][0]["bsdf"]["albedo"] = json!([0.5, 1.5, 0.5])),
            "shapes[0].bsdf.albedo: every component must be in [0, 1]",
        ),
        (
            Box::new(|v| v["emitters"][0]["size"] = json!([1, -1])),
            "emitters[0].size[1]: must be > 0, got -1",
        ),
        (
            Box::new(|v| v["emitters"][0]["size"] = json!([1])),
            "emitters[0].size: expected an array of 2 numbers",
        ),
        (
            Box::new(|v| v["emitters"][1]["radiance"] = json!([1, -1, 1])),
            "emitters[1].radiance: every component must be >= 0",
        ),
    ];
    for (edit, expected) in cases {
        assert_contains(&error_of(base(), edit), expected);
    }
}

#[test]
fn zero_directions_are_rejected() {
    let cases: Vec<Case> = vec![
        (
            Box::new(|v| v["emitters"][0]["normal"] = json!([0, 0, 0])),
            "emitters[0].normal: must be a non-zero vector",
        ),
        (
            Box::new(|v| v["emitters"][0]["u"] = json!([0, 0, 0])),
            "emitters[0].u: must be a non-zero vector",
        ),
        (
            Box::new(|v| v["emitters"][0]["u"] = json!([0, 2, 0])),
            "emitters[0].u: must not be parallel to normal",
        ),
        (
            Box::new(|v| v["shapes"][1]["sdf"]["children"][1]["axis"] = json!([0, 0, 0])),
            "shapes[1].sdf.children[1].axis: must be a non-zero vector",
        ),
        (
            Box::new(|v| v["shapes"][1]["sdf"]["children"][2]["rotate"]["axis"] = json!([0, 0, 0])),
            "shapes[1].sdf.children[2].rotate.axis: must be a non-zero vector",
        ),
        (
            Box::new(|v| {
                v["shapes"][0]["sdf"] = json!({"type": "plane", "normal": [0, 0, 0], "offset": 1})
            }),
            "shapes[0].sdf.normal: must be a non-zero vector",
        ),
        (
            Box::new(|v| v["camera"]["up"] = json!([0, 0, 0])),
            "camera.up: must be a non-zero vector",
        ),
    ];
    for (edit, expected) in cases {
        assert_contains(&error_of(base(), edit), expected);
    }
}

#[test]
fn non_finite_and_non_numeric_values_are_named() {
    let cases: Vec<Case> = vec![
        (
            Box::new(|v| v["shapes"][0]["sdf"]["radius"] = json!("NaN")),
            "shapes[0].sdf.radius: expected a number, got string \"NaN\"",
        ),
        (
            Box::new(|v| v["shapes"][0]["sdf"]["radius"] = json!(1e39)),
            "shapes[0].sdf.radius: must be a finite number",
        ),
        (
            Box::new(|v| v["shapes"][0]["sdf"]["center"] = json!([0, -1e300, 0])),
            "shapes[0].sdf.center[1]: must be a finite number",
        ),
        (
            Box::new(|v| v["camera"]["origin"] = json!([0, null, 4])),
            "camera.origin[1]: expected a number, got null",
        ),
        (
            Box::new(|v| v["camera"]["origin"] = json!([0, 4])),
            "camera.origin: expected an array of 3 numbers, got an array of 2 elements",
        ),
        (
            Box::new(|v| v["emitters"][2]["radiance"] = json!([1, "inf", 1])),
            "emitters[2].radiance[1]: expected a number",
        ),
        (
            Box::new(|v| v["camera"]["width"] = json!("64")),
            "camera.width: expected an integer, got string \"64\"",
        ),
    ];
    for (edit, expected) in cases {
        assert_contains(&error_of(base(), edit), expected);
    }
}

#[test]
fn huge_literal_is_a_one_line_syntax_error() {
    let text = base()
        .to_string()
        .replace("\"radius\":1.0", "\"radius\":1e999");
    assert!(text.contains("1e999"));
    let e = scene::parse(&text, Path::new(".")).unwrap_err().to_string();
    assert_contains(&e, "number out of range at line 1 column");
}

#[test]
fn unknown_types_list_the_alternatives() {
    let cases: Vec<Case> = vec![
        (
            Box::new(|v| v["shapes"][0]["sdf"]["type"] = json!("spere")),
            "shapes[0].sdf.type: unknown type \"spere\", expected one of sphere, box, torus",
        ),
        (
            Box::new(|v| v["shapes"][1]["sdf"]["children"][2]["child"]["type"] = json!(3)),
            "shapes[1].sdf.children[2].child.type: expected a string, got number 3",
        ),
        (
            Box::new(|v| del(&mut v["shapes"][0]["sdf"], "type")),
            "shapes[0].sdf.type: missing, expected one of sphere",
        ),
        (
            Box::new(|v| v["shapes"][0]["bsdf"]["type"] = json!("glossy")),
            "shapes[0].bsdf.type: unknown type \"glossy\", expected one of diffuse",
        ),
        (
            Box::new(|v| v["emitters"][0]["type"] = json!("disk")),
            "emitters[0].type: unknown type \"disk\", expected one of rectangle, sphere, constant",
        ),
        (
            Box::new(|v| v["integrator"] = json!({"type": "bidir"})),
            "integrator.type: unknown type \"bidir\", expected one of direct, path",
        ),
        (
            Box::new(|v| v["camera"]["filter"] = json!("mitchell")),
            "camera.filter: unknown filter \"mitchell\", expected one of tent, gaussian, box",
        ),
    ];
    for (edit, expected) in cases {
        assert_contains(&error_of(base(), edit), expected);
    }
}

#[test]
fn unknown_and_missing_fields_are_named() {
    let cases: Vec<Case> = vec![
        (
            Box::new(|v| v["shapes"][0]["sdf"]["radus"] = json!(1)),
            "shapes[0].sdf.radus: unknown field, expected one of type, name, center, radius",
        ),
        (
            Box::new(|v| v["camera"]["fovy"] = json!(40)),
            "camera.fovy: unknown field",
        ),
        (
            Box::new(|v| v["integrator"] = json!({"type": "direct", "max_depth": 3})),
            "integrator.max_depth: unknown field",
        ),
        (Box::new(|v| v["sp"] = json!(3)), "sp: unknown field"),
        (
            Box::new(|v| del(&mut v["camera"], "fov_y")),
            "camera.fov_y: missing",
        ),
        (Box::new(|v| del(v, "camera")), "camera: missing"),
        (
            Box::new(|v| del(&mut v["shapes"][0], "name")),
            "shapes[0].name: missing",
        ),
        (
            Box::new(|v| v["shapes"] = json!({"ball": 1})),
            "shapes: expected an array, got an object",
        ),
        (
            Box::new(|v| v["shapes"][1]["sdf"]["children"][2]["rotate"]["angel"] = json!(3)),
            "shapes[1].sdf.children[2].rotate.angel: unknown field",
        ),
    ];
    for (edit, expected) in cases {
        assert_contains(&error_of(base(), edit), expected);
    }
}

#[test]
fn names_are_unique_and_well_formed() {
    let cases: Vec<Case> = vec![
        (
            Box::new(|v| v["shapes"][1]["name"] = json!("ball")),
            "shapes[1].name: duplicate name \"ball\" (already used by shapes[0].name)",
        ),
        (
            Box::new(|v| v["emitters"][1]["name"] = json!("ball")),
            "emitters[1].name: duplicate name \"ball\"",
        ),
        (
            Box::new(|v| v["shapes"][1]["sdf"]["children"][3]["name"] = json!("light")),
            "emitters[0].name: duplicate name \"light\" (already used by shapes[1].sdf.children[3].name)",
        ),
        (
            Box::new(|v| v["shapes"][0]["name"] = json!("my.ball")),
            "shapes[0].name: names must be non-empty",
        ),
        (
            Box::new(|v| v["emitters"][0]["name"] = json!("")),
            "emitters[0].name: names must be non-empty",
        ),
    ];
    for (edit, expected) in cases {
        assert_contains(&error_of(base(), edit), expected);
    }
}

#[test]
fn at_most_one_environment() {
    let e = error_of(base(), |v| {
        v["emitters"]
            .as_array_mut()
            .unwrap()
            .push(json!({"name": "sky2", "type": "constant", "radiance": [1, 1, 1]}))
    });
    assert_contains(
        &e,
        "emitters[3].type: at most one environment emitter is allowed, emitters[2] is one already",
    );
}

#[test]
fn syntax_errors_give_line_and_column() {
    let e = scene::parse("{\n  \"spp\": 3,\n  \"camera\": {,}\n}", Path::new("."))
        .unwrap_err()
        .to_string();
    assert_contains(&e, "line 3 column");
    let e = scene::parse("", Path::new(".")).unwrap_err().to_string();
    assert_contains(&e, "line 1 column 0");
    assert_contains(
        &scene::parse("[1, 2]", Path::new("."))
            .unwrap_err()
            .to_string(),
        "expected an object, got an array of 2 elements",
    );
}

#[test]
fn duplicate_keys_are_rejected() {
    let text = base()
        .to_string()
        .replace("\"radius\":1.0", "\"radius\":1.0,\"radius\":2.0");
    let e = scene::parse(&text, Path::new(".")).unwrap_err().to_string();
    assert_contains(&e, "duplicate key \"radius\" at line 1 column");
}

#[test]
fn load_names_the_file() {
    let dir = std::env::temp_dir().join(format!("psdr-scene-parse-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let missing = dir.join("missing.json");
    let e = scene::load(&missing).unwrap_err().to_string();
    assert_contains(&e, "missing.json");
    let broken = dir.join("broken.json");
    std::fs::write(&broken, "{\"spp\": }").unwrap();
    let e = scene::load(&broken).unwrap_err().to_string();
    assert_contains(&e, "broken.json: expected value at line 1 column 9");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Writes a version-1 `.npy` file with the given dtype descriptor, shape and raw little-endian data.
fn write_npy(path: &Path, descr: &str, shape: &[usize], data: &[u8]) {
    std::fs::write(path, common::npy_bytes(descr, shape, data)).unwrap();
}

fn sphere_grid_bytes(n: usize) -> Vec<u8> {
    let mut out = Vec::with_capacity(4 * n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let p = glam::Vec3::new(x as f32, y as f32, z as f32) / (n - 1) as f32 * 2.0
                    - glam::Vec3::ONE;
                out.extend_from_slice(&(p.length() - 0.5).to_le_bytes());
            }
        }
    }
    out
}

fn grid_scene(file: &str) -> Value {
    let mut v = lights_only();
    v["shapes"] = json!([{"name": "g", "sdf": {"type": "grid", "file": file,
        "bbox_min": [-1, -1, -1], "bbox_max": [1, 1, 1]},
        "bsdf": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}]);
    v
}

#[test]
fn bad_grid_files_name_field_and_file() {
    let dir = std::env::temp_dir().join(format!("psdr-grid-parse-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cases: Vec<(&str, &str, Vec<usize>, Vec<u8>)> = vec![
        ("i32.npy", "<i4", vec![4, 4, 4], vec![0u8; 4 * 64]),
        ("flat.npy", "<f4", vec![64], vec![0u8; 4 * 64]),
        ("tiny.npy", "<f4", vec![3, 3, 3], vec![0u8; 4 * 27]),
        ("short.npy", "<f4", vec![8, 8, 8], vec![0u8; 4 * 100]),
    ];
    for (name, descr, shape, data) in &cases {
        write_npy(&dir.join(name), descr, shape, data);
        let e = scene::parse(&grid_scene(name).to_string(), &dir)
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert_contains(&e, "shapes[0].sdf.file: grid file");
        assert_contains(&e, name);
    }
    let e = scene::parse(&grid_scene("nope.npy").to_string(), &dir)
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert_contains(&e, "shapes[0].sdf.file: grid file");
    assert_contains(&e, "nope.npy not found");

    let mut v = grid_scene("nope.npy");
    v["shapes"][0]["sdf"]["bbox_max"] = json!([1, -1, 1]);
    let e = scene::parse(&v.to_string(), &dir)
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert_contains(&e, "shapes[0].sdf.bbox_max: must exceed bbox_min");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn good_grid_file_loads() {
    let dir = std::env::temp_dir().join(format!("psdr-grid-good-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    write_npy(
        &dir.join("ball.npy"),
        "<f4",
        &[8, 8, 8],
        &sphere_grid_bytes(8),
    );
    let scene = scene::parse(&grid_scene("ball.npy").to_string(), &dir).unwrap();
    match &scene.shapes[0].sdf {
        Sdf::Grid {
            data,
            bbox_min,
            level,
            ..
        } => {
            assert_eq!(data.dims, [8, 8, 8]);
            assert_eq!(*bbox_min, glam::Vec3::splat(-1.0));
            assert!((data.values[0] - (3f32.sqrt() - 0.5)).abs() < 1e-6);
            assert_eq!(level.value, 0.0, "level defaults to 0");
        }
        other => panic!("expected a grid, got {other:?}"),
    }
    // An explicit iso-level; a non-number is an error naming the field.
    let mut v = grid_scene("ball.npy");
    v["shapes"][0]["sdf"]["level"] = serde_json::json!(0.25);
    let scene = scene::parse(&v.to_string(), &dir).unwrap();
    assert!(matches!(&scene.shapes[0].sdf, Sdf::Grid { level, .. } if level.value == 0.25));
    v["shapes"][0]["sdf"]["level"] = serde_json::json!("high");
    let err = scene::parse(&v.to_string(), &dir).unwrap_err().to_string();
    assert!(err.contains("level"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn example_scenes_render_lit_images() {
    // Catches scenes whose lights miss everything: the mean must be well above zero, and no pixel may
    // be non-finite. 2 spp keeps this quick; the mean over thousands of pixels is stable enough.
    for name in ["sphere_floor", "csg", "environment", "grid"] {
        let scene = scene::load(&scenes_dir().join(format!("{name}.json"))).unwrap();
        let options = implicit_psdr::integrator::RenderOptions {
            spp: 2,
            ..Default::default()
        };
        let (image, _) = implicit_psdr::integrator::render(&scene, &options);
        assert!(image.rgb.iter().all(|v| v.is_finite()), "{name}");
        let mean = image.rgb.iter().sum::<f32>() / image.rgb.len() as f32;
        assert!(mean > 0.01, "{name}: mean {mean}");
    }
}
