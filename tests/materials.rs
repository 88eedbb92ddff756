//! The materials' sampling routines against their own densities (chi-square goodness of fit, as in
//! Mitsuba 3's test suite: `tests/common/chi2.rs`), the densities' integrals, the rough conductor's
//! reciprocity and energy conservation, and a rendered closed form (a metal plane under a constant
//! sky).

mod common;

use common::Rng;
use common::chi2::{Chi2, assert_fits, gamma_q, ln_gamma};
use glam::{Vec2, Vec3};
use implicit_psdr::bsdf::{Blend, Bsdf, RoughConductor};
use implicit_psdr::math::Frame;
use implicit_psdr::scalar::{Param, Param3};

fn diffuse(a: f32) -> Bsdf {
    Bsdf::Diffuse {
        albedo: Param3::new([a; 3]),
    }
}

/// Gold (at 650, 550, 450 nm) of roughness `alpha`.
fn gold(alpha: f32) -> Bsdf {
    Bsdf::RoughConductor(RoughConductor {
        alpha: Param::new(alpha),
        eta: Param3::new([0.143, 0.374, 1.442]),
        k: Param3::new([3.983, 2.385, 1.603]),
        specular_reflectance: Param3::new([1.0; 3]),
    })
}

/// A conductor whose Fresnel term is 1 (the defaults).
fn mirror_like(alpha: f32) -> Bsdf {
    Bsdf::RoughConductor(RoughConductor {
        alpha: Param::new(alpha),
        eta: Param3::new([0.0; 3]),
        k: Param3::new([1.0; 3]),
        specular_reflectance: Param3::new([1.0; 3]),
    })
}

fn blend(w: f32, a: Bsdf, b: Bsdf) -> Bsdf {
    Bsdf::Blend(Blend {
        weight: Param::new(w),
        bsdfs: vec![a, b],
    })
}

/// A tilted normal, so that the frames are exercised.
fn normal() -> Vec3 {
    Vec3::new(0.3, 0.8, -0.5).normalize()
}

/// The outgoing direction at polar angle `theta` (radians) and azimuth 1 rad.
fn outgoing(theta: f32) -> Vec3 {
    let frame = Frame::from_normal(normal());
    frame.to_world(Vec3::new(
        theta.sin() * 1f32.cos(),
        theta.sin() * 1f32.sin(),
        theta.cos(),
    ))
}

/// χ² test of `bsdf`'s sampling for `wo` at polar angle `theta`, in the normal's frame.
fn fit(label: &str, bsdf: &Bsdf, theta: f32) {
    let n = normal();
    let frame = Frame::from_normal(n);
    let wo = outgoing(theta);
    let outcome = Chi2::default().run(
        |u: Vec2| bsdf.sample(n, wo, u).map(|s| (frame.to_local(s.wi), s.pdf)),
        |d| bsdf.pdf(n, wo, frame.to_world(d)),
    );
    assert_fits(&format!("{label} θo = {theta}"), &outcome, 2e-3);
}

#[test]
fn incomplete_gamma_matches_closed_forms() {
    // Q(1, x) = e^{−x}; Q(1/2, x) = erfc(√x); ln Γ(5) = ln 24.
    for x in [0.1f64, 1.0, 3.0, 20.0] {
        assert!((gamma_q(1.0, x) - (-x).exp()).abs() < 1e-12);
    }
    assert!((gamma_q(0.5, 1.0) - 0.157_299_207_050_285_13).abs() < 1e-10);
    assert!((ln_gamma(5.0) - 24f64.ln()).abs() < 1e-12);
    // χ² with 10 degrees of freedom: P(χ² > 18.307) = 0.05.
    assert!((gamma_q(5.0, 18.307 / 2.0) - 0.05).abs() < 1e-4);
}

#[test]
fn cosine_sampling_fits_its_density() {
    for theta in [0.0, 1.0, 2.5] {
        fit("diffuse", &diffuse(0.5), theta);
    }
}

#[test]
fn ggx_visible_normals_fit_their_density() {
    for alpha in [0.1, 0.3, 0.7, 1.0] {
        for theta in [0.0, 0.6, 1.2, 1.5] {
            fit(&format!("gold α = {alpha}"), &gold(alpha), theta);
        }
    }
}

#[test]
fn blend_sampling_fits_the_mixture_density() {
    fit("blend 0.3", &blend(0.3, diffuse(0.5), gold(0.3)), 0.8);
    fit("blend 0.7", &blend(0.7, gold(0.2), mirror_like(0.6)), 1.3);
    fit(
        "nested blend",
        &blend(0.5, blend(0.4, diffuse(0.5), gold(0.5)), gold(0.15)),
        0.4,
    );
    // From behind, only the two-sided child reflects.
    fit(
        "blend from behind",
        &blend(0.5, diffuse(0.5), gold(0.3)),
        2.2,
    );
}

