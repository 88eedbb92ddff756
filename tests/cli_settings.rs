//! `--set` with the settings that are not parameters (image size, spp, integrator and its depth):
//! the same image, bit for bit, as the edited file, and the file's rules and messages for bad values
//! (exit code 2, one line naming the option and the field, nothing written).

mod common;

use common::{assert_failure, assert_success, outputs, run, write_small_scene};

fn workdir(name: &str) -> std::path::PathBuf {
    common::workdir("cli-settings", name)
}

#[test]
fn settings_render_what_editing_the_file_renders() {
    let dir = workdir("same");
    write_small_scene(&dir, "scene.json", |_| {});
    write_small_scene(&dir, "edited.json", |v| {
        v["camera"]["width"] = 12.into();
        v["camera"]["height"] = 10.into();
        v["spp"] = 3.into();
        v["integrator"] = serde_json::json!({"type": "path", "max_depth": 2});
    });
    let set = [
        "--set",
        "integrator.max_depth=2",
        "--set",
        "camera.width=12",
        "--set",
        "camera.height=10",
        "--set",
        "spp=3",
        // After the depth on purpose: the integrator's type is set first.
        "--set",
        "integrator=path",
    ];
    let render = |scene: &str, out: &str, extra: &[&str]| {
        let (exr, png) = (format!("{out}.exr"), format!("{out}.png"));
        let mut args = vec!["render", scene, "--out", &exr, "--png", &png];
        args.extend(extra);
        assert_success(&run(&dir, &args))
    };
    let stdout = render("scene.json", "set", &set);
    assert!(stdout.starts_with("rendered 12x10 at 3 spp"), "{stdout}");
    render("edited.json", "edited", &[]);
    let read = |f: &str| implicit_psdr::film::read_exr(&dir.join(f)).unwrap();
    assert_eq!(read("set.exr"), read("edited.exr"));
    // A derivative command takes them too (and a parameter beside them).
    let diff = run(
        &dir,
        &[
            "diff",
            "scene.json",
            "--param",
            "ball.radius",
            "--set",
            "camera.width=8",
            "--set",
            "ball.radius=0.8",
        ],
    );
    assert!(assert_success(&diff).contains("rendered 8x16"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_settings_fail_like_the_file() {
    let dir = workdir("bad");
    write_small_scene(&dir, "scene.json", |_| {});
    for (set, expected) in [
        (
            "camera.width=0",
            "--set camera.width=0: scene.json: camera.width: must be >= 1, got 0",
        ),
        (
            "camera.height=2.5",
            "camera.height: must be an integer, got 2.5",
        ),
        (
            "camera.width=wide",
            "camera.width: expected an integer, got string \"wide\"",
        ),
        (
            "spp=-1",
            "--set spp=-1: scene.json: spp: must be >= 1, got -1",
        ),
        (
            "integrator=pth",
            "integrator.type: unknown type \"pth\", expected one of direct, path",
        ),
        (
            "integrator.max_depth=3",
            "integrator.max_depth: the direct integrator has no max_depth (set integrator to path)",
        ),
        ("camera.fov_y=abc", "\"abc\" is not a finite number"),
    ] {
        assert_failure(
            &run(&dir, &["render", "scene.json", "--set", set]),
            expected,
        );
    }
    assert_failure(
        &run(
            &dir,
            &[
                "render",
                "scene.json",
                "--set",
                "integrator=path",
                "--set",
                "max_depth=0",
            ],
        ),
        "integrator.max_depth: must be >= 1, got 0",
    );
    assert_eq!(outputs(&dir, &["scene.json"]), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).unwrap();
}
