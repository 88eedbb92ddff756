//! Bad materials in a scene file: exit code 2, one `error:` line naming the field, no output file;
//! and bad values set as parameters (`--set`) named by their parameter.

mod common;

use common::{assert_failure, outputs, run, workdir};

/// A one-shape scene whose material is `bsdf`.
fn scene(bsdf: &str) -> String {
    format!(
        r#"{{"camera": {{"origin": [0, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 40,
                        "width": 8, "height": 8}},
            "shapes": [{{"name": "ball", "sdf": {{"type": "sphere", "center": [0, 0, 0], "radius": 1}},
                         "bsdf": {bsdf}}}],
            "emitters": [{{"name": "sky", "type": "constant", "radiance": [1, 1, 1]}}]}}"#
    )
}

#[track_caller]
fn assert_render_fails(name: &str, bsdf: &str, expected: &str) {
    let dir = workdir("materials", name);
    std::fs::write(dir.join("scene.json"), scene(bsdf)).unwrap();
    let out = run(&dir, &["render", "scene.json"]);
    assert_failure(&out, expected);
    assert_eq!(outputs(&dir, &["scene.json"]), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn roughness_out_of_range() {
    for (name, alpha) in [
        ("alpha-zero", "0"),
        ("alpha-small", "0.0005"),
        ("alpha-big", "1.5"),
    ] {
        assert_render_fails(
            name,
            &format!(r#"{{"type": "roughconductor", "alpha": {alpha}}}"#),
            "shapes[0].bsdf.alpha: must be in [0.001, 1]",
        );
    }
}

#[test]
fn conductor_colours_out_of_range() {
    assert_render_fails(
        "eta",
        r#"{"type": "roughconductor", "eta": [0.2, -1, 0.3]}"#,
        "shapes[0].bsdf.eta",
    );
    assert_render_fails(
        "k",
        r#"{"type": "roughconductor", "k": [3, 2]}"#,
        "shapes[0].bsdf.k",
    );
    assert_render_fails(
        "specular",
        r#"{"type": "roughconductor", "specular_reflectance": [1.2, 1, 1]}"#,
        "shapes[0].bsdf.specular_reflectance",
    );
    assert_render_fails(
        "unknown",
        r#"{"type": "roughconductor", "roughness": 0.2}"#,
        "roughness",
    );
}

#[test]
fn blend_needs_two_materials_and_a_weight() {
    let d = r#"{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}"#;
    assert_render_fails(
        "blend-one",
        &format!(r#"{{"type": "blend", "weight": 0.5, "bsdfs": [{d}]}}"#),
        "shapes[0].bsdf.bsdfs: must hold exactly 2 nodes, got 1",
    );
    assert_render_fails(
        "blend-three",
        &format!(r#"{{"type": "blend", "weight": 0.5, "bsdfs": [{d}, {d}, {d}]}}"#),
        "shapes[0].bsdf.bsdfs: must hold exactly 2 nodes, got 3",
    );
    assert_render_fails(
        "blend-none",
        r#"{"type": "blend", "weight": 0.5}"#,
        "shapes[0].bsdf.bsdfs",
    );
    assert_render_fails(
        "blend-weight",
        &format!(r#"{{"type": "blend", "weight": 1.5, "bsdfs": [{d}, {d}]}}"#),
        "shapes[0].bsdf.weight: must be in [0, 1]",
    );
    // A bad child is named by its place in the list.
    assert_render_fails(
        "blend-child",
        &format!(
            r#"{{"type": "blend", "weight": 0.5, "bsdfs": [{d}, {{"type": "roughconductor", "alpha": 0}}]}}"#
        ),
        "shapes[0].bsdf.bsdfs[1].alpha",
    );
}

/// A parameter update out of range is refused with the parameter's name, a blend's child included.
#[test]
fn parameter_updates_are_checked() {
    let d = r#"{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}"#;
    let text = scene(&format!(
        r#"{{"type": "blend", "weight": 0.5, "bsdfs": [{d}, {{"type": "roughconductor", "alpha": 0.2}}]}}"#
    ));
    let scene = implicit_psdr::scene::parse(&text, std::path::Path::new(".")).unwrap();
    for (name, value) in [
        ("ball.weight", 1.5),
        ("ball.bsdfs.1.alpha", 0.0),
        ("ball.bsdfs.0.albedo.g", -0.1),
    ] {
        let e = scene.with_parameter(name, value).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{name}: must")), "{e}");
    }
    assert!(scene.with_parameter("ball.bsdfs.1.alpha", 0.5).is_ok());
}
