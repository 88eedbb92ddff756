//! `∂πJ = κV` (supplemental document of Zhou et al. 2024, §1, eq. 11), checked by automatic differentiation of the area element of the displaced
//! surface, a construction that never uses the curvature formula.
//!
//! Supplemental §1 maps the reference surface `B = M` to the moving one by `x = χ(p, π) = p + π V(p) n(p)` (the
//! velocity `v` points along the normal, Eq. 8, with `V = n·v`), and Eqs. 9–11 conclude that the Jacobian
//! `J` of that map (the area ratio, `J = 1` at `π = 0`) has `∂πJ = κV` with `κ = ∇·n` the total curvature
//! (positive on convex surfaces: `φ < 0` inside, the gradient pointing out, the sign note after Eq. 8).
//!
//! Construction, at a surface point `p0` (random points projected by Newton steps along `∇φ`):
//! 1. A tangent frame `(t1, t2, n0)` at `p0` and the local parametrisation of the reference surface
//!    `X(a, b) = q + s(a, b) n0`, `q = p0 + a t1 + b t2`, with `s` solving `φ(q + s n0) = 0` by Newton —
//!    run in truncated-polynomial arithmetic, so `s` carries its exact `a`- and `b`-derivatives (implicit
//!    function theorem, reached by the iteration).
//! 2. The normal velocity `V(x) = −∂πφ(x)/|∇φ(x)|` (the level set `φ(x, π) = 0` moves along `n` at this
//!    speed) and `n(x) = ∇φ/|∇φ|`, from one evaluation of the crate's generic `φ` in a dual type with four
//!    directions `(x, y, z, π)` — the scene parameter is lifted in slot 0 through [`Param`].
//! 3. The displaced surface `Y(a, b; π) = X + π V(X) n(X)` and its area element `A(π) = |∂aY × ∂bY|` at
//!    `a = b = 0`; `∂πJ = ∂πA(0) / A(0)`.
//!
//! Step 3 needs the mixed derivatives `∂a∂πY`, `∂b∂πY`, i.e. derivatives of `V` and `n` along the surface
//! (second derivatives of `φ`). They come from nesting: the outer type [`T`] is the ring
//! `R[a, b, π]/(a², ab, b², π²)` (coefficients of `1, a, b, π, aπ, bπ`: exact first derivatives in
//! `(a, b)`, in `π`, and the mixed ones), the inner type [`D`] a first-order dual over `T` in `(x, y, z, π)`
//! that implements the crate's [`Scalar`], so `Shape::eval::<D>` runs the very same SDF code as rendering.
//! All arithmetic is `f64` (the scene's `f32` numbers enter exactly), so the AD side is accurate to about
//! 1e-12; `κ` is the crate's own `Shape::curvature` in `f32`.
//!
//! Each point is compared with `κ(p0) V(p0)` at relative tolerance 1e-4, the error measured against
//! `max(|κV|, |V|/ℓ)` (`ℓ` the shape's size), so that points where `κV` vanishes (flat faces of a rounded
//! box) are held to the same standard; where `V = 0` exactly (outside a smooth union's blend) the AD
//! derivative must be 0 too. The check can fail: the same data compared with `κV/2` must miss by far
//! (asserted per shape), and the sphere is also checked against the closed form `2/r` (`V = 1`).

// Dual-number products and quotients mix operators by design (the product rule is a sum).
#![allow(clippy::suspicious_arithmetic_impl)]

mod common;

use common::Rng;
use implicit_psdr::bsdf::Bsdf;
use implicit_psdr::scene::Shape;
use implicit_psdr::sdf::{Children, Sdf, bake};
use implicit_psdr::{Param, Param3, Scalar, Vec3};
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

// ---------------------------------------------------------------------------------------------------------
// T: truncated polynomials in (a, b, π) modulo (a², ab, b², π²).
// ---------------------------------------------------------------------------------------------------------

/// Coefficient indices of [`T`].
const C0: usize = 0;
const CA: usize = 1;
const CB: usize = 2;
const CP: usize = 3;
const CAP: usize = 4;
const CBP: usize = 5;

/// `c0 + ca·a + cb·b + cp·π + cap·aπ + cbp·bπ`, exact in the quotient ring (the dropped monomials form an
/// ideal, so products and compositions are exact, not approximations).
#[derive(Copy, Clone, Debug, Default, PartialEq)]
struct T([f64; 6]);

