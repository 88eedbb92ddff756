//! Conformance suite for every [`Scalar`] type, written once as a macro (`scalar_suite!`).
//!
//! For each type and each "spicy" input (0, tiny, negative, large) it evaluates a list of expressions that
//! together use every trait method and operator. Primal values must agree with `f32` (exactly for the
//! in-project [`DualN`] and [`Grad`], whose primal paths perform the same `f32` operations), and
//! derivatives in every direction must agree with central differences of an `f64` evaluation of the same
//! generic code (the local [`F64`] type); for [`Grad`]`<S>` that is the spatial direction and every
//! direction of `S`, and the mixed partials (second differences). The set-valued types ([`Interval`],
//! [`IntervalGrad`]) must enclose the reference values and derivatives, on points and on small sets, and
//! be tight on points. Further tests: a many-input expression where `DualN<8>` must give, slot by slot,
//! what `Dual32` seeded in that input gives; the quotient rule; finite derivatives at the guarded points
//! (`safe_sqrt` at 0, `acos` at ±1, `atan2` at the origin); and `Grad` on an SDF, on and off its surface,
//! against num-dual's spatial gradient.
//!
//! The reverse-mode [`Rev`] (and `Grad<Rev>`) joins the suite: a direction `k` is gradient entry `k`
//! (`Rev::parameter(x, k)`), and it is read back by sweeping the tape from the value
//! ([`Recording::sweep`]), so every check runs inside a [`Recording`] ([`Directions::recorded`]). Its own
//! tests: the eight-input expression swept once against `DualN<8>` slot by slot; a recording refuses to
//! start inside another on the same thread; and the grid's B-spline sum ([`Scalar::lattice_sum`]), one
//! node over 64 values, gives each value the product of its weights and agrees with forward mode along
//! a direction of the values, directly and through a grid SDF (value and spatial gradient).

use implicit_psdr::scalar::interval::{Interval, IntervalGrad};
use implicit_psdr::scalar::{
    Dual2Vec3, Dual32, DualN, DualVec3, Grad, Recording, Rev, Scalar, Slot,
};
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// Reference scalar: plain `f64`, used for central differences with a step far below `f32` resolution.
#[derive(Copy, Clone, Debug, PartialEq)]
struct F64(f64);

macro_rules! f64_ops {
    ($($tr:ident $m:ident $atr:ident $am:ident $op:tt),*) => {$(
        impl $tr for F64 {
            type Output = F64;
            fn $m(self, o: F64) -> F64 { F64(self.0 $op o.0) }
        }
        impl $tr<f32> for F64 {
            type Output = F64;
            fn $m(self, o: f32) -> F64 { F64(self.0 $op o as f64) }
        }
        impl $atr for F64 {
            fn $am(&mut self, o: F64) { self.0 = self.0 $op o.0; }
        }
    )*};
}
f64_ops!(Add add AddAssign add_assign +, Sub sub SubAssign sub_assign -,
         Mul mul MulAssign mul_assign *, Div div DivAssign div_assign /);

impl Neg for F64 {
    type Output = F64;
    fn neg(self) -> F64 {
        F64(-self.0)
    }
}

impl Scalar for F64 {
    fn constant(v: f32) -> Self {
        F64(v as f64)
    }
    fn primal(self) -> f32 {
        self.0 as f32
    }
    fn lift(value: f32, _slot: Slot) -> Self {
        F64(value as f64)
    }
    fn sqrt(self) -> Self {
        F64(self.0.sqrt())
    }
    fn exp(self) -> Self {
        F64(self.0.exp())
    }
    fn ln(self) -> Self {
        F64(self.0.ln())
    }
    fn sin(self) -> Self {
        F64(self.0.sin())
    }
    fn cos(self) -> Self {
        F64(self.0.cos())
    }
    fn atan2(self, x: Self) -> Self {
        F64(self.0.atan2(x.0))
    }
    fn acos(self) -> Self {
        F64(self.0.clamp(-1.0, 1.0).acos())
    }
    fn powf(self, n: f32) -> Self {
        F64(self.0.powf(n as f64))
    }
    // The defaults compare `primal()`, which rounds to f32: compare in f64 so the reference is smooth.
    fn abs(self) -> Self {
        F64(self.0.abs())
    }
    fn max(self, o: Self) -> Self {
        if o.0 > self.0 { o } else { self }
    }
    fn min(self, o: Self) -> Self {
        if o.0 < self.0 { o } else { self }
    }
    fn clamp(self, lo: f32, hi: f32) -> Self {
        F64(self.0.clamp(lo as f64, hi as f64))
    }
    fn safe_sqrt(self) -> Self {
        F64(self.0.max(0.0).sqrt())
    }
}

/// Read access to the derivative directions of a scalar type.
trait Directions: Scalar {
    /// How many directions `lift` can seed.
    const DIRS: usize;
    /// The derivative in direction `k`.
    fn d(self, k: usize) -> f32;
    /// `x` seeded in direction `k` (a constant for `k >= DIRS`, or a direction that is not read).
    fn seed(x: f32, k: usize) -> Self {
        Self::lift(x, Some(k as u32))
    }
    /// Runs `f`, in which values are computed and their directions read, with what the type needs to
    /// record them (a tape for reverse mode; nothing for forward mode).
    fn recorded<R>(f: impl FnOnce() -> R) -> R {
        f()
    }
}

impl Directions for f32 {
    const DIRS: usize = 0;
    fn d(self, _k: usize) -> f32 {
        0.0
    }
}

impl Directions for F64 {
    const DIRS: usize = 0;
    fn d(self, _k: usize) -> f32 {
        0.0
    }
}

