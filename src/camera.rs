//! Pinhole camera. Film coordinates are in pixels: `x` in `[0, width)` to the right, `y` in `[0, height)`
//! downward (row 0 at the top); pixel `(i, j)` has its centre at `(i + 0.5, j + 0.5)`. `up` is up in the
//! image. The camera looks along `target − origin`; `fov_y` is the full vertical angle in degrees.
//!
//! The frame (right-handed): `forward = normalize(target − origin)`, `right = normalize(forward × up)`
//! (image `+x`), `true_up = right × forward` (image `−y`). The focal length in pixels is
//! `f = (height / 2) / tan(fov_y / 2)`. A point `p` with `q = p − origin` projects to
//! `x = width/2 + f (q·right)/(q·forward)`, `y = height/2 − f (q·true_up)/(q·forward)`.
//!
//! The frame is built generically ([`Camera::frame`]) from the lifted parameters, so camera parameters can
//! be differentiated. [`Camera::generate_ray`] rebuilds the `f32` frame on each call (two normalisations
//! and a tangent, small next to tracing the ray); hot loops can build it once with `camera.frame::<f32>()`
//! and call [`CameraFrame::generate_ray`].

use crate::error::{Error, Result};
use crate::film::Filter;
use crate::math::{Ray, Vec3};
use crate::scalar::{DualN, Param, Param3, Scalar};

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

/// The camera's orthonormal frame and focal length in scalar type `S` (see the [module docs](self)).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct CameraFrame<S> {
    /// Eye position.
    pub origin: Vec3<S>,
    /// Unit vector along image `+x`.
    pub right: Vec3<S>,
    /// Unit vector along image `−y` (up in the picture).
    pub up: Vec3<S>,
    /// Unit view direction.
    pub forward: Vec3<S>,
    /// Focal length in pixels, `(height / 2) / tan(fov_y / 2)`.
    pub focal: S,
    /// Image centre `(width / 2, height / 2)` in pixels.
    pub center: (f32, f32),
}

impl Camera {
    /// A camera with undifferentiated parameters from plain values.
    pub fn new(
        origin: glam::Vec3,
        target: glam::Vec3,
        up: glam::Vec3,
        fov_y: f32,
        width: u32,
        height: u32,
        filter: Filter,
    ) -> Self {
        Self {
            origin: origin.into(),
            target: target.into(),
            up: up.into(),
            fov_y: fov_y.into(),
            width,
            height,
            filter,
        }
    }

    /// Checks the values the frame needs: a positive image size, `fov_y` in `(0, 180)`, `target ≠ origin`,
    /// `up` not parallel to the view direction. Field paths are relative to the camera (`fov_y`, `up`, ...).
    pub fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::field(
                "width/height",
                format!("must be > 0, got {}x{}", self.width, self.height),
            ));
        }
        let fov = self.fov_y.value;
        if !(fov > 0.0 && fov < 180.0) {
            return Err(Error::field(
                "fov_y",
                format!("must be in (0, 180) degrees, got {fov}"),
            ));
        }
        let view = self.target.value() - self.origin.value();
        if !view.is_finite() || view.length_squared() == 0.0 {
            return Err(Error::field(
                "target",
                format!("must differ from origin, got {:?}", self.target.value()),
            ));
        }
        let up = self.up.value();
        let cross = view.normalize().cross(up);
        if !up.is_finite() || cross.length() <= 1e-6 * up.length() || up.length_squared() == 0.0 {
            return Err(Error::field(
                "up",
                format!("must not be zero or parallel to the view direction, got {up:?}"),
            ));
        }
        Ok(())
    }

    /// The camera frame with lifted parameters (a constant frame for `f32`). A degenerate camera (see
    /// [`Camera::validate`]) gives zero vectors rather than NaN.
    pub fn frame<S: Scalar>(&self) -> CameraFrame<S> {
        let origin = self.origin.get::<S>();
        let forward = (self.target.get::<S>() - origin).normalize_or_zero();
        let right = forward.cross(self.up.get::<S>()).normalize_or_zero();
        let up = right.cross(forward);
        let half = self.fov_y.get::<S>() * (std::f32::consts::PI / 360.0);
        let (s, c) = (half.sin(), half.cos());
        // tan(fov/2) > 0 for a valid fov; guard the division for a degenerate one.
        let focal = if s.primal() > 0.0 {
            c / s * (0.5 * self.height as f32)
        } else {
            S::zero()
        };
        CameraFrame {
            origin,
            right,
            up,
            forward,
            focal,
            center: (0.5 * self.width as f32, 0.5 * self.height as f32),
        }
    }

    /// The primary ray through film position `film` (pixels).
    pub fn generate_ray(&self, film: glam::Vec2) -> Ray {
        self.frame::<f32>().generate_ray(film)
    }

    /// Film position (pixels) of the point `p`, or `None` behind the camera. Generic: with lifted camera
    /// parameters or an attached `p` it gives the moving projection.
    pub fn project<S: Scalar>(&self, p: Vec3<S>) -> Option<(S, S)> {
        self.frame::<S>().project(p)
    }

    /// `dA_film / dA(p)`: film area (pixels²) per unit surface area at `p` with unit normal `n`, seen from
    /// the eye (`|cos θ_p| / d² · f² / cos³ θ_c`, with `f` the focal length in pixels).
    pub fn film_area_jacobian<S: Scalar>(&self, p: Vec3<S>, n: Vec3<S>) -> S {
        self.frame::<S>().film_area_jacobian(p, n)
    }
}