impl T {
    fn c(v: f64) -> Self {
        let mut t = Self::default();
        t.0[C0] = v;
        t
    }
    /// `f(self)` from `f`, `f'`, `f''` at the constant part: the nilpotent rest `h` has `h³ = 0`, so
    /// `f(x0 + h) = f(x0) + f'(x0) h + f''(x0) h²/2` exactly.
    fn chain(self, f0: f64, f1: f64, f2: f64) -> Self {
        let mut h = self;
        h.0[C0] = 0.0;
        let h2 = h * h;
        let mut r = h * f1 + h2 * (0.5 * f2);
        r.0[C0] = f0;
        r
    }
    fn re(self) -> f64 {
        self.0[C0]
    }
    fn recip(self) -> Self {
        let x = self.re();
        self.chain(1.0 / x, -1.0 / (x * x), 2.0 / (x * x * x))
    }
    fn sqrt(self) -> Self {
        let s = self.re().sqrt();
        self.chain(s, 0.5 / s, -0.25 / (s * s * s))
    }
    fn exp(self) -> Self {
        let e = self.re().exp();
        self.chain(e, e, e)
    }
    fn ln(self) -> Self {
        let x = self.re();
        self.chain(x.ln(), 1.0 / x, -1.0 / (x * x))
    }
    fn sin(self) -> Self {
        let (s, c) = self.re().sin_cos();
        self.chain(s, c, -s)
    }
    fn cos(self) -> Self {
        let (s, c) = self.re().sin_cos();
        self.chain(c, -s, -c)
    }
    fn powf(self, n: f64) -> Self {
        let x = self.re();
        self.chain(
            x.powf(n),
            n * x.powf(n - 1.0),
            n * (n - 1.0) * x.powf(n - 2.0),
        )
    }
    /// `atan2(self, x)`: with `θ0 = atan2(y0, x0)`, `tan(θ − θ0) = u = (x0 y − y0 x)/(x0 x + y0 y)`, and
    /// `atan u = u` exactly here (`u` is nilpotent with `u³ = 0`, and atan has no `u²` term).
    fn atan2(self, x: Self) -> Self {
        let (y0, x0) = (self.re(), x.re());
        let mut u = (self * x0 - x * y0) / (x * x0 + self * y0);
        u.0[C0] = y0.atan2(x0);
        u
    }
    fn acos(self) -> Self {
        let x = self.re();
        let w = 1.0 - x * x;
        if w <= 0.0 {
            return T::c(x.clamp(-1.0, 1.0).acos());
        }
        self.chain(x.acos(), -1.0 / w.sqrt(), -x / (w * w.sqrt()))
    }
}

impl Add for T {
    type Output = T;
    fn add(self, o: T) -> T {
        T(std::array::from_fn(|i| self.0[i] + o.0[i]))
    }
}
impl Sub for T {
    type Output = T;
    fn sub(self, o: T) -> T {
        T(std::array::from_fn(|i| self.0[i] - o.0[i]))
    }
}
impl Neg for T {
    type Output = T;
    fn neg(self) -> T {
        T(self.0.map(|v| -v))
    }
}
impl Mul for T {
    type Output = T;
    fn mul(self, o: T) -> T {
        let (x, y) = (self.0, o.0);
        T([
            x[C0] * y[C0],
            x[C0] * y[CA] + x[CA] * y[C0],
            x[C0] * y[CB] + x[CB] * y[C0],
            x[C0] * y[CP] + x[CP] * y[C0],
            x[C0] * y[CAP] + x[CA] * y[CP] + x[CP] * y[CA] + x[CAP] * y[C0],
            x[C0] * y[CBP] + x[CB] * y[CP] + x[CP] * y[CB] + x[CBP] * y[C0],
        ])
    }
}
impl Mul<f64> for T {
    type Output = T;
    fn mul(self, s: f64) -> T {
        T(self.0.map(|v| v * s))
    }
}
impl Div for T {
    type Output = T;
    fn div(self, o: T) -> T {
        self * o.recip()
    }
}

// ---------------------------------------------------------------------------------------------------------
// D: first-order dual over T in the directions (x, y, z, π) — the crate's Scalar.
// ---------------------------------------------------------------------------------------------------------

