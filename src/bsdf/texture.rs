//! Volume textures: a material field (`albedo`, `specular_reflectance`, `alpha`, `weight`) given by
//! samples on a regular lattice over a box in the shape's frame, interpolated trilinearly.
//!
//! **Lattice.** As for grids ([`crate::sdf::Sdf::Grid`]): the samples of a `.npy` array of shape
//! `[nz, ny, nx]` (a scalar field) or `[nz, ny, nx, 3]` (a colour) sit on the lattice whose first and
//! last samples along each axis lie on the box's faces, `x_i = bbox_min + i (bbox_max − bbox_min) /
//! (n − 1)`. Outside the box the position is clamped to it (the value of the nearest face point).
//!
//! **Frame.** The lookup point is the hit point in the shape's frame ([`crate::scene::Shape::material_point`]):
//! the world point minus the shape's `translate`, then mapped through the inverse of every transform
//! node at the top of the shape's sdf tree (the chain of transforms, and names, above the first other
//! node), so a texture moves, turns and scales with the shape.
//!
//! **Exactness.** The interpolation is written as nested `a + t (b − a)`, so a texture whose texels are
//! all equal returns that value bit for bit, and a material with a constant texture renders exactly as
//! the same material with the constant field.
//!
//! **Derivatives.** The texels are a parameter block `<name>.values` ([`crate::scene::ParamBlock`]): a
//! forward-mode direction adds `ε Σ w_k u_k` to each channel, a reverse-mode block records the eight
//! weights of each channel as one tape node ([`Scalar::block_terms`]). The position enters through
//! the trilinear fractions, so a surface that moves through the texture (a parameter of its sdf)
//! sees its colour change too.

use crate::math::Vec3;
use crate::scalar::{BlockValues, Param, Param3, Scalar};
use std::sync::Arc;

/// A volume texture (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    /// The texture's name, unique in the scene: its block of values is `<name>.values`.
    pub name: String,
    /// Lattice size `[nx, ny, nz]` (each at least 1).
    pub dims: [usize; 3],
    /// Values per texel: 1 (a scalar field) or 3 (a colour).
    pub channels: usize,
    /// The texels, `values[((z · ny + y) · nx + x) · channels + c]` (the `.npy` layout).
    pub values: Arc<Vec<f32>>,
    /// Lower corner of the box (first sample), in the shape's frame.
    pub bbox_min: glam::Vec3,
    /// Upper corner of the box (last sample).
    pub bbox_max: glam::Vec3,
    /// How the texels are differentiated in the current pass (constants unless selected).
    pub selection: BlockValues,
}

/// The eight corners of a trilinear lookup: texel indices (without the channel) and their primal
/// weights, and the fractions along each axis in `S`.
struct Taps<S> {
    index: [usize; 8],
    weight: [f32; 8],
    t: [S; 3],
}

impl Volume {
    /// The `.npy` shape of the values: `[nz, ny, nx]` or `[nz, ny, nx, 3]`.
    pub fn shape(&self) -> Vec<usize> {
        let [nx, ny, nz] = self.dims;
        let mut s = vec![nz, ny, nx];
        if self.channels == 3 {
            s.push(3);
        }
        s
    }

