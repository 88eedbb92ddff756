//! Attached vertices (docs/theory.md §2.1–§2.3): the points of a path traced in `f32`, moved to first order with the
//! scene parameters, in any [`Scalar`] type.
//!
//! - **Shape vertex** `p` (unit normal `n`): `φ_S = φ(p; π)` with lifted parameters gives the normal
//!   velocity `V_S = −(φ_S − detach φ_S)/|∇φ(p)|` (primal zero), the position `x_S = p + V_S n` and the area
//!   factor `J_S = 1 + κ(p) V_S` (`∂πJ = κV`, supplemental §1 eq. 11; `κ` primal only).
//!   The normal moves with the surface: at the moving point, `∇φ(x(π); π) = ∇φ(p) + π (H ∂πx + ∂π∇φ)`, so
//!   `n_S = normalize(∇φ_S(p) + (H n) V_S)`, `∂πn = (I − nnᵀ)(H n V' + ∂π∇φ)/|∇φ|`. `∇φ_S(p)` (the
//!   gradient with lifted parameters) comes from one evaluation in [`Grad`]`<S>`, a spatial gradient dual
//!   whose coefficients are `S`; `H` (primal) comes from [`crate::sdf::Sdf::hessian`], which `κ` needs
//!   anyway.
//! - **Emitter vertex**: emitters move by their parameters keeping the point's relative position: a
//!   rectangle point at relative coordinates `(s, t)` goes to `c_S + u s a_S + v t b_S` with `J = a_S b_S /
//!   (a b)`, a sphere point to `c_S + r_S n` with `J = r_S² / r²`; normals do not move.
//! - **Camera**: the lifted origin.
//!
//! Geometry (`V`, `κ`, `∇φ`, `H`) is read from the field of the faces ([`crate::sdf::Sdf::eval_faces`],
//! theory §7.1): a point within the tracer's tolerance outside a sharp edge gets its face's, not the
//! `1/φ` curvature of the exact distance's rounded level set there.
//!
//! Shapes whose curvature radius can be below a pixel may move by a field with a tangential part
//! instead of the normal field ([`super::velocity`], theory §8), chosen per shape by
//! [`crate::integrator::VelocityField`].
//!
//! Every attached quantity has exactly the recorded primal (position, normal, `J = 1`), so a derivative
//! pass reproduces the image bit for bit. Shapes and emitters without a selected parameter are attached
//! as constants (no Hessian).

use super::options::VelocityField;
use super::path::{Anchor, Attach, Attached};
use super::velocity;
use crate::math::Vec3;
use crate::scalar::{BlockValues, Param, Scalar};
use crate::scene::{Scene, Shape};

pub use crate::scalar::Grad;

/// `1 + (x − detach x)/primal x`: the ratio `x / x_primal` with a primal of exactly 1 (rounding in the
/// primal of `x` cannot leak into the image). 1 when the primal is zero or not finite.
#[inline]
pub fn unit_ratio<S: Scalar>(x: S) -> S {
    let p = x.primal();
    if p != 0.0 && p.is_finite() {
        (x - x.detach()) / p + 1.0
    } else {
        S::one()
    }
}

/// `v` with its primal replaced by exactly `primal` (the derivative kept).
#[inline]
fn with_primal<S: Scalar>(v: Vec3<S>, primal: glam::Vec3) -> Vec3<S> {
    Vec3::constant(primal) + (v - v.detach())
}

/// A copy of `scene` for the derivative pass over slots `lo .. lo + width`: slot `k` in that window
/// becomes `k − lo`, every other slot none (grid directions included; reverse-mode blocks are kept).
pub fn window_slots(scene: &Scene, lo: usize, width: usize) -> Scene {
    let window = |k: u32| {
        let k = k as usize;
        (k >= lo && k < lo + width).then(|| (k - lo) as u32)
    };
    let mut s = scene.clone();
    s.visit_params_mut(&mut |_, p: &mut Param| p.slot = p.slot.and_then(window));
    crate::scene::visit_scene_selections_mut(&mut s, &mut |_, g| {
        if let BlockValues::Direction { slot, .. } = g {
            match window(*slot) {
                Some(k) => *slot = k,
                None => *g = BlockValues::Constant,
            }
        }
    });
    s
}

