//! Closed triangle meshes of simple solids, for tests, benchmarks and examples: a UV sphere and an
//! axis-aligned box, both facing outwards.

use super::TriangleMesh;
use glam::Vec3;

/// A sphere of radius `r` about `centre`: `segments` (≥ 3) around the axis `z`, `rings` (≥ 2) from
/// pole to pole, `2 · segments · (rings − 1)` triangles, vertices on the sphere.
pub fn uv_sphere(centre: Vec3, r: f32, segments: usize, rings: usize) -> TriangleMesh {
    let (segments, rings) = (segments.max(3), rings.max(2));
    let mut vertices = vec![centre + Vec3::Z * r];
    for i in 1..rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            let d = Vec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            vertices.push(centre + d * r);
        }
    }
    vertices.push(centre - Vec3::Z * r);
    let south = (vertices.len() - 1) as u32;
    let ring = |i: usize, j: usize| (1 + (i - 1) * segments + j % segments) as u32;
    let mut faces = Vec::with_capacity(2 * segments * (rings - 1));
    for j in 0..segments {
        faces.push([0, ring(1, j), ring(1, j + 1)]);
        faces.push([south, ring(rings - 1, j + 1), ring(rings - 1, j)]);
    }
    for i in 1..rings - 1 {
        for j in 0..segments {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i, j + 1),
                ring(i + 1, j),
                ring(i + 1, j + 1),
            );
            faces.push([a, c, d]);
            faces.push([a, d, b]);
        }
    }
    let mut mesh = TriangleMesh {
        vertices,
        normals: Vec::new(),
        faces,
    };
    mesh.normals = mesh.vertex_normals();
    mesh
}

/// The box `[lo, hi]` as 12 triangles.
pub fn cuboid(lo: Vec3, hi: Vec3) -> TriangleMesh {
    let vertices: Vec<Vec3> = (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        })
        .collect();
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let faces = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    let mut mesh = TriangleMesh {
        vertices,
        normals: Vec::new(),
        faces,
    };
    mesh.normals = mesh.vertex_normals();
    mesh
}
