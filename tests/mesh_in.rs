//! Meshes in (`io::read_mesh`, `mesh::bake_mesh`, `implicit-psdr bake --mesh`): every format reads the
//! same cube; a closed mesh's baked grid is its exact signed distance (a box's, in closed form); open,
//! doubled, flipped and multi-part meshes get a sensible inside; bad files are refused with one line
//! naming the file, exit code 2 and nothing written.

mod common;

use common::{assert_failure, assert_success, outputs, run, workdir};
use glam::Vec3;
use implicit_psdr::io::{read_mesh, read_npy};
use implicit_psdr::mesh::shapes::{cuboid, uv_sphere};
use implicit_psdr::mesh::{MeshSdf, bake_mesh};
use implicit_psdr::sdf::bake_dims;

/// The corners and quads of the box `[0, 1] × [0, 2] × [0, 3]`, facing outwards.
fn box_corners() -> (Vec<[f32; 3]>, Vec<[usize; 4]>) {
    let m = cuboid(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0));
    let v = m.vertices.iter().map(|v| v.to_array()).collect();
    let quads = (m.faces.chunks(2))
        .map(|t| [t[0][0], t[0][1], t[0][2], t[1][2]].map(|i| i as usize))
        .collect();
    (v, quads)
}

fn obj_text() -> String {
    let (v, q) = box_corners();
    let mut s = String::from("# a box\no box\n");
    for p in &v {
        s += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    for f in &q {
        s += &format!("f {} {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1, f[3] + 1);
    }
    s
}

fn off_text() -> String {
    let (v, q) = box_corners();
    let mut s = format!("OFF\n# comment\n{} {} 0\n", v.len(), q.len());
    for p in &v {
        s += &format!("{} {} {}\n", p[0], p[1], p[2]);
    }
    for f in &q {
        s += &format!("4 {} {} {} {}\n", f[0], f[1], f[2], f[3]);
    }
    s
}

fn ply_ascii() -> String {
    let (v, q) = box_corners();
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
         property float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        v.len(),
        q.len()
    );
    for p in &v {
        s += &format!("{} {} {}\n", p[0], p[1], p[2]);
    }
    for f in &q {
        s += &format!("4 {} {} {} {}\n", f[0], f[1], f[2], f[3]);
    }
    s
}

/// Binary PLY with double coordinates and `vertex_index` as unsigned ints.
fn ply_binary() -> Vec<u8> {
    let (v, q) = box_corners();
    let mut b = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty double x\n\
         property double y\nproperty double z\nelement face {}\n\
         property list uchar uint vertex_index\nend_header\n",
        v.len(),
        q.len()
    )
    .into_bytes();
    for p in &v {
        for x in p {
            b.extend_from_slice(&(*x as f64).to_le_bytes());
        }
    }
    for f in &q {
        b.push(4);
        for i in f {
            b.extend_from_slice(&(*i as u32).to_le_bytes());
        }
    }
    b
}

fn triangles() -> Vec<[[f32; 3]; 3]> {
    let m = cuboid(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0));
    (m.faces.iter())
        .map(|f| f.map(|i| m.vertices[i as usize].to_array()))
        .collect()
}

fn stl_ascii() -> String {
    let mut s = String::from("solid box\n");
    for t in triangles() {
        s += "facet normal 0 0 0\nouter loop\n";
        for p in t {
            s += &format!("vertex {} {} {}\n", p[0], p[1], p[2]);
        }
        s += "endloop\nendfacet\n";
    }
    s + "endsolid box\n"
}

fn stl_binary() -> Vec<u8> {
    let tris = triangles();
    let mut b = vec![0u8; 80];
    b.extend_from_slice(&(tris.len() as u32).to_le_bytes());
    for t in tris {
        b.extend_from_slice(&[0u8; 12]);
        for p in t {
            for x in p {
                b.extend_from_slice(&x.to_le_bytes());
            }
        }
        b.extend_from_slice(&[0u8; 2]);
    }
    b
}