/// Runs `pass(windowed scene, width)` once per window of `window` parameters among slots `0..count`
/// (the window's slots renumbered from 0 by [`window_slots`], `width` of them selected), in slot
/// order; at least once, with `width` 0, when `count` is 0.
pub fn for_each_window<T>(
    scene: &Scene,
    count: usize,
    window: usize,
    mut pass: impl FnMut(&Scene, usize) -> T,
) -> Vec<T> {
    (0..count.max(1))
        .step_by(window.max(1))
        .map(|lo| {
            let width = count.saturating_sub(lo).min(window);
            pass(&window_slots(scene, lo, window), width)
        })
        .collect()
}

/// Whether the geometry of a shape (SDF or translation, not the material) has a selected parameter.
pub(crate) fn geometry_selected(shape: &Shape) -> bool {
    let mut any = shape.translate.c.iter().any(|p| p.slot.is_some());
    shape
        .sdf
        .visit_params("", &mut |_, p: &Param| any |= p.slot.is_some());
    any || shape.sdf.grid_values_selected()
}

/// The [`Attach`] of the derivative pass: attached vertices of [`Scene`]'s shapes, emitters and camera
/// with the scene's selected parameters (see the [module docs](self)).
#[derive(Clone, Debug)]
pub struct SceneAttach<'a> {
    scene: &'a Scene,
    /// Per shape: does its geometry depend on a selected parameter?
    shape_moves: Vec<bool>,
    /// Per shape: the field that moves its points when not the normal field ([`velocity`]).
    field: Vec<Option<velocity::Field<'a>>>,
    /// Per emitter: does its position or size depend on a selected parameter?
    emitter_moves: Vec<bool>,
}

impl<'a> SceneAttach<'a> {
    /// Precomputes which shapes and emitters move with the selected parameters, and the field that
    /// moves each shape's points under the choice `velocity`.
    pub fn new(scene: &'a Scene, velocity: VelocityField) -> Self {
        let shape_moves: Vec<bool> = scene.shapes.iter().map(geometry_selected).collect();
        let field = (scene.shapes.iter().zip(&shape_moves))
            .map(|(shape, &moves)| {
                moves
                    .then(|| velocity::Field::of(scene, shape, velocity))
                    .flatten()
            })
            .collect();
        Self {
            scene,
            shape_moves,
            field,
            emitter_moves: scene
                .emitters
                .iter()
                .map(|e| e.emitter.geometry_selected())
                .collect(),
        }
    }

    /// The attached point `p` (recorded normal `n`) of shape `i`.
    pub fn shape_vertex<S: Scalar>(&self, i: usize, p: glam::Vec3, n: glam::Vec3) -> Attached<S> {
        let constant = Attached {
            x: Vec3::constant(p),
            n: Vec3::constant(n),
            j: S::one(),
        };
        if !self.shape_moves[i] {
            return constant;
        }
        let shape = &self.scene.shapes[i];
        let moved = match &self.field[i] {
            Some(field) => field
                .motion(shape, p, n)
                .and_then(|(d, div)| surface_vertex(shape, p, n, d, div)),
            None => surface_vertex(shape, p, n, Vec3::zero(), S::zero()),
        };
        moved.unwrap_or(constant)
    }

    /// The attached point `p` (normal `n`) of finite emitter `e`.
    pub fn emitter_vertex<S: Scalar>(&self, e: usize, p: glam::Vec3, n: glam::Vec3) -> Attached<S> {
        let constant = Attached {
            x: Vec3::constant(p),
            n: Vec3::constant(n),
            j: S::one(),
        };
        if !self.emitter_moves[e] {
            return constant;
        }
        // How the point moves is the emitter's business; the Jacobian is its area's relative change.
        match self.scene.emitters[e].emitter.attach::<S>(p) {
            Some((x, area)) => Attached {
                x: with_primal(x, p),
                n: Vec3::constant(n),
                j: unit_ratio(area),
            },
            None => constant,
        }
    }
}

