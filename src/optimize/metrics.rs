//! How close a shape is to a reference shape: the intersection over union of their inside sets and a
//! symmetric Chamfer distance between their surfaces; and how close the optimised shapes' mesh is to
//! a reference mesh ([`mesh_quality`], the measures of [`crate::mesh::metrics`]).

use crate::error::Result;
use crate::integrator::surface_sampling::sample_surface;
use crate::math::Aabb;
use crate::sampler::Sampler;
use crate::scene::{Scene, Shape};
use crate::trace::TraceSettings;

/// The random stream of the Chamfer distance's surface points.
const CHAMFER_STREAM: u64 = 0xC4A3_F1E2;

/// `|A ∩ B| / |A ∪ B|` of the inside sets (`φ < 0`) of `a` and `b`, counted at the centres of an
/// `n × n × n` lattice of cells over `region`; 1 when both are empty there.
pub fn iou(a: &Shape, b: &Shape, region: Aabb, n: usize) -> f64 {
    let ext = region.extent();
    let (mut both, mut either) = (0u64, 0u64);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let t = (glam::Vec3::new(x as f32, y as f32, z as f32) + 0.5) / n as f32;
                let p = region.min + ext * t;
                let (ia, ib) = (a.eval_f32(p) < 0.0, b.eval_f32(p) < 0.0);
                both += u64::from(ia && ib);
                either += u64::from(ia || ib);
            }
        }
    }
    if either == 0 {
        1.0
    } else {
        both as f64 / either as f64
    }
}

/// Points on a shape's surface with their area weights (`1/pdf`), from `lines` random lines of the
/// area sampler.
fn surface_points(
    shape: &Shape,
    settings: &TraceSettings,
    lines: usize,
    seed: u64,
) -> Result<Vec<(glam::Vec3, f64)>> {
    let mut out = Vec::new();
    let mut hits = Vec::new();
    for k in 0..lines {
        let mut sampler = Sampler::new(seed, CHAMFER_STREAM, 0, k as u64);
        let u_axis = sampler.next_1d();
        let u_face = sampler.next_2d();
        sample_surface(shape, settings, u_axis, u_face, &mut hits)?;
        out.extend(hits.iter().map(|h| (h.p, 1.0 / h.pdf as f64)));
    }
    Ok(out)
}

/// The symmetric Chamfer distance between the surfaces of `a` and `b`: half the sum of the
/// area-weighted mean distance from points of each surface to the other surface (`lines`
/// area-sampling lines per surface, seed `seed`). The distance from `p` to the other surface is taken
/// as `|φ(p)| / |∇φ(p)|`, its first-order estimate (exact for a signed distance), rather than to the
/// nearest of finitely many sampled points, whose spacing would put a floor under the measure.
/// Infinite if either surface yields no point.
pub fn chamfer(
    a: &Shape,
    b: &Shape,
    settings: &TraceSettings,
    lines: usize,
    seed: u64,
) -> Result<f64> {
    let (pa, pb) = (
        surface_points(a, settings, lines, seed)?,
        surface_points(b, settings, lines, seed.wrapping_add(1))?,
    );
    if pa.is_empty() || pb.is_empty() {
        return Ok(f64::INFINITY);
    }
    let one_way = |from: &[(glam::Vec3, f64)], to: &Shape| {
        let (mut sum, mut weight) = (0.0, 0.0);
        for &(p, w) in from {
            let g = to.gradient(p).length();
            let d = to.eval_f32(p).abs() / if g > 1e-6 { g } else { 1.0 };
            sum += w * d as f64;
            weight += w;
        }
        sum / weight
    };
    Ok(0.5 * (one_way(&pa, b) + one_way(&pb, a)))
}

/// How close shape `name` of `current` is to the shape of the same name in `reference`: `(IoU,
/// Chamfer distance)`, the IoU on a 64³ lattice over the union of the two shapes' bounds, the Chamfer
/// distance from 1000 area-sampling lines per surface (seed 0). `None` if either scene has no such
/// shape or its bounds are not finite.
pub fn shape_quality(current: &Scene, reference: &Scene, name: &str) -> Result<Option<(f64, f64)>> {
    let (Ok(a), Ok(b)) = (current.shape_named(name), reference.shape_named(name)) else {
        return Ok(None);
    };
    let region = a.bounds.union(&b.bounds);
    if !region.is_finite() || region.is_empty() {
        return Ok(None);
    }
    let iou = iou(a, b, region, 64);
    let chamfer = chamfer(a, b, &current.trace, 1000, 0)?;
    Ok(Some((iou, chamfer)))
}