/// Number of inner directions: three spatial ones and the scene parameter.
const N: usize = 4;
/// The inner direction fed by parameter slot 0.
const PARAM: usize = 3;

/// `v + Σ d_i ε_i` with `ε_i ε_j = 0`, every coefficient a [`T`].
#[derive(Copy, Clone, Debug, Default, PartialEq)]
struct D {
    v: T,
    d: [T; N],
}

impl D {
    fn from_t(v: T) -> Self {
        Self {
            v,
            d: [T::default(); N],
        }
    }
    /// `f(self)` given `f(v)` and `f'(v)` (both in `T`).
    fn chain(self, f: T, df: T) -> Self {
        Self {
            v: f,
            d: self.d.map(|d| d * df),
        }
    }
}

impl Add for D {
    type Output = D;
    fn add(self, o: D) -> D {
        D {
            v: self.v + o.v,
            d: std::array::from_fn(|i| self.d[i] + o.d[i]),
        }
    }
}
impl Sub for D {
    type Output = D;
    fn sub(self, o: D) -> D {
        D {
            v: self.v - o.v,
            d: std::array::from_fn(|i| self.d[i] - o.d[i]),
        }
    }
}
impl Neg for D {
    type Output = D;
    fn neg(self) -> D {
        D {
            v: -self.v,
            d: self.d.map(|d| -d),
        }
    }
}
impl Mul for D {
    type Output = D;
    fn mul(self, o: D) -> D {
        D {
            v: self.v * o.v,
            d: std::array::from_fn(|i| self.d[i] * o.v + self.v * o.d[i]),
        }
    }
}
impl Div for D {
    type Output = D;
    fn div(self, o: D) -> D {
        let r = o.v.recip();
        let q = self.v * r;
        D {
            v: q,
            d: std::array::from_fn(|i| (self.d[i] - q * o.d[i]) * r),
        }
    }
}
impl Add<f32> for D {
    type Output = D;
    fn add(self, s: f32) -> D {
        self + D::constant(s)
    }
}
impl Sub<f32> for D {
    type Output = D;
    fn sub(self, s: f32) -> D {
        self - D::constant(s)
    }
}
impl Mul<f32> for D {
    type Output = D;
    fn mul(self, s: f32) -> D {
        let s = f64::from(s);
        D {
            v: self.v * s,
            d: self.d.map(|d| d * s),
        }
    }
}
impl Div<f32> for D {
    type Output = D;
    fn div(self, s: f32) -> D {
        let s = 1.0 / f64::from(s);
        D {
            v: self.v * s,
            d: self.d.map(|d| d * s),
        }
    }
}
impl AddAssign for D {
    fn add_assign(&mut self, o: D) {
        *self = *self + o;
    }
}
impl SubAssign for D {
    fn sub_assign(&mut self, o: D) {
        *self = *self - o;
    }
}
impl MulAssign for D {
    fn mul_assign(&mut self, o: D) {
        *self = *self * o;
    }
}
impl DivAssign for D {
    fn div_assign(&mut self, o: D) {
        *self = *self / o;
    }
}

impl Scalar for D {
    fn constant(v: f32) -> Self {
        D::from_t(T::c(f64::from(v)))
    }
    fn primal(self) -> f32 {
        self.v.re() as f32
    }
    fn lift(value: f32, slot: implicit_psdr::scalar::Slot) -> Self {
        let mut x = D::constant(value);
        if slot == Some(0) {
            x.d[PARAM] = T::c(1.0);
        }
        x
    }
    fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        self.chain(s, (s * 2.0).recip())
    }
    fn exp(self) -> Self {
        let e = self.v.exp();
        self.chain(e, e)
    }
    fn ln(self) -> Self {
        self.chain(self.v.ln(), self.v.recip())
    }
    fn sin(self) -> Self {
        self.chain(self.v.sin(), self.v.cos())
    }
    fn cos(self) -> Self {
        self.chain(self.v.cos(), -self.v.sin())
    }
    fn atan2(self, x: Self) -> Self {
        let r2 = (x.v * x.v + self.v * self.v).recip();
        D {
            v: self.v.atan2(x.v),
            d: std::array::from_fn(|i| (x.v * self.d[i] - self.v * x.d[i]) * r2),
        }
    }
    fn acos(self) -> Self {
        let w = T::c(1.0) - self.v * self.v;
        if w.re() <= 0.0 {
            return D::from_t(self.v.acos());
        }
        self.chain(self.v.acos(), -w.sqrt().recip())
    }
    fn powf(self, n: f32) -> Self {
        let n = f64::from(n);
        self.chain(self.v.powf(n), self.v.powf(n - 1.0) * n)
    }
}

