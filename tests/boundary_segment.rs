//! Boundary-segment geometry (docs/theory.md §5.2): the change of measure `J^B` against the numerical Jacobian
//! of the map `(x_B, θ_B) ↦ (x_S, x_D)`, and `V_∂` by AD against finite differences of the position of a
//! shadow boundary.
//!
//! The numerical Jacobian is independent of the formulas under test: `x_B(u, v)` is a point of the
//! surface found by Newton projection along a fixed normal, `θ` an angle in the tangent plane, the line
//! through `x_B` along `ω(θ)` is cut with receiver planes/spheres, and every derivative comes from
//! forward-mode dual numbers (`DualN<3>` in `u, v, θ`; the surface normal through a nested spatial
//! gradient dual). The measure `dA(x_S) dℓ(x_D)` of the image is read off the 6×3 derivative: `k` spans
//! the kernel of `∂x_S` (the directions that keep `x_S` fixed, along which `x_D` runs on its curve), so
//! the measure of the unit cube is `|∂x_S q₁ × ∂x_S q₂| · |∂x_D k|` (`q₁, q₂, k` orthonormal), and
//! `dA(x_B) dθ` is `|∂_u x_B × ∂_v x_B| du dv dθ`.

use implicit_psdr::bsdf::Bsdf;
use implicit_psdr::integrator::attach::Grad;
use implicit_psdr::integrator::boundary::{
    BoundarySegment, boundary_jacobian, boundary_velocity, is_silhouette_direction,
    primary_measure_change,
};
use implicit_psdr::math::Vec3;
use implicit_psdr::scalar::{Dual32, DualN, Param, Param3, Scalar};
use implicit_psdr::scene::Shape;
use implicit_psdr::sdf::{Sdf, bake};

type D3 = DualN<3>;

/// A small deterministic generator (splitmix64), so the configurations are reproducible.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, a: f64, b: f64) -> f32 {
        (a + (b - a) * self.next()) as f32
    }
    fn unit(&mut self) -> glam::Vec3 {
        let z = 2.0 * self.next() - 1.0;
        let phi = std::f64::consts::TAU * self.next();
        let r = (1.0 - z * z).max(0.0).sqrt();
        glam::DVec3::new(r * phi.cos(), r * phi.sin(), z).as_vec3()
    }
}

fn diffuse() -> Bsdf {
    Bsdf::Diffuse {
        albedo: Param3::new([0.5; 3]),
    }
}

fn dconst(v: glam::Vec3) -> Vec3<D3> {
    Vec3::constant(v)
}

/// Newton projection of `p` onto the zero set along the gradient.
fn project(shape: &Shape, mut p: glam::Vec3) -> glam::Vec3 {
    for _ in 0..60 {
        let (v, g) = (shape.eval_f32(p), shape.gradient(p));
        let g2 = g.length_squared();
        if g2 == 0.0 {
            break;
        }
        p -= g * (v / g2);
    }
    p
}

/// A receiver surface cut by the line, with the hit's derivatives.
#[derive(Copy, Clone)]
enum Receiver {
    Plane {
        n: glam::Vec3,
        p: glam::Vec3,
    },
    /// The line enters the sphere at the hit (the smaller root).
    Sphere {
        c: glam::Vec3,
        r: f32,
    },
}

impl Receiver {
    /// Signed distance `s` along `w` from `o` to the hit (`o + s w` on the receiver).
    fn cut<S: Scalar>(&self, o: Vec3<S>, w: Vec3<S>, forward: bool) -> S {
        match *self {
            Receiver::Plane { n, p } => {
                let nn = Vec3::<S>::constant(n);
                (Vec3::<S>::constant(p) - o).dot(nn) / w.dot(nn)
            }
            Receiver::Sphere { c, r } => {
                let oc = o - Vec3::<S>::constant(c);
                let b = oc.dot(w);
                let disc = b * b - oc.dot(oc) + r * r;
                let sq = disc.safe_sqrt();
                if forward { -b - sq } else { -b + sq }
            }
        }
    }
    fn normal(&self, x: glam::Vec3) -> glam::Vec3 {
        match *self {
            Receiver::Plane { n, .. } => n,
            Receiver::Sphere { c, .. } => (x - c).normalize(),
        }
    }
}

/// One configuration: the base point and frame on `M`, the angle, the receivers.
struct Config {
    x0: glam::Vec3,
    n0: glam::Vec3,
    e1: glam::Vec3,
    e2: glam::Vec3,
    theta0: f32,
    recv_s: Receiver,
    recv_d: Receiver,
}

