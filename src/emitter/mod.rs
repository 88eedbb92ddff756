//! Light sources: a one-sided rectangle, a sphere, a constant environment, an environment map
//! ([`envmap`]), and the delta lights (a point light and a directional sun, [`delta`]).
//!
//! Everything that depends on the kind of emitter lives here (sampling, intersection, how a point on it
//! moves with its parameters, its outline, the scene rules on its fields), so a new kind is added in
//! this folder rather than in every consumer: its variant and code here or in a file of its own, its
//! declaration in `kinds.rs`.

pub mod delta;
pub mod envmap;
mod kinds;

pub use delta::Arrival;
pub use envmap::EnvMap;

use crate::error::{Error, FieldPath};
use crate::math::sampling::{UNIFORM_SPHERE_PDF, uniform_sphere};
use crate::math::{Aabb, Frame, Ray, Vec3};
use crate::scalar::{Param, Param3, Scalar};
use std::f32::consts::PI;
use std::sync::Arc;

/// An emitter. Finite emitters are also surfaces that block light and are seen by rays.
#[derive(Clone, Debug, PartialEq)]
pub enum Emitter {
    /// One-sided rectangle emitting along `normal`, spanned by `u` and `v = normal × u`.
    Rectangle {
        /// Centre.
        center: Param3,
        /// Unit normal: the side that emits.
        normal: glam::Vec3,
        /// Unit first edge direction (orthogonal to `normal`).
        u: glam::Vec3,
        /// Edge lengths along `u` and `v`.
        size: [Param; 2],
        /// Emitted radiance (linear RGB, W·m⁻²·sr⁻¹ in scene units).
        radiance: Param3,
    },
    /// Sphere emitting outward uniformly.
    Sphere {
        /// Centre.
        center: Param3,
        /// Radius (> 0).
        radius: Param,
        /// Emitted radiance.
        radiance: Param3,
    },
    /// Constant radiance arriving from every direction at infinity.
    Constant {
        /// Radiance.
        radiance: Param3,
    },
    /// Radiance arriving from infinity, read from a latitude–longitude image ([`envmap`]).
    Envmap {
        /// The image and its sampling tables (shared: they do not change with the parameters).
        map: Arc<EnvMap>,
        /// Factor on the image's radiance (`>= 0`).
        scale: Param,
        /// Unit axis of the map-to-world rotation.
        axis: glam::Vec3,
        /// Angle of the map-to-world rotation, degrees (right-handed about `axis`).
        angle: Param,
    },
    /// A point light (a delta light, [`delta`]): reached by shadow rays only.
    Point {
        /// Position.
        position: Param3,
        /// Radiant intensity (linear RGB, W/sr).
        intensity: Param3,
    },
    /// A directional light, the sun (a delta light at infinity, [`delta`]).
    Directional {
        /// The direction the light travels (non-zero; normalised where it is used, so a derivative
        /// along it is 0).
        direction: Param3,
        /// Irradiance on a surface facing the light (linear RGB, W/m²).
        irradiance: Param3,
    },
}

/// A point sampled on an emitter for next-event estimation from a reference point.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct EmitterSample {
    /// Unit direction from the reference point towards the emitter.
    pub wi: glam::Vec3,
    /// Distance to the sampled point (`f32::INFINITY` for the environment).
    pub dist: f32,
    /// The sampled point (meaningless for the environment).
    pub p: glam::Vec3,
    /// Unit normal at the sampled point (meaningless for the environment).
    pub n: glam::Vec3,
    /// Density per steradian at the reference point.
    pub pdf: f32,
}

/// The primal geometry of a finite emitter (derivatives dropped), for code that only looks at it.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Geometry {
    /// A one-sided rectangle.
    Rectangle {
        /// Centre.
        center: glam::Vec3,
        /// Unit normal: the side that emits.
        normal: glam::Vec3,
        /// Unit first edge direction.
        u: glam::Vec3,
        /// Unit second edge direction, `normal × u`.
        v: glam::Vec3,
        /// Edge lengths along `u` and `v`.
        size: [f32; 2],
    },
    /// A sphere.
    Sphere {
        /// Centre.
        center: glam::Vec3,
        /// Radius.
        radius: f32,
    },
}

