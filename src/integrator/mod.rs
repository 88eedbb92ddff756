//! Light transport estimators. Paths are traced in `f32`; their contributions are evaluated with the
//! generic shading code, and every estimator hands its samples to a film ([`crate::film::accumulate`])
//! through one parallel driver ([`driver`]).
//!
//! Both estimators share one tracer ([`path::trace_path`]): `Direct` is a path with a single scattering
//! vertex. A pixel is the mean of its samples' radiances: the film offset of each sample is drawn
//! exactly from the pixel filter, so every sample's filter weight over its density is 1.
//!
//! # Example
//!
//! An image and derivative images, as in docs/library.md (run as a doc test):
//!
//! ```
//! use implicit_psdr::integrator::{self, DiffOptions, RenderOptions};
//! use implicit_psdr::{film, scene};
//! use std::path::Path;
//!
//! fn main() -> implicit_psdr::Result<()> {
//!     // An image: the scene file, its samples per pixel, a seed.
//!     let scene = scene::load(Path::new("scenes/sphere_floor.json"))?;
//!     let options = RenderOptions { spp: 16, seed: 0, ..RenderOptions::default() };
//!     let (image, stats) = integrator::render(&scene, &options);
//!     println!("{} exhausted rays", stats.exhausted_rays);
//!
//!     // Derivative images: a selection of parameters (derivative k = the k-th name; grid directions
//!     // with `scene.select_with_grid_directions`), then the complete derivative (interior + primary +
//!     // secondary terms) with the default pixel normalisation and budgets.
//!     let params = ["ball.radius".to_string(), "light.center.x".to_string()];
//!     let selection = scene.select(&params)?;
//!     let d = integrator::render_derivatives(&scene, &selection, &DiffOptions {
//!         render: options.clone(),
//!         ..DiffOptions::default()
//!     })?;
//!     // d.image is `image`; d.total()[k] is d image / d params[k]; d.interior, d.primary and
//!     // d.secondary hold the terms. The channels `diff --terms` writes:
//!     let channels = d.channels(selection.names(), true);
//!     let out = std::env::temp_dir().join("d.exr");
//!     film::write_exr(&out, image.width, image.height, &channels)?;
//!
//!     // A gradient (reverse mode): the loss of the image against a target and its gradient with
//!     // respect to named parameters and whole grids (`GradientLayout::select(&scene, &params,
//!     // &["blob".into()])`), all terms, at once. The entries follow the layout: named parameters
//!     // first, then each grid's values.
//!     let target = film::read_exr_rgb(&out)?;
//!     let layout = integrator::GradientLayout::select(&scene, &params, &[])?;
//!     let g = integrator::loss_gradient(&scene, &layout, &target, integrator::Loss::L2,
//!                                       &DiffOptions { render: options, ..DiffOptions::default() })?;
//!     println!("loss {} d loss / d ball.radius {}", g.loss, g.gradient.total()[0]);
//!     // A new surface without reloading: `scene.set_grid_values("blob", values)?` (on a `mut` scene),
//!     // then render again with the same selection.
//!     Ok(())
//! }
//! ```

pub mod attach;
pub mod boundary;
pub mod diff;
pub mod driver;
pub mod fd;
pub mod gradient;
pub mod options;
pub mod path;
pub mod primal;
pub mod shading;
pub mod silhouette_boxes;
pub mod silhouette_curve;
pub mod surface_sampling;
pub mod velocity;

pub use crate::film::Normalization;
pub use crate::scene::IntegratorKind;
pub use diff::{
    DerivativeImages, render_derivatives, render_derivatives_with_boundary, render_interior,
    render_interior_in,
};
pub use driver::RenderStats;
pub use gradient::{Gradient, GradientLayout, Loss, LossGradient, loss_gradient, render_gradient};
pub use options::{BoundaryBudget, DiffOptions, Progress, RenderOptions, VelocityField};
pub use primal::{CAMERA_STREAM, camera_ray, render, sample_pixel, trace_sample, trace_samples};