/// Everything the map `(u, v, θ) ↦ (x_B, x_S, x_D)` gives at 0: primal points and 3×3 derivatives
/// (`m[i][j] = ∂x_i/∂param_j`, params `u, v, θ`).
struct MapDerivative {
    x_b: glam::Vec3,
    x_s: glam::Vec3,
    x_d: glam::Vec3,
    dx_b: [[f64; 3]; 3],
    dx_s: [[f64; 3]; 3],
    dx_d: [[f64; 3]; 3],
}

fn jac(v: Vec3<D3>) -> [[f64; 3]; 3] {
    [v.x, v.y, v.z].map(|c| c.eps.map(f64::from))
}

fn eval_map(shape: &Shape, cfg: &Config) -> MapDerivative {
    let u = D3::variable(0.0, 0);
    let v = D3::variable(0.0, 1);
    let th = D3::variable(0.0, 2);
    // x_B(u, v): the surface point on the line q + s n0, q = x0 + u e1 + v e2. Newton in f32 for s, then
    // one dual step (implicit function theorem: ∂s = −∇φ·∂q / ∇φ·n0).
    let mut s = 0.0f32;
    for _ in 0..60 {
        let p = cfg.x0 + cfg.n0 * s;
        let d = shape.gradient(p).dot(cfg.n0);
        if d == 0.0 {
            break;
        }
        s -= shape.eval_f32(p) / d;
    }
    let q = dconst(cfg.x0) + dconst(cfg.e1) * u + dconst(cfg.e2) * v;
    let p_star = q + dconst(cfg.n0) * D3::constant(s);
    let d = shape.gradient(p_star.primal()).dot(cfg.n0);
    let s_d = D3::constant(s) - shape.eval(p_star) / d;
    let x_b = q + dconst(cfg.n0) * s_d;
    // ∇φ(x_B) with its (u, v) derivatives: a spatial gradient dual whose coefficients are D3.
    let (z, o) = (D3::zero(), D3::one());
    let seed = Vec3::new(
        Grad {
            v: x_b.x,
            g: [o, z, z],
        },
        Grad {
            v: x_b.y,
            g: [z, o, z],
        },
        Grad {
            v: x_b.z,
            g: [z, z, o],
        },
    );
    let g = shape.eval(seed).g;
    let n = Vec3::new(g[0], g[1], g[2]).normalize_or_zero();
    let e1 = dconst(cfg.e1);
    let t1 = (e1 - n * e1.dot(n)).normalize_or_zero();
    let t2 = n.cross(t1);
    let ang = th + cfg.theta0;
    let w = t1 * ang.cos() + t2 * ang.sin();
    let s_s = cfg.recv_s.cut(x_b, w, false);
    let s_d = cfg.recv_d.cut(x_b, w, true);
    let x_s = x_b + w * s_s;
    let x_d = x_b + w * s_d;
    MapDerivative {
        x_b: x_b.primal(),
        x_s: x_s.primal(),
        x_d: x_d.primal(),
        dx_b: jac(x_b),
        dx_s: jac(x_s),
        dx_d: jac(x_d),
    }
}

fn mat_vec(m: &[[f64; 3]; 3], k: glam::DVec3) -> glam::DVec3 {
    glam::DVec3::new(
        m[0][0] * k.x + m[0][1] * k.y + m[0][2] * k.z,
        m[1][0] * k.x + m[1][1] * k.y + m[1][2] * k.z,
        m[2][0] * k.x + m[2][1] * k.y + m[2][2] * k.z,
    )
}

/// Numerical measures from the map's derivative.
struct Measures {
    /// `dA(x_S) dℓ(x_D) / (dA(x_B) dθ)`.
    area_jacobian: f64,
    /// `dA(x_S) dψ / (dA(x_B) dθ)`, `ψ` the angle swept by the direction from `x_S` (x_D at infinity).
    directional_jacobian: f64,
    /// `dℓ(x_D)/dℓ(x_B)` with `x_S` fixed (the silhouette's arc length at `x_B`): supplemental eq. 15.
    fiber_ratio: f64,
    /// `dℓ(x_D)` over the motion of `x_B` across the segment, `x_S` fixed: supplemental eq. 15 as written.
    fiber_ratio_across: f64,
    /// Unit direction in which `x_B` moves with `x_S` fixed: the silhouette tangent.
    silhouette: glam::DVec3,
    /// `dℓ_t(x_S)/dθ`: supplemental eq. 20.
    dl_t_dtheta: f64,
    /// Unit direction of `∂x_S/∂θ` (the curve `c_t`).
    c_t: glam::DVec3,
}

