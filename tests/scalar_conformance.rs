//! Conformance suite for every [`Scalar`] type, written once as a macro (`scalar_suite!`).
//!
//! For each type and each "spicy" input (0, tiny, negative, large) it evaluates a list of expressions that
//! together use every trait method and operator. Primal values must agree with `f32` (exactly for the
//! in-project [`DualN`], whose primal path performs the same `f32` operations), and derivatives in every
//! direction must agree with central differences of an `f64` evaluation of the same generic code (the
//! local [`F64`] type). Further tests: a many-input expression where `DualN<8>` must give, slot by slot,
//! what `Dual32` seeded in that input gives; the quotient rule; and finite derivatives at the guarded
//! points (`safe_sqrt` at 0, `acos` at ±1, `atan2` at the origin).

use implicit_psdr::scalar::{Dual2Vec3, Dual32, DualN, DualVec3, Scalar, Slot};
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
        let reference = exprs(x);
        let fd = reference_derivatives(x);
        // Every direction, plus one slot past the last (which must give a constant).
        for k in 0..=S::DIRS {
            let values = exprs(S::lift(x, Some(k as u16)));
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
        let v = S::lift(x, Some(0)).detach() * S::lift(x, Some(0));
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
}

macro_rules! scalar_suite {
    ($name:ident, $t:ty, exact = $exact:expr) => {
        #[test]
        fn $name() {
            check_type::<$t>($exact);
        }
    };
}

scalar_suite!(f32_conforms, f32, exact = true);
scalar_suite!(f64_reference_conforms, F64, exact = false);
scalar_suite!(dualvec3_conforms, DualVec3, exact = false);
scalar_suite!(dual2vec3_conforms, Dual2Vec3, exact = false);
scalar_suite!(dual32_conforms, Dual32, exact = false);
scalar_suite!(dual_n1_conforms, DualN<1>, exact = true);
scalar_suite!(dual_n3_conforms, DualN<3>, exact = true);
scalar_suite!(dual_n8_conforms, DualN<8>, exact = true);

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
            DualN::<8>::lift(p[i], Some(i as u16))
        }));
        let few = eight(std::array::from_fn(|i| {
            DualN::<3>::lift(p[i], Some(i as u16))
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
    // DualN also guards atan2 at the origin (num-dual returns NaN there).
    let o = DualN::<2>::lift(0.0, Some(0)).atan2(DualN::<2>::lift(0.0, Some(1)));
    assert_eq!(o.re, 0.0);
    assert_eq!(o.eps, [0.0, 0.0]);
}