// The spatial types treat scene parameters as constants: only their primal values are checked here.
impl Directions for DualVec3 {
    const DIRS: usize = 0;
    fn d(self, _k: usize) -> f32 {
        0.0
    }
}

impl Directions for Dual2Vec3 {
    const DIRS: usize = 0;
    fn d(self, _k: usize) -> f32 {
        0.0
    }
}

impl Directions for Dual32 {
    const DIRS: usize = 1;
    fn d(self, k: usize) -> f32 {
        assert_eq!(k, 0);
        self.eps
    }
}

impl<const N: usize> Directions for DualN<N> {
    const DIRS: usize = N;
    fn d(self, k: usize) -> f32 {
        self.eps[k]
    }
}

/// Direction `k` is gradient entry `k`, read by sweeping the tape backwards from the value (the tape
/// of the [`Recording`] that [`Directions::recorded`] holds; entries reported several times are summed).
/// Seeds past `DIRS` are parameters whose entries are not read, so they look constant.
impl Directions for Rev {
    const DIRS: usize = 3;
    fn d(self, k: usize) -> f32 {
        let mut sum = 0.0;
        Recording::sweep(self, |entry, d| {
            if entry as usize == k {
                sum += d;
            }
        });
        sum
    }
    fn recorded<R>(f: impl FnOnce() -> R) -> R {
        let _tape = Recording::start();
        f()
    }
}

/// Direction 0 is the spatial one (`g[0]`, seeded as `Grad::seed` seeds an axis); directions `1..` are
/// those of `S`, carried by the value (scene parameters are constants in space).
impl<S: Directions> Directions for Grad<S> {
    const DIRS: usize = 1 + S::DIRS;
    fn d(self, k: usize) -> f32 {
        if k == 0 {
            self.g[0].primal()
        } else {
            self.v.d(k - 1)
        }
    }
    fn seed(x: f32, k: usize) -> Self {
        let z = S::zero();
        if k == 0 {
            Grad {
                v: S::constant(x),
                g: [S::one(), z, z],
            }
        } else {
            Grad {
                v: S::seed(x, k - 1),
                g: [z; 3],
            }
        }
    }
    fn recorded<R>(f: impl FnOnce() -> R) -> R {
        S::recorded(f)
    }
}

/// Inputs: zero, tiny of both signs, ordinary negative and positive values, large of both signs.
const SPICY: [f32; 9] = [0.0, 1e-6, -1e-6, -0.7, 0.45, 2.5, -3.0, 150.0, -1.0e4];

/// Expressions that are smooth at every [`SPICY`] input (kinks are placed elsewhere) and together use
/// every operator and trait method. Each entry is one idea so its magnitude is predictable.
fn exprs<S: Scalar>(x: S) -> Vec<S> {
    let mut assign = x;
    assign += S::constant(1.0);
    assign *= x;
    assign -= S::constant(0.5);
    assign /= x.sqr() + 2.0;
    assign += x * 0.25;
    assign -= S::constant(0.25);
    assign *= S::constant(3.0);
    assign /= S::constant(2.0);
    vec![
        // Arithmetic, dual and mixed.
        x * x * 0.5 + x * 3.0 - 1.0,
        (x + 1.5) / (x.sqr() + 1.0) - x / 4.0,
        -x * (S::one() - S::zero() * x) + S::constant(2.0) - x,
        assign,
        (x.sqr() + 0.3).recip(),
        // Elementary functions.
        (x.sqr() + 1.0).sqrt(),
        (x * 0.5).sin() * (x * 0.3).cos(),
        (x.sqr() + 0.5).ln(),
        (-(x.sqr()) * 0.1).exp() + (x * 0.001).exp(),
        (x - 0.2).atan2(S::constant(0.7) + x * 0.1),
        S::constant(-0.4).atan2(x),
        (x * 0.5).acos(),
        (x.sqr() + 0.25).powf(1.7),
        x.abs().powf(3.0),
        // Primal-branching functions: kinks at 0.1, 0.25, -2, -1, 2 and 0.5, none of them spicy.
        (x - 0.1).abs() * 2.0,
        x.max(S::constant(0.25)) + x.min(x * 0.5 - 1.0),
        x.clamp(-1.0, 2.0) * x,
        (x - 0.5).safe_sqrt(),
    ]
}

/// `|a - b| <= rel · max(|b|, 1)`.
fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs().max(1.0)
}

/// Central difference in `f64` of expression `i` at `x`.
fn reference_derivatives(x: f32) -> Vec<f64> {
    let h = 1e-6 * (x.abs() as f64).max(1.0);
    let hi = exprs(F64(x as f64 + h));
    let lo = exprs(F64(x as f64 - h));
    hi.iter()
        .zip(&lo)
        .map(|(a, b)| (a.0 - b.0) / (2.0 * h))
        .collect()
}

/// Checks one type: primal agreement with `f32` (`exact` for bitwise) and derivatives in every direction.
fn check_type<S: Directions>(exact: bool) {
    for &x in &SPICY {
        S::recorded(|| check_at::<S>(x, exact));
    }
}