fn measures(m: &MapDerivative) -> Measures {
    let rows = m.dx_s.map(glam::DVec3::from_array);
    // The kernel of ∂x_S (rank 2): normal to its row space, the best-conditioned cross product of rows.
    let cands = [
        rows[0].cross(rows[1]),
        rows[1].cross(rows[2]),
        rows[2].cross(rows[0]),
    ];
    let k = cands
        .iter()
        .copied()
        .max_by(|a, b| a.length().total_cmp(&b.length()))
        .unwrap()
        .normalize();
    let q1 = k.any_orthonormal_vector();
    let q2 = k.cross(q1);
    let area_s = mat_vec(&m.dx_s, q1).cross(mat_vec(&m.dx_s, q2)).length();
    let xd_k = mat_vec(&m.dx_d, k);
    let fiber_d = xd_k.length();
    let sd = (m.x_d - m.x_s).as_dvec3();
    let dir = sd.normalize();
    let dpsi = (xd_k - dir * xd_k.dot(dir)).length() / sd.length();
    let xu = glam::DVec3::new(m.dx_b[0][0], m.dx_b[1][0], m.dx_b[2][0]);
    let xv = glam::DVec3::new(m.dx_b[0][1], m.dx_b[1][1], m.dx_b[2][1]);
    let area_b = xu.cross(xv).length();
    let xb_k = mat_vec(&m.dx_b, k);
    let fiber_b = xb_k.length();
    let w = (m.x_b - m.x_s).as_dvec3().normalize();
    let across_b = (xb_k - w * xb_k.dot(w)).length();
    let ds_dtheta = glam::DVec3::new(m.dx_s[0][2], m.dx_s[1][2], m.dx_s[2][2]);
    Measures {
        area_jacobian: area_s * fiber_d / area_b,
        directional_jacobian: area_s * dpsi / area_b,
        fiber_ratio: fiber_d / fiber_b,
        fiber_ratio_across: fiber_d / across_b,
        silhouette: xb_k / fiber_b,
        dl_t_dtheta: ds_dtheta.length(),
        c_t: ds_dtheta.normalize(),
    }
}

/// A random unit vector whose |·ω| is at least `lo` (so the line crosses the receiver clearly).
fn transverse_unit(rng: &mut Rng, w: glam::Vec3, lo: f32) -> glam::Vec3 {
    loop {
        let n = rng.unit();
        if n.dot(w).abs() >= lo {
            return n;
        }
    }
}