/// Every format gives the same box: 12 triangles, volume 6, area 22.
#[test]
fn every_format_reads_the_same_box() {
    let dir = workdir("mesh_in", "formats");
    let files: Vec<(&str, Vec<u8>)> = vec![
        ("box.obj", obj_text().into_bytes()),
        ("box.OFF", off_text().into_bytes()),
        ("box.ply", ply_ascii().into_bytes()),
        ("binary.ply", ply_binary()),
        ("box.stl", stl_ascii().into_bytes()),
        ("binary.stl", stl_binary()),
    ];
    for (name, bytes) in files {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let mesh = read_mesh(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(mesh.faces.len(), 12, "{name}");
        assert!(
            (mesh.volume() - 6.0).abs() < 1e-5,
            "{name}: {}",
            mesh.volume()
        );
        assert!((mesh.area() - 22.0).abs() < 1e-5, "{name}: {}", mesh.area());
        assert_eq!(mesh.boundary_edges(), 0, "{name}: corners shared");
    }
}

/// The signed distance of the box `[lo, hi]` in closed form.
fn box_sdf(p: Vec3, lo: Vec3, hi: Vec3) -> f32 {
    let c = (lo + hi) / 2.0;
    let q = (p - c).abs() - (hi - lo) / 2.0;
    q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
}

/// A closed mesh's grid is its exact signed distance: a box's, sample by sample, on the lattice and
/// box `bake` documents (first and last samples on the padded box's faces).
#[test]
fn a_closed_box_bakes_to_its_exact_signed_distance() {
    let (lo, hi) = (Vec3::new(-0.3, 0.1, 0.2), Vec3::new(0.9, 0.7, 1.0));
    let baked = bake_mesh(&cuboid(lo, hi), 40, 0.1).unwrap();
    let pad = 0.1 * 1.2;
    assert!((baked.bbox_min - (lo - pad)).abs().max_element() < 1e-6);
    assert!((baked.bbox_max - (hi + pad)).abs().max_element() < 1e-6);
    let [nx, ny, nz] = baked.grid.dims;
    assert_eq!(
        baked.grid.dims,
        bake_dims(baked.bbox_min, baked.bbox_max, 40)
    );
    assert_eq!([nx, ny, nz], [40, 24, 29]);
    let step = (baked.bbox_max - baked.bbox_min) / Vec3::new(39.0, 23.0, 28.0);
    let mut worst = 0.0f32;
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let p = baked.bbox_min + Vec3::new(x as f32, y as f32, z as f32) * step;
                let want = box_sdf(p, lo, hi);
                let got = baked.grid.values[(z * ny + y) * nx + x];
                if want.abs() > 1e-5 {
                    assert_eq!(got < 0.0, want < 0.0, "sign at {p}: {got} vs {want}");
                }
                worst = worst.max((got - want).abs());
            }
        }
    }
    assert!(worst < 1e-5, "largest error {worst}");
}

/// A sphere's mesh bakes to its distance: within the tessellation's sagitta of `|p| − r`, with the
/// sign exact away from the surface.
#[test]
fn a_sphere_bakes_to_its_distance() {
    let mesh = uv_sphere(Vec3::new(0.1, 0.0, -0.2), 0.8, 96, 48);
    let baked = bake_mesh(&mesh, 48, 0.2).unwrap();
    let [nx, ny, nz] = baked.grid.dims;
    let step =
        (baked.bbox_max - baked.bbox_min) / (Vec3::new(nx as f32, ny as f32, nz as f32) - 1.0);
    // The sagitta of a 96-gon of radius 0.8 is 0.8 (1 − cos(π/96)) ≈ 4.3e-4; a pole's fan twice that.
    let tol = 1.5e-3;
    for (k, got) in baked.grid.values.iter().enumerate() {
        let (x, y, z) = (k % nx, (k / nx) % ny, k / (nx * ny));
        let p = baked.bbox_min + Vec3::new(x as f32, y as f32, z as f32) * step;
        let want = (p - Vec3::new(0.1, 0.0, -0.2)).length() - 0.8;
        assert!((got - want).abs() < tol, "{p}: {got} vs {want}");
    }
}

fn centre_and_far(sdf: &MeshSdf, centre: Vec3) {
    assert!(sdf.inside(centre), "w = {}", sdf.winding(centre));
    for far in [
        Vec3::splat(3.0),
        Vec3::new(-2.5, 0.3, 0.0),
        Vec3::new(0.0, 0.0, 2.0),
    ] {
        assert!(!sdf.inside(far), "{far}: w = {}", sdf.winding(far));
    }
}

