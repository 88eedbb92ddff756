//! implicit-psdr: physically based rendering of implicit surfaces, generic over the scalar type so that
//! the same code produces images (`f32`) and derivative images (dual numbers), following *Path-Space
//! Differentiable Rendering of Implicit Surfaces* (Zhou et al., SIGGRAPH 2024).
//!
//! Data flows one way: scene file ([`scene`]) → [`scene::Scene`] (stored in `f32`) → tracer ([`trace`],
//! `f32`) → integrand in `S: Scalar` ([`integrator`], [`bsdf`], [`emitter`], [`camera`]) → [`film`] → EXR/PNG.
//!
//! Citations in the documentation: "docs/theory.md §k" is the theory as this repository states it
//! (`docs/theory.md`, with numbered sections and equations); "supplemental §k, eq. m" is the
//! supplemental document of Zhou et al. 2024, from which the equations are taken.
#![warn(missing_docs)]

pub mod bsdf;
pub mod camera;
pub mod compare;
pub mod emitter;
pub mod error;
pub mod film;
pub mod integrator;
pub mod io;
pub mod math;
pub mod optimize;
#[cfg(feature = "python")]
mod python;
pub mod report;
pub mod sampler;
pub mod scalar;
pub mod scene;
pub mod sdf;
pub mod trace;

pub use error::{Error, Result};
pub use math::Vec3;
pub use scalar::{Param, Param3, Scalar};
