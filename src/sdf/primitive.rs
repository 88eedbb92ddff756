//! Primitives kept in files of their own: the interface each implements ([`SdfPrimitive`]) and the
//! registration macro that makes them sdf nodes ([`super::Primitive`], [`Sdf::Primitive`]).
//!
//! A new primitive is one file (its struct, an `impl SdfPrimitive`, its scene-file declaration
//! `KIND` and a constructor on [`Sdf`]) plus one line in the `primitives!` list of the sdf module:
//! parsing, parameter names, write-back, validation, evaluation in every scalar type, bounds and
//! tracing then work for it. What it does not provide falls back to the general method: sphere tracing
//! instead of closed-form crossings, the normal velocity field instead of a known motion, no crease
//! edges.

use crate::math::{Aabb, Vec3};
use crate::scalar::Scalar;

#[cfg(doc)]
use super::Sdf;

/// What a primitive provides. Evaluation is generic over the scalar type, as for every node.
pub trait SdfPrimitive: Clone + std::fmt::Debug + PartialEq + Send + Sync + 'static {
    /// `φ(p)`, negative inside; a distance (Lipschitz bound 1) or a bound of one.
    fn eval<S: Scalar>(&self, p: Vec3<S>) -> S;

    /// A box holding the surface and the interior.
    fn bounds(&self) -> Aabb;

    /// Whether the solid is convex whatever its parameters' values ([`Sdf::is_convex`]).
    fn is_convex(&self) -> bool {
        false
    }

    /// The position to which the primitive's motion carries a point `q` of its surface, with the
    /// parameters lifted into `S` ([`Sdf::carried`]); `None` where no motion is known.
    fn carried<S: Scalar>(&self, _q: Vec3<S>) -> Option<Vec3<S>> {
        None
    }

    /// An upper bound of the magnitude of the total curvature (1/length; infinite where none is
    /// known, [`Sdf::curvature_bound`]).
    fn curvature_bound(&self) -> f32 {
        f32::INFINITY
    }
}

/// Declares the primitives kept in files of their own, one `module => Type` line each: the module,
/// the [`super::Primitive`] enum over their types with its dispatch, and the list of their kinds.
macro_rules! primitives {
    ($($module:ident => $ty:ident),* $(,)?) => {
        $(mod $module;)*
        $(pub use $module::$ty;)*

        /// A primitive kept in a file of its own, implementing [`SdfPrimitive`]; each is registered
        /// with one line in the sdf module's `primitives!` list.
        #[derive(Clone, Debug, PartialEq)]
        pub enum Primitive {
            $(
                #[doc = concat!("A [`", stringify!($ty), "`].")]
                $ty($ty),
            )*
        }

        impl Primitive {
            /// `φ(p)` ([`SdfPrimitive::eval`]).
            #[inline(always)]
            pub fn eval<S: Scalar>(&self, p: Vec3<S>) -> S {
                match self { $(Self::$ty(x) => x.eval(p),)* }
            }
            /// [`SdfPrimitive::bounds`].
            pub fn bounds(&self) -> Aabb {
                match self { $(Self::$ty(x) => x.bounds(),)* }
            }
            /// [`SdfPrimitive::is_convex`].
            pub fn is_convex(&self) -> bool {
                match self { $(Self::$ty(x) => x.is_convex(),)* }
            }
            /// [`SdfPrimitive::carried`].
            pub fn carried<S: Scalar>(&self, q: Vec3<S>) -> Option<Vec3<S>> {
                match self { $(Self::$ty(x) => x.carried(q),)* }
            }
            /// [`SdfPrimitive::curvature_bound`].
            pub fn curvature_bound(&self) -> f32 {
                match self { $(Self::$ty(x) => x.curvature_bound(),)* }
            }
            /// The primitive's scene-file declaration.
            pub(super) fn kind(&self) -> &'static Kind<Sdf> {
                match self { $(Self::$ty(_) => &$module::KIND,)* }
            }
        }

        /// The declarations of the primitives kept in files of their own, in registration order.
        const PRIMITIVE_KINDS: &[&Kind<Sdf>] = &[$(&$module::KIND),*];
    };
}
pub(super) use primitives;
