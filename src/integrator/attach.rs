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
//! Every attached quantity has exactly the recorded primal (position, normal, `J = 1`), so a derivative
//! pass reproduces the image bit for bit. Shapes and emitters without a selected parameter are attached
//! as constants (no Hessian).

use super::path::{Anchor, Attach, Attached};
use crate::math::Vec3;
use crate::scalar::{GridValues, Param, Scalar};
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
    for shape in &mut s.shapes {
        shape.sdf.visit_grid_selections_mut(&mut |g| {
            if let GridValues::Direction { slot, .. } = g {
                match window(*slot) {
                    Some(k) => *slot = k,
                    None => *g = GridValues::Constant,
                }
            }
        });
    }
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
fn geometry_selected(shape: &Shape) -> bool {
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
    /// Per emitter: does its position or size depend on a selected parameter?
    emitter_moves: Vec<bool>,
}

impl<'a> SceneAttach<'a> {
    /// Precomputes which shapes and emitters move with the selected parameters.
    pub fn new(scene: &'a Scene) -> Self {
        Self {
            scene,
            shape_moves: scene.shapes.iter().map(geometry_selected).collect(),
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
        let r = shape.eval::<Grad<S>>(Grad::seed(p));
        let grad = Vec3::new(r.g[0], r.g[1], r.g[2]);
        let (_, g, h) = shape.sdf.hessian(p - shape.translate.value());
        let gl = g.length();
        if !(gl > 1e-12 && gl.is_finite()) {
            return constant;
        }
        let v = -(r.v - r.v.detach()) / gl;
        let kappa = curvature(g, h, gl);
        let x = Vec3::constant(p) + Vec3::constant(n) * v;
        // ∇φ at the moving point with the moving parameters, to first order.
        let hn = h * n;
        let moved = (grad + Vec3::constant(hn) * v).normalize_or_zero();
        Attached {
            x: with_primal(x, p),
            n: with_primal(moved, n),
            j: v * kappa + 1.0,
        }
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
        let attach = SceneAttach::new(&scene);
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
        let attach = SceneAttach::new(&scene);
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
}