/// Lattice points along the longest side of a shape's box when its mesh is extracted to be measured
/// against a reference mesh ([`crate::mesh::extract_shape`]).
pub const MESH_RESOLUTION: usize = 64;

/// The surfaces of the shapes named `shapes` of `scene`, extracted at `res` ([`MESH_RESOLUTION`] for
/// the measures), as one mesh in scene coordinates. Errors: an unknown or unbounded shape.
pub fn shapes_mesh(
    scene: &Scene,
    shapes: &[String],
    res: usize,
) -> Result<crate::mesh::TriangleMesh> {
    let mut out = crate::mesh::TriangleMesh::default();
    for name in shapes {
        let mesh = crate::mesh::extract_shape(scene.shape_named(name)?, res)?;
        let base = out.vertices.len() as u32;
        out.vertices.extend(mesh.vertices);
        out.normals.extend(mesh.normals);
        out.faces
            .extend(mesh.faces.iter().map(|f| f.map(|i| i + base)));
    }
    Ok(out)
}

/// Chamfer distance, normal consistency and IoU ([`crate::mesh::metrics`], default options) of the
/// shapes `shapes` of `scene` (extracted at [`MESH_RESOLUTION`]) against `reference`; NaN each when
/// the shapes have no surface to measure (an empty grid, say).
pub fn mesh_quality(
    scene: &Scene,
    shapes: &[String],
    reference: &crate::mesh::metrics::Measured,
) -> crate::mesh::metrics::MeshMetrics {
    use crate::mesh::metrics::{Measured, MeshMetrics, MetricOptions, compare_prepared};
    let measured = shapes_mesh(scene, shapes, MESH_RESOLUTION)
        .and_then(|mesh| Measured::new(&mesh))
        .and_then(|mesh| compare_prepared(&mesh, reference, &MetricOptions::default()));
    measured.unwrap_or(MeshMetrics {
        chamfer: f64::NAN,
        normal_consistency: f64::NAN,
        iou: f64::NAN,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::Bsdf;
    use crate::scalar::Param3;
    use crate::sdf::Sdf;

    fn ball(c: [f32; 3], r: f32) -> Shape {
        let bsdf = Bsdf::Diffuse {
            albedo: Param3::new([0.5; 3]),
        };
        Shape::new("s", Sdf::sphere(c, r), bsdf)
    }

    #[test]
    fn iou_of_shifted_balls_matches_the_lens_volume() {
        // Two unit balls a distance d apart: the lens has volume π(4 + d)(2 − d)²/12.
        let d = 0.5f64;
        let (a, b) = (ball([0.0; 3], 1.0), ball([d as f32, 0.0, 0.0], 1.0));
        let region = Aabb::new(glam::Vec3::splat(-1.5), glam::Vec3::splat(2.0));
        let lens = std::f64::consts::PI * (4.0 + d) * (2.0 - d).powi(2) / 12.0;
        let ball_volume = 4.0 / 3.0 * std::f64::consts::PI;
        let want = lens / (2.0 * ball_volume - lens);
        let got = iou(&a, &b, region, 64);
        // The lattice resolves the volumes to about a cell's share of the surface (~1%).
        assert!((got - want).abs() < 0.01, "{got} vs {want}");
        assert_eq!(iou(&a, &a, region, 16), 1.0);
    }

    #[test]
    fn chamfer_of_concentric_balls_is_the_gap() {
        let (a, b) = (ball([0.0; 3], 1.0), ball([0.0; 3], 1.2));
        let settings = TraceSettings::default();
        let got = chamfer(&a, &b, &settings, 2000, 1).unwrap();
        // Every point of one sphere is 0.2 from the other (to the points' own rounding).
        assert!((got - 0.2).abs() < 1e-4, "{got}");
        let same = chamfer(&a, &a, &settings, 2000, 1).unwrap();
        assert!(same < 1e-5, "{same}");
        // Off-centre: the mean distance between the surfaces of two unit balls 0.3 apart is
        // between 0 and 0.3, and symmetric.
        let c = ball([0.3, 0.0, 0.0], 1.0);
        let (ac, ca) = (
            chamfer(&a, &c, &settings, 2000, 1).unwrap(),
            chamfer(&c, &a, &settings, 2000, 1).unwrap(),
        );
        assert!(ac > 0.1 && ac < 0.3, "{ac}");
        assert!((ac - ca).abs() < 0.01, "{ac} vs {ca}");
    }
}
