//! Light transport estimators. Paths are traced in `f32`; their contributions are evaluated with the
//! generic shading code, and every estimator hands its samples to a film ([`crate::film::accumulate`])
//! through one parallel driver ([`driver`]).
//!
//! Both estimators share one tracer ([`path::trace_path`]): `Direct` is a path with a single scattering
//! vertex. A pixel is the mean of its samples' radiances: the film offset of each sample is drawn
//! exactly from the pixel filter, so every sample's filter weight over its density is 1.

pub mod attach;
pub mod boundary;
pub mod diff;
pub mod driver;
pub mod fd;
pub mod options;
pub mod path;
pub mod primal;
pub mod shading;
pub mod silhouette_boxes;
pub mod silhouette_curve;
pub mod surface_sampling;

pub use crate::film::Normalization;
pub use crate::scene::IntegratorKind;
pub use diff::{
    DerivativeImages, render_derivatives, render_derivatives_with_boundary, render_interior,
    render_interior_in,
};
pub use driver::RenderStats;
pub use options::{BoundaryBudget, DiffOptions, Progress, RenderOptions};
pub use primal::{CAMERA_STREAM, render, sample_pixel, trace_sample};
