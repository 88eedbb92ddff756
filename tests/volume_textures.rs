//! Volume textures in materials: a constant texture renders exactly as the constant field, the
//! trilinear lookup hits its samples on the box's faces and clamps outside, in the shape's frame;
//! texel derivatives agree between reverse mode, forward mode and finite differences; bad texture
//! files fail cleanly on the command line.

mod common;

use common::{assert_failure, assert_success, npy_bytes, run};
use implicit_psdr::bsdf::Volume;
use implicit_psdr::film::Image;
use implicit_psdr::integrator::{
    self, DiffOptions, GradientLayout, Normalization, RenderOptions, render_gradient,
};
use implicit_psdr::math::Vec3;
use implicit_psdr::scene::{self, GridDirection, Scene};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Image size of the test scenes.
const SIZE: u32 = 16;
/// The texture's `.npy` shape: three different sizes, so that a transposed layout shows.
const SHAPE: [usize; 4] = [2, 3, 4, 3];

fn workdir(name: &str) -> PathBuf {
    common::workdir("volume-textures", name)
}

/// A float32 `.npy` of shape `shape` holding `values`.
fn npy_f32(shape: &[usize], values: &[f32]) -> Vec<u8> {
    let data: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    npy_bytes("<f4", shape, &data)
}

/// Distinct texel values in `[0.2, 0.9]`.
fn texels(n: usize) -> Vec<f32> {
    (0..n)
        .map(|i| 0.2 + 0.7 * ((i * 7919) % 97) as f32 / 96.0)
        .collect()
}

/// `scenes/sphere_floor.json` at `SIZE`², with the ball's material `bsdf` (a JSON value).
fn scene_doc(bsdf: Value, integrator: Value) -> Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/sphere_floor.json");
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    v["camera"]["width"] = SIZE.into();
    v["camera"]["height"] = SIZE.into();
    v["integrator"] = integrator;
    v["shapes"][0]["bsdf"] = bsdf;
    v
}

/// A volume texture named `name` over the ball's box, read from `file`.
fn volume(name: &str, file: &str) -> Value {
    json!({"type": "volume", "name": name, "file": file,
           "bbox_min": [-1, -1, -1], "bbox_max": [1, 1, 1]})
}

fn parse(doc: &Value, dir: &Path) -> Scene {
    scene::parse(&doc.to_string(), dir).unwrap()
}

fn render_options(spp: u32, seed: u64) -> RenderOptions {
    RenderOptions {
        spp,
        seed,
        ..RenderOptions::default()
    }
}

fn bits(image: &Image) -> Vec<u32> {
    image.rgb.iter().map(|v| v.to_bits()).collect()
}

/// A texture whose texels all hold the constant gives the image, and the derivative images of a
/// geometric parameter, of the constant field bit for bit: for each textured field of each material.
#[test]
fn a_constant_texture_renders_as_the_constant_field() {
    let dir = workdir("constant");
    let cases: [(Value, &str, Vec<usize>, f32); 4] = [
        (
            json!({"type": "diffuse", "albedo": [0.7, 0.7, 0.7]}),
            "albedo",
            vec![2, 3, 4, 3],
            0.7,
        ),
        (
            json!({"type": "roughconductor", "alpha": 0.3, "specular_reflectance": [0.6, 0.6, 0.6]}),
            "alpha",
            vec![2, 3, 4],
            0.3,
        ),
        (
            json!({"type": "roughconductor", "alpha": 0.3, "specular_reflectance": [0.6, 0.6, 0.6]}),
            "specular_reflectance",
            vec![3, 2, 2, 3],
            0.6,
        ),
        (
            json!({"type": "blend", "weight": 0.4, "bsdfs": [
                {"type": "diffuse", "albedo": [0.7, 0.5, 0.3]},
                {"type": "roughconductor", "alpha": 0.2}]}),
            "weight",
            vec![2, 2, 5],
            0.4,
        ),
    ];
    for (k, (bsdf, key, shape, value)) in cases.into_iter().enumerate() {
        let file = format!("c{k}.npy");
        let n: usize = shape.iter().product();
        std::fs::write(dir.join(&file), npy_f32(&shape, &vec![value; n])).unwrap();
        let mut textured = bsdf.clone();
        textured[key] = volume(&format!("paint{k}"), &file);
        for integrator in [
            json!({"type": "direct"}),
            json!({"type": "path", "max_depth": 3}),
        ] {
            let plain = parse(&scene_doc(bsdf.clone(), integrator.clone()), &dir);
            let tex = parse(&scene_doc(textured.clone(), integrator.clone()), &dir);
            let options = render_options(4, 7);
            let (a, _) = integrator::render(&plain, &options);
            let (b, _) = integrator::render(&tex, &options);
            assert!(bits(&a) == bits(&b), "{key} ({integrator}): images differ");
            let diff = DiffOptions {
                render: options,
                ..DiffOptions::default()
            };
            let da = integrator::render_derivatives(
                &plain,
                &plain.select(&["ball.radius"]).unwrap(),
                &diff,
            )
            .unwrap();
            let db =
                integrator::render_derivatives(&tex, &tex.select(&["ball.radius"]).unwrap(), &diff)
                    .unwrap();
            for (x, y) in da.total().iter().zip(db.total().iter()) {
                assert!(
                    bits(x) == bits(y),
                    "{key} ({integrator}): derivatives differ"
                );
            }
        }
    }
}