// ---------------------------------------------------------------------------------------------------------
// The area element of the displaced surface.
// ---------------------------------------------------------------------------------------------------------

type V3 = [f64; 3];

fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}

/// `φ` at the `T`-valued point `x`: value, gradient `∇φ` and `∂πφ`, each a `T`.
fn field(shape: &Shape, x: [T; 3]) -> (T, [T; 3], T) {
    let seed = |i: usize| {
        let mut c = D::from_t(x[i]);
        c.d[i] = T::c(1.0);
        c
    };
    let r = shape.eval(Vec3::new(seed(0), seed(1), seed(2)));
    (r.v, [r.d[0], r.d[1], r.d[2]], r.d[PARAM])
}

/// `φ`, `∇φ`, `∂πφ` at a plain point.
fn field_f64(shape: &Shape, p: V3) -> (f64, V3, f64) {
    let (v, g, dp) = field(shape, p.map(T::c));
    (v.re(), g.map(T::re), dp.re())
}

/// Projects `p` onto `φ = 0` by Newton steps along `∇φ`; `None` if the gradient degenerates or the
/// iteration does not reach `|φ| < 1e-6`. The result is rounded to `f32` (the crate's curvature takes
/// `f32` points) and must still satisfy `|φ| < 1e-5`.
fn project(shape: &Shape, p: glam::Vec3) -> Option<glam::Vec3> {
    let mut x = p.to_array().map(f64::from);
    for _ in 0..50 {
        let (v, g, _) = field_f64(shape, x);
        let g2 = dot(g, g);
        if g2.is_nan() || g2 <= 1e-4 {
            return None;
        }
        if v.abs() < 1e-9 {
            break;
        }
        x = std::array::from_fn(|i| x[i] - v * g[i] / g2);
    }
    let q = glam::Vec3::new(x[0] as f32, x[1] as f32, x[2] as f32);
    let (v, g, _) = field_f64(shape, q.to_array().map(f64::from));
    (v.abs() < 1e-5 && dot(g, g) > 1e-4).then_some(q)
}

/// One point's result.
struct Sample {
    p: glam::Vec3,
    /// `∂πJ` by AD of the area element.
    dj: f64,
    /// `V(p0)`.
    v: f64,
    /// `κ(p0)` from `Shape::curvature`.
    kappa: f64,
}

