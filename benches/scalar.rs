//! Cost of one shading evaluation per scalar type: `f32`, `Dual32` (one direction), the in-project
//! `DualN<8>` and num-dual's `DualSVec32<8>` (eight directions each).
//!
//! The expression is a direct-lighting integrand at a point near a sphere: sphere SDF and normal, a point
//! light's direction and inverse-square falloff, Lambertian BRDF, emitter cosine and a soft shadow term
//! (about 50 flops with two `sqrt`, divisions, `exp` and `max`). Eight scene parameters feed it (sphere
//! centre and radius, albedo, light position); every one is seeded for the multi-direction types.
//! Each iteration shades a batch of 1024 precomputed points.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use implicit_psdr::Vec3;
use implicit_psdr::scalar::{Dual32, DualN, Scalar, Slot};
use num_dual::{DualNum, DualSVec32};
use std::hint::black_box;
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};
use std::time::Duration;

/// num-dual's eight-direction dual behind a local newtype, so the same generic code runs on it (the orphan
/// rule forbids implementing the crate's `Scalar` for a foreign type here).
#[derive(Copy, Clone, Debug)]
struct NumDual8(DualSVec32<8>);

macro_rules! wrap_ops {
    ($($tr:ident $m:ident $atr:ident $am:ident $op:tt),*) => {$(
        impl $tr for NumDual8 {
            type Output = Self;
            #[inline(always)]
            fn $m(self, o: Self) -> Self { Self(self.0 $op o.0) }
        }
        impl $tr<f32> for NumDual8 {
            type Output = Self;
            #[inline(always)]
            fn $m(self, o: f32) -> Self { Self(self.0 $op o) }
        }
        impl $atr for NumDual8 {
            #[inline(always)]
            fn $am(&mut self, o: Self) { self.0 = self.0 $op o.0; }
        }
    )*};
}
wrap_ops!(Add add AddAssign add_assign +, Sub sub SubAssign sub_assign -,
          Mul mul MulAssign mul_assign *, Div div DivAssign div_assign /);

impl Neg for NumDual8 {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self(-self.0)
    }
}

impl Scalar for NumDual8 {
    #[inline(always)]
    fn constant(v: f32) -> Self {
        Self(DualSVec32::from_re(v))
    }
    #[inline(always)]
    fn primal(self) -> f32 {
        self.0.re
    }
    #[inline(always)]
    fn lift(value: f32, slot: Slot) -> Self {
        match slot {
            Some(k) if k < 8 => Self(DualSVec32::from_re(value).derivative(k as usize)),
            _ => Self::constant(value),
        }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Self(DualNum::sqrt(&self.0))
    }
    #[inline(always)]
    fn exp(self) -> Self {
        Self(DualNum::exp(&self.0))
    }
    #[inline(always)]
    fn ln(self) -> Self {
        Self(DualNum::ln(&self.0))
    }
    #[inline(always)]
    fn sin(self) -> Self {
        Self(DualNum::sin(&self.0))
    }
    #[inline(always)]
    fn cos(self) -> Self {
        Self(DualNum::cos(&self.0))
    }
    #[inline(always)]
    fn atan2(self, x: Self) -> Self {
        Self(DualNum::atan2(&self.0, x.0))
    }
    #[inline(always)]
    fn acos(self) -> Self {
        Self(DualNum::acos(&self.0))
    }
    #[inline(always)]
    fn powf(self, n: f32) -> Self {
        Self(DualNum::powf(&self.0, n))
    }
}

/// Direct lighting at `x` (a point near a sphere) from a point light, with the scene parameters `p`:
/// sphere centre (3), radius, albedo, light position (3).
#[inline(always)]
fn shade<S: Scalar>(p: &[S; 8], x: glam::Vec3) -> S {
    let center = Vec3::new(p[0], p[1], p[2]);
    let radius = p[3];
    let albedo = p[4];
    let light = Vec3::new(p[5], p[6], p[7]);
    let xs = Vec3::<S>::constant(x);
    // Sphere SDF and its normal (gradient of |x - c| - r).
    let d = xs - center;
    let dist = d.length_squared().safe_sqrt();
    let sdf = dist - radius;
    let n = d / dist.max(S::constant(1e-6));
    // Point light: direction, inverse-square falloff.
    let to_l = light - xs;
    let r2 = to_l.length_squared();
    let wi = to_l / r2.sqrt();
    let cos_s = n.dot(wi).max(S::zero());
    // Emitter oriented downwards: cosine at the light.
    let cos_l = (-wi.y).max(S::zero());
    let geometry = cos_s * cos_l / r2;
    // Lambertian BRDF, with a soft "near the surface" weight from the SDF.
    let brdf = albedo * std::f32::consts::FRAC_1_PI;
    let near = (-(sdf.sqr()) * 8.0).exp();
    brdf * geometry * near * 40.0 + sdf.abs() * 0.01
}

fn points() -> Vec<glam::Vec3> {
    // A deterministic spiral of points around the unit sphere, some on it, some off it.
    (0..1024)
        .map(|i| {
            let t = i as f32 * 0.618_034;
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / 1024.0;
            let rho = (1.0 - z * z).sqrt();
            let r = 1.0 + 0.05 * (t * 7.0).sin();
            glam::Vec3::new(
                rho * (t * std::f32::consts::TAU).cos(),
                z,
                rho * (t * std::f32::consts::TAU).sin(),
            ) * r
        })
        .collect()
}

const PARAMS: [f32; 8] = [0.0, 0.0, 0.0, 1.0, 0.8, 1.5, 4.0, 2.0];

fn run<S: Scalar>(pts: &[glam::Vec3], seeded: usize) -> f32 {
    let p: [S; 8] = std::array::from_fn(|i| {
        S::lift(
            black_box(PARAMS[i]),
            if i < seeded { Some(i as u32) } else { None },
        )
    });
    let mut acc = S::zero();
    for &x in pts {
        acc += shade(&p, x);
    }
    black_box(acc).primal()
}

fn bench(c: &mut Criterion) {
    let pts = points();
    // Sanity: all types agree on the primal value.
    let want = run::<f32>(&pts, 0);
    for got in [
        run::<Dual32>(&pts, 1),
        run::<DualN<8>>(&pts, 8),
        run::<NumDual8>(&pts, 8),
    ] {
        assert!((got - want).abs() <= 1e-4 * want.abs(), "{got} vs {want}");
    }
    let mut g = c.benchmark_group("shade");
    g.throughput(Throughput::Elements(pts.len() as u64));
    g.sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    g.bench_function("f32", |b| b.iter(|| run::<f32>(black_box(&pts), 0)));
    g.bench_function("Dual32", |b| b.iter(|| run::<Dual32>(black_box(&pts), 1)));
    g.bench_function("DualN<8>", |b| {
        b.iter(|| run::<DualN<8>>(black_box(&pts), 8))
    });
    g.bench_function("DualSVec32<8>", |b| {
        b.iter(|| run::<NumDual8>(black_box(&pts), 8))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
