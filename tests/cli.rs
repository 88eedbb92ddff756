//! The command-line tool: bad inputs exit with code 2, a one-line `error:` naming the field, and no
//! output file; a tiny render writes both images.

mod common;

use common::{assert_failure, npy_bytes, outputs, run};
use std::path::PathBuf;

/// A fresh, empty working folder for one test.
fn workdir(name: &str) -> PathBuf {
    common::workdir("cli", name)
}

/// A tiny valid scene as JSON text, with `edit` applied to it.
fn scene(edit: impl FnOnce(&mut serde_json::Value)) -> String {
    let mut v = serde_json::json!({
        "camera": {"origin": [0, 3, 4], "target": [0, 0, 0], "up": [0, 1, 0],
                   "fov_y": 45.0, "width": 16, "height": 16},
        "spp": 4,
        "shapes": [
            {"name": "ball", "sdf": {"type": "sphere", "center": [0, 0, 0], "radius": 1.0},
             "bsdf": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}}
        ],
        "emitters": [{"name": "sky", "type": "constant", "radiance": [1, 1, 1]}]
    });
    edit(&mut v);
    v.to_string()
}

/// Runs `render scene.json` on `text` and checks for a clean failure mentioning `expected`.
#[track_caller]
fn assert_render_fails(name: &str, text: &str, extra: &[(&str, &[u8])], expected: &str) {
    let dir = workdir(name);
    std::fs::write(dir.join("scene.json"), text).unwrap();
    let mut inputs = vec!["scene.json"];
    for (file, bytes) in extra {
        std::fs::write(dir.join(file), bytes).unwrap();
        inputs.push(file);
    }
    let out = run(&dir, &["render", "scene.json"]);
    assert_failure(&out, expected);
    assert_eq!(
        outputs(&dir, &inputs),
        Vec::<String>::new(),
        "output files created"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn missing_scene_file() {
    let dir = workdir("missing");
    let out = run(&dir, &["render", "nope.json"]);
    assert_failure(&out, "error: nope.json: ");
    assert_eq!(outputs(&dir, &[]), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn malformed_json() {
    assert_render_fails(
        "malformed",
        "{\"camera\": [1, 2,}",
        &[],
        "error: scene.json: expected value at line 1 column 18",
    );
}

#[test]
fn unknown_type() {
    let text = scene(|v| v["shapes"][0]["sdf"]["type"] = "spere".into());
    assert_render_fails(
        "unknown-type",
        &text,
        &[],
        "shapes[0].sdf.type: unknown type \"spere\"",
    );
}

#[test]
fn negative_radius() {
    let text = scene(|v| v["shapes"][0]["sdf"]["radius"] = (-1.0).into());
    assert_render_fails(
        "negative-radius",
        &text,
        &[],
        "shapes[0].sdf.radius: must be > 0, got -1",
    );
}

#[test]
fn zero_size_image() {
    let text = scene(|v| v["camera"]["height"] = 0.into());
    assert_render_fails(
        "zero-size",
        &text,
        &[],
        "camera.height: must be >= 1, got 0",
    );
}

#[test]
fn non_finite_numbers() {
    let text = scene(|v| v["camera"]["fov_y"] = "NaN".into());
    assert_render_fails(
        "nan-string",
        &text,
        &[],
        "camera.fov_y: expected a number, got string \"NaN\"",
    );
    let text = scene(|v| v["shapes"][0]["sdf"]["radius"] = 1e300.into());
    assert_render_fails(
        "huge",
        &text,
        &[],
        "shapes[0].sdf.radius: must be a finite number",
    );
    let text = scene(|_| {}).replace("\"radius\":1.0", "\"radius\":1e999");
    assert_render_fails("inf-literal", &text, &[], "number out of range at line 1");
}

/// A version-1 `.npy` file with the given dtype descriptor and shape, zero-filled.
fn npy(descr: &str, shape: &[usize], item: usize) -> Vec<u8> {
    npy_bytes(
        descr,
        shape,
        &vec![0; item * shape.iter().product::<usize>()],
    )
}

#[test]
fn bad_grid_files() {
    let grid = |v: &mut serde_json::Value| {
        v["shapes"][0]["sdf"] = serde_json::json!({"type": "grid", "file": "g.npy",
            "bbox_min": [-1, -1, -1], "bbox_max": [1, 1, 1]});
    };
    let text = scene(grid);
    assert_render_fails(
        "grid-dtype",
        &text,
        &[("g.npy", &npy("<i4", &[8, 8, 8], 4))],
        "shapes[0].sdf.file: grid file",
    );
    assert_render_fails(
        "grid-shape",
        &text,
        &[("g.npy", &npy("<f4", &[8, 64], 4))],
        "g.npy",
    );
    assert_render_fails("grid-missing", &text, &[], "shapes[0].sdf.file: grid file");
}

#[test]
fn usage_errors_exit_2() {
    let dir = workdir("usage");
    assert_failure(&run(&dir, &["render"]), "<SCENE>");
    assert_failure(&run(&dir, &["render", "x.json", "--spp", "0"]), "--spp");
    assert_failure(&run(&dir, &["frobnicate"]), "frobnicate");
    assert_failure(
        &run(
            &dir,
            &[
                "bake", "x.json", "--shape", "a", "--res", "2", "--out", "g.npy",
            ],
        ),
        "--res",
    );
    let help = run(&dir, &["render", "--help"]);
    assert_eq!(help.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&help.stdout).contains("--spp"));
    assert_eq!(outputs(&dir, &[]), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn unwritable_output_fails_before_rendering() {
    let dir = workdir("unwritable");
    std::fs::write(dir.join("scene.json"), scene(|_| {})).unwrap();
    let out = run(
        &dir,
        &["render", "scene.json", "--out", "scene.json/folder/x.exr"],
    );
    assert_failure(
        &out,
        "--out scene.json/folder/x.exr: scene.json is a file, not a folder",
    );
    assert_eq!(outputs(&dir, &["scene.json"]), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bake_rejects_unknown_and_unbounded_shapes() {
    let dir = workdir("bake-bad");
    let text = scene(|v| {
        v["shapes"].as_array_mut().unwrap().push(serde_json::json!(
            {"name": "ground", "sdf": {"type": "plane", "normal": [0, 1, 0], "offset": -1},
             "bsdf": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}));
    });
    std::fs::write(dir.join("scene.json"), text).unwrap();
    let args = [
        "bake",
        "scene.json",
        "--res",
        "8",
        "--out",
        "g.npy",
        "--shape",
    ];
    let mut a = args.to_vec();
    a.push("teapot");
    assert_failure(&run(&dir, &a), "no shape named \"teapot\"");
    let mut a = args.to_vec();
    a.push("ground");
    assert_failure(&run(&dir, &a), "\"ground\" is unbounded");
    assert_eq!(outputs(&dir, &["scene.json"]), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn tiny_render_writes_both_files() {
    let dir = workdir("render-ok");
    std::fs::write(dir.join("scene.json"), scene(|_| {})).unwrap();
    let out = run(
        &dir,
        &["render", "scene.json", "--spp", "2", "--png", "img.png"],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "stderr: {stderr}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("samples/s"), "stdout: {stdout}");
    let exr = std::fs::metadata(dir.join("out.exr")).unwrap();
    let png = std::fs::read(dir.join("img.png")).unwrap();
    assert!(
        exr.len() > 16 * 16 * 3 * 4 / 8,
        "EXR too small: {} bytes",
        exr.len()
    );
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let mut names = outputs(&dir, &["scene.json"]);
    names.sort();
    assert_eq!(names, ["img.png", "out.exr"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bake_then_render_grid() {
    let dir = workdir("bake-ok");
    std::fs::write(dir.join("scene.json"), scene(|_| {})).unwrap();
    let out = run(
        &dir,
        &[
            "bake",
            "scene.json",
            "--shape",
            "ball",
            "--res",
            "16",
            "--out",
            "ball.npy",
        ],
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("\"bbox_min\": ["), "stdout: {stdout}");
    let bytes = std::fs::read(dir.join("ball.npy")).unwrap();
    assert_eq!(&bytes[..6], b"\x93NUMPY");
    let text = scene(|v| {
        v["shapes"][0]["sdf"] = serde_json::json!({"type": "grid", "file": "ball.npy",
            "bbox_min": [-1.2, -1.2, -1.2], "bbox_max": [1.2, 1.2, 1.2]});
    });
    std::fs::write(dir.join("grid.json"), text).unwrap();
    let out = run(&dir, &["render", "grid.json", "--spp", "1"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Runs the tool with `args` in `dir`, stdout a pipe whose reader takes `lines` lines (none: it is
/// closed at once) and goes away; returns the exit status and stderr.
fn run_with_reader_gone(
    dir: &std::path::Path,
    args: &[&str],
    lines: usize,
) -> (std::process::ExitStatus, String) {
    use std::io::BufRead;
    use std::process::{Command, Stdio};
    let mut child = Command::new(common::BIN)
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run implicit-psdr");
    let mut reader = std::io::BufReader::new(child.stdout.take().unwrap());
    for _ in 0..lines {
        let mut line = String::new();
        reader.read_line(&mut line).unwrap();
        assert!(!line.is_empty(), "stdout ended early");
    }
    drop(reader);
    let out = child.wait_with_output().unwrap();
    (
        out.status,
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn a_reader_that_goes_away_ends_the_report_quietly() {
    let dir = workdir("broken-pipe");
    // `params` of 3000 spheres: about 30,000 lines, far more than a pipe holds (64 KiB), so the tool
    // is still writing when the reader leaves after one line (`| head -1`).
    let text = scene(|v| {
        let ball = v["shapes"][0].clone();
        v["shapes"] = (0..3000)
            .map(|i| {
                let mut b = ball.clone();
                b["name"] = format!("ball{i}").into();
                b
            })
            .collect();
    });
    std::fs::write(dir.join("scene.json"), text).unwrap();
    let (status, stderr) = run_with_reader_gone(&dir, &["params", "scene.json"], 1);
    assert!(status.success(), "{status}; stderr: {stderr}");
    assert_eq!(stderr, "", "params");
    // A command that reports after its work: the reader is gone before it prints; the files are
    // written all the same.
    std::fs::write(dir.join("small.json"), scene(|_| {})).unwrap();
    let (status, stderr) = run_with_reader_gone(&dir, &["render", "small.json"], 0);
    assert!(status.success(), "{status}; stderr: {stderr}");
    assert_eq!(stderr, "", "render");
    assert_eq!(
        outputs(&dir, &["scene.json", "small.json"]),
        ["out.exr", "out.png"]
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