/// `f(x, y, z) = 0.2 + 0.1 x + 0.1 y + 0.05 z` (in `[0.2, 0.725]` over the box below): trilinear
/// interpolation reproduces it.
fn linear(p: glam::Vec3) -> f32 {
    0.2 + 0.1 * p.x + 0.1 * p.y + 0.05 * p.z
}

/// The trilinear lookup: the first and last samples sit on the box's faces, a linear field is
/// reproduced between them, a point outside reads the nearest face point, and a colour texture's
/// channels are the three interleaved values of each texel.
#[test]
fn trilinear_lookup_at_known_points() {
    let (lo, hi) = (
        glam::Vec3::new(-1.0, 0.0, 2.0),
        glam::Vec3::new(1.0, 3.0, 2.5),
    );
    let dims = [4usize, 3, 2]; // nx, ny, nz
    let at = |x: usize, y: usize, z: usize| {
        let t = glam::Vec3::new(
            x as f32 / (dims[0] - 1) as f32,
            y as f32 / (dims[1] - 1) as f32,
            z as f32 / (dims[2] - 1) as f32,
        );
        lo + (hi - lo) * t
    };
    let mut values = Vec::new();
    let mut colours = Vec::new();
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let v = linear(at(x, y, z));
                values.push(v);
                colours.extend([v, 1.0 - v, 0.5 * v]);
            }
        }
    }
    let scalar =
        Volume::from_array("s", &[2, 3, 4], values.clone(), 1, (0.0, 1.0), [lo, hi]).unwrap();
    let colour = Volume::from_array("c", &[2, 3, 4, 3], colours, 3, (0.0, 1.0), [lo, hi]).unwrap();
    let read = |p: glam::Vec3| scalar.number::<f32>(Vec3::constant(p));
    // Samples on the corners and faces: exactly the texel.
    assert_eq!(read(lo), values[0]);
    assert_eq!(read(hi), *values.last().unwrap());
    assert_eq!(read(at(3, 0, 0)), values[3]);
    assert_eq!(read(at(0, 2, 1)), values[(3) * 4 + 2 * 4]);
    // Between samples: the linear field, to rounding.
    for p in [
        glam::Vec3::new(0.1, 1.7, 2.2),
        glam::Vec3::new(-0.9, 0.3, 2.45),
        glam::Vec3::new(0.95, 2.9, 2.01),
    ] {
        assert!(
            (read(p) - linear(p)).abs() < 1e-6,
            "{p}: {} vs {}",
            read(p),
            linear(p)
        );
        let c = colour.color::<f32>(Vec3::constant(p)).primal();
        let want = glam::Vec3::new(linear(p), 1.0 - linear(p), 0.5 * linear(p));
        assert!((c - want).abs().max_element() < 1e-6, "{p}: {c} vs {want}");
    }
    // Outside: the value at the nearest point of the box.
    for p in [
        glam::Vec3::new(-5.0, 1.0, 2.2),
        glam::Vec3::new(3.0, -2.0, 9.0),
        glam::Vec3::new(0.3, 7.0, 2.3),
    ] {
        let q = p.clamp(lo, hi);
        assert_eq!(read(p), read(q), "{p}");
    }
}

