//! What one run of an estimator renders: the scene, the parameter differentiated and the
//! finite-difference step, and the call of the right integrator for each [`Estimator`].

use super::Estimator;
use crate::error::{Error, Result};
use crate::film::Image;
use crate::integrator::fd::{self, finite_difference};
use crate::integrator::{
    BoundaryBudget, DerivativeImages, DiffOptions, RenderOptions, render,
    render_derivatives_with_boundary, render_interior,
};
use crate::scene::{Scene, Selection};

/// A scene and, for the derivative estimators, the parameter they differentiate.
#[derive(Clone, Debug)]
pub struct Subject {
    /// The scene as loaded: what every estimator renders.
    plain: Scene,
    /// The parameter as the derivative estimators' selection; `None` for the image itself.
    selected: Option<Selection>,
    /// The parameter, `None` for the image.
    parameter: Option<String>,
    /// `fd`'s step: the default step of the parameter's value ([`fd::default_step`]).
    step: f32,
}

impl Subject {
    /// The image of `scene` (what [`Estimator::Primal`] estimates).
    pub fn image(scene: &Scene) -> Self {
        Self {
            plain: scene.clone(),
            selected: None,
            parameter: None,
            step: 0.0,
        }
    }

    /// The derivative of `scene`'s image with respect to `parameter`. Errors: an unknown name (with
    /// near matches).
    pub fn derivative(scene: &Scene, parameter: &str) -> Result<Self> {
        let value = fd::parameter_value(scene, parameter)?;
        let selected = scene.select(&[parameter])?;
        Ok(Self {
            plain: scene.clone(),
            selected: Some(selected),
            parameter: Some(parameter.to_string()),
            step: fd::default_step(value),
        })
    }

    /// The parameter, `None` for the image.
    pub fn parameter(&self) -> Option<&str> {
        self.parameter.as_deref()
    }

    /// The scene as loaded.
    pub fn scene(&self) -> &Scene {
        &self.plain
    }

    /// `fd`'s step (the default step of the parameter's value).
    pub fn step(&self) -> f32 {
        self.step
    }

    /// Central differences with step `h`, `spp` samples per pixel and `seed`.
    pub fn finite_difference(&self, h: f32, spp: u32, seed: u64) -> Result<Image> {
        let name = self.parameter.as_deref().ok_or_else(no_parameter)?;
        finite_difference(&self.plain, name, h, &render_options(spp, seed))
    }

    /// One run of `estimator` at `spp` samples per pixel with `seed`: the derivative image (channel
    /// planes R, G, B) or, for [`Estimator::Primal`], the image. Errors: those of the integrators
    /// (e.g. a box pixel filter for the derivative estimators, a step out of a parameter's range for
    /// `fd`), or a derivative estimator asked of the image.
    pub fn run(&self, estimator: Estimator, spp: u32, seed: u64) -> Result<Image> {
        if estimator == Estimator::Primal {
            return Ok(render(&self.plain, &render_options(spp, seed)).0);
        }
        if estimator == Estimator::Fd {
            return self.finite_difference(self.step, spp, seed);
        }
        Ok(self
            .derivative_terms(estimator, spp, seed)?
            .total()
            .remove(0))
    }

    /// Whether the boundary terms (silhouettes and shadows) of the parameter are all zero at `spp`
    /// samples per pixel: then the boundary-budget variants equal [`Estimator::Complete`] and say
    /// nothing about the budgets. Errors: those of the complete derivative.
    pub fn boundary_terms_vanish(&self, spp: u32, seed: u64) -> Result<bool> {
        let out = self.derivative_terms(Estimator::Complete, spp, seed)?;
        let terms = out.primary.iter().chain(&out.secondary);
        Ok(terms.flat_map(|t| &t.rgb).all(|v| *v == 0.0))
    }

    /// The terms of a derivative estimator's run: the interior term alone, or all three with the
    /// estimator's multiple of the default boundary budgets.
    fn derivative_terms(
        &self,
        estimator: Estimator,
        spp: u32,
        seed: u64,
    ) -> Result<DerivativeImages> {
        let selection = self.selected.as_ref().ok_or_else(no_parameter)?;
        let scene = &self.plain;
        let options = DiffOptions {
            render: render_options(spp, seed),
            ..DiffOptions::default()
        };
        match estimator.boundary_scale() {
            None => render_interior(scene, selection, &options),
            Some((num, den)) => {
                let (primary, secondary) = BoundaryBudget::default().totals(scene, spp);
                // At least one sample each, so that a quarter of a tiny budget still samples the term.
                let scale = |n: u64| (n * num / den).max(1);
                render_derivatives_with_boundary(
                    scene,
                    selection,
                    &options,
                    scale(primary),
                    scale(secondary),
                )
            }
        }
    }

    /// Why `fd` cannot run with step `h` (a value `P ± h` out of the parameter's range, a step too
    /// small for `f32`), checked without rendering; `None` when it can.
    pub fn finite_difference_refused(&self, h: f32) -> Option<String> {
        let name = self.parameter.as_deref()?;
        let value = fd::parameter_value(&self.plain, name).ok()?;
        if (value + h) - (value - h) <= 0.0 {
            return Some(format!(
                "the step {h} does not change {name} = {value} in f32"
            ));
        }
        for v in [value + h, value - h] {
            if let Err(e) = self.plain.with_parameter(name, v) {
                return Some(format!("the step {h} takes {name} to {v}: {e}"));
            }
        }
        None
    }
}

/// Options of one render: `spp` samples per pixel with `seed`, no progress reporting (the report
/// shows its own).
fn render_options(spp: u32, seed: u64) -> RenderOptions {
    RenderOptions {
        spp,
        seed,
        progress: Default::default(),
    }
}

fn no_parameter() -> Error {
    Error::Unsupported("a derivative estimator needs a parameter".into())
}
