//! implicit-psdr: physically based rendering of implicit surfaces, generic over the scalar type so that
//! the same code produces images (`f32`) and derivative images (dual numbers), following *Path-Space
//! Differentiable Rendering of Implicit Surfaces* (Zhou et al., SIGGRAPH 2024).
//!
//! The user guide is in the repository's `docs/` folder (the command line, the scene format, the
//! derivatives and their options, reverse mode, performance); `docs/library.md` shows the library's
//! calls, and the example of [`integrator`] runs them.
//!
//! # Where to start reading
//!
//! Data flows one way: scene file → scene → tracer → integrand → film → EXR/PNG.
//!
//! 1. **Scene.** [`scene::load`] parses a scene file into a [`scene::Scene`] (stored in `f32`): its
//!    [`scene::Shape`]s, each an [`sdf::Sdf`] tree with a material from [`bsdf`]; its emitters
//!    ([`scene::NamedEmitter`], [`emitter`]); its [`camera::Camera`]. Numbers that can be differentiated
//!    are [`Param`]s; [`scene::Scene::select`] returns the [`scene::Selection`] of those that carry
//!    derivatives, which the estimators take with the scene.
//! 2. **Tracer**, in `f32`. [`scene::Scene::intersect`] finds a ray's first hit through [`trace`]
//!    (sphere tracing, closed forms where the answer is certain, [`trace::TraceSettings`] for the
//!    tolerances); [`integrator::path::trace_path`] records a whole light path as a
//!    [`integrator::path::PathRecord`].
//! 3. **Integrand**, in `S: `[`Scalar`]. [`integrator::path::contribution`] evaluates a recorded path's
//!    contribution with `f32` for the image, [`scalar::DualN`] for derivative images and
//!    [`scalar::Rev`] for gradients; surface points move with the parameters through
//!    [`integrator::attach`]. The boundary terms are in [`integrator::boundary`].
//! 4. **Film.** Every estimator hands its samples to a [`film::Film`] ([`film::PixelFilm`] for camera
//!    samples, [`film::SplatFilm`] for boundary samples, [`film::AdjointFilm`] for reverse mode) through
//!    one parallel driver ([`integrator::driver::run`]); the result is a [`film::Image`], written by
//!    [`film::write_exr`].
//!
//! The entry points that run all four: [`integrator::render`], [`integrator::render_derivatives`] and
//! [`integrator::loss_gradient`]; [`optimize`] and [`report`] are built on them. Files (EXR, PNG,
//! `.npy`, strict JSON) are read and written in [`io`]. The command-line tool is [`cli`] (the binary and
//! the Python package's `implicit-psdr` command both run it).
//!
//! # Adding a kind of node
//!
//! Every sdf node kind, emitter kind and material kind declares its fields once, beside its own code
//! ([`declare::Kind`]); the scene parser, the parameter names, the write-back of values into the scene
//! JSON and the field rules all work from that declaration. A new primitive is one file (see
//! `src/sdf/capsule.rs`: its struct, an [`sdf::SdfPrimitive`] implementation, its declaration and a
//! constructor) plus one line in the sdf module's `primitives!` list; a new emitter or material is its
//! variant, its code and its declaration in [`emitter`] or [`bsdf`].
//!
//! Citations in the documentation: "docs/theory.md §k" is the theory as this repository states it
//! (`docs/theory.md`, with numbered sections and equations); "supplemental §k, eq. m" is the
//! supplemental document of Zhou et al. 2024, from which the equations are taken.
#![warn(missing_docs)]

pub mod bsdf;
pub mod camera;
pub mod cli;
pub mod compare;
pub mod declare;
pub mod emitter;
pub mod error;
pub mod film;
pub mod integrator;
pub mod io;
pub mod math;
pub mod mesh;
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