#[test]
fn conductor_is_black_from_behind() {
    let n = normal();
    let c = gold(0.3);
    let wo = outgoing(2.0);
    let mut rng = Rng::new(3);
    for _ in 0..1000 {
        let u = Vec2::new(rng.f32(), rng.f32());
        assert!(c.sample(n, wo, u).is_none());
        let wi = outgoing(rng.f32() * 3.1);
        assert_eq!(c.pdf(n, wo, wi), 0.0);
        assert_eq!(
            c.eval::<f32>(n.into(), wi.into(), wo.into()).primal(),
            Vec3::ZERO
        );
    }
}

/// `f(wi, wo) = f(wo, wi)` (the Fresnel term takes `wo · h`, equal to `wi · h` up to rounding).
#[test]
fn rough_conductor_is_reciprocal() {
    let n = normal();
    let mut rng = Rng::new(5);
    for alpha in [0.01, 0.2, 1.0] {
        let c = gold(alpha);
        for _ in 0..2000 {
            let a = outgoing(rng.f32() * 1.57);
            let b = Frame::from_normal(n).to_world(
                common::Rng::new(rng.f32().to_bits() as u64)
                    .in_box(Vec3::new(-1.0, -1.0, 0.01), Vec3::ONE)
                    .normalize(),
            );
            let fab: Vec3 = c.eval::<f32>(n.into(), a.into(), b.into()).into();
            let fba: Vec3 = c.eval::<f32>(n.into(), b.into(), a.into()).into();
            let scale = fab.max_element().max(1e-6);
            assert!(
                (fab - fba).abs().max_element() <= 1e-4 * scale,
                "α {alpha}: {fab} vs {fba}"
            );
        }
    }
}

/// The directional albedo `∫ f cos θi dωi` is at most 1, from a quadrature on a grid in `(cos θi, φ)`
/// independent of the sampling; it agrees with the importance-sampled estimate (whose weight
/// `f cos θi / p = F G1(wi) ≤ 1` is checked sample by sample); and at normal incidence it equals the
/// one-dimensional integral of [`normal_incidence_albedo`].
#[test]
fn rough_conductor_conserves_energy() {
    let n = normal();
    let frame = Frame::from_normal(n);
    for alpha in [0.3f32, 0.6, 1.0] {
        for theta in [0.0f32, 0.8, 1.4] {
            let c = mirror_like(alpha);
            let wo = outgoing(theta);
            let (nc, np) = (800, 400);
            let mut quad = 0.0f64;
            for i in 0..nc {
                let ct = (i as f64 + 0.5) / nc as f64;
                let st = (1.0 - ct * ct).sqrt();
                for j in 0..np {
                    let phi = (j as f64 + 0.5) / np as f64 * std::f64::consts::TAU;
                    let wi = frame.to_world(Vec3::new(
                        (st * phi.cos()) as f32,
                        (st * phi.sin()) as f32,
                        ct as f32,
                    ));
                    let f: Vec3 = c.eval::<f32>(n.into(), wi.into(), wo.into()).into();
                    quad += f.x as f64 * ct / nc as f64 * std::f64::consts::TAU / np as f64;
                }
            }
            let mut rng = Rng::new(9);
            let count = 200_000;
            let mut mc = 0.0f64;
            for _ in 0..count {
                let u = Vec2::new(rng.f32(), rng.f32());
                if let Some(s) = c.sample(n, wo, u) {
                    let f: Vec3 = c.eval::<f32>(n.into(), s.wi.into(), wo.into()).into();
                    let w = f.x * n.dot(s.wi) / s.pdf;
                    assert!(w <= 1.0 + 1e-4, "α {alpha} θ {theta}: sample weight {w}");
                    mc += w as f64 / count as f64;
                }
            }
            if theta == 0.0 {
                let want = normal_incidence_albedo(alpha as f64);
                assert!(
                    (quad - want).abs() < 2e-3,
                    "α {alpha}: albedo {quad} vs {want}"
                );
            }
            println!("α {alpha} θo {theta}: albedo quadrature {quad:.5}, sampled {mc:.5}");
            assert!(quad <= 1.0 + 1e-3, "α {alpha} θ {theta}: albedo {quad}");
            assert!(
                (quad - mc).abs() < 5e-3,
                "α {alpha} θ {theta}: {quad} vs {mc}"
            );
        }
    }
}

/// The albedo of the Fresnel-free GGX conductor lit along its normal, from the closed forms of `D` and
/// `G1` in `f64` (Walter et al. 2007, eqs. 33–34): with `wo = n`, `wi` is `wo` reflected about `m` (at
/// `2θm`), `f cos θi dωi = D(m) G1(wi) cos θm dωm` (the reflection's Jacobian `dωi = 4 (wo·m) dωm`
/// and `G1(wo) = 1`), and microfacets beyond `θm = 45°` reflect below the horizon:
/// `E = ∫₀^{π/4} D(θ) G1(2θ) cos θ sin θ 2π dθ`.
fn normal_incidence_albedo(alpha: f64) -> f64 {
    use std::f64::consts::PI;
    let a2 = alpha * alpha;
    let n = 200_000;
    let top = PI / 4.0;
    (0..n)
        .map(|i| {
            let t = (i as f64 + 0.5) / n as f64 * top;
            let (s, c) = t.sin_cos();
            let d = 1.0 / (PI * a2 * (s * s / a2 + c * c).powi(2));
            let tan2 = (2.0 * t).tan().powi(2);
            let g1 = 2.0 / (1.0 + (1.0 + a2 * tan2).sqrt());
            d * g1 * c * s * 2.0 * PI * top / n as f64
        })
        .sum()
}