/// `∂πJ` at `p0` by the construction in the module notes, with `V(p0)` and the crate's `κ(p0)`.
fn area_derivative(shape: &Shape, p0: glam::Vec3) -> Sample {
    let p = p0.to_array().map(f64::from);
    let (_, g0, _) = field_f64(shape, p);
    let n0 = g0.map(|c| c / norm(g0));
    // Any unit vector not parallel to n0, then Gram–Schmidt.
    let helper = if n0[0].abs() < 0.6 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let t1 = cross(n0, helper);
    let t1 = t1.map(|c| c / norm(t1));
    let t2 = cross(n0, t1);

    // q(a, b) = p0 + a t1 + b t2.
    let q: [T; 3] = std::array::from_fn(|i| {
        let mut c = T::c(p[i]);
        c.0[CA] = t1[i];
        c.0[CB] = t2[i];
        c
    });
    // X(a, b) = q + s(a, b) n0 with φ(X) = 0: Newton in T. Once the constant part has converged, each
    // further step fixes the derivative coefficients exactly (the error is nilpotent), so a fixed number of
    // steps beyond convergence suffices; the residual is checked below.
    let at = |s: T| -> [T; 3] { std::array::from_fn(|i| q[i] + s * n0[i]) };
    let mut s = T::default();
    for _ in 0..40 {
        let (phi, g, _) = field(shape, at(s));
        let dphi_ds = g[0] * n0[0] + g[1] * n0[1] + g[2] * n0[2];
        s = s - phi / dphi_ds;
    }
    let x = at(s);
    let (phi, g, dphi_dpi) = field(shape, x);
    assert!(
        phi.0.iter().all(|c| c.abs() < 1e-9),
        "projection along n0 did not converge at {p0}: φ(X) = {phi:?}"
    );

    // n(X) = ∇φ/|∇φ|, V(X) = −∂πφ/|∇φ|, Y = X + π V n.
    let glen = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
    let inv = glen.recip();
    let vel = -dphi_dpi * inv;
    let mut pi = T::default();
    pi.0[CP] = 1.0;
    let y: [T; 3] = std::array::from_fn(|i| x[i] + pi * vel * g[i] * inv);

    // ∂aY and ∂bY at π = 0 and their π-derivatives; A = |∂aY × ∂bY|.
    let ya: V3 = y.map(|c| c.0[CA]);
    let yb: V3 = y.map(|c| c.0[CB]);
    let ya_p: V3 = y.map(|c| c.0[CAP]);
    let yb_p: V3 = y.map(|c| c.0[CBP]);
    let c0 = cross(ya, yb);
    let c1a = cross(ya_p, yb);
    let c1b = cross(ya, yb_p);
    let c1: V3 = std::array::from_fn(|i| c1a[i] + c1b[i]);
    let a0 = norm(c0);
    let dj = dot(c0, c1) / (a0 * a0);

    Sample {
        p: p0,
        dj,
        v: vel.re(),
        kappa: f64::from(shape.curvature(p0)),
    }
}

/// Relative tolerance: the AD side is `f64`, `κ` the crate's `f32` curvature.
const TOL: f64 = 1e-4;

/// Error of `dj` against `target`, relative to `max(|κV|, |V|/ℓ)`; for `V = 0` the absolute error.
fn rel_err(s: &Sample, target: f64, size: f64) -> f64 {
    let scale = (s.kappa * s.v).abs().max(s.v.abs() / size);
    if scale > 0.0 {
        (s.dj - target).abs() / scale
    } else {
        (s.dj - target).abs()
    }
}

/// Samples `count` surface points (starting points drawn from the boxes in `regions`, in turn), checks
/// `∂πJ = κV` at each, checks that `κV/2` would fail, and returns the samples. `size` is `ℓ`.
fn check(
    label: &str,
    shape: &Shape,
    regions: &[(glam::Vec3, glam::Vec3)],
    size: f64,
    count: usize,
) -> Vec<Sample> {
    // A seed per label (FNV-1a), so that two parameters of one shape see different points.
    let seed = label.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, c| {
        (h ^ u64::from(c)).wrapping_mul(0x100_0000_01b3)
    });
    let mut rng = Rng::new(seed);
    let mut samples = Vec::with_capacity(count);
    let mut tries = 0;
    while samples.len() < count {
        tries += 1;
        assert!(tries < 20 * count, "{label}: too few projectable points");
        let (lo, hi) = regions[tries % regions.len()];
        let Some(p0) = project(shape, rng.in_box(lo, hi)) else {
            continue;
        };
        samples.push(area_derivative(shape, p0));
    }
    let (mut worst, mut at) = (0.0f64, glam::Vec3::ZERO);
    let mut worst_half = 0.0f64;
    let mut moving = 0;
    for s in &samples {
        let kv = s.kappa * s.v;
        let e = rel_err(s, kv, size);
        assert!(
            e <= TOL,
            "{label}: ∂πJ = {} by AD but κV = {kv} (κ = {}, V = {}) at {}: relative error {e:.3e}",
            s.dj,
            s.kappa,
            s.v,
            s.p
        );
        if e > worst {
            (worst, at) = (e, s.p);
        }
        if s.v != 0.0 {
            moving += 1;
        }
        if kv.abs() > 1e-3 * s.v.abs() / size {
            worst_half = worst_half.max(rel_err(s, 0.5 * kv, size));
        }
    }
    // The comparison has teeth: a factor of 2 in κV (a classic slip: mean vs total curvature) fails.
    assert!(
        worst_half > 100.0 * TOL,
        "{label}: κV/2 would pass too (worst {worst_half:.3e}): the data cannot tell"
    );
    println!(
        "{label}: {} points ({moving} with V ≠ 0), worst relative error {worst:.3e} at {at}; κV/2 misses by {worst_half:.3e}",
        samples.len()
    );
    samples
}