/// Open, doubled, partly flipped and multi-part meshes: the inside a person would name.
#[test]
fn imperfect_meshes_get_a_sensible_inside() {
    let sphere = uv_sphere(Vec3::ZERO, 1.0, 48, 24);
    // A hole: the triangles within 30 degrees of the north pole removed.
    let mut open = sphere.clone();
    open.faces
        .retain(|f| f.iter().any(|&i| open.vertices[i as usize].z < 0.85));
    assert!(open.boundary_edges() > 0);
    let sdf = MeshSdf::new(&open).unwrap();
    centre_and_far(&sdf, Vec3::ZERO);
    // Just below the hole the triangles still wrap the point more than halfway.
    assert!(sdf.inside(Vec3::new(0.0, 0.0, 0.6)));
    // Above the hole, outside.
    assert!(!sdf.inside(Vec3::new(0.0, 0.0, 1.2)));

    // Every triangle twice: winding number 2 inside (to the far field's ~1%).
    let mut doubled = sphere.clone();
    doubled.faces.extend(sphere.faces.clone());
    let sdf = MeshSdf::new(&doubled).unwrap();
    assert!((sdf.winding(Vec3::ZERO) - 2.0).abs() < 0.05);
    centre_and_far(&sdf, Vec3::ZERO);

    // One triangle in twenty flipped.
    let mut flipped = sphere.clone();
    for f in flipped.faces.iter_mut().step_by(20) {
        f.swap(1, 2);
    }
    centre_and_far(&MeshSdf::new(&flipped).unwrap(), Vec3::ZERO);

    // Two separate spheres, and two overlapping ones (self-intersecting union).
    for offset in [3.0, 1.0] {
        let mut two = sphere.clone();
        let other = uv_sphere(Vec3::new(offset, 0.0, 0.0), 1.0, 48, 24);
        let base = two.vertices.len() as u32;
        two.vertices.extend(other.vertices);
        two.faces
            .extend(other.faces.iter().map(|f| f.map(|i| i + base)));
        let sdf = MeshSdf::new(&two).unwrap();
        assert!(sdf.inside(Vec3::ZERO) && sdf.inside(Vec3::new(offset, 0.0, 0.0)));
        assert!(
            sdf.inside(Vec3::new(0.5, 0.0, 0.0)),
            "the overlap is inside"
        );
        assert!(!sdf.inside(Vec3::new(offset / 2.0, 1.5, 0.0)));
    }
}

