//! `bake --mesh`'s work on a 100k-triangle mesh at 128³: a bumpy sphere (100,172 triangles), its
//! exact distances and winding-number signs on the lattice, as `mesh::bake_mesh` computes them.
//! Run with `cargo bench --bench mesh_bake`; on two cores the figure in docs/cli.md was measured.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use implicit_psdr::mesh::{bake_mesh, shapes::uv_sphere};

/// A sphere of radius about 1 with a bump pattern, so that the closest triangles change along every
/// lattice row.
fn bumpy_sphere() -> implicit_psdr::mesh::TriangleMesh {
    let mut mesh = uv_sphere(Vec3::ZERO, 1.0, 317, 159);
    for v in &mut mesh.vertices {
        let (theta, phi) = (v.z.clamp(-1.0, 1.0).acos(), v.y.atan2(v.x));
        *v *= 1.0 + 0.1 * (5.0 * phi).sin() * (4.0 * theta).sin();
    }
    mesh.normals = mesh.vertex_normals();
    mesh
}

fn bench(c: &mut Criterion) {
    let mesh = bumpy_sphere();
    assert_eq!(mesh.faces.len(), 100_172);
    let mut group = c.benchmark_group("mesh_bake");
    group.sample_size(10);
    group.bench_function("100k_triangles_128", |b| {
        b.iter(|| bake_mesh(&mesh, 128, 0.1).unwrap())
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
