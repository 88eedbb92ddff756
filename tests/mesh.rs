//! Meshes out of shapes (`implicit-psdr mesh`, `mesh::extract_shape`): closed, on the surface, with
//! sharp edges kept sharp (a rotated box's mesh has its exact volume and area, and a vertex at each
//! corner), the topology of each shape (a torus has genus 1), translations carried, and the files
//! readable; bad input is refused with nothing written.

mod common;

use common::{assert_failure, assert_success, run};
use implicit_psdr::mesh::{TriangleMesh, extract_shape};
use implicit_psdr::scene::{self, Scene};
use std::path::Path;

/// A scene of one shape `sdf` (JSON), no light needed for meshing.
fn scene_of(sdf: &str) -> Scene {
    let json = format!(
        r#"{{"camera": {{"origin": [0, 0, 6], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 40,
                        "width": 8, "height": 8}},
            "integrator": {{"type": "direct"}}, "spp": 1,
            "shapes": [{{"name": "s", "sdf": {sdf}, "bsdf": {{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}}}],
            "emitters": [{{"name": "sky", "type": "constant", "radiance": [1, 1, 1]}}]}}"#
    );
    scene::parse(&json, Path::new(".")).unwrap()
}

/// Closed, of Euler characteristic `euler` (counted on a mesh whose few non-manifold edges, at most
/// one in a thousand, are each counted once), every vertex within `1e-4 ×` the box diagonal of the
/// surface, unit normals.
#[track_caller]
fn assert_good(scene: &Scene, mesh: &TriangleMesh, euler: i64) {
    let shape = &scene.shapes[0];
    assert!(mesh.faces.len() > 100, "{} faces", mesh.faces.len());
    assert_eq!(mesh.boundary_edges(), 0, "closed");
    let pinched = mesh.non_manifold_edges();
    assert!(
        pinched * 1000 <= mesh.edge_count(),
        "{pinched} non-manifold edges"
    );
    if pinched == 0 {
        assert_eq!(mesh.euler_characteristic(), euler);
    }
    let size = shape.bounds.extent().length();
    let t = shape.translate.value();
    let worst = (mesh.vertices.iter())
        .map(|v| shape.sdf.eval_f32(*v - t).abs())
        .fold(0.0f32, f32::max);
    assert!(worst <= 1e-4 * size, "a vertex is {worst} off the surface");
    for n in &mesh.normals {
        assert!((n.length() - 1.0).abs() < 1e-4, "{n}");
    }
    assert!(mesh.volume() > 0.0, "triangles face outwards");
}

const ROTATED_BOX: &str = r#"{"type": "transform", "rotate": {"axis": [0.3, 1, -0.2], "angle": 33},
    "child": {"type": "box", "center": [0, 0, 0], "half_size": [0.5, 0.3, 0.4]}}"#;

/// A rotated sharp box: exact volume and area (marching cubes would cut every edge and corner), and
/// a vertex on each corner.
#[test]
fn a_rotated_box_keeps_its_edges_and_corners() {
    let scene = scene_of(ROTATED_BOX);
    let mesh = extract_shape(&scene.shapes[0], 64).unwrap();
    assert_good(&scene, &mesh, 2);
    let (volume, area) = (mesh.volume(), mesh.area());
    let (exact_volume, exact_area) = (0.48, 2.0 * (0.6 + 0.8 + 0.48));
    println!("box: volume {volume} ({exact_volume}), area {area} ({exact_area})");
    assert!(
        (volume / exact_volume - 1.0).abs() < 2e-3,
        "volume {volume}"
    );
    assert!((area / exact_area - 1.0).abs() < 2e-3, "area {area}");
    let rotate = glam::Quat::from_axis_angle(
        glam::Vec3::new(0.3, 1.0, -0.2).normalize(),
        33f32.to_radians(),
    );
    let cell = 1.3 / 63.0;
    let mut distances = Vec::new();
    for corner in 0..8 {
        let local = glam::Vec3::new(
            if corner & 1 == 0 { -0.5 } else { 0.5 },
            if corner & 2 == 0 { -0.3 } else { 0.3 },
            if corner & 4 == 0 { -0.4 } else { 0.4 },
        );
        let c = rotate * local;
        let nearest = (mesh.vertices.iter())
            .map(|v| v.distance(c))
            .fold(f32::INFINITY, f32::min);
        distances.push(nearest / cell);
    }
    println!("corners: nearest vertex / cell {distances:?}");
    // A corner's cell whose edges meet only two of its faces places its vertex on the edge, off the
    // corner (measured: 0.066 of a cell for two corners); the others are on their corners to rounding.
    distances.sort_by(f32::total_cmp);
    assert!(distances[7] < 0.1, "{distances:?}");
    assert!(distances[3] < 1e-3, "{distances:?}");
}

