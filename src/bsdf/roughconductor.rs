//! A rough metal: the Cook–Torrance microfacet reflection with the GGX distribution (Walter et al.
//! 2007, *Microfacet Models for Refraction through Rough Surfaces*, eq. 20), the separable Smith
//! shadowing–masking `G = G1(wi) G1(wo)`, and the Fresnel reflectance of a conductor:
//!
//! ```text
//!   f(wi, wo) = F(wo · h; η + iκ) D(h) G1(wi, h) G1(wo, h) / (4 cos θi cos θo) · specular_reflectance,
//!   h = (wi + wo) / |wi + wo|,
//! ```
//!
//! zero unless both directions lie on the front side (`cos θi, cos θo > 0`: one-sided, black from
//! behind). This is Mitsuba 3's `roughconductor` with `distribution: ggx`, isotropic, term for term
//! (its `eval` returns `f cos θo`); see [`super::microfacet`] and [`super::fresnel`].
//!
//! Sampling draws a microfacet normal `m` from the normals visible from `wo` ([`sample_visible`]) and
//! reflects `wo` about it; the density of `wi` is `D_wo(m) / (4 wo·m) = D(m) G1(wo, m) / (4 cos θo)`
//! (the Jacobian of the reflection, Walter et al. eq. 14). Reflections below the horizon are dropped,
//! so the density integrates to `≤ 1` over the hemisphere.
//!
//! Every quantity is smooth in `α`, `η`, `κ`, the reflectance and the geometry on the front side; `f
//! cos θi` tends to zero as `wi` grazes (through `G1`), so the one-sided cut adds no discontinuity
//! of its own to the integrand.

use super::microfacet::{d, g1, sample_visible};
use super::{At, BLANK, Bsdf, BsdfSample, fresnel};
use crate::declare::{Components, Field, Kind, Rule, on};
use crate::math::{Frame, Vec3};
use crate::scalar::{Param, Param3, Scalar};

/// Smallest roughness accepted: below it `D` overflows `f32` near the specular direction.
pub const MIN_ALPHA: f32 = 1e-3;

/// A GGX rough conductor (see the module documentation).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct RoughConductor {
    /// GGX roughness `α` in `[0.001, 1]`.
    pub alpha: Param,
    /// Real part of the complex index of refraction, per channel (`>= 0`).
    pub eta: Param3,
    /// Imaginary part (extinction), per channel (`>= 0`).
    pub k: Param3,
    /// Linear RGB factor in `[0, 1]`.
    pub specular_reflectance: Param3,
}

impl RoughConductor {
    /// `f(wi, wo)`, generic.
    #[inline]
    pub fn eval<S: Scalar>(&self, n: Vec3<S>, wi: Vec3<S>, wo: Vec3<S>) -> Vec3<S> {
        self.eval_node(&At::none(), 0, n, wi, wo)
    }

    /// [`RoughConductor::eval`] of material node `node` with its textured fields read at `at`.
    #[inline]
    pub(crate) fn eval_node<S: Scalar>(
        &self,
        at: &At<S>,
        node: usize,
        n: Vec3<S>,
        wi: Vec3<S>,
        wo: Vec3<S>,
    ) -> Vec3<S> {
        let (ci, co) = (n.dot(wi), n.dot(wo));
        if !(ci.primal() > 0.0 && co.primal() > 0.0) {
            return Vec3::zero();
        }
        let h = (wi + wo).normalize_or_zero();
        let alpha = at.number(node, "alpha", &self.alpha);
        let dh = d(alpha, n.dot(h), n.cross(h).length_squared());
        if dh.primal() == 0.0 {
            return Vec3::zero();
        }
        let cos_h = wo.dot(h);
        let g = g1(alpha, ci, n.cross(wi).length_squared(), wi.dot(h).primal())
            * g1(alpha, co, n.cross(wo).length_squared(), cos_h.primal());
        let common = dh * g / (ci * co * 4.0);
        let (eta, k) = (self.eta.get::<S>(), self.k.get::<S>());
        let f = Vec3::new(
            fresnel::conductor(cos_h, eta.x, k.x),
            fresnel::conductor(cos_h, eta.y, k.y),
            fresnel::conductor(cos_h, eta.z, k.z),
        );
        f * at.color(node, "specular_reflectance", &self.specular_reflectance) * common
    }