#[derive(Default, Debug)]
struct Errors {
    tested: usize,
    rejected_concave: usize,
    area: f64,
    fiber: f64,
    fiber_seed15: f64,
    silhouette_tangent: f64,
    /// Largest relative deviation of eq. 15 read with the silhouette's arc length (not an error: the
    /// obliquity `sin α_B`).
    eq15_vs_arc: f64,
    dl_t: f64,
    seed_oblique: f64,
    directional: f64,
    /// Largest relative deviation of the literal eq. 23 from the area Jacobian (not an error: the
    /// obliquity factor).
    seed_vs_area: f64,
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Runs `count` random silhouette configurations on `shape`; `surface_point` draws a point near the
/// surface.
fn check_shape(
    name: &str,
    shape: &Shape,
    count: usize,
    seed: u64,
    surface_point: impl Fn(&mut Rng) -> glam::Vec3,
) -> Errors {
    let mut rng = Rng(seed);
    let mut err = Errors::default();
    while err.tested < count {
        let x0 = project(shape, surface_point(&mut rng));
        let n0 = shape.normal(x0);
        let e1 = n0.any_orthonormal_vector();
        let e2 = n0.cross(e1);
        let theta0 = rng.range(0.0, std::f64::consts::TAU);
        let w0 = e1 * theta0.cos() + e2 * theta0.sin();
        if !is_silhouette_direction(shape, x0, w0) {
            err.rejected_concave += 1;
            continue;
        }
        let kn = shape.sdf.normal_curvature(x0 - shape.translate.value(), w0);
        if kn < 0.05 {
            // Nearly parabolic: a valid silhouette, but J → 0 and the relative comparison is moot.
            continue;
        }
        let a = rng.range(0.3, 3.0);
        let b = rng.range(0.3, 3.0);
        let ps = x0 - w0 * a;
        let pd = x0 + w0 * b;
        let recv_s = Receiver::Plane {
            n: transverse_unit(&mut rng, w0, 0.2),
            p: ps,
        };
        let recv_d = if rng.next() < 0.5 {
            Receiver::Plane {
                n: transverse_unit(&mut rng, w0, 0.2),
                p: pd,
            }
        } else {
            // A sphere entered at pd: outward normal m with m·ω ≤ −0.2.
            let m = -transverse_unit(&mut rng, w0, 0.2) * 1.0;
            let m = if m.dot(w0) > 0.0 { -m } else { m };
            let r = rng.range(0.3, 2.0);
            Receiver::Sphere { c: pd - m * r, r }
        };
        let cfg = Config {
            x0,
            n0,
            e1,
            e2,
            theta0,
            recv_s,
            recv_d,
        };
        let md = eval_map(shape, &cfg);
        let ms = measures(&md);
        let seg = BoundarySegment::from_shape(
            shape,
            md.x_s,
            md.x_b,
            md.x_d,
            recv_s.normal(md.x_s),
            recv_d.normal(md.x_d),
        )
        .expect("segment");
        assert!(seg.kappa_n > 0.0);
        let j = f64::from(boundary_jacobian(&seg));
        let j_seed = f64::from(seg.seed_jacobian());
        let fiber = f64::from(primary_measure_change(
            seg.x_s,
            seg.x_b,
            seg.n_b,
            seg.tangent_b,
            seg.x_d,
            seg.n_d,
        ));
        // Seed eq. 15 literally: |x_S x_D| / (|x_S x_B| sin θ_D).
        let fiber15 =
            f64::from(seg.x_s.distance(seg.x_d) / (seg.x_s.distance(seg.x_b) * seg.sin_theta_d()));
        let dl_t = f64::from(seg.x_s.distance(seg.x_b) / seg.sin_theta_s());
        let c_n = seg.n_s.cross(seg.across()).normalize().as_dvec3();
        let oblique = ms.c_t.cross(c_n).length();
        let e = [
            rel(j, ms.area_jacobian),
            rel(fiber, ms.fiber_ratio),
            rel(fiber15, ms.fiber_ratio_across),
            // Silhouette tangent: 1 − |cos| of the angle to the numerical direction.
            1.0 - ms.silhouette.dot(seg.tangent_b.as_dvec3()).abs(),
            rel(dl_t, ms.dl_t_dtheta),
            rel(j_seed * oblique, ms.area_jacobian),
            rel(
                f64::from(seg.jacobian_directional()),
                ms.directional_jacobian,
            ),
        ];
        assert!(
            e.iter().all(|&e| e < 1e-3),
            "{name}: config {} relative errors {e:?} (J {j}, numerical {}, κ_n {kn})",
            err.tested,
            ms.area_jacobian
        );
        err.area = err.area.max(e[0]);
        err.fiber = err.fiber.max(e[1]);
        err.fiber_seed15 = err.fiber_seed15.max(e[2]);
        err.silhouette_tangent = err.silhouette_tangent.max(e[3]);
        err.dl_t = err.dl_t.max(e[4]);
        err.seed_oblique = err.seed_oblique.max(e[5]);
        err.directional = err.directional.max(e[6]);
        err.eq15_vs_arc = err.eq15_vs_arc.max(rel(fiber15, ms.fiber_ratio));
        err.seed_vs_area = err.seed_vs_area.max(rel(j_seed, ms.area_jacobian));
        err.tested += 1;
    }
    eprintln!("{name}: {err:?}");
    err
}

#[test]
fn jacobian_sphere() {
    let c = glam::Vec3::new(0.2, -0.1, 0.3);
    let shape = Shape::new("ball", Sdf::sphere(c, 0.8), diffuse());
    let err = check_shape("sphere", &shape, 300, 1, |rng| c + rng.unit() * 0.8);
    assert_eq!(err.rejected_concave, 0, "a sphere is convex everywhere");
    // On a sphere the silhouette is perpendicular to the ray: supplemental eq. 15 holds with the arc length too.
    assert!(err.eq15_vs_arc < 1e-3, "{err:?}");
}

#[test]
fn jacobian_torus() {
    let c = glam::Vec3::new(-0.1, 0.2, 0.05);
    let axis = glam::Vec3::new(0.3, 1.0, 0.2).normalize();
    let shape = Shape::new("donut", Sdf::torus(c, axis, 1.0, 0.4), diffuse());
    let err = check_shape("torus", &shape, 300, 2, |rng| {
        let a = axis.any_orthonormal_vector();
        let b = axis.cross(a);
        let (phi, psi) = (
            rng.range(0.0, std::f64::consts::TAU),
            rng.range(0.0, std::f64::consts::TAU),
        );
        let radial = a * phi.cos() + b * phi.sin();
        c + radial * (1.0 + 0.4 * psi.cos()) + axis * (0.4 * psi.sin())
    });
    assert!(
        err.rejected_concave > 0,
        "the torus's inner side has concave directions"
    );
    // Obliquity is generic: the literal eq. 23 differs from the area Jacobian somewhere.
    assert!(err.seed_vs_area > 1e-2, "{err:?}");
    // The torus's silhouette is oblique to the ray somewhere: eq. 15 needs sin α_B there.
    assert!(err.eq15_vs_arc > 1e-2, "{err:?}");
}

#[test]
fn jacobian_grid() {
    let c = glam::Vec3::new(0.05, -0.02, 0.1);
    let sphere = Sdf::sphere(c, 0.8);
    let (lo, hi) = (glam::Vec3::splat(-1.2), glam::Vec3::splat(1.2));
    let grid = Sdf::grid(bake(&sphere, lo, hi, 40), lo, hi).unwrap();
    let shape = Shape::new("baked", grid, diffuse());
    check_shape("grid", &shape, 300, 3, |rng| c + rng.unit() * 0.8);
}

/// Degenerate configurations give weight 0, never NaN or infinity.
#[test]
fn jacobian_guards() {
    let shape = Shape::new("ball", Sdf::sphere(glam::Vec3::ZERO, 1.0), diffuse());
    let x_b = glam::Vec3::new(0.0, 1.0, 0.0);
    let (x_s, x_d) = (
        glam::Vec3::new(-2.0, 1.0, 0.0),
        glam::Vec3::new(3.0, 1.0, 0.0),
    );
    let up = glam::Vec3::Y;
    let tilted = glam::Vec3::new(-1.0, 1.0, 0.0).normalize();
    let ok = BoundarySegment::from_shape(&shape, x_s, x_b, x_d, tilted, glam::Vec3::X).unwrap();
    assert!(ok.jacobian() > 0.0 && ok.jacobian().is_finite());
    // Segment grazing x_S's surface (n_S ⟂ ω) and grazing x_D's surface.
    let graze_s = BoundarySegment { n_s: up, ..ok };
    assert_eq!(graze_s.jacobian(), 0.0);
    let graze_d = BoundarySegment { n_d: up, ..ok };
    assert_eq!(graze_d.jacobian(), 0.0);
    assert!(graze_d.curve_normal().is_none());
    // Concave or flat directions are not silhouettes.
    let concave = BoundarySegment {
        kappa_n: -0.5,
        n_s: glam::Vec3::X,
        ..ok
    };
    assert_eq!(concave.jacobian(), 0.0);
    assert_eq!(concave.jacobian_directional(), 0.0);
    let flat = BoundarySegment {
        kappa_n: 0.0,
        ..concave
    };
    assert_eq!(flat.seed_jacobian(), 0.0);
    assert!(!is_silhouette_direction(
        &Shape::new("floor", Sdf::plane(up, 0.0), diffuse()),
        glam::Vec3::ZERO,
        glam::Vec3::X
    ));
}

// ---------------------------------------------------------------------------------------------------
// V_∂ by AD against finite differences of the shadow boundary's position.

/// Bisection for the crossing of `blocked` along `s ∈ [lo, hi]` (`blocked(lo)`, `!blocked(hi)`).
fn crossing(lo: f64, hi: f64, blocked: impl Fn(f64) -> bool) -> f64 {
    assert!(
        blocked(lo) && !blocked(hi),
        "n_∂ must point to the clear side"
    );
    let (mut a, mut b) = (lo, hi);
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if blocked(m) {
            a = m
        } else {
            b = m
        }
        if b - a < 1e-14 {
            break;
        }
    }
    0.5 * (a + b)
}