/// [`check_type`] at one input `x`.
fn check_at<S: Directions>(x: f32, exact: bool) {
    let reference = exprs(x);
    let fd = reference_derivatives(x);
    // Every direction, plus one slot past the last (which must give a constant).
    for k in 0..=S::DIRS {
        let values = exprs(S::seed(x, k));
        for (i, (v, &r)) in values.iter().zip(&reference).enumerate() {
            let p = v.primal();
            if exact {
                assert_eq!(p.to_bits(), r.to_bits(), "expr {i} at x = {x}: {p} vs {r}");
            } else {
                assert!(
                    close(p as f64, r as f64, 1e-4),
                    "expr {i} at x = {x}: {p} vs {r}"
                );
            }
            for j in 0..S::DIRS {
                let d = v.d(j) as f64;
                let want = if j == k { fd[i] } else { 0.0 };
                assert!(
                    close(d, want, 1e-3),
                    "expr {i} at x = {x}, seeded {k}, direction {j}: {d} vs {want}"
                );
            }
        }
    }
    // `detach` drops the derivative of its factor: d(detach(x) · x) = x.
    let v = S::seed(x, 0).detach() * S::seed(x, 0);
    assert_eq!(v.primal(), x * x);
    if S::DIRS > 0 {
        assert_eq!(v.d(0), x);
    }
    // Unseeded lifts are constants.
    let c = exprs(S::lift(x, None));
    for v in c {
        for j in 0..S::DIRS {
            assert_eq!(v.d(j), 0.0);
        }
    }
}

macro_rules! scalar_suite {
    ($name:ident, $t:ty, exact = $exact:expr) => {
        #[test]
        fn $name() {
            check_type::<$t>($exact);
        }
    };
    ($name:ident, $t:ty, enclosure) => {
        #[test]
        fn $name() {
            check_enclosure::<$t>();
        }
    };
}

/// Set-valued scalars: a set of inputs, and read access to the enclosures.
trait SetValued: Scalar {
    /// The input set `[lo, hi]`, seeded in the spatial direction `x` if the type has derivatives.
    fn set(lo: f64, hi: f64) -> Self;
    /// The enclosure of the value.
    fn value(self) -> Interval;
    /// The enclosure of the derivative along the seeded direction, if the type has one.
    fn derivative(self) -> Option<Interval>;
}

impl SetValued for Interval {
    fn set(lo: f64, hi: f64) -> Self {
        Interval::new(lo, hi)
    }
    fn value(self) -> Interval {
        self
    }
    fn derivative(self) -> Option<Interval> {
        None
    }
}

impl SetValued for IntervalGrad {
    fn set(lo: f64, hi: f64) -> Self {
        IntervalGrad {
            v: Interval::new(lo, hi),
            g: [Interval::point(1.0), Interval::ZERO, Interval::ZERO],
        }
    }
    fn value(self) -> Interval {
        self.v
    }
    fn derivative(self) -> Option<Interval> {
        Some(self.g[0])
    }
}

/// `i` holds `v` up to `slack · max(|v|, 1)` (the `f64` reference is itself rounded).
fn holds(i: Interval, v: f64, slack: f64) -> bool {
    let t = slack * v.abs().max(1.0);
    i.lo - t <= v && v <= i.hi + t
}

/// Checks a set-valued type: on each [`SPICY`] point, every expression's enclosure holds the `f64`
/// reference value (and derivative) and is only a few ulps wide; on a small set around the point, it holds
/// the reference at samples across the set.
fn check_enclosure<S: SetValued>() {
    for &x in &SPICY {
        let xf = x as f64;
        let fd = reference_derivatives(x);
        let exact = exprs(F64(xf));
        let point = exprs(S::set(xf, xf));
        for (i, (e, r)) in point.iter().zip(&exact).enumerate() {
            let v = e.value();
            assert!(
                holds(v, r.0, 1e-12),
                "expr {i} at x = {x}: {v:?} misses {}",
                r.0
            );
            assert!(
                v.width() <= 1e-9 * r.0.abs().max(1.0),
                "expr {i} at x = {x}: {v:?} is loose"
            );
            if let Some(d) = e.derivative() {
                assert!(
                    holds(d, fd[i], 1e-5),
                    "expr {i} at x = {x}: ∂ {d:?} misses {}",
                    fd[i]
                );
                // Beyond acos's clamp the derivative enclosure is the hull of the clamp's 0 and the
                // unbounded interior derivative: sound, not tight.
                let acos_clamped = i == 11 && (xf * 0.5).abs() >= 1.0;
                if !acos_clamped {
                    assert!(
                        d.width() <= 1e-6 * fd[i].abs().max(1.0),
                        "expr {i} at x = {x}: ∂ {d:?} is loose"
                    );
                }
            }
        }
        // A set of width 2w around x (crossing no kink: the nearest is 0.05 away from a spicy input).
        let w = 1e-3 * xf.abs().clamp(1.0, 10.0);
        let wide = exprs(S::set(xf - w, xf + w));
        for t in [-1.0, -0.5, 0.0, 0.3, 1.0] {
            let xs = xf + t * w;
            let r = exprs(F64(xs));
            let h = 1e-6 * xs.abs().max(1.0);
            let (rp, rm) = (exprs(F64(xs + h)), exprs(F64(xs - h)));
            for (i, e) in wide.iter().enumerate() {
                let v = e.value();
                assert!(
                    holds(v, r[i].0, 1e-12),
                    "expr {i} on x = {x} ± {w} at {xs}: {v:?} misses {}",
                    r[i].0
                );
                if let Some(d) = e.derivative() {
                    let fd = (rp[i].0 - rm[i].0) / (2.0 * h);
                    assert!(
                        holds(d, fd, 1e-5),
                        "expr {i} on x = {x} ± {w} at {xs}: ∂ {d:?} misses {fd}"
                    );
                }
            }
        }
    }
}