/// In a shape whose sdf is a transform (translated, rotated, scaled) and which is translated itself,
/// the texture is read at the point mapped back through both: the world image of a frame point reads
/// the frame point's texel.
#[test]
fn the_texture_is_read_in_the_shapes_frame() {
    let dir = workdir("frame");
    let n = 2 * 3 * 4 * 3;
    let values = texels(n);
    std::fs::write(dir.join("paint.npy"), npy_f32(&SHAPE, &values)).unwrap();
    let mut doc = scene_doc(
        json!({"type": "diffuse", "albedo": volume("paint", "paint.npy")}),
        json!({"type": "direct"}),
    );
    doc["shapes"][0]["translate"] = json!([0.2, -0.1, 0.3]);
    doc["shapes"][0]["sdf"] = json!({"type": "transform", "translate": [0.5, 0.25, -0.5],
        "rotate": {"axis": [0, 0, 1], "angle": 90}, "scale": 2.0,
        "child": {"type": "sphere", "center": [0, 0, 0], "radius": 0.5}});
    let scene = parse(&doc, &dir);
    let shape = &scene.shapes[0];
    // Frame point (x, y, z) → rotate 90° about z: (−y, x, z) → ×2 → + (0.5, 0.25, −0.5) → + translate.
    let frame = glam::Vec3::new(0.3, -0.6, 0.8);
    let world = glam::Vec3::new(-frame.y, frame.x, frame.z) * 2.0
        + glam::Vec3::new(0.5, 0.25, -0.5)
        + glam::Vec3::new(0.2, -0.1, 0.3);
    let mapped = shape.material_point::<f32>(Vec3::constant(world)).primal();
    assert!(
        (mapped - frame).abs().max_element() < 1e-5,
        "{mapped} vs {frame}"
    );
    // The material's albedo there is the texture's: a diffuse f is albedo / π.
    let volume = &shape.textures[0].volume;
    let want = volume.color::<f32>(Vec3::constant(frame)).primal() / std::f32::consts::PI;
    let n_ = Vec3::constant(glam::Vec3::Z);
    let f = shape
        .bsdf_eval::<f32>(Vec3::constant(world), n_, n_, n_)
        .primal();
    assert!((f - want).abs().max_element() < 1e-6, "{f} vs {want}");
}

/// The textured test scene: the ball's albedo a 2×3×4 colour texture of distinct texels.
fn textured_scene(dir: &Path, integrator: Value) -> Scene {
    std::fs::write(dir.join("paint.npy"), npy_f32(&SHAPE, &texels(72))).unwrap();
    let doc = scene_doc(
        json!({"type": "diffuse", "albedo": volume("paint", "paint.npy")}),
        integrator,
    );
    parse(&doc, dir)
}

/// A fixed pixel adjoint (a ramp of both signs).
fn adjoint() -> Image {
    let n = (SIZE * SIZE * 3) as usize;
    Image {
        width: SIZE,
        height: SIZE,
        rgb: (0..n).map(|i| ((i * 31) % 17) as f32 / 8.0 - 1.0).collect(),
    }
}

fn dot(g: &Image, image: &Image) -> f64 {
    (g.rgb.iter().zip(&image.rgb))
        .map(|(a, b)| *a as f64 * *b as f64)
        .sum()
}

/// `Σ g · I` with the texels `values`, seed `seed`.
fn weighted(scene: &Scene, values: Vec<f32>, spp: u32, seed: u64) -> f64 {
    let mut s = scene.clone();
    s.set_block_values("paint", values).unwrap();
    dot(
        &adjoint(),
        &integrator::render(&s, &render_options(spp, seed)).0,
    )
}

