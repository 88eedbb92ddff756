//! Sphere tracing in `f32`: first hit along a ray, and every hit along a line.

use crate::math::Ray;
use crate::sdf::Sdf;

/// Tolerances of the tracer.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct TraceSettings {
    /// Hit tolerance in scene units (|φ| below this, after refinement, is a hit). Set from the scene scale.
    pub eps: f32,
    /// Steps before a ray is declared exhausted.
    pub max_steps: u32,
}

impl Default for TraceSettings {
    fn default() -> Self {
        Self {
            eps: 1e-4,
            max_steps: 512,
        }
    }
}

/// Result of tracing one implicit surface over a parameter interval.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum ShapeTrace {
    /// First crossing of the surface at parameter `t`.
    Hit(f32),
    /// No crossing in the interval.
    Miss,
    /// Ran out of steps before deciding; `t` is where it stopped.
    Exhausted(f32),
}

/// First zero crossing of `sdf` (Lipschitz bound `lipschitz`) along `ray` in `[t0, t1]`.
pub fn sphere_trace(
    sdf: &Sdf,
    lipschitz: f32,
    ray: &Ray,
    t0: f32,
    t1: f32,
    settings: &TraceSettings,
) -> ShapeTrace {
    let _ = (sdf, lipschitz, ray, t0, t1, settings);
    todo!("trace: sphere_trace")
}

/// Every zero crossing of `sdf` along `ray` in `[t0, t1]`, in increasing order.
pub fn all_hits(
    sdf: &Sdf,
    lipschitz: f32,
    ray: &Ray,
    t0: f32,
    t1: f32,
    settings: &TraceSettings,
) -> Vec<f32> {
    let _ = (sdf, lipschitz, ray, t0, t1, settings);
    todo!("trace: all_hits")
}