/// The share of a pixel's angular size that camera rays resolve ([`CameraFrame::spread`]).
pub const PIXEL_RESOLUTION: f32 = 1.0 / 16.0;

impl CameraFrame<f32> {
    /// The detail a camera ray along the unit direction `d` must resolve, per unit distance from the
    /// eye ([`crate::trace::TraceSettings::spread`]): [`PIXEL_RESOLUTION`] times the angular size of a
    /// pixel there, `cos²θ / f` (`θ` the angle to the optical axis, `f` the focal length in pixels:
    /// the smaller of a pixel's radial and tangential sizes), so that a silhouette seen at a tiny field
    /// of view is traced to a fraction of a pixel, whatever the scene's size.
    #[inline]
    pub fn spread(&self, d: glam::Vec3) -> f32 {
        let cos = d.dot(self.forward.into());
        PIXEL_RESOLUTION * cos * cos / self.focal
    }

    /// The primary ray through film position `film` (pixels), from the eye, with a unit direction.
    #[inline]
    pub fn generate_ray(&self, film: glam::Vec2) -> Ray {
        let right: glam::Vec3 = self.right.into();
        let up: glam::Vec3 = self.up.into();
        let forward: glam::Vec3 = self.forward.into();
        let d =
            right * (film.x - self.center.0) - up * (film.y - self.center.1) + forward * self.focal;
        Ray::new(self.origin.into(), d.normalize_or_zero())
    }
}

impl<S: Scalar> CameraFrame<S> {
    /// [`CameraFrame::project`] and [`CameraFrame::film_area_jacobian`] of a surface point `p` with
    /// unit normal `n`. For a recorded type ([`Scalar::RECORDED`]) and a frame that does not move
    /// with the parameters, each result is one [`Scalar::affine`] number over `p` and `n`, its
    /// partials from a six-direction dual in `f32` (same primal bits, derivatives to rounding), where
    /// the two formulas take about forty nodes.
    #[inline]
    pub fn film_position(&self, p: Vec3<S>, n: Vec3<S>) -> Option<((S, S), S)> {
        let fixed = [self.origin, self.right, self.up, self.forward]
            .iter()
            .all(|v| v.x.is_constant() && v.y.is_constant() && v.z.is_constant())
            && self.focal.is_constant();
        if !(S::RECORDED && S::FIRST_ORDER && fixed) {
            return Some((self.project(p)?, self.film_area_jacobian(p, n)));
        }
        type D6 = DualN<6>;
        let constant = |v: Vec3<S>| Vec3::<D6>::constant(v.primal());
        let frame = CameraFrame::<D6> {
            origin: constant(self.origin),
            right: constant(self.right),
            up: constant(self.up),
            forward: constant(self.forward),
            focal: D6::constant(self.focal.primal()),
            center: self.center,
        };
        let seeded = |v: Vec3<S>, first: usize| {
            Vec3::new(
                D6::variable(v.x.primal(), first),
                D6::variable(v.y.primal(), first + 1),
                D6::variable(v.z.primal(), first + 2),
            )
        };
        let (p6, n6) = (seeded(p, 0), seeded(n, 3));
        let (x, y) = frame.project(p6)?;
        let jacobian = frame.film_area_jacobian(p6, n6);
        let over = [p.x, p.y, p.z, n.x, n.y, n.z];
        let fuse = |d: D6, k: usize| {
            let terms: [(S, f32); 6] = std::array::from_fn(|i| (over[i], d.eps[i]));
            S::affine(d.re, &terms[..k])
        };
        Some(((fuse(x, 3), fuse(y, 3)), fuse(jacobian, 6)))
    }

    /// Film position (pixels) of `p`, or `None` if `p` is not in front of the eye (`(p − o)·forward ≤ 0`).
    #[inline]
    pub fn project(&self, p: Vec3<S>) -> Option<(S, S)> {
        let q = p - self.origin;
        let z = q.dot(self.forward);
        if z.primal() <= 0.0 {
            return None;
        }
        let k = self.focal / z;
        Some((
            k * q.dot(self.right) + self.center.0,
            -(k * q.dot(self.up)) + self.center.1,
        ))
    }

    /// `dA_film / dA(p)` for a surface element at `p` with unit normal `n`.
    ///
    /// With `q = p − o`, `d = |q|`, `z = q·forward`: `|cos θ_p|/d² · f²/cos³ θ_c` with `cos θ_p = n·q/d`
    /// and `cos θ_c = z/d` simplifies to `f² |n·q| / z³` (solid angle `|cos θ_p| dA/d²` times the film area
    /// per solid angle `f²/cos³ θ_c`). Zero for points not in front of the eye.
    #[inline]
    pub fn film_area_jacobian(&self, p: Vec3<S>, n: Vec3<S>) -> S {
        let q = p - self.origin;
        let z = q.dot(self.forward);
        if z.primal() <= 0.0 {
            return S::zero();
        }
        self.focal * self.focal * n.dot(q).abs() / (z * z * z)
    }
}
