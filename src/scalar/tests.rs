//! Conformance suite: every [`Scalar`] type must agree with `f32` on primal values, and the derivative
//! types with central differences.

use super::*;

/// Applies the same expression to every scalar type and checks primal values and `Dual32` derivatives.
fn expr<S: Scalar>(x: S) -> S {
    let a = x.sqr() * 0.5 + x.sin() * x.cos() - (x + 2.0).ln() + x.exp() / (x.abs() + 1.0);
    let b = (x.sqr() + 1.0).sqrt() + (x * 0.3).atan2(S::one() + x.sqr()) + (x * 0.2).acos();
    a * b + (x.abs() + 0.5).powf(1.7) + x.max(S::constant(0.1)) - x.min(S::constant(-0.2))
}

macro_rules! scalar_suite {
    ($name:ident, $t:ty) => {
        #[test]
        fn $name() {
            for &x in &[0.0f32, 1e-6, -0.3, 0.7, 1.9, -1.2] {
                let v: $t = expr(<$t>::constant(x));
                assert!(
                    (v.primal() - expr(x)).abs() <= 1e-5 * expr(x).abs().max(1.0),
                    "x = {x}"
                );
                assert_eq!(<$t>::constant(x).detach().primal(), x);
            }
        }
    };
}

scalar_suite!(f32_primal, f32);
scalar_suite!(dual32_primal, Dual32);
scalar_suite!(dualvec3_primal, DualVec3);
scalar_suite!(dual2vec3_primal, Dual2Vec3);

#[test]
fn dual32_derivative_matches_central_difference() {
    for &x in &[0.05f32, -0.3, 0.7, 1.9, -1.2] {
        let d = expr(Dual32::lift(x, Some(0))).eps;
        let h = 1e-3f64;
        // Central difference in f64 of the f32 expression is too noisy; evaluate in f64 via f32 steps.
        let fd =
            (expr((x as f64 + h) as f32) as f64 - expr((x as f64 - h) as f32) as f64) / (2.0 * h);
        assert!(
            (d as f64 - fd).abs() <= 2e-2 * fd.abs().max(1.0),
            "x = {x}: {d} vs {fd}"
        );
    }
}

#[test]
fn lift_seeds_only_its_slot() {
    assert_eq!(Dual32::lift(2.0, Some(0)).eps, 1.0);
    assert_eq!(Dual32::lift(2.0, Some(1)).eps, 0.0);
    assert_eq!(Dual32::lift(2.0, None).eps, 0.0);
    assert_eq!(f32::lift(2.0, Some(0)), 2.0);
}

#[test]
fn guarded_operations_have_finite_derivatives() {
    let z = Dual32::lift(0.0, Some(0));
    assert!(z.safe_sqrt().eps.is_finite());
    assert!(Dual32::lift(1.0, Some(0)).acos().eps.is_finite());
    assert!(Dual32::lift(-1.0, Some(0)).acos().eps.is_finite());
}