scalar_suite!(f32_conforms, f32, exact = true);
scalar_suite!(f64_reference_conforms, F64, exact = false);
scalar_suite!(dualvec3_conforms, DualVec3, exact = false);
scalar_suite!(dual2vec3_conforms, Dual2Vec3, exact = false);
scalar_suite!(dual32_conforms, Dual32, exact = false);
scalar_suite!(dual_n1_conforms, DualN<1>, exact = true);
scalar_suite!(dual_n3_conforms, DualN<3>, exact = true);
scalar_suite!(dual_n8_conforms, DualN<8>, exact = true);
scalar_suite!(grad_f32_conforms, Grad<f32>, exact = true);
scalar_suite!(grad_dual_n2_conforms, Grad<DualN<2>>, exact = true);
scalar_suite!(grad_dual32_conforms, Grad<Dual32>, exact = false);
scalar_suite!(rev_conforms, Rev, exact = true);
scalar_suite!(grad_rev_conforms, Grad<Rev>, exact = true);
scalar_suite!(interval_encloses, Interval, enclosure);
scalar_suite!(interval_grad_encloses, IntervalGrad, enclosure);

/// `Grad<S>` seeded in space and in the first direction of `S` at once: `g[0]`'s derivative in that
/// direction is the mixed partial, here `f''(x)`, against a second difference in `f64`. This is what the
/// attached normals read (`∂π∇φ`); a rule whose local derivative were computed from primal values only
/// would give 0 here.
fn check_mixed_partials<S: Directions>() {
    S::recorded(mixed_partials_at_spicy_points::<S>);
}

/// [`check_mixed_partials`]'s body (inside a recording for reverse mode).
fn mixed_partials_at_spicy_points<S: Directions>() {
    for &x in &SPICY {
        // A step growing like √|x|: the oscillating entries need a short step at large |x|, the
        // polynomial ones a step long enough that rounding of their large values stays small.
        let h = 1e-3 * (x.abs() as f64).max(1.0).sqrt();
        let at = |t: f64| exprs(F64(x as f64 + t));
        let (hi, mid, lo) = (at(h), at(0.0), at(-h));
        let z = S::zero();
        let values = exprs(Grad {
            v: S::seed(x, 0),
            g: [S::one(), z, z],
        });
        for (i, v) in values.iter().enumerate() {
            let want = (hi[i].0 - 2.0 * mid[i].0 + lo[i].0) / (h * h);
            let first = (hi[i].0 - lo[i].0) / (2.0 * h);
            let (d2, d1, dv) = (v.g[0].d(0) as f64, v.g[0].primal() as f64, v.v.d(0) as f64);
            assert!(
                close(d2, want, 2e-3),
                "expr {i} at x = {x}: f'' {d2} vs {want}"
            );
            // Spatial and parameter directions see the same first derivative.
            assert!(
                close(d1, first, 1e-3) && close(dv, first, 1e-3),
                "expr {i} at x = {x}"
            );
        }
    }
}

#[test]
fn grad_mixed_partials_match_second_differences() {
    check_mixed_partials::<DualN<1>>();
    check_mixed_partials::<Dual32>();
    check_mixed_partials::<Rev>();
}

/// A shading-like function of eight inputs: a normal from three, a light direction from three, an albedo
/// and a distance; cosine term, inverse-square falloff, an angle and a smooth exponential.
fn eight<S: Scalar>(x: [S; 8]) -> S {
    let [nx, ny, nz, lx, ly, lz, albedo, dist] = x;
    let n_len = (nx.sqr() + ny.sqr() + nz.sqr()).sqrt();
    let l_len = (lx * lx + ly * ly + lz * lz).safe_sqrt();
    let cos_t = (nx * lx + ny * ly + nz * lz) / (n_len * l_len);
    let falloff = (dist.sqr() + 0.1).recip();
    let angle = cos_t.acos() + ny.atan2(nx);
    cos_t.max(S::zero()) * albedo * falloff + angle.sin() * 0.1 + (-(dist * 0.3).abs()).exp()
        - (albedo + 2.0).ln() * (dist.powf(1.5) / 7.0)
}

const POINTS: [[f32; 8]; 3] = [
    [0.1, 0.9, 0.2, 0.3, 0.8, -0.1, 0.7, 1.5],
    [-0.5, 0.4, 0.6, -0.2, 0.5, 0.9, 0.25, 3.0],
    [2.0, -1.0, 0.5, 4.0, -1.5, 1.0, 0.9, 0.2],
];

#[test]
fn dual_n8_slots_match_dual32_seeded_per_input() {
    for p in POINTS {
        let many = eight(std::array::from_fn(|i| {
            DualN::<8>::lift(p[i], Some(i as u32))
        }));
        let few = eight(std::array::from_fn(|i| {
            DualN::<3>::lift(p[i], Some(i as u32))
        }));
        // Lanes are independent: the first three lanes of `DualN<8>` are those of `DualN<3>`, bit for bit.
        assert_eq!(few.eps, many.eps[..3]);
        assert_eq!(few.re.to_bits(), many.re.to_bits());
        for k in 0..8 {
            let one = eight(std::array::from_fn(|i| {
                Dual32::lift(p[i], if i == k { Some(0) } else { None })
            }));
            assert!(close(many.re as f64, one.re as f64, 1e-6));
            assert!(
                close(many.eps[k] as f64, one.eps as f64, 1e-5),
                "input {k} at {p:?}: {} vs {}",
                many.eps[k],
                one.eps
            );
            // And both against a central difference in f64.
            let h = 1e-6;
            let at = |s: f64| {
                eight(std::array::from_fn(|i| {
                    F64(p[i] as f64 + if i == k { s } else { 0.0 })
                }))
                .0
            };
            let fd = (at(h) - at(-h)) / (2.0 * h);
            assert!(
                close(many.eps[k] as f64, fd, 1e-4),
                "input {k} at {p:?}: {} vs {fd}",
                many.eps[k]
            );
        }
    }
}