/// `Param` fed to derivative slot 0.
fn seeded(value: f32) -> Param {
    Param {
        value,
        slot: Some(0),
    }
}

fn shape(sdf: Sdf) -> Shape {
    Shape::new(
        "s",
        sdf,
        Bsdf::Diffuse {
            albedo: Param3::new([0.5; 3]),
        },
    )
}

fn around(shape: &Shape, margin: f32) -> (glam::Vec3, glam::Vec3) {
    let b = shape.bounds;
    (
        b.min - glam::Vec3::splat(margin),
        b.max + glam::Vec3::splat(margin),
    )
}

#[test]
fn sphere_radius() {
    let r = 0.7f32;
    let s = shape(Sdf::Sphere {
        center: Param3::new([0.1, -0.2, 0.3]),
        radius: seeded(r),
    });
    let samples = check("sphere radius", &s, &[around(&s, 0.5)], 1.0, 100);
    // Closed form: V = 1, κ = 2/r.
    let closed = 2.0 / f64::from(r);
    for x in &samples {
        assert!((x.v - 1.0).abs() < 1e-6, "V = {} at {}", x.v, x.p);
        assert!(
            (x.dj - closed).abs() < TOL * closed,
            "∂πJ = {} at {}, 2/r = {closed}",
            x.dj,
            x.p
        );
    }
}

#[test]
fn sphere_center() {
    // V = n_x, κV = 2 n_x / r: a parameter whose V changes sign over the surface.
    let mut center = Param3::new([0.1, -0.2, 0.3]);
    center.c[0] = seeded(0.1);
    let s = shape(Sdf::Sphere {
        center,
        radius: Param::new(0.7),
    });
    check("sphere center.x", &s, &[around(&s, 0.5)], 1.0, 60);
}

fn torus(major: Param, minor: Param) -> Shape {
    shape(Sdf::Torus {
        center: Param3::new([0.0, 0.1, -0.1]),
        axis: glam::Vec3::new(0.3, 1.0, 0.2).normalize(),
        major_radius: major,
        minor_radius: minor,
    })
}

#[test]
fn torus_radii() {
    let s = torus(seeded(1.0), Param::new(0.35));
    check("torus major_radius", &s, &[around(&s, 0.3)], 1.0, 150);
    let s = torus(Param::new(1.0), seeded(0.35));
    check("torus minor_radius", &s, &[around(&s, 0.3)], 1.0, 150);
}

fn blob(k: Param, cx: Param) -> Shape {
    let mut c0 = Param3::new([-0.45, 0.0, 0.0]);
    c0.c[0] = cx;
    shape(Sdf::SmoothUnion {
        children: Children::new(vec![
            Sdf::Sphere {
                center: c0,
                radius: Param::new(0.5),
            },
            Sdf::Sphere {
                center: Param3::new([0.45, 0.05, 0.0]),
                radius: Param::new(0.4),
            },
        ]),
        k,
    })
}

#[test]
fn smooth_union_k_and_child() {
    // Half of the starting points near the neck, where the blend (and ∂kφ) lives.
    let neck = (
        glam::Vec3::new(-0.25, -0.8, -0.8),
        glam::Vec3::new(0.25, 0.8, 0.8),
    );
    let s = blob(seeded(0.4), Param::new(-0.45));
    let samples = check("smooth union k", &s, &[around(&s, 0.3), neck], 1.0, 160);
    assert!(samples.iter().filter(|x| x.v.abs() > 1e-3).count() > 40);
    let s = blob(Param::new(0.4), seeded(-0.45));
    check(
        "smooth union child center.x",
        &s,
        &[around(&s, 0.3), neck],
        1.0,
        160,
    );
}

fn rounded_box(hx: Param, rounding: Param) -> Shape {
    let mut half = Param3::new([0.8, 0.6, 0.45]);
    half.c[0] = hx;
    shape(Sdf::Box {
        center: Param3::new([0.05, 0.0, -0.1]),
        half_size: half,
        rounding,
    })
}