/// Other topologies and creases: a torus (genus 1), a sharp cylinder (two circular rims), a hard
/// difference (a box with a spherical bite), a smooth union, each closed and on its surface.
#[test]
fn tori_cylinders_and_csg_are_closed_and_on_their_surfaces() {
    for (sdf, euler) in [
        (
            r#"{"type": "torus", "center": [0, 0, 0], "axis": [0.2, 1, 0.1], "major_radius": 0.7, "minor_radius": 0.2}"#,
            0,
        ),
        (
            r#"{"type": "cylinder", "center": [0, 0, 0], "axis": [1, 0.5, 0], "radius": 0.4, "half_height": 0.6}"#,
            2,
        ),
        (
            r#"{"type": "difference", "children": [
                {"type": "box", "center": [0, 0, 0], "half_size": [0.6, 0.6, 0.6]},
                {"type": "sphere", "center": [0.5, 0.5, 0.5], "radius": 0.6}]}"#,
            2,
        ),
        (
            r#"{"type": "smooth_union", "k": 0.3, "children": [
                {"type": "sphere", "center": [-0.4, 0, 0], "radius": 0.5},
                {"type": "sphere", "center": [0.4, 0, 0], "radius": 0.4}]}"#,
            2,
        ),
    ] {
        let scene = scene_of(sdf);
        let mesh = extract_shape(&scene.shapes[0], 48).unwrap();
        assert_good(&scene, &mesh, euler);
    }
    // The cylinder's volume is exact to the contouring's accuracy: its rims stay sharp.
    let cylinder = scene_of(
        r#"{"type": "cylinder", "center": [0, 0, 0], "axis": [1, 0.5, 0], "radius": 0.4, "half_height": 0.6}"#,
    );
    let volume = extract_shape(&cylinder.shapes[0], 96).unwrap().volume();
    let exact = std::f64::consts::PI * 0.16 * 1.2;
    assert!((volume / exact - 1.0).abs() < 3e-3, "{volume} vs {exact}");
}

/// A shape's translation moves its mesh and nothing else; an unbounded shape has no mesh.
#[test]
fn translations_carry_and_planes_are_refused() {
    let scene = scene_of(ROTATED_BOX);
    let mut moved = scene.clone();
    moved = moved.with_parameter("s.translate.x", 1e3).unwrap();
    let (a, b) = (
        extract_shape(&scene.shapes[0], 24).unwrap(),
        extract_shape(&moved.shapes[0], 24).unwrap(),
    );
    assert_eq!(a.faces, b.faces);
    for (p, q) in a.vertices.iter().zip(&b.vertices) {
        assert!((*q - *p - glam::Vec3::X * 1e3).length() < 1e-3 * 1e3 * f32::EPSILON * 64.0);
    }
    let plane = scene_of(r#"{"type": "plane", "normal": [0, 1, 0], "offset": 0}"#);
    let e = extract_shape(&plane.shapes[0], 24).unwrap_err().to_string();
    assert!(e.contains("unbounded"), "{e}");
}

/// The command writes a binary PLY whose header and sizes match the mesh, and an OBJ; bad input
/// (an unbounded shape, an unknown shape, another extension) fails with one line and writes nothing.
#[test]
fn the_mesh_command_writes_ply_and_obj() {
    let dir = common::workdir("mesh", "command");
    let scene = dir.join("scene.json");
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/blocks.json"),
        &scene,
    )
    .unwrap();
    let out = run(
        &dir,
        &["mesh", "scene.json", "--shape", "can", "--res", "32"],
    );
    assert_success(&out);
    let ply = std::fs::read(dir.join("can.ply")).unwrap();
    let end = b"end_header\n";
    let at = ply.windows(end.len()).position(|w| w == end).unwrap() + end.len();
    let header = String::from_utf8_lossy(&ply[..at]).to_string();
    assert!(
        header.starts_with("ply\nformat binary_little_endian 1.0\n"),
        "{header}"
    );
    let count = |element: &str| -> usize {
        let line = header.lines().find(|l| l.starts_with(element)).unwrap();
        line.rsplit(' ').next().unwrap().parse().unwrap()
    };
    let (vertices, faces) = (count("element vertex"), count("element face"));
    assert_eq!(ply.len() - at, vertices * 24 + faces * 13);
    let loaded = scene::load(&scene).unwrap();
    let can = loaded.shape_named("can").unwrap();
    let mesh = extract_shape(can, 32).unwrap();
    assert_eq!((vertices, faces), (mesh.vertices.len(), mesh.faces.len()));

    let out = run(
        &dir,
        &[
            "mesh",
            "scene.json",
            "--shape",
            "can",
            "--res",
            "16",
            "--out",
            "r.obj",
        ],
    );
    assert_success(&out);
    let obj = std::fs::read_to_string(dir.join("r.obj")).unwrap();
    let small = extract_shape(can, 16).unwrap();
    assert_eq!(
        obj.lines().filter(|l| l.starts_with("v ")).count(),
        small.vertices.len()
    );
    assert_eq!(
        obj.lines().filter(|l| l.starts_with("f ")).count(),
        small.faces.len()
    );

    for (args, says) in [
        (&["--shape", "floor", "--out", "f.ply"][..], "unbounded"),
        (&["--shape", "nothing", "--out", "n.ply"][..], "nothing"),
        (&["--shape", "can", "--out", "c.stl"][..], ".ply or .obj"),
    ] {
        let mut full = vec!["mesh", "scene.json"];
        full.extend_from_slice(args);
        let out = run(&dir, &full);
        assert_failure(&out, says);
        assert!(!dir.join(args[3]).exists());
    }
}