    /// Reflects `wo` about a visible microfacet normal; `None` from behind, for a reflection below the
    /// horizon, or where the density vanishes.
    #[inline]
    // Negated comparisons, so that a NaN fails each test.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    pub fn sample(&self, n: glam::Vec3, wo: glam::Vec3, u: glam::Vec2) -> Option<BsdfSample> {
        self.sample_with(self.alpha.value, n, wo, u)
    }

    /// [`RoughConductor::sample`] with roughness `alpha` (a texture's value at the point).
    #[inline]
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    pub fn sample_with(
        &self,
        alpha: f32,
        n: glam::Vec3,
        wo: glam::Vec3,
        u: glam::Vec2,
    ) -> Option<BsdfSample> {
        if !(n.dot(wo) > 0.0) {
            return None;
        }
        let frame = Frame::from_normal(n);
        let v = frame.to_local(wo);
        if !(v.z > 0.0) {
            return None;
        }
        let m = sample_visible(alpha, v, u);
        let vm = v.dot(m);
        if !(vm > 0.0) {
            return None;
        }
        let local = m * (2.0 * vm) - v;
        if !(local.z > 0.0) {
            return None;
        }
        let sin2 = |w: glam::Vec3| w.x * w.x + w.y * w.y;
        let pdf = d(alpha, m.z, sin2(m)) * g1(alpha, v.z, sin2(v), vm) / (4.0 * v.z);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some(BsdfSample {
            wi: frame.to_world(local),
            pdf,
        })
    }

    /// Density of [`RoughConductor::sample`]: `D(h) G1(wo, h) / (4 cos θo)` on the front side.
    #[inline]
    pub fn pdf(&self, n: glam::Vec3, wo: glam::Vec3, wi: glam::Vec3) -> f32 {
        self.pdf_with(self.alpha.value, n, wo, wi)
    }

    /// [`RoughConductor::pdf`] with roughness `alpha`.
    #[inline]
    pub fn pdf_with(&self, alpha: f32, n: glam::Vec3, wo: glam::Vec3, wi: glam::Vec3) -> f32 {
        let (ci, co) = (n.dot(wi), n.dot(wo));
        if !(ci > 0.0 && co > 0.0) {
            return 0.0;
        }
        let h = (wi + wo).normalize_or_zero();
        let (ih, oh) = (wi.dot(h), wo.dot(h));
        if !(ih > 0.0 && oh > 0.0) {
            return 0.0;
        }
        d(alpha, n.dot(h), n.cross(h).length_squared())
            * g1(alpha, co, n.cross(wo).length_squared(), oh)
            / (4.0 * co)
    }
}

/// `{"type": "roughconductor", "alpha": α, "eta": [r, g, b], "k": [r, g, b], "specular_reflectance":
/// [r, g, b]}`: `alpha` in `[0.001, 1]` (default 0.1), `eta` and `k` `>= 0` (defaults 0 and 1, whose
/// Fresnel term is 1), `specular_reflectance` in `[0, 1]` (default 1), Mitsuba 3's defaults.
pub(super) const ROUGHCONDUCTOR: Kind<Bsdf> = Kind {
    type_name: "roughconductor",
    fields: &[
        Field::number(
            "alpha",
            on!(Bsdf::RoughConductor(RoughConductor { alpha, .. }) => alpha),
            Some(0.1),
            Rule::Relation {
                ok: |_, v| (MIN_ALPHA..=1.0).contains(&v),
                text: |_| format!("must be in [{MIN_ALPHA}, 1]"),
            },
        ),
        Field::vector(
            "eta",
            on!(Bsdf::RoughConductor(RoughConductor { eta, .. }) => eta),
            Components::Rgb,
            Some(0.0),
            Rule::NonNegative,
        ),
        Field::vector(
            "k",
            on!(Bsdf::RoughConductor(RoughConductor { k, .. }) => k),
            Components::Rgb,
            Some(1.0),
            Rule::NonNegative,
        ),
        Field::vector(
            "specular_reflectance",
            on!(Bsdf::RoughConductor(RoughConductor { specular_reflectance, .. }) => specular_reflectance),
            Components::Rgb,
            Some(1.0),
            Rule::UnitInterval,
        ),
    ],
    blank: || {
        Bsdf::RoughConductor(RoughConductor {
            alpha: BLANK,
            eta: Param3::new([0.0; 3]),
            k: Param3::new([0.0; 3]),
            specular_reflectance: Param3::new([0.0; 3]),
        })
    },
    // Gold at 650, 550 and 450 nm.
    example: r#"{"type": "roughconductor", "alpha": 0.2, "eta": [0.143, 0.374, 1.442], "k": [3.983, 2.385, 1.603], "specular_reflectance": [0.9, 0.9, 0.9]}"#,
};