/// Reverse mode: the gradient of `Σ g · I` with respect to the texels against central differences of
/// the same loss with common random numbers (with `direct`, `I` is linear in the albedo, so the two
/// agree to rounding), and forward mode along a direction `u` equals `gradient · u`.
#[test]
fn texel_gradients_match_finite_differences_and_forward_mode() {
    let dir = workdir("gradient");
    let scene = textured_scene(&dir, json!({"type": "direct"}));
    let (spp, seed) = (4, 11);
    let options = DiffOptions {
        render: render_options(spp, seed),
        normalization: Normalization::Fixed,
        ..DiffOptions::default()
    };
    let layout = GradientLayout::select(&scene, &[], &["paint".to_string()]).unwrap();
    assert_eq!(layout.entries, 72);
    let g = render_gradient(&scene, &layout, &adjoint(), &options)
        .unwrap()
        .total();
    assert!(g.iter().all(|v| v.is_finite()));
    let values = texels(72);
    let h = 0.05;
    let mut checked = 0;
    for k in (0..72).step_by(5) {
        let (mut up, mut down) = (values.clone(), values.clone());
        up[k] += h;
        down[k] -= h;
        let fd = (weighted(&scene, up, spp, seed) - weighted(&scene, down, spp, seed))
            / (2.0 * h as f64);
        let tol = 1e-3 * fd.abs().max(1e-2);
        assert!(
            (g[k] - fd).abs() <= tol,
            "texel {k}: reverse {} vs fd {fd}",
            g[k]
        );
        checked += (fd.abs() > 1e-3) as usize;
    }
    assert!(checked >= 5, "only {checked} texels are seen");

    // Forward mode along u: Σ g · dI/du = gradient · u.
    let u: Vec<f32> = (0..72).map(|i| ((i * 13) % 7) as f32 / 3.0 - 1.0).collect();
    let direction = GridDirection {
        node: "paint.values".into(),
        shape: SHAPE.to_vec(),
        values: Arc::new(u.clone()),
        source: "u".into(),
    };
    let selection = scene
        .select_with_grid_directions::<&str>(&[], &[direction])
        .unwrap();
    assert_eq!(selection.names(), ["paint.values"]);
    let forward = integrator::render_derivatives(&scene, &selection, &options).unwrap();
    let along = dot(&adjoint(), &forward.total()[0]);
    let predicted: f64 = g.iter().zip(&u).map(|(a, b)| a * *b as f64).sum();
    assert!(
        (along - predicted).abs() <= 1e-4 * predicted.abs().max(1e-3),
        "forward {along} vs reverse · u {predicted}"
    );
}

/// The derivative image along a texel direction against central differences with common random
/// numbers, for `direct` and `path` (where light bounces off the textured ball more than once, so the
/// image is not linear in the albedo).
#[test]
fn derivative_images_along_a_texel_direction_match_finite_differences() {
    for (name, integrator) in [
        ("direct", json!({"type": "direct"})),
        ("path", json!({"type": "path", "max_depth": 4})),
    ] {
        let dir = workdir(&format!("images-{name}"));
        let scene = textured_scene(&dir, integrator);
        let u: Vec<f32> = (0..72).map(|i| ((i * 5) % 9) as f32 / 8.0 - 0.5).collect();
        let direction = GridDirection {
            node: "paint".into(),
            shape: SHAPE.to_vec(),
            values: Arc::new(u.clone()),
            source: "u".into(),
        };
        let selection = scene
            .select_with_grid_directions::<&str>(&[], &[direction])
            .unwrap();
        let (spp, seed) = (8, 5);
        let options = DiffOptions {
            render: render_options(spp, seed),
            ..DiffOptions::default()
        };
        let d = integrator::render_derivatives(&scene, &selection, &options)
            .unwrap()
            .total()
            .remove(0);
        let h = 0.1f32;
        let shifted = |sign: f32| {
            let values = (texels(72).iter().zip(&u))
                .map(|(v, du)| v + sign * h * du)
                .collect();
            let mut s = scene.clone();
            s.set_block_values("paint", values).unwrap();
            integrator::render(&s, &render_options(spp, seed)).0
        };
        let (up, down) = (shifted(1.0), shifted(-1.0));
        let fd: Vec<f64> = (up.rgb.iter().zip(&down.rgb))
            .map(|(a, b)| (*a as f64 - *b as f64) / (2.0 * h as f64))
            .collect();
        let d: Vec<f64> = d.rgb.iter().map(|v| *v as f64).collect();
        assert!(d.iter().all(|v| v.is_finite()));
        let norm = fd.iter().map(|v| v * v).sum::<f64>().sqrt();
        let err = d
            .iter()
            .zip(&fd)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(norm > 1e-2, "{name}: the texture does not show ({norm})");
        // Common random numbers: the only differences are float rounding and, for `path`, the
        // O(h²) curvature of the image in the albedo.
        assert!(
            err <= 2e-3 * norm,
            "{name}: |d − fd| = {err}, |fd| = {norm}"
        );
    }
}

