//! Boundary terms of the derivative (DESIGN.md §3 "Boundary integrals"): visibility along a segment jumps
//! where the segment touches a surface tangentially.
//!
//! [`segment`] holds the geometry of one boundary segment `(x_S, x_B, x_D)`: the measure changes
//! (`J^B`, seed §2 eqs. 12–23; the primary `dℓ(x_D)/dℓ(x_B)`, seed eq. 15), the silhouette test, and the
//! normal velocity `V_∂` of the discontinuity curve by AD. [`secondary`] estimates the secondary
//! boundary term (shadows) of the `direct` integrator with them, [`primary`] its primary boundary term
//! (silhouettes seen from the camera; a library function, not yet wired into `diff`).

pub mod primary;
pub mod secondary;
pub mod segment;

pub use segment::{
    BoundarySegment, boundary_jacobian, boundary_velocity, is_silhouette_direction,
    primary_measure_change, silhouette_tangent,
};