/// The attached vertex of point `p` (normal `n`) of `shape` whose points move by `d` (any motion; primal
/// zero) with surface divergence `div` (theory §8, eq. 8.1): the normal part corrected to the surface's
/// normal velocity `V`, `x = p + d + (V − n·d) n`, `J = 1 + κ (V − n·d) + div`, and the normal of the
/// moved surface at the moved point, `normalize(∇φ_S(p) + H ẋ)` (2.5). `d = 0`, `div = 0` is the normal
/// field (2.4). `None` where the gradient vanishes.
pub(super) fn surface_vertex<S: Scalar>(
    shape: &Shape,
    p: glam::Vec3,
    n: glam::Vec3,
    d: Vec3<S>,
    div: S,
) -> Option<Attached<S>> {
    // The face's geometry, not the exterior distance's rounding around a sharp edge: `p` may lie
    // outside one by the tracer's tolerance `φ`, where the latter's curvature is `1/φ`.
    let r = shape.eval_faces::<Grad<S>>(Grad::seed(p));
    let grad = Vec3::new(r.g[0], r.g[1], r.g[2]);
    let (_, g, h) = shape.sdf.hessian_faces(p - shape.translate.value());
    let gl = g.length();
    if !(gl > 1e-12 && gl.is_finite()) {
        return None;
    }
    let v = -(r.v - r.v.detach()) / gl;
    let off_surface = v - d.dot_f32(n);
    let kappa = curvature(g, h, gl);
    let x = Vec3::constant(p) + d + Vec3::constant(n) * off_surface;
    // ∇φ at the moving point with the moving parameters, to first order: ∇φ + ∂π∇φ + H ẋ.
    let hd = Vec3::constant(h.x_axis) * d.x
        + Vec3::constant(h.y_axis) * d.y
        + Vec3::constant(h.z_axis) * d.z;
    let moved = (grad + Vec3::constant(h * n) * off_surface + hd).normalize_or_zero();
    Some(Attached {
        x: with_primal(x, p),
        n: with_primal(moved, n),
        j: off_surface * kappa + 1.0 + div,
    })
}

/// `κ = (tr H − gᵀHg/|g|²)/|g|`, 0 where not finite.
#[inline]
fn curvature(g: glam::Vec3, h: glam::Mat3, gl: f32) -> f32 {
    let tr = h.x_axis.x + h.y_axis.y + h.z_axis.z;
    let k = (tr - g.dot(h * g) / (gl * gl)) / gl;
    if k.is_finite() { k } else { 0.0 }
}