/// `bake --mesh`: the file's grid, and the node printed as for a shape.
#[test]
fn the_bake_command_takes_a_mesh() {
    let dir = workdir("mesh_in", "cli");
    std::fs::write(dir.join("box.obj"), obj_text()).unwrap();
    let out = run(
        &dir,
        &[
            "bake",
            "--mesh",
            "box.obj",
            "--res",
            "16",
            "--out",
            "box.npy",
            "--padding",
            "0.25",
        ],
    );
    let stdout = assert_success(&out);
    let grid = read_npy(&dir.join("box.npy")).unwrap();
    assert_eq!(grid.dims, [9, 13, 16]);
    assert!(
        stdout.contains(r#"{"type": "grid", "file": "box.npy", "bbox_min": [-0.75, -0.75, -0.75], "bbox_max": [1.75, 2.75, 3.75]}"#),
        "{stdout}"
    );
    // The box's centre is inside.
    let centre = grid.values[(7 * 13 + 6) * 9 + 4];
    assert!(centre < -0.4, "{centre}");
}

/// Bad meshes: one line naming the file and what is wrong, exit code 2, nothing written.
#[test]
fn bad_meshes_are_refused() {
    let dir = workdir("mesh_in", "bad");
    let cases: &[(&str, &[u8], &str)] = &[
        ("garbage.ply", b"this is not a ply file\n", "garbage.ply: not a readable PLY file"),
        ("garbage.stl", b"solid x\nfacet nonsense\n", "garbage.stl: not a readable STL file"),
        ("garbage.off", b"OFF\n3 1 0\n0 0 0\n", "garbage.off: not a readable OFF file"),
        ("mesh.xyz", b"0 0 0\n", "mesh.xyz: unknown mesh format"),
        ("empty.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\n", "empty.obj: the mesh has no faces"),
        ("nan.obj", b"v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "nan.obj: vertex 0 has a coordinate that is not finite"),
        ("nan.off", b"OFF\n3 1 0\n0 0 NaN\n1 0 0\n0 1 0\n3 0 1 2\n", "nan.off: vertex 0 has a coordinate"),
        ("range.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "range.off: face 0 uses vertex 7, out of range"),
        ("range.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "range.obj"),
        ("range.ply", b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "range.ply: face 0 uses vertex 3, out of range"),
    ];
    for (name, bytes, says) in cases {
        std::fs::write(dir.join(name), bytes).unwrap();
        let out = run(
            &dir,
            &["bake", "--mesh", name, "--res", "8", "--out", "g.npy"],
        );
        assert_failure(&out, says);
    }
    let out = run(
        &dir,
        &[
            "bake",
            "--mesh",
            "missing.obj",
            "--res",
            "8",
            "--out",
            "g.npy",
        ],
    );
    assert_failure(&out, "missing.obj");
    let inputs: Vec<&str> = cases.iter().map(|c| c.0).collect();
    assert!(
        outputs(&dir, &inputs).is_empty(),
        "{:?}",
        outputs(&dir, &inputs)
    );
    // Neither a scene and a mesh together, nor neither.
    let out = run(&dir, &["bake", "--res", "8", "--out", "g.npy"]);
    assert_eq!(out.status.code(), Some(2));
    let out = run(
        &dir,
        &[
            "bake",
            "s.json",
            "--shape",
            "a",
            "--mesh",
            "range.obj",
            "--res",
            "8",
            "--out",
            "g.npy",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
}

/// A mesh's signed distance at a point equals the closed form for a box seen from every side, and
/// the winding number of a box is exactly 0 or 1.
#[test]
fn box_queries_are_exact() {
    let (lo, hi) = (Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0));
    let sdf = MeshSdf::new(&cuboid(lo, hi)).unwrap();
    for p in [
        Vec3::new(0.5, 1.0, 1.5),
        Vec3::new(0.1, 0.1, 0.1),
        Vec3::new(-1.0, -1.0, -1.0),
        Vec3::new(2.0, 1.0, 1.0),
        Vec3::new(0.5, 2.5, 3.5),
    ] {
        assert!((sdf.signed(p) - box_sdf(p, lo, hi)).abs() < 1e-6, "{p}");
        let w = sdf.winding(p);
        assert!(w.abs() < 1e-9 || (w - 1.0).abs() < 1e-9, "{p}: {w}");
    }
}

/// The metrics on shapes whose distances are known: a sphere against a finer, larger sphere (every
/// point of one is the radius difference from the other), a box against a shifted box (IoU in closed
/// form), a mesh against itself.
#[test]
fn metrics_match_closed_forms() {
    use implicit_psdr::mesh::metrics::{MetricOptions, compare};
    let options = MetricOptions::default();
    let (a, b) = (
        uv_sphere(Vec3::ZERO, 1.0, 96, 48),
        uv_sphere(Vec3::ZERO, 1.2, 192, 96),
    );
    let m = compare(&a, &b, &options).unwrap();
    let diagonal = 2.4 * 3f64.sqrt();
    // The tessellations' sagittas (5e-4 and 1.6e-4 of the radius) bound the departure from 0.2.
    assert!((m.chamfer * diagonal - 0.2).abs() < 1e-3, "{m:?}");
    assert!(m.normal_consistency > 0.999, "{m:?}");
    // IoU (1/1.2)³ to a cell's share of the surface (64 cells across 2.4).
    assert!((m.iou - (1.0 / 1.2f64).powi(3)).abs() < 0.02, "{m:?}");

    let box_a = cuboid(Vec3::ZERO, Vec3::ONE);
    let box_b = cuboid(Vec3::new(0.25, 0.0, 0.0), Vec3::new(1.25, 1.0, 1.0));
    let m = compare(&box_a, &box_b, &options).unwrap();
    // Overlap 0.75, union 1.25: 0.6, to the lattice's cells (1.25/64 wide: each face at x is
    // placed to within half a cell, so the lengths to within 0.02 and the ratio to within 0.02).
    assert!((m.iou - 0.6).abs() < 0.02, "{m:?}");
    let same = compare(&box_a, &box_a, &options).unwrap();
    assert!(
        same.chamfer < 1e-7 && same.iou == 1.0 && same.normal_consistency > 0.999,
        "{same:?}"
    );
}
