//! Small math: the generic [`Vec3`], axis-aligned boxes, orthonormal frames, sampling warps, and curves
//! where two implicit functions vanish ([`implicit_curve`]).
//! Everything except [`Vec3`] is `f32`-only and uses glam.

mod aabb;
mod frame;
pub mod implicit_curve;
pub mod sampling;
mod vec3;

pub use aabb::Aabb;
pub use frame::Frame;
pub use vec3::Vec3;

/// A ray in `f32`: origin and unit direction. Points along it are `o + t d`, `t >= 0`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Ray {
    /// Origin, in scene units.
    pub o: glam::Vec3,
    /// Unit direction.
    pub d: glam::Vec3,
}

impl Ray {
    /// A ray from `o` along the unit vector `d`.
    #[inline]
    pub fn new(o: glam::Vec3, d: glam::Vec3) -> Self {
        Self { o, d }
    }
    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> glam::Vec3 {
        self.o + self.d * t
    }
}