/// num-dual 0.15 computes `atan2(y, x)` as `atan(y / x)`, whose derivative is NaN at `x = 0`; the
/// `Scalar` impl for the num-dual types avoids that quotient. ∂atan2(y, x)/∂x = −y / (x² + y²) = 2.5 here.
#[test]
fn atan2_at_zero_x_has_finite_derivatives() {
    let v = Dual32::constant(-0.4).atan2(Dual32::lift(0.0, Some(0)));
    assert!(close(v.eps as f64, 2.5, 1e-6), "{v:?}");
    let c = Dual32::constant(-0.4).atan2(Dual32::constant(0.0));
    assert_eq!(c.eps, 0.0);
    let w = DualN::<1>::constant(-0.4).atan2(DualN::<1>::lift(0.0, Some(0)));
    assert!(close(w.eps[0] as f64, 2.5, 1e-6));
    // Every quadrant and both axes agree with the rule table.
    for (y, x) in [
        (0.3f32, 0.7f32),
        (0.7, -0.3),
        (-0.2, -0.9),
        (-0.8, 0.1),
        (0.5, 0.0),
        (0.0, -0.5),
    ] {
        let (value, dy, dx) = implicit_psdr::scalar::rules::atan2(y, x);
        let a = Dual32::lift(y, Some(0)).atan2(Dual32::constant(x));
        let b = Dual32::constant(y).atan2(Dual32::lift(x, Some(0)));
        assert!(close(a.re as f64, value as f64, 1e-6) && close(a.eps as f64, dy as f64, 1e-5));
        assert!(
            close(b.eps as f64, dx as f64, 1e-5),
            "({y}, {x}): {b:?} vs {dx}"
        );
    }
}

#[test]
fn quotient_rule() {
    let (a, b) = (1.3f32, -0.6f32);
    // Independent numerator and denominator: d(x/y) = (1/y, -x/y²).
    let q = DualN::<3>::lift(a, Some(0)) / DualN::<3>::lift(b, Some(1));
    assert_eq!(q.re, a / b);
    assert!(close(q.eps[0] as f64, 1.0 / b as f64, 1e-6));
    assert!(close(
        q.eps[1] as f64,
        -(a as f64) / (b as f64).powi(2),
        1e-6
    ));
    assert_eq!(q.eps[2], 0.0);
    // Denominator depending on the numerator's variable: x / (2x + y), d/dx = y / (2x + y)².
    let x = DualN::<3>::lift(a, Some(0));
    let y = DualN::<3>::lift(b, Some(1));
    let q = x / (x * 2.0 + y);
    let den = 2.0 * a as f64 + b as f64;
    assert!(close(q.eps[0] as f64, b as f64 / den.powi(2), 1e-6));
    assert!(close(q.eps[1] as f64, -(a as f64) / den.powi(2), 1e-6));
    let qd = Dual32::lift(a, Some(0)) / (Dual32::lift(a, Some(0)) * 2.0 + Dual32::lift(b, None));
    assert!(close(qd.eps as f64, q.eps[0] as f64, 1e-6));
    // Constant over dual: d(c / y) = -c / y² · dy.
    let r = 2.0f32 / y;
    assert!(close(r.eps[1] as f64, -2.0 / (b as f64).powi(2), 1e-6));
    assert_eq!(r.re, 2.0 / b);
    // And the other mixed operations with f32 on the left.
    let s = 2.0f32 - y + 3.0f32 * y + (1.0f32 + y);
    assert_eq!(s.eps, [0.0, 3.0, 0.0]);
}

#[test]
fn guarded_points_have_finite_derivatives() {
    fn check<S: Directions>() {
        S::recorded(guarded::<S>);
    }
    fn guarded<S: Directions>() {
        let z = S::lift(0.0, Some(0)).safe_sqrt();
        assert_eq!((z.primal(), z.d(0)), (0.0, 0.0));
        let n = S::lift(-1e-3, Some(0)).safe_sqrt();
        assert_eq!((n.primal(), n.d(0)), (0.0, 0.0));
        let one = S::lift(1.0, Some(0)).acos();
        assert_eq!((one.primal(), one.d(0)), (0.0, 0.0));
        let m = S::lift(-1.0, Some(0)).acos();
        assert_eq!((m.primal(), m.d(0)), (std::f32::consts::PI, 0.0));
        let beyond = S::lift(1.5, Some(0)).acos();
        assert_eq!(beyond.d(0), 0.0);
    }
    check::<Dual32>();
    check::<DualN<1>>();
    check::<DualN<8>>();
    check::<Rev>();
    // DualN also guards atan2 at the origin (num-dual returns NaN there).
    let o = DualN::<2>::lift(0.0, Some(0)).atan2(DualN::<2>::lift(0.0, Some(1)));
    assert_eq!(o.re, 0.0);
    assert_eq!(o.eps, [0.0, 0.0]);
}