#[test]
fn rounded_box_half_size_and_rounding() {
    let s = rounded_box(seeded(0.8), Param::new(0.2));
    let samples = check("rounded box half_size.x", &s, &[around(&s, 0.3)], 1.0, 200);
    // Both kinds of points occur: flat faces (κ = 0) and rounded edges/corners.
    assert!(samples.iter().any(|x| x.kappa == 0.0 && x.v.abs() > 0.5));
    assert!(samples.iter().any(|x| x.kappa > 1.0 && x.v.abs() > 0.1));
    let s = rounded_box(Param::new(0.8), seeded(0.2));
    check("rounded box rounding", &s, &[around(&s, 0.3)], 1.0, 200);
}

#[test]
fn grid_translate() {
    let (lo, hi) = (glam::Vec3::splat(-1.1), glam::Vec3::splat(1.1));
    let data = bake(&Sdf::sphere([0.0, 0.0, 0.0], 0.75), lo, hi, 32);
    let grid = Sdf::grid(data, lo, hi).expect("valid grid");
    let mut translate = Param3::new([0.05, -0.1, 0.2]);
    translate.c[0] = seeded(0.05);
    let s = Shape::translated(
        "g",
        grid,
        Bsdf::Diffuse {
            albedo: Param3::new([0.5; 3]),
        },
        translate,
    );
    let samples = check("grid translate.x", &s, &[around(&s, 0.0)], 1.0, 120);
    // A rigid translation along x: V = n_x.
    for x in &samples {
        let n = s.normal(x.p);
        assert!(
            (x.v - f64::from(n.x)).abs() < 1e-5,
            "V = {} but n_x = {}",
            x.v,
            n.x
        );
    }

    // A baked torus: principal curvatures of both signs (κ from 1/r − 1/(R − r) ≈ 0.83 on the inner
    // equator to 1/r + 1/(R + r) ≈ 4.33 on the outer one), translated along y (V = n_y).
    let (lo, hi) = (
        glam::Vec3::new(-1.1, -0.5, -1.1),
        glam::Vec3::new(1.1, 0.5, 1.1),
    );
    let torus = Sdf::torus([0.0, 0.0, 0.0], glam::Vec3::Y, 0.7, 0.3);
    let grid = Sdf::grid(bake(&torus, lo, hi, 48), lo, hi).expect("valid grid");
    let mut translate = Param3::new([0.0, 0.1, 0.0]);
    translate.c[1] = seeded(0.1);
    let s = Shape::translated(
        "t",
        grid,
        Bsdf::Diffuse {
            albedo: Param3::new([0.5; 3]),
        },
        translate,
    );
    let samples = check("baked torus translate.y", &s, &[around(&s, 0.0)], 1.0, 120);
    assert!(samples.iter().any(|x| x.kappa < 1.5) && samples.iter().any(|x| x.kappa > 3.5));
}

#[test]
fn truncated_ring_arithmetic() {
    // The T rules against closed forms: x = 2 + a + 3π, f = sqrt: coefficients of a, π, aπ are
    // f'(2), 3f'(2), 3f''(2) (the aπ term of f''(x0) h²/2 with h = a + 3π is f''·3).
    let mut x = T::c(2.0);
    x.0[CA] = 1.0;
    x.0[CP] = 3.0;
    let checks: [(&str, T, f64, f64, f64); 5] = [
        (
            "sqrt",
            x.sqrt(),
            2f64.sqrt(),
            0.5 / 2f64.sqrt(),
            -0.25 / 2f64.powf(1.5),
        ),
        ("exp", x.exp(), 2f64.exp(), 2f64.exp(), 2f64.exp()),
        ("recip", x.recip(), 0.5, -0.25, 0.25),
        (
            "atan2(x, 1)",
            x.atan2(T::c(1.0)),
            2f64.atan(),
            0.2,
            -4.0 / 25.0,
        ),
        (
            "powf 1.5",
            x.powf(1.5),
            2f64.powf(1.5),
            1.5 * 2f64.sqrt(),
            0.75 / 2f64.sqrt(),
        ),
    ];
    for (name, r, f0, f1, f2) in checks {
        let want = [f0, f1, 0.0, 3.0 * f1, 3.0 * f2, 0.0];
        for (i, (&g, w)) in r.0.iter().zip(want).enumerate() {
            assert!(
                (g - w).abs() < 1e-12,
                "{name}: coefficient {i} is {g}, expected {w}"
            );
        }
    }
}
