//! Surface scattering. Directions point away from the surface; `n` is the outward unit normal; `wo`
//! points towards the camera (the direction given when sampling), `wi` towards the light.
//!
//! Each material kind lives in its own file with its declaration ([`crate::declare`]): [`diffuse`]
//! (Lambertian, two-sided), [`roughconductor`] (a GGX microfacet metal, one-sided, as Mitsuba 3's
//! `roughconductor`), [`blend`] (a mixture of two materials, as Mitsuba 3's `blendbsdf`). The shared
//! pieces are [`microfacet`] (the GGX distribution and its visible normals) and [`fresnel`].
//!
//! A BSDF is evaluated in any [`Scalar`] (its parameters and the geometry carry derivatives) and sampled
//! in `f32`; [`Bsdf::pdf`] is the exact density of [`Bsdf::sample`]'s directions per steradian, which
//! the integrators use for their throughput and for multiple importance sampling. Sampling may fail
//! (return `None`) on part of `[0, 1)²`: the density then integrates to less than one over the
//! returned directions, and is still the density of what was returned, so estimates stay unbiased.

pub mod blend;
pub mod diffuse;
pub mod fresnel;
pub mod microfacet;
pub mod roughconductor;
pub mod texture;

use crate::declare::{Family, Kind};
use crate::error::{Error, FieldPath};
use crate::math::Vec3;
use crate::scalar::{Param, Param3, Scalar};
pub use blend::Blend;
pub use roughconductor::RoughConductor;
pub use texture::{At, MaterialTexture, Volume};

/// A BSDF.
#[derive(Clone, Debug, PartialEq)]
pub enum Bsdf {
    /// Lambertian reflector, two-sided: `albedo / π` when `wi` and `wo` lie on the same side.
    Diffuse {
        /// Linear RGB albedo in `[0, 1]`.
        albedo: Param3,
    },
    /// A rough metal: GGX microfacets with a conductor's Fresnel term, one-sided ([`roughconductor`]).
    RoughConductor(RoughConductor),
    /// `(1 − w) A + w B` ([`blend`]).
    Blend(Blend),
}

/// A direction sampled from a BSDF.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct BsdfSample {
    /// Unit incident direction (pointing away from the surface).
    pub wi: glam::Vec3,
    /// Density per steradian.
    pub pdf: f32,
}

impl Bsdf {
    /// The broken rules of the BSDF's own fields (an albedo in `[0, 1]`, a roughness in `[0.001, 1]`,
    /// ...), named by `at`; empty when valid. A blend's children are checked as their own nodes
    /// (their parameters are named `<prefix>.bsdfs.<i>.<field>`). The rules are the material kind's
    /// declaration ([`crate::declare::Kind`]).
    pub fn validate(&self, at: FieldPath) -> Vec<Error> {
        crate::declare::violations(self, at)
    }

    /// `f(wi, wo)` (without the cosine), generic, with every field its constant (see
    /// [`Bsdf::eval_at`] for textured fields).
    ///
    /// Side tests look at primal values only: the jump of `f` where `wi` crosses the tangent plane is
    /// a visibility-like discontinuity whose derivative belongs to the boundary terms, not to this one
    /// (and for the rough conductor `f |cos θi|` vanishes there anyway, through `G1`).
    #[inline]
    pub fn eval<S: Scalar>(&self, n: Vec3<S>, wi: Vec3<S>, wo: Vec3<S>) -> Vec3<S> {
        self.eval_node(&At::none(), 0, n, wi, wo)
    }

    /// [`Bsdf::eval`] with the textured fields read at `at` ([`texture`]).
    #[inline]
    pub fn eval_at<S: Scalar>(&self, at: &At<S>, n: Vec3<S>, wi: Vec3<S>, wo: Vec3<S>) -> Vec3<S> {
        self.eval_node(at, 0, n, wi, wo)
    }