/// `Grad<S>` through a whole SDF (a smooth union of two spheres, the second one's centre a parameter):
/// on the surface, at a point where the blend is active, far away and at a sphere's centre (where the
/// distance's gradient is singular and `safe_sqrt` guards it), the gradient agrees with num-dual's spatial
/// gradient and the mixed partial `∂π∇φ` with a central difference of that gradient.
#[test]
fn grad_on_an_sdf_matches_the_spatial_dual() {
    use implicit_psdr::sdf::Sdf;
    let scene = |cx: f32, select: bool| {
        let mut b = Sdf::sphere([cx, 0.3, 0.0], 0.7);
        if let (Sdf::Sphere { center, .. }, true) = (&mut b, select) {
            center.c[0].slot = Some(0);
        }
        Sdf::smooth_union(vec![Sdf::sphere([0.0; 3], 1.0), b], 0.5)
    };
    // `Sdf::gradient` is num-dual's spatial gradient (`DualVec3`).
    let spatial = |sdf: &Sdf, p: glam::Vec3| sdf.gradient(p).to_array();
    let cx = 1.2;
    let sdf = scene(cx, true);
    let on_surface = glam::Vec3::new(1.0, 0.0, 0.0) * {
        let (mut lo, mut hi) = (0.0f32, 4.0f32);
        for _ in 0..60 {
            let m = 0.5 * (lo + hi);
            if sdf.eval_f32(glam::Vec3::new(m, 0.0, 0.0)) < 0.0 {
                lo = m;
            } else {
                hi = m;
            }
        }
        0.5 * (lo + hi)
    };
    for p in [
        glam::Vec3::new(0.0, 1.0, 0.0),
        on_surface,
        glam::Vec3::new(0.6, 0.9, 0.2),
        glam::Vec3::new(40.0, -30.0, 1e4),
        glam::Vec3::new(1e-6, 0.0, -1e-6),
        glam::Vec3::ZERO,
    ] {
        let r = sdf.eval::<Grad<DualN<1>>>(Grad::seed(p));
        assert_eq!(r.v.re, sdf.eval_f32(p), "at {p}");
        let g = spatial(&sdf, p);
        let h = 1e-3;
        let (gp, gm) = (
            spatial(&scene(cx + h, false), p),
            spatial(&scene(cx - h, false), p),
        );
        for i in 0..3 {
            assert!(
                close(r.g[i].re as f64, g[i] as f64, 1e-5),
                "at {p}: ∇φ {:?} vs {g:?}",
                r.g
            );
            let fd = (gp[i] as f64 - gm[i] as f64) / (2.0 * h as f64);
            assert!(
                close(r.g[i].eps[0] as f64, fd, 5e-3),
                "at {p}: ∂π∇φ_{i} {} vs {fd}",
                r.g[i].eps[0]
            );
        }
    }
}

/// One sweep of the eight-input expression gives all eight partials: slot by slot what `DualN<8>` gives
/// (rounding apart: the adjoints are summed in another order; 1e-5 is ~100 f32 ulps, the expression has
/// about 40 operations), with the primal bit for bit. A parameter at the largest entry is reported as
/// that entry.
#[test]
fn rev_sweep_matches_dual_n8_slot_by_slot() {
    for p in POINTS {
        let forward = eight(std::array::from_fn(|i| {
            DualN::<8>::lift(p[i], Some(i as u32))
        }));
        let _tape = Recording::start();
        let value = eight(std::array::from_fn(|i| Rev::lift(p[i], Some(i as u32))));
        assert_eq!(value.primal().to_bits(), forward.re.to_bits(), "at {p:?}");
        let mut grad = [0.0f32; 8];
        Recording::sweep(value, |entry, d| grad[entry as usize] += d);
        for (k, (r, f)) in grad.iter().zip(forward.eps).enumerate() {
            assert!(
                close(*r as f64, f as f64, 1e-5),
                "input {k} at {p:?}: reverse {r} vs forward {f}"
            );
        }
    }
    let _tape = Recording::start();
    let last = implicit_psdr::scalar::MAX_GRADIENT_ENTRY;
    let y = Rev::parameter(3.0, last) * Rev::parameter(2.0, 0);
    let mut seen = Vec::new();
    Recording::sweep(y, |entry, d| seen.push((entry, d)));
    seen.sort_by_key(|&(e, _)| e);
    assert_eq!(seen, vec![(0, 3.0), (last, 2.0)]);
}

/// A recording refuses to start while another is active on the same thread (their tapes would
/// interleave), and the refusal leaves the active one intact; other threads have their own tapes; once
/// the guard is dropped a new recording may start.
#[test]
fn recording_refuses_to_start_inside_another() {
    assert!(!Recording::is_active());
    {
        let _outer = Recording::start();
        assert!(Recording::is_active());
        let x = Rev::parameter(1.5, 0);
        let y = x * x + x.sin();
        let nested = std::panic::catch_unwind(Recording::start);
        let message = nested.err().expect("a nested recording must panic");
        let message = message
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| message.downcast_ref::<&str>().copied())
            .unwrap_or("");
        assert!(message.contains("already active"), "{message:?}");
        // The outer tape survived: d(x² + sin x) = 2x + cos x.
        let mut d = 0.0;
        Recording::sweep(y, |_, v| d += v);
        assert!(close(d as f64, 3.0 + 1.5f64.cos(), 1e-6), "{d}");
        // Another thread records on its own tape meanwhile.
        let other = std::thread::spawn(|| {
            let _tape = Recording::start();
            let z = Rev::parameter(2.0, 4).exp();
            let mut d = 0.0;
            Recording::sweep(z, |_, v| d += v);
            d
        })
        .join()
        .unwrap();
        assert!(close(other as f64, 2.0f64.exp(), 1e-6));
        assert!(Recording::is_active());
    }
    assert!(!Recording::is_active());
    let _again = Recording::start();
}

/// The same refusal as a `should_panic` test: the message names the cause.
#[test]
#[should_panic(expected = "already active on this thread")]
fn nested_recording_panics() {
    let _outer = Recording::start();
    let _inner = Recording::start();
}

/// A 5×4×6 lattice of values (x fastest) with distinct, irregular magnitudes.
fn lattice_values(dims: [usize; 3]) -> Vec<f32> {
    (0..dims.iter().product::<usize>())
        .map(|i| ((i as f32 * 0.37).sin() * 1.7 + (i % 7) as f32 * 0.11) - 0.4)
        .collect()
}