/// `F` of a conductor in `f64` from complex Snell's law (independent of the renderer's real form).
fn fresnel_complex(c: f64, eta: f64, k: f64) -> f64 {
    // n² − sin²θ = (η² − κ² − s²) + 2ηκ i; cos θt·n = √(n² − sin²θ).
    let s2 = 1.0 - c * c;
    let (re, im) = (eta * eta - k * k - s2, 2.0 * eta * k);
    let r = (re * re + im * im).sqrt();
    let (a, b) = (((r + re) / 2.0).sqrt(), ((r - re) / 2.0).sqrt());
    // r_s = (c − (a + ib)) / (c + (a + ib)); r_p = (n² c − (a + ib)) / (n² c + (a + ib)).
    let rs = ((c - a).powi(2) + b * b) / ((c + a).powi(2) + b * b);
    let (n2r, n2i) = (eta * eta - k * k, 2.0 * eta * k);
    let (pr, pi) = (n2r * c, n2i * c);
    let rp = ((pr - a).powi(2) + (pi - b).powi(2)) / ((pr + a).powi(2) + (pi + b).powi(2));
    0.5 * (rs + rp)
}

/// [`normal_incidence_albedo`] with the Fresnel term of index `eta + i k` (at `wo · m = cos θm`).
fn normal_incidence_albedo_fresnel(alpha: f64, eta: f64, k: f64) -> f64 {
    use std::f64::consts::PI;
    let a2 = alpha * alpha;
    let n = 200_000;
    let top = PI / 4.0;
    (0..n)
        .map(|i| {
            let t = (i as f64 + 0.5) / n as f64 * top;
            let (s, c) = t.sin_cos();
            let d = 1.0 / (PI * a2 * (s * s / a2 + c * c).powi(2));
            let tan2 = (2.0 * t).tan().powi(2);
            let g1 = 2.0 / (1.0 + (1.0 + a2 * tan2).sqrt());
            fresnel_complex(c, eta, k) * d * g1 * c * s * 2.0 * PI * top / n as f64
        })
        .sum()
}

/// A gold plane seen from straight above under a constant sky of radiance 1 (a furnace): each pixel is
/// the directional albedo, which along the normal is the one-dimensional integral above, per channel,
/// for `direct` and `path` (whose further bounces find nothing but the sky). The camera's narrow field
/// (2°) keeps every pixel within 1° of the normal, where the albedo varies by less than 1e-3.
#[test]
fn metal_plane_in_a_furnace_reflects_its_albedo() {
    let eta = [0.143, 0.374, 1.442];
    let k = [3.983, 2.385, 1.603];
    for integrator in [
        r#"{"type": "direct"}"#,
        r#"{"type": "path", "max_depth": 3}"#,
    ] {
        for alpha in [0.2, 0.6] {
            let text = format!(
                r#"{{"camera": {{"origin": [0, 5, 0], "target": [0, 0, 0], "up": [0, 0, -1], "fov_y": 2,
                                "width": 8, "height": 8, "filter": "gaussian"}},
                    "integrator": {integrator},
                    "shapes": [{{"name": "floor", "sdf": {{"type": "plane", "normal": [0, 1, 0], "offset": 0}},
                                 "bsdf": {{"type": "roughconductor", "alpha": {alpha},
                                          "eta": {eta:?}, "k": {k:?}}}}}],
                    "emitters": [{{"name": "sky", "type": "constant", "radiance": [1, 1, 1]}}]}}"#
            );
            let scene = implicit_psdr::scene::parse(&text, std::path::Path::new(".")).unwrap();
            let options = implicit_psdr::integrator::RenderOptions {
                spp: 1024,
                seed: 1,
                ..Default::default()
            };
            let (image, _) = implicit_psdr::integrator::render(&scene, &options);
            for c in 0..3 {
                let got: f64 = image
                    .rgb
                    .iter()
                    .skip(c)
                    .step_by(3)
                    .map(|v| *v as f64)
                    .sum::<f64>()
                    / 64.0;
                let want = normal_incidence_albedo_fresnel(alpha, eta[c], k[c]);
                println!("{integrator} α {alpha} channel {c}: image {got:.5}, albedo {want:.5}");
                assert!(
                    (got - want).abs() < 0.005 * want,
                    "{integrator} α {alpha} channel {c}: {got} vs {want}"
                );
            }
        }
    }
}