/// Bad texture files: exit code 2, one line naming the field and the file, nothing written.
#[test]
fn bad_texture_files_fail_cleanly() {
    let dir = workdir("bad");
    std::fs::write(dir.join("rgb.npy"), npy_f32(&SHAPE, &texels(72))).unwrap();
    std::fs::write(dir.join("hot.npy"), npy_f32(&SHAPE, &[1.5; 72])).unwrap();
    let cases: [(&str, Value, &str); 4] = [
        // A colour array for a scalar field.
        (
            "shape",
            json!({"type": "roughconductor", "alpha": volume("rough", "rgb.npy")}),
            "shapes[0].bsdf.alpha: volume file",
        ),
        (
            "range",
            json!({"type": "diffuse", "albedo": volume("paint", "hot.npy")}),
            "shapes[0].bsdf.albedo: volume file",
        ),
        (
            "missing",
            json!({"type": "diffuse", "albedo": volume("paint", "nowhere.npy")}),
            "shapes[0].bsdf.albedo: volume file",
        ),
        (
            "weight",
            json!({"type": "blend", "weight": volume("w", "rgb.npy"), "bsdfs": [
                {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]},
                {"type": "diffuse", "albedo": [0.1, 0.1, 0.1]}]}),
            "shapes[0].bsdf.weight: volume file",
        ),
    ];
    for (name, bsdf, expected) in cases {
        let file = format!("{name}.json");
        let doc = scene_doc(bsdf, json!({"type": "direct"}));
        std::fs::write(dir.join(&file), doc.to_string()).unwrap();
        let out = run(&dir, &["render", &file, "--out", "o.exr", "--png", "o.png"]);
        assert_failure(&out, expected);
        let stderr = String::from_utf8_lossy(&out.stderr);
        let npy = match name {
            "range" => "hot.npy",
            "missing" => "nowhere.npy",
            _ => "rgb.npy",
        };
        assert!(stderr.contains(npy), "{name}: {stderr}");
        assert!(!dir.join("o.exr").exists() && !dir.join("o.png").exists());
    }
}

/// `params` lists the texels as one block and hides the field's constant; `grad --grid` writes their
/// gradient as a `.npy` of the block's shape; `diff --grid-direction` takes a direction of that shape.
#[test]
fn the_command_line_names_the_block() {
    let dir = workdir("cli");
    let scene = textured_scene(&dir, json!({"type": "direct"}));
    let doc = scene_doc(
        json!({"type": "diffuse", "albedo": volume("paint", "paint.npy")}),
        json!({"type": "direct"}),
    );
    drop(scene);
    std::fs::write(dir.join("scene.json"), doc.to_string()).unwrap();
    let listing = assert_success(&run(&dir, &["params", "scene.json"]));
    assert!(
        listing.contains("paint.values [2, 3, 4, 3] (72 values; select with --grid paint"),
        "{listing}"
    );
    assert!(!listing.contains("ball.albedo"), "{listing}");
    assert_success(&run(
        &dir,
        &[
            "render",
            "scene.json",
            "--out",
            "t.exr",
            "--png",
            "t.png",
            "--spp",
            "2",
        ],
    ));
    let out = assert_success(&run(
        &dir,
        &[
            "grad",
            "scene.json",
            "--target",
            "t.exr",
            "--grid",
            "paint",
            "--spp",
            "2",
        ],
    ));
    assert!(out.contains("72 values of 1 volume texture"), "{out}");
    let g = implicit_psdr::io::read_npy_array(&dir.join("grad.paint.values.npy")).unwrap();
    assert_eq!(g.shape, SHAPE.to_vec());
    std::fs::write(dir.join("u.npy"), npy_f32(&SHAPE, &[1.0; 72])).unwrap();
    assert_success(&run(
        &dir,
        &[
            "diff",
            "scene.json",
            "--grid-direction",
            "paint=u.npy",
            "--spp",
            "2",
        ],
    ));
    // A direction of another shape names its file.
    std::fs::write(dir.join("bad.npy"), npy_f32(&[2, 3, 4], &[1.0; 24])).unwrap();
    let out = run(
        &dir,
        &["diff", "scene.json", "--grid-direction", "paint=bad.npy"],
    );
    assert_failure(&out, "bad.npy");
}