/// A direction of the values, in `[-1, 1]`.
fn lattice_direction(n: usize) -> Vec<f32> {
    (0..n).map(|i| (i as f32 * 1.913 + 0.3).cos()).collect()
}

/// `Rev::lattice_sum` with a block, directly on taps: the primal is the nested `f32` sum bit for bit;
/// each value `i` gets the entry `first + i` with the product of its three weights (summed where the
/// ghost layer repeats an index); no entry outside the block; and each non-constant weight gets the
/// sum with that weight's axis replaced by the unit vector, as `DualN` seeded in that weight gives.
/// Along a direction `u` of the values the gradient gives `lattice_sum_nested(taps, u)`, the term
/// forward mode adds (`GridValues::Direction`).
///
/// Tolerances: a product of three weights in `[0, 1]` is rounded twice in `f32` (≤ 2.4e-7 relative);
/// the weight partials and the directional sums add 16 or 64 such products of values ≤ 2.5 in
/// different orders (≤ 64 · 2.5 · 2 ulp ≈ 4e-5 absolute): bounds 1e-6 and 1e-4.
#[test]
fn rev_lattice_sum_gives_each_value_its_weight_product() {
    use implicit_psdr::scalar::{LatticeTaps, lattice_sum_nested};
    let dims = [5usize, 4, 6];
    let [nx, ny, nz] = dims;
    let values = lattice_values(dims);
    let u = lattice_direction(values.len());
    // Interior taps on x and z, the high ghost fold on y (index 3 twice, extra weight 0).
    let f32_taps = LatticeTaps {
        index: [[0, 1, 2, 3], [1, 2, 3, 3], [2, 3, 4, 5]],
        weight: [
            [0.02, 0.48, 0.45, 0.05],
            [0.1, 0.3, 0.6, 0.0],
            [0.17, 0.66, 0.16, 0.01],
        ],
    };
    let first = 12u32;
    for moving in [false, true] {
        let _tape = Recording::start();
        // Moving weights are parameters 0..12 (axis-major), as a point's coordinates make them.
        let taps = LatticeTaps {
            index: f32_taps.index,
            weight: std::array::from_fn(|a| {
                std::array::from_fn(|k| {
                    let w = f32_taps.weight[a][k];
                    if moving {
                        Rev::parameter(w, (4 * a + k) as u32)
                    } else {
                        Rev::constant(w)
                    }
                })
            }),
        };
        let v = Rev::lattice_sum(&taps, &values, dims, Some(first));
        let want = lattice_sum_nested::<f32>(&f32_taps, &values, nx, ny);
        assert_eq!(v.primal().to_bits(), want.to_bits());
        let mut grad = vec![0.0f64; first as usize + values.len()];
        Recording::sweep(v, |entry, d| grad[entry as usize] += d as f64);
        // Each value: the product of its weights.
        let mut product = vec![0.0f64; values.len()];
        let [ix, iy, iz] = f32_taps.index;
        let [wx, wy, wz] = f32_taps.weight;
        for c in 0..4 {
            for b in 0..4 {
                for a in 0..4 {
                    product[(iz[c] * ny + iy[b]) * nx + ix[a]] +=
                        wx[a] as f64 * wy[b] as f64 * wz[c] as f64;
                }
            }
        }
        assert!(iz.iter().all(|&z| z < nz));
        for (i, p) in product.iter().enumerate() {
            let got = grad[first as usize + i];
            assert!(
                (got - p).abs() <= 1e-6,
                "moving {moving}, value {i}: {got} vs {p}"
            );
        }
        // Along u, as forward mode's direction term.
        let along: f64 = (0..values.len())
            .map(|i| grad[first as usize + i] * u[i] as f64)
            .sum();
        let forward = lattice_sum_nested::<f32>(&f32_taps, &u, nx, ny) as f64;
        assert!(
            (along - forward).abs() <= 1e-4,
            "moving {moving}: {along} vs {forward}"
        );
        // The weights: nothing when constant; otherwise what DualN seeded in that weight gives.
        for a in 0..3 {
            for k in 0..4 {
                let got = grad[4 * a + k];
                let want = if moving {
                    let mut seeded = f32_taps.map(|_, w| DualN::<1>::constant(w));
                    seeded.weight[a][k] = DualN::<1>::lift(f32_taps.weight[a][k], Some(0));
                    lattice_sum_nested(&seeded, &values, nx, ny).eps[0] as f64
                } else {
                    0.0
                };
                assert!(
                    (got - want).abs() <= 1e-4,
                    "moving {moving}, weight {a}/{k}: {got} vs {want}"
                );
            }
        }
    }
}

/// `grid` (a grid node) with its values differentiated as `selection`.
fn select_values(
    mut grid: implicit_psdr::sdf::Sdf,
    selection: implicit_psdr::scalar::GridValues,
) -> implicit_psdr::sdf::Sdf {
    match &mut grid {
        implicit_psdr::sdf::Sdf::Grid { selection: s, .. } => *s = selection,
        _ => panic!("not a grid"),
    }
    grid
}