/// The outline of a finite emitter seen from an eye point (see [`Emitter::outline`]).
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Outline {
    /// A rectangle's four edges `(a, b, outward)`, going round it; `outward` (unit) points off the
    /// rectangle in its plane.
    Edges {
        /// The rectangle's unit normal.
        normal: glam::Vec3,
        /// The edges.
        edges: [(glam::Vec3, glam::Vec3, glam::Vec3); 4],
    },
    /// A sphere's silhouette circle `centre + radius (cos θ e1 + sin θ e2)`.
    Circle {
        /// Centre of the circle.
        centre: glam::Vec3,
        /// Radius of the circle.
        radius: f32,
        /// First unit axis of the circle's plane.
        e1: glam::Vec3,
        /// Second unit axis of the circle's plane.
        e2: glam::Vec3,
        /// Centre of the sphere.
        sphere_centre: glam::Vec3,
        /// Radius of the sphere.
        sphere_radius: f32,
    },
}

/// A rectangle's second edge direction `v = normal × u`, the one place it is defined.
#[inline]
fn second_edge(normal: glam::Vec3, u: glam::Vec3) -> glam::Vec3 {
    normal.cross(u)
}

/// Below this `sin² θmax` the cone around a far sphere is too thin for `f32` (pbrt-v4 uses the same
/// threshold, sin² 1.5°): `1 − cos θmax` is then taken from its series `sin²/2 + sin⁴/8`.
const THIN_CONE_SIN2: f32 = 0.000_685_23;

/// `1 − cos θmax` of the cone subtended by a sphere with `sin² θmax = sin2`, without cancellation.
#[inline]
fn one_minus_cos_max(sin2: f32) -> f32 {
    if sin2 < THIN_CONE_SIN2 {
        0.5 * sin2 + 0.125 * sin2 * sin2
    } else {
        1.0 - (1.0 - sin2).max(0.0).sqrt()
    }
}

impl Emitter {
    /// The emitted radiance; a point light's intensity, a sun's irradiance. `None` for an
    /// environment map, whose radiance depends on the direction ([`Emitter::mean_radiance`]).
    pub fn radiance(&self) -> Option<&Param3> {
        match self {
            Emitter::Rectangle { radiance, .. }
            | Emitter::Sphere { radiance, .. }
            | Emitter::Constant { radiance } => Some(radiance),
            Emitter::Point { intensity, .. } => Some(intensity),
            Emitter::Directional { irradiance, .. } => Some(irradiance),
            Emitter::Envmap { .. } => None,
        }
    }

    /// The radiance averaged over the emitter's directions (an environment map's mean over the
    /// sphere times its scale; [`Emitter::radiance`]'s value for the others), at primal values.
    pub fn mean_radiance(&self) -> glam::Vec3 {
        match self {
            Emitter::Envmap { map, scale, .. } => map.mean() * scale.value,
            _ => self.radiance().map_or(glam::Vec3::ZERO, Param3::value),
        }
    }

    /// The primal geometry of a finite emitter; `None` for the environment and delta lights.
    pub fn geometry(&self) -> Option<Geometry> {
        match self {
            Emitter::Rectangle {
                center,
                normal,
                u,
                size,
                ..
            } => Some(Geometry::Rectangle {
                center: center.value(),
                normal: *normal,
                u: *u,
                v: second_edge(*normal, *u),
                size: [size[0].value, size[1].value],
            }),
            Emitter::Sphere { center, radius, .. } => Some(Geometry::Sphere {
                center: center.value(),
                radius: radius.value,
            }),
            Emitter::Constant { .. }
            | Emitter::Envmap { .. }
            | Emitter::Point { .. }
            | Emitter::Directional { .. } => None,
        }
    }

