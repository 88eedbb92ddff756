//! Pinhole camera. Film coordinates are in pixels: `x` in `[0, width)` to the right, `y` in `[0, height)`
//! downward (row 0 at the top); pixel `(i, j)` has its centre at `(i + 0.5, j + 0.5)`. `up` is up in the
//! image. The camera looks along `target − origin`; `fov_y` is the full vertical angle in degrees.

use crate::film::Filter;
use crate::math::{Ray, Vec3};
use crate::scalar::{Param, Param3, Scalar};

/// A pinhole camera with its film.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub origin: Param3,
    /// A point the camera looks at.
    pub target: Param3,
    /// Up direction (need not be orthogonal to the view direction, must not be parallel to it).
    pub up: Param3,
    /// Full vertical field of view in degrees, in `(0, 180)`.
    pub fov_y: Param,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Pixel reconstruction filter.
    pub filter: Filter,
}

impl Camera {
    /// The primary ray through film position `film` (pixels).
    pub fn generate_ray(&self, film: glam::Vec2) -> Ray {
        let _ = film;
        todo!("camera: generate_ray")
    }

    /// Film position (pixels) of the point `p`, or `None` behind the camera. Generic: with lifted camera
    /// parameters or an attached `p` it gives the moving projection.
    pub fn project<S: Scalar>(&self, p: Vec3<S>) -> Option<(S, S)> {
        let _ = p;
        todo!("camera: project")
    }

    /// `dA_film / dA(p)`: film area (pixels²) per unit surface area at `p` with unit normal `n`, seen from
    /// the eye (`|cos θ_p| / d² · f² / cos³ θ_c`, with `f` the focal length in pixels).
    pub fn film_area_jacobian<S: Scalar>(&self, p: Vec3<S>, n: Vec3<S>) -> S {
        let _ = (p, n);
        todo!("camera: film_area_jacobian")
    }
}