/// A tiny `optimize` run fits a ball's albedo texture to images of a painted ball: the texels end
/// near the truth (a mean error under a third of the start's), and result.json names the fitted texels' `.npy` (of the texture's shape, in
/// range) in the texture's `file`.
#[test]
fn optimize_recovers_an_albedo_texture() {
    let dir = workdir("optimize");
    let corner = |i: usize| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32];
    let target: Vec<f32> = (0..8)
        .flat_map(|i| corner(i).map(|c| 0.15 + 0.7 * c))
        .collect();
    std::fs::write(dir.join("target.npy"), npy_f32(&[2, 2, 2, 3], &target)).unwrap();
    std::fs::write(dir.join("start.npy"), npy_f32(&[2, 2, 2, 3], &[0.5; 24])).unwrap();
    for (name, file) in [("target", "target.npy"), ("start", "start.npy")] {
        let mut doc = scene_doc(
            json!({"type": "diffuse", "albedo": volume("paint", file)}),
            json!({"type": "direct"}),
        );
        doc["emitters"]
            .as_array_mut()
            .unwrap()
            .push(json!({"name": "sky", "type": "constant", "radiance": [0.5, 0.5, 0.5]}));
        std::fs::write(dir.join(format!("{name}.json")), doc.to_string()).unwrap();
    }
    let opt = json!({
        "scene": "start.json",
        "target": {"scene": "target.json"},
        "views": {"orbit": {"count": 3, "radius": 4, "height": 1.5, "fov_y": 40}},
        "optimize": {"grids": ["paint"]},
        "iterations": 25,
        "spp": 4,
        "learning_rate": {"grids": 0.05, "params": 0.01},
        // A constant rate: 25 steps of a cosine decay travel about half as far.
        "learning_rate_decay": "none",
        "target_spp": 32,
        "seed": 0
    });
    std::fs::write(dir.join("opt.json"), opt.to_string()).unwrap();
    assert_success(&run(&dir, &["optimize", "opt.json", "--out", "out"]));
    let progress = std::fs::read_to_string(dir.join("out/progress.csv")).unwrap();
    let mut lines = progress.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let column = header.iter().position(|h| *h == "loss").unwrap();
    let losses: Vec<f64> = lines
        .map(|l| l.split(',').nth(column).unwrap().parse().unwrap())
        .collect();
    assert_eq!(losses.len(), 25);
    let (first, last) = (losses[0], losses[losses.len() - 1]);
    // The loss keeps the noise of 4-spp renders against 32-spp targets: it falls, but the texels
    // tell how well the texture is recovered.
    assert!(last < 0.8 * first, "loss {first} -> {last}");
    let result: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/result.json")).unwrap())
            .unwrap();
    assert_eq!(result["shapes"][0]["bsdf"]["albedo"]["file"], "paint.npy");
    let fitted = implicit_psdr::io::read_npy_array(&dir.join("out/paint.npy")).unwrap();
    assert_eq!(fitted.shape, [2, 2, 2, 3]);
    assert!(fitted.values.iter().all(|v| (0.0..=1.0).contains(v)));
    // Every texel starts 0.35 from the truth (0.5 against 0.15 or 0.85).
    let errors: Vec<f32> = (fitted.values.iter().zip(&target))
        .map(|(a, b)| (a - b).abs())
        .collect();
    let mean = errors.iter().sum::<f32>() / errors.len() as f32;
    let worst = errors.iter().copied().fold(0.0, f32::max);
    assert!(
        mean < 0.1 && worst < 0.25,
        "texel error: mean {mean}, worst {worst}"
    );
    // The fitted scene loads (its texture in range) from the output folder.
    scene::load(&dir.join("out/result.json")).unwrap();
}