    /// Whether a selected parameter (one with a derivative slot) moves or resizes the emitter (a point
    /// light's position included); its radiance does not. A sun's direction is not a place: it is
    /// read from the parameter where it is used ([`Emitter::delta_arrival`]).
    pub fn geometry_selected(&self) -> bool {
        let sel = |p: &Param| p.slot.is_some();
        match self {
            Emitter::Rectangle { center, size, .. } => {
                center.c.iter().any(sel) || size.iter().any(sel)
            }
            Emitter::Sphere { center, radius, .. } => center.c.iter().any(sel) || sel(radius),
            Emitter::Point { position, .. } => position.c.iter().any(sel),
            Emitter::Constant { .. } | Emitter::Envmap { .. } | Emitter::Directional { .. } => {
                false
            }
        }
    }

    /// The point `p` of this finite emitter carried along by its parameters, generic: it keeps its
    /// relative position (a rectangle's fractional coordinates along `u` and `v`, a sphere's direction
    /// from the centre) as the emitter moves and scales. Returned with a generic quantity proportional
    /// to the area (`a·b`, `r²`) whose derivative over its value is the area element's. A point light's
    /// position, with 1. `None` for the environment and the sun, which have no points.
    pub fn attach<S: Scalar>(&self, p: glam::Vec3) -> Option<(Vec3<S>, S)> {
        match self {
            Emitter::Rectangle {
                center,
                normal,
                u,
                size,
                ..
            } => {
                let v = second_edge(*normal, *u);
                let local = p - center.value();
                let (a, b) = (size[0].value, size[1].value);
                let (s, t) = (local.dot(*u) / a, local.dot(v) / b);
                let (a_s, b_s) = (size[0].get::<S>(), size[1].get::<S>());
                let x = center.get::<S>()
                    + Vec3::constant(*u) * (a_s * s)
                    + Vec3::constant(v) * (b_s * t);
                Some((x, a_s * b_s))
            }
            Emitter::Sphere { center, radius, .. } => {
                let r_s = radius.get::<S>();
                let dir = (p - center.value()).normalize_or_zero();
                let x = center.get::<S>() + Vec3::constant(dir) * r_s;
                Some((x, r_s * r_s))
            }
            Emitter::Point { position, .. } => Some((position.get::<S>(), S::one())),
            Emitter::Constant { .. } | Emitter::Envmap { .. } | Emitter::Directional { .. } => None,
        }
    }

    /// The outline of a finite emitter seen from `eye`: a rectangle's four edges, or a sphere's
    /// silhouette circle. `None` for the environment, for a rectangle seen edge-on (the eye in its
    /// plane, so it covers no area) or without area, and for a sphere seen from inside or on it.
    pub fn outline(&self, eye: glam::Vec3) -> Option<Outline> {
        match self.geometry()? {
            Geometry::Rectangle {
                center: c,
                normal,
                u,
                v,
                size,
            } => {
                let (ha, hb) = (0.5 * size[0], 0.5 * size[1]);
                if !(ha > 0.0 && hb > 0.0) || (eye - c).dot(normal) == 0.0 {
                    return None;
                }
                let corner = |s: f32, t: f32| c + u * (s * ha) + v * (t * hb);
                Some(Outline::Edges {
                    normal,
                    edges: [
                        (corner(-1.0, -1.0), corner(1.0, -1.0), -v),
                        (corner(1.0, -1.0), corner(1.0, 1.0), u),
                        (corner(1.0, 1.0), corner(-1.0, 1.0), v),
                        (corner(-1.0, 1.0), corner(-1.0, -1.0), -u),
                    ],
                })
            }
            Geometry::Sphere {
                center: o,
                radius: r,
            } => {
                let to = o - eye;
                let d = to.length();
                if !(r > 0.0 && d > r && d.is_finite()) {
                    return None;
                }
                let w = to / d;
                let k = r / d;
                let frame = Frame::from_normal(w);
                Some(Outline::Circle {
                    centre: o - w * (r * k),
                    radius: r * (1.0 - k * k).max(0.0).sqrt(),
                    e1: frame.to_world(glam::Vec3::X),
                    e2: frame.to_world(glam::Vec3::Y),
                    sphere_centre: o,
                    sphere_radius: r,
                })
            }
        }
    }