    /// Number of values (texels times channels).
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Whether the texture has no values (never, for a loaded one).
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// The taps at `p` (shape frame), clamped to the box.
    #[inline]
    fn taps<S: Scalar>(&self, p: Vec3<S>) -> Taps<S> {
        let ext = self.bbox_max - self.bbox_min;
        let axis = |a: usize, c: S| -> (usize, usize, S) {
            let n = self.dims[a];
            if n < 2 || ext[a] <= 0.0 {
                return (0, 0, S::zero());
            }
            let u = ((c - self.bbox_min[a]) * ((n - 1) as f32 / ext[a])).clamp(0.0, (n - 1) as f32);
            // `as usize` truncates: the floor for u ≥ 0 (NaN to 0).
            let i = (u.primal() as usize).min(n - 2);
            (i, i + 1, u - i as f32)
        };
        let (x0, x1, tx) = axis(0, p.x);
        let (y0, y1, ty) = axis(1, p.y);
        let (z0, z1, tz) = axis(2, p.z);
        let [nx, ny, _] = self.dims;
        let at = |x: usize, y: usize, z: usize| (z * ny + y) * nx + x;
        let (fx, fy, fz) = (tx.primal(), ty.primal(), tz.primal());
        let (gx, gy, gz) = (1.0 - fx, 1.0 - fy, 1.0 - fz);
        Taps {
            index: [
                at(x0, y0, z0),
                at(x1, y0, z0),
                at(x0, y1, z0),
                at(x1, y1, z0),
                at(x0, y0, z1),
                at(x1, y0, z1),
                at(x0, y1, z1),
                at(x1, y1, z1),
            ],
            weight: [
                gx * gy * gz,
                fx * gy * gz,
                gx * fy * gz,
                fx * fy * gz,
                gx * gy * fz,
                fx * gy * fz,
                gx * fy * fz,
                fx * fy * fz,
            ],
            t: [tx, ty, tz],
        }
    }

    /// Channel `c` at the taps: the nested linear interpolation (exact for equal texels) plus the
    /// derivative of the selected block.
    #[inline]
    fn channel<S: Scalar>(&self, taps: &Taps<S>, c: usize) -> S {
        let k = self.channels;
        let v = taps.index.map(|i| self.values[i * k + c]);
        let [tx, ty, tz] = taps.t;
        let lerp_x = |a: f32, b: f32| tx * (b - a) + a;
        let lerp = |a: S, b: S, t: S| a + t * (b - a);
        let y0 = lerp(lerp_x(v[0], v[1]), lerp_x(v[2], v[3]), ty);
        let y1 = lerp(lerp_x(v[4], v[5]), lerp_x(v[6], v[7]), ty);
        let value = lerp(y0, y1, tz);
        match &self.selection {
            BlockValues::Constant => value,
            BlockValues::Direction { slot, u } if u.len() == self.values.len() => {
                let du: f32 = (0..8)
                    .map(|j| taps.weight[j] * u[taps.index[j] * k + c])
                    .sum();
                value + S::lift(0.0, Some(*slot)) * du
            }
            BlockValues::Direction { .. } => value,
            BlockValues::Gradient { first } => {
                let terms =
                    std::array::from_fn::<_, 8, _>(|j| (taps.index[j] * k + c, taps.weight[j]));
                value + S::block_terms(*first, &terms)
            }
        }
    }

    /// The colour at `p` (shape frame); a scalar texture gives its value in every channel.
    #[inline]
    pub fn color<S: Scalar>(&self, p: Vec3<S>) -> Vec3<S> {
        let taps = self.taps(p);
        if self.channels == 3 {
            Vec3::new(
                self.channel(&taps, 0),
                self.channel(&taps, 1),
                self.channel(&taps, 2),
            )
        } else {
            Vec3::splat(self.channel(&taps, 0))
        }
    }

    /// The value at `p` (shape frame) of a scalar texture (the first channel of a colour).
    #[inline]
    pub fn number<S: Scalar>(&self, p: Vec3<S>) -> S {
        self.channel(&self.taps(p), 0)
    }

    /// A texture from the values of a `.npy` array of `shape`, for a field with `channels` values
    /// (1 or 3) whose values lie in `range` (inclusive), checked: the shape, the range (which also
    /// rejects NaN). The error is one line without the file's name (the caller adds it and the field).
    pub fn from_array(
        name: &str,
        shape: &[usize],
        values: Vec<f32>,
        channels: usize,
        range: (f32, f32),
        bbox: [glam::Vec3; 2],
    ) -> Result<Self, String> {
        let dims = match (shape, channels) {
            (&[nz, ny, nx], 1) => [nx, ny, nz],
            (&[nz, ny, nx, 3], 3) => [nx, ny, nz],
            _ => {
                let want = if channels == 3 {
                    "[nz, ny, nx, 3] (a colour field)"
                } else {
                    "[nz, ny, nx] (a scalar field)"
                };
                return Err(format!("has shape {shape:?}, expected {want}"));
            }
        };
        if dims.contains(&0) {
            return Err(format!(
                "has shape {shape:?}: every dimension must be at least 1"
            ));
        }
        let (lo, hi) = range;
        if let Some(i) = values.iter().position(|v| !(lo..=hi).contains(v)) {
            return Err(format!(
                "value {} at index {i} is outside [{lo}, {hi}]",
                values[i]
            ));
        }
        Ok(Self {
            name: name.to_string(),
            dims,
            channels,
            values: Arc::new(values),
            bbox_min: bbox[0],
            bbox_max: bbox[1],
            selection: BlockValues::Constant,
        })
    }
}