fn seg_sphere_blocked(xs: glam::DVec3, y: glam::DVec3, c: glam::DVec3, r: f64) -> bool {
    let d = y - xs;
    let t = ((c - xs).dot(d) / d.length_squared()).clamp(0.0, 1.0);
    (xs + d * t - c).length() < r
}

fn slotted(v: f32, slot: u32) -> Param {
    Param {
        value: v,
        slot: Some(slot),
    }
}

/// `|a − b| / max(|b|, 1e-2)`: relative, with a floor for velocities near zero.
fn rel_floor(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-2)
}

/// A sphere between a floor point `x_S` and a wall: radius, centre, the sphere's translation, the wall
/// and the floor moving. `V_∂` from one `DualN<4>` pass and from `Dual32` passes against central
/// differences of the shadow boundary's position along `n_∂` on the wall.
#[test]
fn velocity_sphere_shadow() {
    let c = glam::Vec3::new(0.0, 1.0, 0.0);
    let r = 0.5f32;
    let wall_z = -3.0f32;
    let (up, wall_n) = (glam::Vec3::Y, glam::Vec3::Z);
    let ball4 = Shape::new(
        "ball",
        Sdf::sphere(
            Param3 {
                c: [slotted(c.x, 1), slotted(c.y, 2), slotted(c.z, 3)],
            },
            slotted(r, 0),
        ),
        diffuse(),
    );
    let ball_plain = Shape::new("ball", Sdf::sphere(c, r), diffuse());
    let ball_moved = Shape::translated(
        "ball",
        Sdf::sphere(c, r),
        diffuse(),
        Param3 {
            c: [Param::new(0.0), slotted(0.0, 0), Param::new(0.0)],
        },
    );
    let mut rng = Rng(11);
    let h = 1e-4f64;
    let mut worst = [0.0f64; 7];
    let mut tested = 0;
    while tested < 100 {
        let xs = glam::Vec3::new(rng.range(-1.0, 1.0), 0.0, rng.range(0.5, 2.0));
        let axis = c - xs;
        let l = axis.length();
        let a = axis / l;
        let beta = (r / l).asin();
        let (u, v) = (
            a.any_orthonormal_vector(),
            a.cross(a.any_orthonormal_vector()),
        );
        let phi = rng.range(0.0, std::f64::consts::TAU);
        let w = a * beta.cos() + (u * phi.cos() + v * phi.sin()) * beta.sin();
        if w.z > -0.15 {
            continue;
        }
        let xb = xs + w * (l * beta.cos());
        let xd = xs + w * ((wall_z - xs.z) / w.z);
        let seg = BoundarySegment::from_shape(&ball_plain, xs, xb, xd, up, wall_n).unwrap();
        let n_curve = seg.curve_normal().unwrap().as_dvec3();

        // AD: four sphere parameters in one pass, and the same with Dual32 one at a time.
        let v4: DualN<4> = boundary_velocity(&ball4, &seg, Vec3::constant(xs), Vec3::constant(xd));
        assert_eq!(v4.re, 0.0);
        for k in 0..4 {
            let mut one = ball4.clone();
            if let Sdf::Sphere { center, radius } = &mut one.sdf {
                radius.slot = (k == 0).then_some(0);
                for (i, p) in center.c.iter_mut().enumerate() {
                    p.slot = (k == i + 1).then_some(0);
                }
            }
            let v1: Dual32 = boundary_velocity(&one, &seg, Vec3::constant(xs), Vec3::constant(xd));
            assert!((v1.eps - v4.eps[k]).abs() <= 1e-6 * v4.eps[k].abs().max(1.0));
        }
        let v_translate: Dual32 =
            boundary_velocity(&ball_moved, &seg, Vec3::constant(xs), Vec3::constant(xd));
        // Wall and floor moving along their normals: attached x_D and x_S.
        let p = Dual32::new(0.0, 1.0);
        let zero = Dual32::new(0.0, 0.0);
        let xd_moving = Vec3::constant(xd) + Vec3::new(zero, zero, p);
        let v_wall: Dual32 = boundary_velocity(&ball_plain, &seg, Vec3::constant(xs), xd_moving);
        let xs_moving = Vec3::constant(xs) + Vec3::new(zero, p, zero);
        let v_floor: Dual32 = boundary_velocity(&ball_plain, &seg, xs_moving, Vec3::constant(xd));

        // Finite differences in f64: (Δc, Δr, Δwall, Δfloor) ↦ the boundary's position along n_∂.
        let (xs64, xd64, c64) = (xs.as_dvec3(), xd.as_dvec3(), c.as_dvec3());
        let pos = |dc: glam::DVec3, dr: f64, dwall: f64, dfloor: f64| {
            let xs_p = xs64 + glam::DVec3::Y * dfloor;
            let line0 = xd64 + glam::DVec3::Z * dwall;
            crossing(-0.2, 0.2, |s| {
                seg_sphere_blocked(xs_p, line0 + n_curve * s, c64 + dc, f64::from(r) + dr)
            })
        };
        let z3 = glam::DVec3::ZERO;
        let fd = |f: &dyn Fn(f64) -> f64| (f(h) - f(-h)) / (2.0 * h);
        let fds = [
            fd(&|e| pos(z3, e, 0.0, 0.0)),
            fd(&|e| pos(glam::DVec3::X * e, 0.0, 0.0, 0.0)),
            fd(&|e| pos(glam::DVec3::Y * e, 0.0, 0.0, 0.0)),
            fd(&|e| pos(glam::DVec3::Z * e, 0.0, 0.0, 0.0)),
            fd(&|e| pos(z3, 0.0, e, 0.0)),
            fd(&|e| pos(z3, 0.0, 0.0, e)),
        ];
        let ads = [
            v4.eps[0],
            v4.eps[1],
            v4.eps[2],
            v4.eps[3],
            v_wall.eps,
            v_floor.eps,
        ]
        .map(f64::from);
        for i in 0..6 {
            let e = rel_floor(ads[i], fds[i]);
            assert!(
                e < 1e-3,
                "config {tested} term {i}: AD {} FD {}",
                ads[i],
                fds[i]
            );
            worst[i] = worst[i].max(e);
        }
        let e = rel_floor(f64::from(v_translate.eps), fds[2]);
        assert!(
            e < 1e-3,
            "translate.y: AD {} FD {}",
            v_translate.eps,
            fds[2]
        );
        worst[6] = worst[6].max(e);
        tested += 1;
    }
    eprintln!("V_∂ sphere (radius, c.x, c.y, c.z, wall, floor, translate.y): {worst:?}");
}