    /// The broken scene rules of the emitter's fields (sizes and radius `> 0`, a radiance `>= 0`),
    /// named by `at` (the emitter's path or parameter prefix), in a fixed order; empty when valid. The
    /// rules are the emitter kind's declaration ([`crate::declare::Kind`]).
    ///
    /// Directions (`normal`, `u`) are checked where they are read: they are not parameters.
    pub fn validate(&self, at: FieldPath) -> Vec<Error> {
        crate::declare::violations(self, at)
    }

    /// Surface area of a finite emitter (`∞` for the environment, 0 for delta lights).
    pub fn area(&self) -> f32 {
        match self {
            Emitter::Rectangle { size, .. } => size[0].value * size[1].value,
            Emitter::Sphere { radius, .. } => 4.0 * PI * radius.value * radius.value,
            Emitter::Constant { .. } | Emitter::Envmap { .. } => f32::INFINITY,
            Emitter::Point { .. } | Emitter::Directional { .. } => 0.0,
        }
    }

    /// Nearest intersection `(t, outward normal)` of `ray` with a finite emitter in `(0, t_max)`; `None`
    /// for delta lights, which no ray hits.
    ///
    /// Both sides of a rectangle block rays; its returned normal is always the emitting side's `normal`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, glam::Vec3)> {
        match self {
            Emitter::Rectangle {
                center,
                normal,
                u,
                size,
                ..
            } => {
                let denom = ray.d.dot(*normal);
                if denom == 0.0 {
                    return None;
                }
                let c = center.value();
                let t = (c - ray.o).dot(*normal) / denom;
                if !(t > 0.0 && t < t_max) {
                    return None;
                }
                let local = ray.at(t) - c;
                let v = second_edge(*normal, *u);
                let inside = local.dot(*u).abs() <= 0.5 * size[0].value
                    && local.dot(v).abs() <= 0.5 * size[1].value;
                inside.then_some((t, *normal))
            }
            Emitter::Sphere { center, radius, .. } => {
                let c = center.value();
                let r = radius.value;
                // Ray-sphere in the form of Hearn & Baker (as pbrt): the closest approach avoids the
                // cancellation of the textbook discriminant for far spheres.
                let oc = ray.o - c;
                let b = oc.dot(ray.d);
                let closest = oc - ray.d * b;
                let disc = r * r - closest.length_squared();
                if disc < 0.0 {
                    return None;
                }
                let q = -b - b.signum() * disc.sqrt();
                let c_term = oc.length_squared() - r * r;
                let (mut t0, mut t1) = if q != 0.0 {
                    (c_term / q, q)
                } else {
                    (0.0, 0.0)
                };
                if t0 > t1 {
                    std::mem::swap(&mut t0, &mut t1);
                }
                let t = if t0 > 0.0 { t0 } else { t1 };
                if !(t > 0.0 && t < t_max) {
                    return None;
                }
                let n = (ray.at(t) - c).normalize_or_zero();
                Some((t, n))
            }
            Emitter::Constant { .. }
            | Emitter::Envmap { .. }
            | Emitter::Point { .. }
            | Emitter::Directional { .. } => None,
        }
    }

    /// Samples a direction towards the emitter from `reference`.
    ///
    /// - Rectangle: uniform by area, density `d² / (A cos θ_light)` per steradian; `None` when the
    ///   reference sees the non-emitting side (the sample would carry no light).
    /// - Sphere: uniform in the cone of directions it subtends (density `1 / (2π (1 − cos θmax))`);
    ///   uniform by area from inside.
    /// - Constant: uniform over the sphere of directions (`1 / 4π`): `sample_li` does not know the
    ///   surface normal, so it cannot favour the upper hemisphere.
    /// - Environment map: by luminance times `sin θ` ([`envmap`]); `None` for a black map.
    /// - Delta lights: the one direction towards the light, `pdf` 1 standing for the delta
    ///   ([`delta`]).
    #[inline]
    pub fn sample_li(&self, reference: glam::Vec3, u: glam::Vec2) -> Option<EmitterSample> {
        match self {
            Emitter::Rectangle {
                center,
                normal,
                u: eu,
                size,
                ..
            } => {
                let v = second_edge(*normal, *eu);
                let (a, b) = (size[0].value, size[1].value);
                let p = center.value() + *eu * ((u.x - 0.5) * a) + v * ((u.y - 0.5) * b);
                let to = p - reference;
                let d2 = to.length_squared();
                if d2.is_nan() || d2 <= 0.0 {
                    return None;
                }
                let dist = d2.sqrt();
                let wi = to / dist;
                let cos_l = -wi.dot(*normal);
                if cos_l.is_nan() || cos_l <= 0.0 {
                    return None;
                }
                let pdf = d2 / (a * b * cos_l);
                (pdf.is_finite() && pdf > 0.0).then_some(EmitterSample {
                    wi,
                    dist,
                    p,
                    n: *normal,
                    pdf,
                })
            }
            Emitter::Sphere { center, radius, .. } => {
                let c = center.value();
                let r = radius.value;
                let dc = c - reference;
                let d2c = dc.length_squared();
                if d2c <= r * r {
                    return self.sample_sphere_area(reference, c, r, u);
                }
                let dist_c = d2c.sqrt();
                let axis = dc / dist_c;
                let sin2 = (r * r / d2c).min(1.0);
                let omc = one_minus_cos_max(sin2);
                // Uniform cone written with `1 − cos θmax` (not `cos θmax`) so thin cones keep precision.
                let one_minus_z = u.x * omc;
                let z = 1.0 - one_minus_z;
                let s = (one_minus_z * (2.0 - one_minus_z)).max(0.0).sqrt();
                let phi = 2.0 * PI * u.y;
                let local = glam::Vec3::new(s * phi.cos(), s * phi.sin(), z);
                let wi = Frame::from_normal(axis).to_world(local).normalize();
                // Nearest hit along wi; the discriminant is clamped because directions at the cone's
                // rim graze the sphere and round-off may push them just outside.
                let b = dc.dot(wi);
                let closest2 = (dc - wi * b).length_squared();
                let t = (b - (r * r - closest2).max(0.0).sqrt()).max(0.0);
                let p = reference + wi * t;
                let n = (p - c).normalize_or_zero();
                let pdf = 1.0 / (2.0 * PI * omc);
                (pdf.is_finite() && pdf > 0.0).then_some(EmitterSample {
                    wi,
                    dist: t,
                    p,
                    n,
                    pdf,
                })
            }
            Emitter::Constant { .. } => {
                let wi = uniform_sphere(u);
                Some(EmitterSample {
                    wi,
                    dist: f32::INFINITY,
                    p: reference + wi,
                    n: -wi,
                    pdf: UNIFORM_SPHERE_PDF,
                })
            }
            Emitter::Envmap {
                map, axis, angle, ..
            } => {
                let (local, pdf) = map.sample(u)?;
                // Uniform sampling is the same in every frame: drawn in the world's, as the
                // constant emitter draws it. Otherwise the density is read back from the rotated
                // direction, so that it is `pdf_li`'s to the bit (a direction rounded across a
                // cell's edge takes the neighbour's density, as `pdf_li` does).
                let (wi, pdf) = if map.is_uniform() || (angle.value == 0.0 && angle.slot.is_none())
                {
                    (local, pdf)
                } else {
                    let wi = map_rotation::<f32>(*axis, angle, false).rotate(local.into());
                    let wi = glam::Vec3::from(wi).normalize();
                    (wi, self.pdf_li(reference, wi, reference + wi, -wi))
                };
                if !(pdf > 0.0 && pdf.is_finite()) {
                    return None;
                }
                Some(EmitterSample {
                    wi,
                    dist: f32::INFINITY,
                    p: reference + wi,
                    n: -wi,
                    pdf,
                })
            }
            Emitter::Point { .. } | Emitter::Directional { .. } => self.sample_delta_li(reference),
        }
    }

    /// Uniform area sampling of a sphere, converted to solid angle at `reference`.
    fn sample_sphere_area(
        &self,
        reference: glam::Vec3,
        c: glam::Vec3,
        r: f32,
        u: glam::Vec2,
    ) -> Option<EmitterSample> {
        let n = uniform_sphere(u);
        let p = c + n * r;
        let to = p - reference;
        let d2 = to.length_squared();
        if d2.is_nan() || d2 <= 0.0 {
            return None;
        }
        let dist = d2.sqrt();
        let wi = to / dist;
        let cos_l = wi.dot(n).abs();
        let pdf = d2 / (4.0 * PI * r * r * cos_l);
        (pdf.is_finite() && pdf > 0.0).then_some(EmitterSample {
            wi,
            dist,
            p,
            n,
            pdf,
        })
    }

    /// Density per steradian of [`Emitter::sample_li`] from `reference` to the point `p` (normal `n`) it
    /// would have produced (`p` ignored for the environment, where `wi` alone matters). 0 for delta
    /// lights: no direction found by other means reaches them.
    #[inline]
    pub fn pdf_li(
        &self,
        reference: glam::Vec3,
        wi: glam::Vec3,
        p: glam::Vec3,
        n: glam::Vec3,
    ) -> f32 {
        match self {
            Emitter::Rectangle { size, .. } => {
                let cos_l = -wi.dot(n);
                if cos_l.is_nan() || cos_l <= 0.0 {
                    return 0.0;
                }
                let d2 = (p - reference).length_squared();
                let pdf = d2 / (size[0].value * size[1].value * cos_l);
                if pdf.is_finite() { pdf } else { 0.0 }
            }
            Emitter::Sphere { center, radius, .. } => {
                let c = center.value();
                let r = radius.value;
                let d2c = (c - reference).length_squared();
                let pdf = if d2c <= r * r {
                    let cos_l = wi.dot(n).abs();
                    (p - reference).length_squared() / (4.0 * PI * r * r * cos_l)
                } else {
                    1.0 / (2.0 * PI * one_minus_cos_max((r * r / d2c).min(1.0)))
                };
                if pdf.is_finite() { pdf } else { 0.0 }
            }
            Emitter::Constant { .. } => UNIFORM_SPHERE_PDF,
            Emitter::Envmap {
                map, axis, angle, ..
            } => {
                let local = map_rotation::<f32>(*axis, angle, true).rotate(wi.into());
                map.pdf(local.into())
            }
            Emitter::Point { .. } | Emitter::Directional { .. } => 0.0,
        }
    }

    /// Radiance leaving point `p` (normal `n`) in direction `w` (away from the emitter), generic.
    ///
    /// Finite emitters emit on the side of `n` only; the side test looks at primal values (its jump is a
    /// visibility-like discontinuity handled by boundary terms). Delta lights have no radiance
    /// (their light is [`Emitter::delta_arrival`]). The environment ignores `p` and `n`: its
    /// radiance arrives from direction `−w` (an environment map looks it up there, rotated into the
    /// map's frame with the lifted angle, times the lifted scale).
    #[inline]
    pub fn emitted<S: Scalar>(&self, p: Vec3<S>, n: Vec3<S>, w: Vec3<S>) -> Vec3<S> {
        let _ = p;
        match self {
            Emitter::Envmap {
                map,
                scale,
                axis,
                angle,
            } => {
                let local = map_rotation::<S>(*axis, angle, true).rotate(-w);
                map.eval(local) * scale.get::<S>()
            }
            Emitter::Rectangle { radiance, .. } | Emitter::Sphere { radiance, .. } => {
                if n.dot(w).primal() > 0.0 {
                    radiance.get::<S>()
                } else {
                    Vec3::zero()
                }
            }
            Emitter::Constant { radiance } => radiance.get::<S>(),
            Emitter::Point { .. } | Emitter::Directional { .. } => Vec3::zero(),
        }
    }

    /// Box around a finite emitter; `None` for the environment and delta lights.
    pub fn bounds(&self) -> Option<Aabb> {
        match self {
            Emitter::Rectangle {
                center,
                normal,
                u,
                size,
                ..
            } => {
                let v = second_edge(*normal, *u);
                let half = (u.abs() * size[0].value + v.abs() * size[1].value) * 0.5;
                Some(Aabb::around(center.value(), half))
            }
            Emitter::Sphere { center, radius, .. } => Some(Aabb::around(
                center.value(),
                glam::Vec3::splat(radius.value),
            )),
            Emitter::Constant { .. }
            | Emitter::Envmap { .. }
            | Emitter::Point { .. }
            | Emitter::Directional { .. } => None,
        }
    }
    /// True for the environment emitters (constant and map): radiance arriving from infinity along
    /// every direction (the sun, a delta light at infinity, is not one: see [`Emitter::is_delta`]).
    pub fn is_infinite(&self) -> bool {
        matches!(self, Emitter::Constant { .. } | Emitter::Envmap { .. })
    }

    /// Whether next-event estimation samples this emitter: every emitter but the constant
    /// environment. A uniform light sample knows nothing the BSDF's does not (against radiance that
    /// is the same from every direction, a diffuse surface's cosine sample is exactly proportional
    /// to the unoccluded integrand), so BSDF-sampled rays alone estimate it, with MIS weight 1, and
    /// the light samples and shadow rays spent on it are saved, as pbrt-v4's uniform infinite light
    /// does with its incomplete densities (Pharr, Jakob and Humphreys, *Physically Based Rendering*,
    /// 4th ed., §12.5.1). Every BSDF here samples every direction it reflects into, so nothing is
    /// missed. An environment map is always light-sampled, even one of one luminance: its estimator
    /// must not change while its texels are optimised.
    pub fn is_light_sampled(&self) -> bool {
        !matches!(self, Emitter::Constant { .. })
    }
}

