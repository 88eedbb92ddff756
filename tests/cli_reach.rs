//! Warnings about what cannot show in the image, before rendering: a rectangle light that faces away
//! from everything the camera sees (a black image otherwise unexplained), and a shape outside the
//! camera's view; one line `warning: ...` each on stderr, and the run goes on. The example scenes
//! warn about nothing.

mod common;

use common::{assert_success, run, write_small_scene};
use serde_json::json;

fn workdir(name: &str) -> std::path::PathBuf {
    common::workdir("cli-reach", name)
}

/// The warnings of `render` of `dir/scene.json` (after checking the run succeeds).
fn warnings(dir: &std::path::Path, extra: &[&str]) -> Vec<String> {
    let mut args = vec!["render", "scene.json"];
    args.extend(extra);
    let out = run(dir, &args);
    assert_success(&out);
    String::from_utf8_lossy(&out.stderr)
        .lines()
        .map(String::from)
        .collect()
}

#[test]
fn a_light_facing_away_from_the_view_is_named() {
    let dir = workdir("light");
    // sphere_floor's light turned to face up, away from the ball, the floor and the camera; the sky
    // removed, so the image is black.
    write_small_scene(&dir, "scene.json", |v| {
        v["emitters"][0]["normal"] = json!([0, 1, 0]);
        v["emitters"].as_array_mut().unwrap().truncate(1);
    });
    let lines = warnings(&dir, &[]);
    assert_eq!(lines.len(), 1, "{lines:?}");
    assert!(
        lines[0].starts_with("warning: emitter \"light\" lights nothing the camera sees"),
        "{lines:?}"
    );
    let image = implicit_psdr::film::read_exr_rgb(&dir.join("out.exr")).unwrap();
    assert!(image.rgb.iter().all(|&v| v == 0.0), "the image is black");
    // Facing down again: it lights the ball and the floor.
    write_small_scene(&dir, "scene.json", |_| {});
    assert_eq!(warnings(&dir, &[]), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_shape_outside_the_view_is_named() {
    let dir = workdir("shape");
    write_small_scene(&dir, "scene.json", |v| {
        let mut far = v["shapes"][0].clone();
        far["name"] = "behind".into();
        far["sdf"]["center"] = json!([0, 1, 20]);
        v["shapes"].as_array_mut().unwrap().push(far);
    });
    let lines = warnings(&dir, &[]);
    assert_eq!(lines.len(), 1, "{lines:?}");
    assert!(
        lines[0].starts_with("warning: shape \"behind\" lies outside the camera's view"),
        "{lines:?}"
    );
    // Moving the camera back brings it into view: no warning.
    assert_eq!(
        warnings(
            &dir,
            &["--set", "camera.origin.z=40", "--set", "camera.origin.y=6"]
        ),
        Vec::<String>::new()
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn optimize_names_a_shape_outside_every_view() {
    let dir = workdir("optimize");
    write_small_scene(&dir, "scene.json", |v| {
        let mut far = v["shapes"][0].clone();
        far["name"] = "behind".into();
        far["sdf"]["center"] = json!([0, 1, 20]);
        v["shapes"].as_array_mut().unwrap().push(far);
    });
    let front = json!({"origin": [0, 3, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 45});
    let back = json!({"origin": [0, 6, 40], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 45});
    let stderr = |views: serde_json::Value| -> Vec<String> {
        let opt = json!({"scene": "scene.json", "target": {"scene": "scene.json"}, "views": views,
                         "optimize": {"params": ["ball.radius"]}, "iterations": 1, "spp": 1,
                         "target_spp": 1});
        std::fs::write(dir.join("opt.json"), opt.to_string()).unwrap();
        let out = run(&dir, &["optimize", "opt.json", "--out", "run"]);
        assert_success(&out);
        (String::from_utf8_lossy(&out.stderr).lines())
            .filter(|l| l.starts_with("warning:"))
            .map(String::from)
            .collect()
    };
    let lines = stderr(json!([front, front]));
    assert_eq!(lines.len(), 1, "{lines:?}");
    assert!(
        lines[0].starts_with("warning: shape \"behind\" lies outside every view"),
        "{lines:?}"
    );
    // One view that sees it is enough.
    assert_eq!(stderr(json!([front, back])), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_example_scenes_warn_about_nothing() {
    let scenes = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    for entry in std::fs::read_dir(&scenes).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "json") {
            let scene = implicit_psdr::scene::load(&path).unwrap();
            assert_eq!(
                scene.reach_warnings(),
                Vec::<String>::new(),
                "{}",
                path.display()
            );
        }
    }
}