impl<S: Scalar> Attach<S> for SceneAttach<'_> {
    #[inline]
    fn attach(&self, at: Anchor, p: glam::Vec3, n: glam::Vec3) -> Attached<S> {
        match at {
            Anchor::Camera => {
                let o = self.scene.camera.origin.get::<S>();
                Attached {
                    x: with_primal(o, p),
                    n: Vec3::zero(),
                    j: S::one(),
                }
            }
            Anchor::Shape(i) => self.shape_vertex(i, p, n),
            Anchor::Emitter(e) => self.emitter_vertex(e, p, n),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::Bsdf;
    use crate::camera::Camera;
    use crate::film::Filter;
    use crate::integrator::IntegratorKind;
    use crate::scalar::Dual32;
    use crate::scalar::Param3;
    use crate::sdf::Sdf;

    fn scene_with(sdf: Sdf) -> Scene {
        let camera = Camera::new(
            glam::Vec3::new(0.0, 0.0, 5.0),
            glam::Vec3::ZERO,
            glam::Vec3::Y,
            40.0,
            8,
            8,
            Filter::Tent,
        );
        let bsdf = Bsdf::Diffuse {
            albedo: Param3::new([0.5; 3]),
        };
        Scene::new(
            camera,
            IntegratorKind::Direct,
            1,
            vec![Shape::new("s", sdf, bsdf)],
            vec![],
        )
    }

    /// Two spheres blended by a smooth union; parameter: the second child's centre x (slot 0 when
    /// `select`), value `cx`.
    fn blob(cx: f32, select: bool) -> Scene {
        let mut b = Sdf::sphere([cx, 0.3, 0.0], 0.7);
        if let (Sdf::Sphere { center, .. }, true) = (&mut b, select) {
            center.c[0].slot = Some(0);
        }
        scene_with(Sdf::smooth_union(vec![Sdf::sphere([0.0; 3], 1.0), b], 0.5))
    }

    /// A point on the surface along direction `d` from the origin, by bisection.
    fn surface_point(shape: &Shape, d: glam::Vec3) -> glam::Vec3 {
        let (mut lo, mut hi) = (0.0f32, 4.0f32);
        for _ in 0..60 {
            let m = 0.5 * (lo + hi);
            if shape.eval_f32(d * m) < 0.0 {
                lo = m;
            } else {
                hi = m;
            }
        }
        d * (0.5 * (lo + hi))
    }

    #[test]
    fn grad_matches_gradient_and_mixed_partial() {
        let cx = 1.2;
        let scene = blob(cx, true);
        let shape = &scene.shapes[0];
        let p = glam::Vec3::new(0.9, 0.6, 0.2);
        let r = shape.eval::<Grad<Dual32>>(Grad::seed(p));
        let g = shape.gradient(p);
        let h = 1e-2;
        let gp = blob(cx + h, false).shapes[0].gradient(p);
        let gm = blob(cx - h, false).shapes[0].gradient(p);
        for i in 0..3 {
            assert!((r.g[i].re - g[i]).abs() < 1e-5, "{:?} vs {g}", r.g);
            let fd = (gp[i] - gm[i]) / (2.0 * h);
            assert!(
                (r.g[i].eps - fd).abs() < 2e-3 * (1.0 + fd.abs()),
                "∂π∇φ_{i}: {} vs {fd}",
                r.g[i].eps
            );
        }
    }

    /// The attached point and normal against the perturbed surface: `x(±h) = p ± h ∂πx` lies on the
    /// surface with parameter `π ± h` (to second order), and the normal there is `n ± h ∂πn`.
    #[test]
    fn attached_normal_matches_perturbed_surface() {
        let cx = 1.2;
        let scene = blob(cx, true);
        let attach = SceneAttach::new(&scene, VelocityField::Auto);
        let h = 2e-3;
        let (plus, minus) = (blob(cx + h, false), blob(cx - h, false));
        let mut largest = 0.0f32;
        for d in [
            glam::Vec3::new(1.0, 0.4, 0.1),
            glam::Vec3::new(0.6, 0.8, -0.3),
            glam::Vec3::new(0.9, -0.2, 0.5),
            glam::Vec3::new(0.2, 1.0, 0.0),
        ] {
            let shape = &scene.shapes[0];
            let p = surface_point(shape, d.normalize());
            let n = shape.normal(p);
            let a = attach.shape_vertex::<Dual32>(0, p, n);
            assert_eq!(a.x.primal(), p);
            assert_eq!(a.n.primal(), n);
            assert_eq!(a.j.re, 1.0);
            let dx = glam::Vec3::new(a.x.x.eps, a.x.y.eps, a.x.z.eps);
            let dn = glam::Vec3::new(a.n.x.eps, a.n.y.eps, a.n.z.eps);
            let (xp, xm) = (p + dx * h, p - dx * h);
            // On the perturbed surfaces to second order in h.
            assert!(plus.shapes[0].eval_f32(xp).abs() < 1e-4);
            assert!(minus.shapes[0].eval_f32(xm).abs() < 1e-4);
            let fd = (plus.shapes[0].normal(xp) - minus.shapes[0].normal(xm)) / (2.0 * h);
            assert!(
                (dn - fd).length() < 5e-3 * (1.0 + fd.length()),
                "at {p}: ∂πn = {dn} vs FD {fd}"
            );
            largest = largest.max(dn.length());
            assert!(dn.dot(n).abs() < 1e-5);
        }
        assert!(largest > 0.1, "the test must see a moving normal");
    }

    #[test]
    fn area_factor_is_kappa_v_on_a_sphere() {
        // Radius r: V = 1, κ = 2/r, so ∂πJ = 2/r and ∂πx = n.
        let mut scene = scene_with(Sdf::sphere([0.0; 3], 1.5));
        if let Sdf::Sphere { radius, .. } = &mut scene.shapes[0].sdf {
            radius.slot = Some(0);
        }
        let attach = SceneAttach::new(&scene, VelocityField::Auto);
        let n = glam::Vec3::new(0.36, 0.48, 0.8);
        let a = attach.shape_vertex::<Dual32>(0, n * 1.5, n);
        assert!((a.j.eps - 2.0 / 1.5).abs() < 1e-5, "{}", a.j.eps);
        for (c, e) in [(a.x.x, n.x), (a.x.y, n.y), (a.x.z, n.z)] {
            assert!((c.eps - e).abs() < 1e-5);
        }
        for c in [a.n.x, a.n.y, a.n.z] {
            assert!(c.eps.abs() < 1e-5);
        }
    }

    /// A one-shape scene from the JSON of its sdf, parameter `param` selected.
    fn json_scene(sdf: &str, param: &str) -> Scene {
        let json = format!(
            r#"{{"camera": {{"origin": [0, 0, 6], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 40,
                "width": 8, "height": 8}},
               "integrator": {{"type": "direct"}}, "spp": 1,
               "shapes": [{{"name": "s", "sdf": {sdf}, "bsdf": {{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}}}],
               "emitters": [{{"name": "sky", "type": "constant", "radiance": [1, 1, 1]}}]}}"#
        );
        let scene = crate::scene::parse(&json, std::path::Path::new(".")).unwrap();
        scene.select(&[param]).unwrap().apply(&scene).unwrap()
    }

    /// Surface points of shape 0: the first crossing of rays from outside towards its centre region.
    fn surface_points(scene: &Scene) -> Vec<(glam::Vec3, glam::Vec3)> {
        let shape = &scene.shapes[0];
        let c = shape.bounds.center();
        let reach = shape.bounds.extent().length() + 1.0;
        let mut out = Vec::new();
        for k in 0..40 {
            // Directions spread over the sphere (a spiral), aimed a little off the centre.
            let z = 1.0 - 2.0 * (k as f32 + 0.5) / 40.0;
            let a = k as f32 * 2.399_963;
            let d = glam::Vec3::new(
                (1.0 - z * z).sqrt() * a.cos(),
                z,
                (1.0 - z * z).sqrt() * a.sin(),
            );
            let aim =
                c + 0.3 * glam::Vec3::new(a.sin(), 0.5 * a.cos(), 0.2) * shape.bounds.extent();
            let o = aim + d * reach;
            let span = 2.0 * reach;
            // March to the first sign change, then bisect.
            let steps = 4000;
            let at = |i: u32| span * i as f32 / steps as f32;
            let Some(i) = (1..=steps).find(|&i| shape.eval_f32(o - d * at(i)) < 0.0) else {
                continue;
            };
            let (mut t0, mut t1) = (at(i - 1), at(i));
            for _ in 0..40 {
                let m = 0.5 * (t0 + t1);
                if shape.eval_f32(o - d * m) < 0.0 {
                    t1 = m
                } else {
                    t0 = m
                }
            }
            let p = o - d * (0.5 * (t0 + t1));
            out.push((p, shape.normal(p)));
        }
        assert!(out.len() >= 12, "only {} surface points", out.len());
        out
    }

    const CARRIED: [(&str, &str); 9] = [
        (
            r#"{"type": "torus", "center": [0.1, 0, 0], "axis": [0, 1, 0], "major_radius": 1.2, "minor_radius": 0.3}"#,
            "s.major_radius",
        ),
        (
            r#"{"type": "torus", "center": [0.1, 0, 0], "axis": [0.6, 0.8, 0], "major_radius": 1.2, "minor_radius": 0.3}"#,
            "s.minor_radius",
        ),
        (
            r#"{"type": "torus", "center": [0.1, 0, 0], "axis": [0, 1, 0], "major_radius": 1.2, "minor_radius": 0.3}"#,
            "s.center.x",
        ),
        (
            r#"{"type": "sphere", "center": [0.2, 0.1, 0], "radius": 0.8}"#,
            "s.radius",
        ),
        (
            r#"{"type": "capsule", "a": [-0.5, 0, 0], "b": [0.6, 0.3, 0.1], "radius": 0.4}"#,
            "s.a.y",
        ),
        (
            r#"{"type": "capsule", "a": [-0.5, 0, 0], "b": [0.6, 0.3, 0.1], "radius": 0.4}"#,
            "s.radius",
        ),
        (
            r#"{"type": "box", "center": [0, 0.2, 0], "half_size": [0.6, 0.5, 0.4], "rounding": 0.1}"#,
            "s.center.y",
        ),
        (
            r#"{"type": "transform", "translate": [0.1, 0.2, 0], "rotate": {"axis": [0.6, 0, 0.8], "angle": 35}, "scale": 1.3,
             "child": {"type": "torus", "center": [0, 0, 0], "axis": [0, 1, 0], "major_radius": 0.8, "minor_radius": 0.2}}"#,
            "s.sdf.angle",
        ),
        (
            r#"{"type": "transform", "translate": [0.1, 0.2, 0], "rotate": {"axis": [0.6, 0, 0.8], "angle": 35}, "scale": 1.3,
             "child": {"type": "torus", "center": [0, 0, 0], "axis": [0, 1, 0], "major_radius": 0.8, "minor_radius": 0.2}}"#,
            "s.sdf.scale",
        ),
    ];

    /// A carried point stays on the moving surface (`∂π φ(x(π); π) = 0`), its normal velocity is the
    /// surface's (`∂πx·n = V`), and its moved normal is the normal of the moved surface there.
    #[test]
    fn carried_points_stay_on_the_moving_surface() {
        for (sdf, param) in CARRIED {
            let scene = json_scene(sdf, param);
            let normal = json_scene(sdf, param);
            let attach = SceneAttach::new(&scene, VelocityField::Carried);
            let reference = SceneAttach::new(&normal, VelocityField::Normal);
            assert!(attach.field[0].is_some(), "{param}: carried");
            for (p, n) in surface_points(&scene) {
                let a = attach.shape_vertex::<Dual32>(0, p, n);
                let b = reference.shape_vertex::<Dual32>(0, p, n);
                assert_eq!((a.x.primal(), a.n.primal(), a.j.re), (p, n, 1.0));
                let dx = glam::Vec3::new(a.x.x.eps, a.x.y.eps, a.x.z.eps);
                let v = glam::Vec3::new(b.x.x.eps, b.x.y.eps, b.x.z.eps).dot(n);
                let on = scene.shapes[0].eval::<Dual32>(a.x).eps;
                assert!(on.abs() < 2e-3, "{param} at {p}: ∂πφ(x) = {on}");
                assert!(
                    (dx.dot(n) - v).abs() < 2e-3,
                    "{param} at {p}: {} vs V {v}",
                    dx.dot(n)
                );
                // The normal of the moved surface at the moved point, by AD of φ at x(π).
                let g = scene.shapes[0].eval::<Grad<Dual32>>(Grad::seed(p));
                let h = scene.shapes[0]
                    .sdf
                    .hessian(p - scene.shapes[0].translate.value())
                    .2;
                let grad = glam::Vec3::new(g.g[0].eps, g.g[1].eps, g.g[2].eps) + h * dx;
                let gl = scene.shapes[0].gradient(p).length();
                let dn = (grad - n * n.dot(grad)) / gl;
                let an = glam::Vec3::new(a.n.x.eps, a.n.y.eps, a.n.z.eps);
                assert!(
                    (an - dn).length() < 2e-3 * (1.0 + dn.length()),
                    "{param} at {p}: ∂πn {an} vs {dn}"
                );
            }
        }
    }

    /// `∂πJ` in closed form at a surface point.
    type ExpectedJ = fn(glam::Vec3) -> f32;

    /// The area factor in closed form: `∂πJ = 1/ρ` for a torus's major radius (`ρ` the distance from
    /// its axis), 0 for rigid motions (a centre, a rotation), `2/s` for a transform's scale `s`, `κ`
    /// (= the normal field's) for a sphere's radius.
    #[test]
    fn carried_area_factor_in_closed_form() {
        let cases: [(usize, ExpectedJ); 5] = [
            (0, |p| 1.0 / glam::Vec2::new(p.x - 0.1, p.z).length()),
            (2, |_| 0.0),
            (3, |_| 2.0 / 0.8),
            (6, |_| 0.0),
            (7, |_| 0.0),
        ];
        for (i, expected) in cases {
            let (sdf, param) = CARRIED[i];
            let scene = json_scene(sdf, param);
            let attach = SceneAttach::new(&scene, VelocityField::Carried);
            for (p, n) in surface_points(&scene) {
                let j = attach.shape_vertex::<Dual32>(0, p, n).j.eps;
                let e = expected(p);
                assert!(
                    (j - e).abs() < 1e-3 * (1.0 + e.abs()),
                    "{param} at {p}: ∂πJ {j} vs {e}"
                );
            }
        }
        // The scale of a transform changes areas by s² per unit s: ∂πJ = 2/s.
        let (sdf, param) = CARRIED[8];
        let scene = json_scene(sdf, param);
        let attach = SceneAttach::new(&scene, VelocityField::Carried);
        for (p, n) in surface_points(&scene) {
            let j = attach.shape_vertex::<Dual32>(0, p, n).j.eps;
            assert!((j - 2.0 / 1.3).abs() < 1e-3, "scale at {p}: ∂πJ {j}");
        }
    }

    /// `Auto` carries a thin torus seen from afar (curvature radius below a pixel) and keeps the normal
    /// field for a ball, for CSG with a moving child, and for a thin torus around the eye.
    #[test]
    fn auto_carries_only_thin_shapes_seen_from_afar() {
        let thin = r#"{"type": "torus", "center": [0, 0, 0], "axis": [0, 1, 0], "major_radius": 1, "minor_radius": 0.002}"#;
        let auto = |sdf: &str, param: &str| {
            SceneAttach::new(&json_scene(sdf, param), VelocityField::Auto).field[0].is_some()
        };
        assert!(auto(thin, "s.major_radius"));
        assert!(!auto(
            r#"{"type": "sphere", "center": [0, 0, 0], "radius": 1}"#,
            "s.center.x"
        ));
        assert!(!auto(
            r#"{"type": "union", "children": [{"name": "a", "type": "sphere", "center": [0, 0, 0], "radius": 0.01},
                {"type": "sphere", "center": [1, 0, 0], "radius": 1}]}"#,
            "a.center.x"
        ));
        let around_eye = r#"{"type": "torus", "center": [0, 0, 6], "axis": [0, 1, 0], "major_radius": 1, "minor_radius": 0.002}"#;
        assert!(!auto(around_eye, "s.major_radius"));
        assert!(
            SceneAttach::new(&json_scene(thin, "s.major_radius"), VelocityField::Normal).field[0]
                .is_none()
        );
    }
}
