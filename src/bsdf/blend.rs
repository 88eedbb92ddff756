//! A mixture of two materials, `f = (1 − w) f_A + w f_B` (Mitsuba 3's `blendbsdf`), sampled by picking
//! `A` with probability `1 − w` and `B` with probability `w` (the first coordinate of the random pair
//! is reused for the child after rescaling); the density is the mixture's, `(1 − w) p_A + w p_B`,
//! so that multiple importance sampling sees the density of the whole material.
//!
//! At `w = 0` (or 1) every value is the child's bit for bit: `1 · x + 0 · y = x` in floating point,
//! the rescaled random number is the original, and the sampled density is the child's own.

use super::{At, BLANK, Bsdf, BsdfSample};
use crate::declare::{Field, Kind, Rule, Value, on};
use crate::math::Vec3;
use crate::scalar::{Param, Scalar};

/// The largest `f32` below 1.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// `(1 − weight) · bsdfs[0] + weight · bsdfs[1]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Blend {
    /// Weight of the second material, in `[0, 1]`.
    pub weight: Param,
    /// The two materials (exactly two).
    pub bsdfs: Vec<Bsdf>,
}

impl Blend {
    /// `f(wi, wo)`, generic.
    #[inline]
    pub fn eval<S: Scalar>(&self, n: Vec3<S>, wi: Vec3<S>, wo: Vec3<S>) -> Vec3<S> {
        self.eval_node(&At::none(), 0, n, wi, wo)
    }

    /// The material nodes of the two children when this blend is node `node` (depth-first).
    #[inline]
    fn children(&self, node: usize) -> [usize; 2] {
        [node + 1, node + 1 + self.bsdfs[0].node_count()]
    }

    /// [`Blend::eval`] of material node `node` with its textured fields read at `at`.
    #[inline]
    pub(crate) fn eval_node<S: Scalar>(
        &self,
        at: &At<S>,
        node: usize,
        n: Vec3<S>,
        wi: Vec3<S>,
        wo: Vec3<S>,
    ) -> Vec3<S> {
        let w = at.number(node, "weight", &self.weight);
        let [na, nb] = self.children(node);
        let a = self.bsdfs[0].eval_node(at, na, n, wi, wo);
        let b = self.bsdfs[1].eval_node(at, nb, n, wi, wo);
        a * (S::one() - w) + b * w
    }

    /// Picks a child with `u.x`, samples it with the rescaled `u`, and returns the mixture's density.
    #[inline]
    pub fn sample(&self, n: glam::Vec3, wo: glam::Vec3, u: glam::Vec2) -> Option<BsdfSample> {
        self.sample_node(&At::none(), 0, n, wo, u)
    }

    /// [`Blend::sample`] of material node `node` with its textured fields read at `at`.
    #[inline]
    pub(crate) fn sample_node(
        &self,
        at: &At<f32>,
        node: usize,
        n: glam::Vec3,
        wo: glam::Vec3,
        u: glam::Vec2,
    ) -> Option<BsdfSample> {
        let w = at.value(node, "weight", &self.weight);
        let [na, nb] = self.children(node);
        let (chosen, other, w_chosen, w_other, ux) = if u.x < 1.0 - w {
            let ux = u.x / (1.0 - w);
            ((&self.bsdfs[0], na), (&self.bsdfs[1], nb), 1.0 - w, w, ux)
        } else {
            let ux = (u.x - (1.0 - w)) / w;
            ((&self.bsdfs[1], nb), (&self.bsdfs[0], na), w, 1.0 - w, ux)
        };
        let u = glam::Vec2::new(ux.min(ONE_MINUS_EPSILON), u.y);
        let s = chosen.0.sample_node(at, chosen.1, n, wo, u)?;
        let other_pdf = if w_other > 0.0 {
            other.0.pdf_node(at, other.1, n, wo, s.wi)
        } else {
            0.0
        };
        Some(BsdfSample {
            wi: s.wi,
            pdf: w_chosen * s.pdf + w_other * other_pdf,
        })
    }

    /// `(1 − w) p_A + w p_B`.
    #[inline]
    pub fn pdf(&self, n: glam::Vec3, wo: glam::Vec3, wi: glam::Vec3) -> f32 {
        self.pdf_node(&At::none(), 0, n, wo, wi)
    }

    /// [`Blend::pdf`] of material node `node` with its textured fields read at `at`.
    #[inline]
    pub(crate) fn pdf_node(
        &self,
        at: &At<f32>,
        node: usize,
        n: glam::Vec3,
        wo: glam::Vec3,
        wi: glam::Vec3,
    ) -> f32 {
        let w = at.value(node, "weight", &self.weight);
        let [na, nb] = self.children(node);
        (1.0 - w) * self.bsdfs[0].pdf_node(at, na, n, wo, wi)
            + w * self.bsdfs[1].pdf_node(at, nb, n, wo, wi)
    }
}

/// `{"type": "blend", "weight": w, "bsdfs": [A, B]}`: `w` in `[0, 1]`, exactly two materials.
pub(super) const BLEND: Kind<Bsdf> = Kind {
    type_name: "blend",
    fields: &[
        Field::number(
            "weight",
            on!(Bsdf::Blend(Blend { weight, .. }) => weight),
            None,
            Rule::UnitInterval,
        ),
        Field {
            key: "bsdfs",
            value: Value::Children {
                access: on!(Bsdf::Blend(Blend { bsdfs, .. }) => bsdfs),
                count: Some(2),
            },
        },
    ],
    blank: || {
        Bsdf::Blend(Blend {
            weight: BLANK,
            bsdfs: Vec::new(),
        })
    },
    example: r#"{"type": "blend", "weight": 0.3, "bsdfs": [{"type": "diffuse", "albedo": [0.6, 0.5, 0.3]}, {"type": "roughconductor", "alpha": 0.2, "specular_reflectance": [0.9, 0.8, 0.7]}]}"#,
};