/// The torus's implicit function in f64 (as `Sdf::torus`: major radius in the plane across `axis`).
fn torus64(p: glam::DVec3, c: glam::DVec3, axis: glam::DVec3, big: f64, small: f64) -> f64 {
    let q = p - c;
    let y = q.dot(axis);
    let rho = (q - axis * y).length();
    (rho - big).hypot(y) - small
}

/// Minimum of a unimodal `f` on `[a, b]` by golden-section search.
fn golden_min(mut a: f64, mut b: f64, f: impl Fn(f64) -> f64) -> f64 {
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..120 {
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = f(d);
        }
    }
    fc.min(fd)
}

/// A torus occluder (oblique silhouettes, varying curvature) between tilted planes: both radii and the
/// centre, from one `DualN<4>` pass, against central differences of the local boundary's position.
#[test]
fn velocity_torus_occluder() {
    let axis = glam::Vec3::new(0.3, 1.0, 0.2).normalize();
    let (big, small) = (1.0f32, 0.4f32);
    let torus4 = Shape::new(
        "donut",
        Sdf::torus(
            Param3 {
                c: [slotted(0.0, 2), Param::new(0.0), slotted(0.0, 3)],
            },
            axis,
            slotted(big, 0),
            slotted(small, 1),
        ),
        diffuse(),
    );
    let mut rng = Rng(12);
    let h = 1e-4f64;
    let mut worst = [0.0f64; 4];
    let mut tested = 0;
    while tested < 100 {
        let p0 = axis.any_orthonormal_vector();
        let p1 = axis.cross(p0);
        let (phi, psi) = (
            rng.range(0.0, std::f64::consts::TAU),
            rng.range(0.0, std::f64::consts::TAU),
        );
        let radial = p0 * phi.cos() + p1 * phi.sin();
        let xb = project(
            &torus4,
            radial * (big + small * psi.cos()) + axis * (small * psi.sin()),
        );
        let n = torus4.normal(xb);
        let (t0, t1) = (
            n.any_orthonormal_vector(),
            n.cross(n.any_orthonormal_vector()),
        );
        let th = rng.range(0.0, std::f64::consts::TAU);
        let w = t0 * th.cos() + t1 * th.sin();
        if torus4.sdf.normal_curvature(xb, w) < 0.1 {
            continue;
        }
        let xs = xb - w * rng.range(0.5, 2.0);
        let xd = xb + w * rng.range(0.5, 2.0);
        let n_s = transverse_unit(&mut rng, w, 0.3);
        let n_d = transverse_unit(&mut rng, w, 0.3);
        let seg = BoundarySegment::from_shape(&torus4, xs, xb, xd, n_s, n_d).unwrap();
        let n_curve = seg.curve_normal().unwrap().as_dvec3();
        let v4: DualN<4> = boundary_velocity(&torus4, &seg, Vec3::constant(xs), Vec3::constant(xd));

        let (xs64, xd64, ax) = (xs.as_dvec3(), xd.as_dvec3(), axis.as_dvec3());
        let t_b = f64::from(seg.t_b());
        let half = 0.15 / (xd64 - xs64).length();
        let pos = |dc: glam::DVec3, dbig: f64, dsmall: f64| {
            crossing(-0.05, 0.05, |s| {
                let y = xd64 + n_curve * s;
                let m = golden_min(t_b - half, t_b + half, |t| {
                    torus64(
                        xs64 + (y - xs64) * t,
                        dc,
                        ax,
                        f64::from(big) + dbig,
                        f64::from(small) + dsmall,
                    )
                });
                m < 0.0
            })
        };
        let z3 = glam::DVec3::ZERO;
        let fd = |f: &dyn Fn(f64) -> f64| (f(h) - f(-h)) / (2.0 * h);
        let fds = [
            fd(&|e| pos(z3, e, 0.0)),
            fd(&|e| pos(z3, 0.0, e)),
            fd(&|e| pos(glam::DVec3::X * e, 0.0, 0.0)),
            fd(&|e| pos(glam::DVec3::Z * e, 0.0, 0.0)),
        ];
        for i in 0..4 {
            let e = rel_floor(f64::from(v4.eps[i]), fds[i]);
            assert!(
                e < 1e-3,
                "config {tested} term {i}: AD {} FD {}",
                v4.eps[i],
                fds[i]
            );
            worst[i] = worst[i].max(e);
        }
        tested += 1;
    }
    eprintln!("V_∂ torus (major, minor, c.x, c.z): {worst:?}");
}