/// Through a whole grid SDF (a sphere baked at 8³): `Rev` with the values as a block (entries `3..`)
/// and the point as entries 0–2 against `DualN<4>` with the point in slots 0–2 and the values along `u`
/// in slot 3 (`GridValues::Direction`), in the interior, in the first and last cells (the ghost folds),
/// on a lattice node and outside the box (clamped); the values' partials sum to 1 (the B-spline's
/// partition of unity: `Σ ∂φ/∂c_i = −∂φ/∂level`). And `Grad<Rev>` against `Grad<DualN<1>>` along `u`:
/// the value and the three spatial partials (the mixed partials `∂c∇φ` that attached normals read).
///
/// Tolerances: both sides are `f32` sums of the same ~64 products in different orders; 1e-5 relative
/// to the sum of their magnitudes `Σ |u_i ∂φ/∂c_i|` (≥ 0.1 here) is ~100 ulps.
#[test]
fn rev_grid_sdf_matches_forward_direction() {
    use implicit_psdr::Vec3;
    use implicit_psdr::scalar::GridValues;
    use implicit_psdr::sdf::{Sdf, bake};
    use std::sync::Arc;
    let (lo, hi) = (glam::Vec3::splat(-1.0), glam::Vec3::splat(1.0));
    let data = bake(
        &Sdf::sphere(glam::Vec3::new(0.05, -0.1, 0.02), 0.6),
        lo,
        hi,
        8,
    );
    let n = data.values.len();
    let grid = Sdf::grid(data, lo, hi).unwrap();
    let u = Arc::new(lattice_direction(n));
    let reverse = select_values(grid.clone(), GridValues::Gradient { first: 3 });
    let forward = select_values(
        grid.clone(),
        GridValues::Direction {
            slot: 3,
            u: u.clone(),
        },
    );
    let spatial = select_values(
        grid.clone(),
        GridValues::Direction {
            slot: 0,
            u: u.clone(),
        },
    );
    let step = 2.0 / 7.0;
    for p in [
        glam::Vec3::new(0.1, 0.2, -0.3),
        glam::Vec3::new(-0.95, 0.1, 0.05),
        glam::Vec3::new(0.9, -0.9, 0.8),
        glam::Vec3::new(-1.0 + 3.0 * step, -1.0 + 2.0 * step, -1.0 + 5.0 * step),
        glam::Vec3::new(1.3, 0.2, -0.1),
    ] {
        let _tape = Recording::start();
        let v = reverse.eval(Vec3::new(
            Rev::parameter(p.x, 0),
            Rev::parameter(p.y, 1),
            Rev::parameter(p.z, 2),
        ));
        let f = forward.eval(Vec3::new(
            DualN::<4>::lift(p.x, Some(0)),
            DualN::<4>::lift(p.y, Some(1)),
            DualN::<4>::lift(p.z, Some(2)),
        ));
        assert_eq!(v.primal().to_bits(), grid.eval_f32(p).to_bits(), "at {p}");
        assert_eq!(f.re.to_bits(), grid.eval_f32(p).to_bits(), "at {p}");
        let mut grad = vec![0.0f64; 3 + n];
        Recording::sweep(v, |entry, d| grad[entry as usize] += d as f64);
        for (k, (r, fk)) in grad.iter().zip(&f.eps[..3]).enumerate() {
            assert!(
                close(*r, *fk as f64, 1e-5),
                "at {p}: ∂φ/∂p_{k} reverse {r} vs forward {fk}"
            );
        }
        let values = &grad[3..];
        let along: f64 = values
            .iter()
            .zip(u.iter())
            .map(|(g, u)| g * *u as f64)
            .sum();
        let scale: f64 = values
            .iter()
            .zip(u.iter())
            .map(|(g, u)| (g * *u as f64).abs())
            .sum();
        assert!(scale > 0.1, "at {p}: {scale}");
        assert!(
            (along - f.eps[3] as f64).abs() <= 1e-5 * scale,
            "at {p}: along u reverse {along} vs forward {}",
            f.eps[3]
        );
        let unity: f64 = values.iter().sum();
        assert!((unity - 1.0).abs() <= 1e-5, "at {p}: Σ ∂φ/∂c = {unity}");
        // Grad<Rev>: value and spatial gradient, each swept along u.
        let gr = reverse.eval::<Grad<Rev>>(Grad::seed(p));
        let gf = spatial.eval::<Grad<DualN<1>>>(Grad::seed(p));
        // A swept value's derivative along u, and the sum of its terms' magnitudes.
        let along_u = |r: Rev| {
            let (mut along, mut scale) = (0.0f64, 0.0f64);
            Recording::sweep(r, |entry, d| {
                let term = d as f64 * u[entry as usize - 3] as f64;
                along += term;
                scale += term.abs();
            });
            (along, scale)
        };
        for (what, r, f) in [
            ("φ", gr.v, gf.v),
            ("∂xφ", gr.g[0], gf.g[0]),
            ("∂yφ", gr.g[1], gf.g[1]),
            ("∂zφ", gr.g[2], gf.g[2]),
        ] {
            assert_eq!(r.primal().to_bits(), f.re.to_bits(), "{what} at {p}");
            let (along, scale) = along_u(r);
            assert!(
                (along - f.eps[0] as f64).abs() <= 1e-5 * scale.max(0.1),
                "{what} at {p}: along u reverse {along} vs forward {}",
                f.eps[0]
            );
        }
        // All four in one sweep (their value shares are summed per lookup before they are reported).
        let c = [0.7f32, -1.3, 0.4, 2.1];
        let combined = Rev::linear_combination(&[
            (gr.v, c[0]),
            (gr.g[0], c[1]),
            (gr.g[1], c[2]),
            (gr.g[2], c[3]),
        ]);
        let want = c[0] * gf.v.eps[0]
            + c[1] * gf.g[0].eps[0]
            + c[2] * gf.g[1].eps[0]
            + c[3] * gf.g[2].eps[0];
        let (along, scale) = along_u(combined);
        assert!(
            (along - want as f64).abs() <= 1e-5 * scale.max(0.1),
            "the four at {p}: along u reverse {along} vs forward {want}"
        );
    }
}
