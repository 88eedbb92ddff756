use crate::scalar::Scalar;
use std::ops::{Add, AddAssign, Div, Mul, Neg, Sub, SubAssign};

/// A 3-vector of any [`Scalar`]: points, directions and linear RGB colours in shading code.
///
/// `*` between two vectors is component-wise (as for colours); use [`Vec3::dot`] for the inner product.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct Vec3<S> {
    /// First component (x, or red).
    pub x: S,
    /// Second component (y, or green).
    pub y: S,
    /// Third component (z, or blue).
    pub z: S,
}

impl<S: Scalar> Vec3<S> {
    /// A vector from components.
    #[inline(always)]
    pub fn new(x: S, y: S, z: S) -> Self {
        Self { x, y, z }
    }
    /// The same value in every component.
    #[inline(always)]
    pub fn splat(v: S) -> Self {
        Self::new(v, v, v)
    }
    /// The zero vector.
    #[inline(always)]
    pub fn zero() -> Self {
        Self::splat(S::zero())
    }
    /// A constant vector from a glam vector.
    #[inline(always)]
    pub fn constant(v: glam::Vec3) -> Self {
        Self::new(S::constant(v.x), S::constant(v.y), S::constant(v.z))
    }
    /// The primal values as a glam vector.
    #[inline(always)]
    pub fn primal(&self) -> glam::Vec3 {
        glam::Vec3::new(self.x.primal(), self.y.primal(), self.z.primal())
    }
    /// The same vector with derivatives dropped.
    #[inline(always)]
    pub fn detach(&self) -> Self {
        Self::constant(self.primal())
    }
    /// Inner product.
    #[inline(always)]
    pub fn dot(self, o: Self) -> S {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    /// Inner product with a constant vector.
    #[inline(always)]
    pub fn dot_f32(self, o: glam::Vec3) -> S {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    /// Cross product (right-handed).
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        Self::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }
    /// Squared length.
    #[inline(always)]
    pub fn length_squared(self) -> S {
        self.dot(self)
    }
    /// Length; its derivative is zero (not NaN) for the zero vector.
    #[inline(always)]
    pub fn length(self) -> S {
        self.length_squared().safe_sqrt()
    }
    /// Unit vector in the same direction, or the zero vector (with zero derivative) if the length is 0.
    #[inline]
    pub fn normalize_or_zero(self) -> Self {
        let l2 = self.length_squared();
        if l2.primal() > 0.0 {
            self * l2.sqrt().recip()
        } else {
            Self::zero()
        }
    }
    /// Scale by a constant.
    #[inline(always)]
    pub fn scale(self, s: f32) -> Self {
        Self::new(self.x * s, self.y * s, self.z * s)
    }
    /// Apply `f` to each component.
    #[inline(always)]
    pub fn map(self, f: impl Fn(S) -> S) -> Self {
        Self::new(f(self.x), f(self.y), f(self.z))
    }
    /// Component-wise absolute value.
    #[inline(always)]
    pub fn abs(self) -> Self {
        self.map(|v| v.abs())
    }
    /// Component-wise maximum with a constant.
    #[inline(always)]
    pub fn max_f32(self, v: f32) -> Self {
        self.map(|c| c.max(S::constant(v)))
    }
    /// Largest component by primal value.
    #[inline(always)]
    pub fn max_element(self) -> S {
        self.x.max(self.y).max(self.z)
    }
    /// Component `i` (0, 1 or 2).
    #[inline(always)]
    pub fn get(&self, i: usize) -> S {
        match i {
            0 => self.x,
            1 => self.y,
            _ => self.z,
        }
    }
    /// Mean of the three components (luminance-free average of a colour).
    #[inline(always)]
    pub fn mean(self) -> S {
        (self.x + self.y + self.z) * (1.0 / 3.0)
    }
}

impl From<glam::Vec3> for Vec3<f32> {
    #[inline(always)]
    fn from(v: glam::Vec3) -> Self {
        Self::new(v.x, v.y, v.z)
    }
}

impl From<Vec3<f32>> for glam::Vec3 {
    #[inline(always)]
    fn from(v: Vec3<f32>) -> Self {
        glam::Vec3::new(v.x, v.y, v.z)
    }
}

impl<S: Scalar> Add for Vec3<S> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}
impl<S: Scalar> Add<glam::Vec3> for Vec3<S> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: glam::Vec3) -> Self {
        Self::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}
impl<S: Scalar> AddAssign for Vec3<S> {
    #[inline(always)]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}
impl<S: Scalar> Sub for Vec3<S> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}
impl<S: Scalar> Sub<glam::Vec3> for Vec3<S> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: glam::Vec3) -> Self {
        Self::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}
impl<S: Scalar> SubAssign for Vec3<S> {
    #[inline(always)]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}
impl<S: Scalar> Neg for Vec3<S> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self::new(-self.x, -self.y, -self.z)
    }
}
impl<S: Scalar> Mul<S> for Vec3<S> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: S) -> Self {
        Self::new(self.x * s, self.y * s, self.z * s)
    }
}
impl<S: Scalar> Mul for Vec3<S> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        Self::new(self.x * o.x, self.y * o.y, self.z * o.z)
    }
}
impl<S: Scalar> Div<S> for Vec3<S> {
    type Output = Self;
    #[inline(always)]
    fn div(self, s: S) -> Self {
        let r = s.recip();
        Self::new(self.x * r, self.y * r, self.z * r)
    }
}