    /// [`Bsdf::eval_at`] of this node, node `node` of the material tree (depth-first).
    #[inline]
    pub(crate) fn eval_node<S: Scalar>(
        &self,
        at: &At<S>,
        node: usize,
        n: Vec3<S>,
        wi: Vec3<S>,
        wo: Vec3<S>,
    ) -> Vec3<S> {
        match self {
            Bsdf::Diffuse { albedo } => {
                diffuse::eval_with(at.color(node, "albedo", albedo), n, wi, wo)
            }
            Bsdf::RoughConductor(c) => c.eval_node(at, node, n, wi, wo),
            Bsdf::Blend(b) => b.eval_node(at, node, n, wi, wo),
        }
    }

    /// Samples `wi` given `wo`. `None` when no direction is produced (`wo` in the tangent plane, a
    /// one-sided material seen from behind, a reflection below the horizon). Every field is its
    /// constant (see [`Bsdf::sample_at`]).
    #[inline]
    pub fn sample(&self, n: glam::Vec3, wo: glam::Vec3, u: glam::Vec2) -> Option<BsdfSample> {
        self.sample_node(&At::none(), 0, n, wo, u)
    }

    /// [`Bsdf::sample`] with the textured fields read at `at`.
    #[inline]
    pub fn sample_at(
        &self,
        at: &At<f32>,
        n: glam::Vec3,
        wo: glam::Vec3,
        u: glam::Vec2,
    ) -> Option<BsdfSample> {
        self.sample_node(at, 0, n, wo, u)
    }

    #[inline]
    pub(crate) fn sample_node(
        &self,
        at: &At<f32>,
        node: usize,
        n: glam::Vec3,
        wo: glam::Vec3,
        u: glam::Vec2,
    ) -> Option<BsdfSample> {
        match self {
            Bsdf::Diffuse { .. } => diffuse::sample(n, wo, u),
            Bsdf::RoughConductor(c) => c.sample_with(at.value(node, "alpha", &c.alpha), n, wo, u),
            Bsdf::Blend(b) => b.sample_node(at, node, n, wo, u),
        }
    }

    /// Density of [`Bsdf::sample`] per steradian.
    #[inline]
    pub fn pdf(&self, n: glam::Vec3, wo: glam::Vec3, wi: glam::Vec3) -> f32 {
        self.pdf_node(&At::none(), 0, n, wo, wi)
    }

    /// Density of [`Bsdf::sample_at`] per steradian.
    #[inline]
    pub fn pdf_at(&self, at: &At<f32>, n: glam::Vec3, wo: glam::Vec3, wi: glam::Vec3) -> f32 {
        self.pdf_node(at, 0, n, wo, wi)
    }

    #[inline]
    pub(crate) fn pdf_node(
        &self,
        at: &At<f32>,
        node: usize,
        n: glam::Vec3,
        wo: glam::Vec3,
        wi: glam::Vec3,
    ) -> f32 {
        match self {
            Bsdf::Diffuse { .. } => diffuse::pdf(n, wo, wi),
            Bsdf::RoughConductor(c) => c.pdf_with(at.value(node, "alpha", &c.alpha), n, wo, wi),
            Bsdf::Blend(b) => b.pdf_node(at, node, n, wo, wi),
        }
    }

    /// Number of material nodes in this tree (itself and every node below it).
    pub fn node_count(&self) -> usize {
        match self {
            Bsdf::Blend(b) => 1 + b.bsdfs.iter().map(Bsdf::node_count).sum::<usize>(),
            _ => 1,
        }
    }
}

/// Every material kind ([`crate::declare`]), in the order the scene file's errors list them.
const KINDS: &[&Kind<Bsdf>] = &[
    &diffuse::DIFFUSE,
    &roughconductor::ROUGHCONDUCTOR,
    &blend::BLEND,
];

impl Family for Bsdf {
    fn kinds() -> &'static [&'static Kind<Bsdf>] {
        KINDS
    }

    fn kind(&self) -> &'static Kind<Bsdf> {
        match self {
            Bsdf::Diffuse { .. } => &diffuse::DIFFUSE,
            Bsdf::RoughConductor(_) => &roughconductor::ROUGHCONDUCTOR,
            Bsdf::Blend(_) => &blend::BLEND,
        }
    }
}

/// A placeholder number for a blank node, which reading the file overwrites.
const BLANK: Param = Param::new(0.0);