/// A material field given by a volume texture instead of its constant.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialTexture {
    /// Depth-first index of the material node in the shape's material tree (0: the root; a blend's
    /// children follow it, the first child's subtree before the second).
    pub node: usize,
    /// The field's key (`albedo`, `specular_reflectance`, `alpha` or `weight`).
    pub key: &'static str,
    /// The field's parameter prefix (`ball.albedo`, `ball.bsdfs.1.alpha`): its constant's parameters
    /// are not parameters while a texture stands in for it.
    pub field: String,
    /// The texture.
    pub volume: Volume,
}

/// The material fields that may be volume textures, per material type: `(type, key, channels, the
/// range of its values)`.
pub const TEXTURED_FIELDS: &[(&str, &str, usize, (f32, f32))] = &[
    ("diffuse", "albedo", 3, (0.0, 1.0)),
    ("roughconductor", "specular_reflectance", 3, (0.0, 1.0)),
    (
        "roughconductor",
        "alpha",
        1,
        (super::roughconductor::MIN_ALPHA, 1.0),
    ),
    ("blend", "weight", 1, (0.0, 1.0)),
];

/// The channels and range of field `key` of material type `ty` if it may be a texture.
pub fn textured_field(ty: &str, key: &str) -> Option<(&'static str, usize, (f32, f32))> {
    (TEXTURED_FIELDS.iter())
        .find(|(t, k, _, _)| *t == ty && *k == key)
        .map(|&(_, k, c, r)| (k, c, r))
}

/// Where a material is evaluated: its shape's textures and the point in the shape's frame.
#[derive(Copy, Clone, Debug)]
pub struct At<'a, S> {
    textures: &'a [MaterialTexture],
    p: Vec3<S>,
}

impl<'a, S: Scalar> At<'a, S> {
    /// No texture: every field is its constant.
    #[inline]
    pub fn none() -> Self {
        Self {
            textures: &[],
            p: Vec3::zero(),
        }
    }

    /// The fields of `textures` read at `p` (the shape's frame).
    #[inline]
    pub fn new(textures: &'a [MaterialTexture], p: Vec3<S>) -> Self {
        Self { textures, p }
    }

    #[inline]
    fn find(&self, node: usize, key: &str) -> Option<&Volume> {
        (self.textures.iter())
            .find(|t| t.node == node && t.key == key)
            .map(|t| &t.volume)
    }

    /// Colour field `key` of material node `node`: its texture at the point, or `constant`.
    #[inline]
    pub fn color(&self, node: usize, key: &str, constant: &Param3) -> Vec3<S> {
        if self.textures.is_empty() {
            return constant.get::<S>();
        }
        match self.find(node, key) {
            Some(v) => v.color(self.p),
            None => constant.get::<S>(),
        }
    }

    /// Number field `key` of material node `node`: its texture at the point, or `constant`.
    #[inline]
    pub fn number(&self, node: usize, key: &str, constant: &Param) -> S {
        if self.textures.is_empty() {
            return constant.get::<S>();
        }
        match self.find(node, key) {
            Some(v) => v.number(self.p),
            None => constant.get::<S>(),
        }
    }
}

impl At<'_, f32> {
    /// [`At::number`] as a plain value (sampling and densities run in `f32`).
    #[inline]
    pub fn value(&self, node: usize, key: &str, constant: &Param) -> f32 {
        self.number(node, key, constant)
    }
}
