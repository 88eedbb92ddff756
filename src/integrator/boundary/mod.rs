//! Boundary terms of the derivative (DESIGN.md §3 "Boundary integrals"): visibility along a segment jumps
//! where the segment touches a surface tangentially.
//!
//! [`segment`] holds the geometry of one boundary segment `(x_S, x_B, x_D)`: the measure changes
//! (`J^B`, seed §2 eqs. 12–23; the primary `dℓ(x_D)/dℓ(x_B)`, seed eq. 15), the silhouette test, and the
//! normal velocity `V_∂` of the discontinuity curve by AD. [`secondary`] estimates the secondary
//! boundary term (shadows, on every segment of a path after the first) with them, its tangent angles
//! steered towards the emitters by [`tangent_sampling`] and [`subpaths`] estimating the camera and
//! light sides of segments deep in a path; [`primary`] the primary boundary term (silhouettes seen from
//! the camera), with [`emitter_edges`] for the outlines of emitters seen directly. Both integrators
//! (`direct` is `path` with one scattering vertex).

pub mod emitter_edges;
pub mod primary;
pub mod secondary;
pub mod segment;
pub mod subpaths;
pub mod tangent_sampling;

pub use segment::{
    BoundarySegment, boundary_jacobian, boundary_velocity, is_silhouette_direction,
    primary_measure_change, silhouette_tangent,
};

use crate::error::{Error, Result};
use crate::film::Image;
use crate::integrator::attach::window_slots;
use crate::integrator::derivative::Directions;
use crate::scene::Scene;

/// The boundary terms exist for both integrators (`direct` is `path` with one scattering vertex) and
/// continuous pixel filters; `term` names the term in the error.
fn check_supported(scene: &Scene, term: &str) -> Result<()> {
    if !scene.camera.filter.is_continuous() {
        return Err(Error::Unsupported(format!(
            "the {term} boundary term with the box filter needs pixel-edge terms: use the tent or \
             gaussian filter"
        )));
    }
    Ok(())
}

/// Runs `pass(windowed scene, width)` once per window of `S::COUNT` parameters of slots `0..count`
/// (the window's slots renumbered from 0) and concatenates the per-parameter images in slot order.
fn in_windows<S: Directions>(
    scene: &Scene,
    count: usize,
    mut pass: impl FnMut(&Scene, usize) -> Vec<Image>,
) -> Vec<Image> {
    let mut out = Vec::with_capacity(count);
    for lo in (0..count).step_by(S::COUNT) {
        let width = (count - lo).min(S::COUNT);
        out.extend(pass(&window_slots(scene, lo, S::COUNT), width));
    }
    out
}