/// The cubic smooth minimum of `Sdf::smooth_union` in f64 (lowering at most `k/6`).
fn smin64(a: f64, b: f64, k: f64) -> f64 {
    let s = (a - b).abs();
    if s >= k {
        return a.min(b);
    }
    let h = (k - s) / k;
    a.min(b) - h * h * h * k / 6.0
}

/// A smooth union of two spheres with `x_B` in the blend, where `|∇φ| ≠ 1`: the rate
/// `t_B ∇φ(x_B)·n_∂` must use the unnormalised gradient. Parameters `k`, one centre, the other radius
/// and centre.
#[test]
fn velocity_smooth_union_blend() {
    let (c1, r1) = (glam::Vec3::new(-0.5, 0.0, 0.0), 0.6f32);
    let (c2, r2) = (glam::Vec3::new(0.5, 0.1, 0.0), 0.5f32);
    let k = 0.5f32;
    let blob = Shape::new(
        "blob",
        Sdf::smooth_union(
            vec![
                Sdf::sphere(
                    Param3 {
                        c: [slotted(c1.x, 1), Param::new(c1.y), Param::new(c1.z)],
                    },
                    r1,
                ),
                Sdf::sphere(
                    Param3 {
                        c: [Param::new(c2.x), slotted(c2.y, 3), Param::new(c2.z)],
                    },
                    slotted(r2, 2),
                ),
            ],
            slotted(k, 0),
        ),
        diffuse(),
    );
    let phi64 = |p: glam::DVec3, dk: f64, dc1x: f64, dr2: f64, dc2y: f64| {
        let a = (p - c1.as_dvec3() - glam::DVec3::X * dc1x).length() - f64::from(r1);
        let b = (p - c2.as_dvec3() - glam::DVec3::Y * dc2y).length() - f64::from(r2) - dr2;
        smin64(a, b, f64::from(k) + dk)
    };
    let mut rng = Rng(13);
    let h = 1e-4f64;
    let mut worst = [0.0f64; 4];
    let mut grad_dev = 0.0f32;
    let mut tested = 0;
    let mut tries = 0;
    while tested < 60 {
        tries += 1;
        assert!(tries < 200_000, "too few blend configurations");
        let q = glam::Vec3::new(rng.range(-0.2, 0.2), 0.0, 0.0) + rng.unit() * 0.5;
        let xb = project(&blob, q);
        let (a, b) = (xb.distance(c1) - r1, xb.distance(c2) - r2);
        if (a - b).abs() > 0.8 * k {
            continue;
        }
        let n = blob.normal(xb);
        let (t0, t1) = (
            n.any_orthonormal_vector(),
            n.cross(n.any_orthonormal_vector()),
        );
        let th = rng.range(0.0, std::f64::consts::TAU);
        let w = t0 * th.cos() + t1 * th.sin();
        if blob.sdf.normal_curvature(xb, w) < 0.1 {
            continue;
        }
        let xs = xb - w * rng.range(0.5, 2.0);
        let xd = xb + w * rng.range(0.5, 2.0);
        let n_s = transverse_unit(&mut rng, w, 0.3);
        let n_d = transverse_unit(&mut rng, w, 0.3);
        let seg = BoundarySegment::from_shape(&blob, xs, xb, xd, n_s, n_d).unwrap();
        grad_dev = grad_dev.max((seg.grad_b.length() - 1.0).abs());
        let n_curve = seg.curve_normal().unwrap().as_dvec3();
        let v4: DualN<4> = boundary_velocity(&blob, &seg, Vec3::constant(xs), Vec3::constant(xd));

        let (xs64, xd64) = (xs.as_dvec3(), xd.as_dvec3());
        let t_b = f64::from(seg.t_b());
        let half = 0.1 / (xd64 - xs64).length();
        let pos = |d: [f64; 4]| {
            crossing(-0.02, 0.02, |s| {
                let y = xd64 + n_curve * s;
                let m = golden_min(t_b - half, t_b + half, |t| {
                    phi64(xs64 + (y - xs64) * t, d[0], d[1], d[2], d[3])
                });
                m < 0.0
            })
        };
        for i in 0..4 {
            let mut dp = [0.0; 4];
            dp[i] = h;
            let mut dm = [0.0; 4];
            dm[i] = -h;
            let fd = (pos(dp) - pos(dm)) / (2.0 * h);
            let e = rel_floor(f64::from(v4.eps[i]), fd);
            assert!(
                e < 1e-3,
                "config {tested} term {i}: AD {} FD {fd}",
                v4.eps[i]
            );
            worst[i] = worst[i].max(e);
        }
        tested += 1;
    }
    eprintln!("V_∂ smooth union (k, c1.x, r2, c2.y): {worst:?}, max ||∇φ| − 1| {grad_dev}");
    assert!(
        grad_dev > 0.05,
        "the blend must exercise a non-unit gradient"
    );
}