/// An environment map's rotation (map to world; `inverse`: world to map) in the generic scalar, the
/// angle lifted; the identity when the angle is 0 and not differentiated.
#[inline]
fn map_rotation<S: Scalar>(axis: glam::Vec3, angle: &Param, inverse: bool) -> MapRotation<S> {
    if angle.value == 0.0 && angle.slot.is_none() {
        return MapRotation { axis, trig: None };
    }
    let theta = angle.get::<S>() * (PI / 180.0);
    let s = theta.sin();
    MapRotation {
        axis,
        trig: Some((theta.cos(), if inverse { -s } else { s })),
    }
}

/// A rotation about a unit axis by the angle of cosine and sine `trig` (`None`: the identity).
struct MapRotation<S> {
    axis: glam::Vec3,
    trig: Option<(S, S)>,
}

impl<S: Scalar> MapRotation<S> {
    /// `v` rotated (Rodrigues: `v c + (k × v) s + k (k·v)(1 − c)`).
    #[inline]
    fn rotate(&self, v: Vec3<S>) -> Vec3<S> {
        let Some((c, s)) = self.trig else {
            return v;
        };
        let k = Vec3::<S>::constant(self.axis);
        let kv = v.dot_f32(self.axis) * (S::one() - c);
        v * c + k.cross(v) * s + k * kv
    }
}
