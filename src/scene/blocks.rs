//! Parameter blocks: arrays of values listed, selected and replaced as a whole rather than value by
//! value. Two kinds: the samples of every grid node, named `<node>.values` (`<node>` the node's prefix
//! of [`Scene::parameters`], e.g. `blob.values`, shape `[nz, ny, nx]`), and the texels of every volume
//! texture, named `<name>.values` (`paint.values`, shape `[nz, ny, nx, 3]` for a colour, `[nz, ny, nx]`
//! for a number), and the texels of an environment map, named `<name>.values` (`<name>` the emitter's,
//! shape `[H, W, 3]`, row 0 the zenith). A block is selected for differentiation as a whole (a forward-mode direction or a
//! reverse-mode gradient block, [`BlockValues`]) and can be replaced in memory between renders.
//!
//! A new kind of block is one more [`BlockKind`], one more arm in [`Scene::blocks`] and the selection
//! walk ([`visit_scene_selections_mut`]), and its values in [`Scene::block_values`] /
//! [`Scene::set_block_values`].

use super::params::root_prefix;
use super::{Scene, Shape};
use crate::declare;
use crate::emitter::{Emitter, EnvMap};
use crate::error::{Error, Result};
use crate::scalar::BlockValues;
use crate::sdf::{GridData, Sdf};
use std::sync::Arc;

/// What a parameter block holds.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum BlockKind {
    /// A grid node's samples.
    Grid,
    /// A volume texture's texels ([`crate::bsdf::Volume`]).
    Volume,
    /// An environment map's texels ([`crate::emitter::EnvMap`]).
    Envmap,
}

impl BlockKind {
    /// What the block is, in words (`grid`, `volume texture`, `environment map`).
    pub fn describe(self) -> &'static str {
        match self {
            BlockKind::Grid => "grid",
            BlockKind::Volume => "volume texture",
            BlockKind::Envmap => "environment map",
        }
    }
}

/// One parameter block: a grid's samples, a volume texture's or an environment map's texels.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamBlock {
    /// What the block holds.
    pub kind: BlockKind,
    /// The shape the block belongs to (for an environment map, its emitter).
    pub shape_name: String,
    /// The block's node: a grid node's prefix (`blob`), a texture's name (`paint`) or an environment
    /// map emitter's (`sky`), what `--grid` and `--grid-direction` take.
    pub node: String,
    /// The block's name, `<node>.values`.
    pub name: String,
    /// The `.npy` shape of the values: `[nz, ny, nx]` for a grid or a scalar texture, `[nz, ny, nx,
    /// 3]` for a colour texture, `[H, W, 3]` for an environment map.
    pub shape: Vec<usize>,
}

/// The former name of [`ParamBlock`].
pub type GridBlock = ParamBlock;

impl ParamBlock {
    /// Number of values.
    pub fn len(&self) -> usize {
        self.shape.iter().product()
    }
    /// Whether the block has no values (never, for a valid grid or texture).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// The shape as `[a, b, c]` text.
    pub fn shape_text(&self) -> String {
        let dims: Vec<String> = self.shape.iter().map(|n| n.to_string()).collect();
        format!("[{}]", dims.join(", "))
    }
}

/// One entry of the parameter listing ([`Scene::parameter_entries`]).
#[derive(Clone, Debug, PartialEq)]
pub enum ParameterEntry {
    /// A parameter and its current value (as [`Scene::parameters`] lists it).
    Value(String, f32),
    /// A parameter block (a grid node's values or a volume texture's).
    Grid(ParamBlock),
}

/// A forward-mode direction for a block's values ([`Scene::select_with_grid_directions`]): a
/// perturbation of each value.
#[derive(Clone, Debug, PartialEq)]
pub struct GridDirection {
    /// The block's node, as `NODE` or its block name `NODE.values`.
    pub node: String,
    /// The shape of `values` (checked against the block's).
    pub shape: Vec<usize>,
    /// The perturbation of each value, in the block's layout (C order of its shape).
    pub values: Arc<Vec<f32>>,
    /// Where the direction comes from (a file, an argument), named in a shape error.
    pub source: String,
}

/// Generates the walk over the grid nodes of an sdf tree, shared or mutable: `f(prefix, data, selection)`
/// with the node prefixes of [`Scene::parameters`] (the tree walk of the node declarations).
macro_rules! grid_walk {
    ($walk:ident, $tree:ident $(, $m:tt)?) => {
        fn $walk(
            sdf: &$($m)? Sdf,
            prefix: &str,
            f: &mut dyn FnMut(&str, &$($m)? Arc<GridData>, &$($m)? BlockValues, [glam::Vec3; 2]),
        ) {
            declare::$tree(sdf, prefix, &mut |prefix, node| {
                if let Sdf::Grid {
                    data, selection, bbox_min, bbox_max, ..
                } = node
                {
                    f(prefix, data, selection, [*bbox_min, *bbox_max]);
                }
            });
        }
    };
}
grid_walk!(walk, walk);
grid_walk!(walk_mut, walk_mut, mut);

/// Calls `f(node, selection)` for every block of `shape` (its grids, then its textures), to renumber
/// or clear the selections.
fn visit_selections_mut(shape: &mut Shape, f: &mut dyn FnMut(&str, &mut BlockValues)) {
    let prefix = root_prefix(&shape.name, &shape.sdf);
    walk_mut(&mut shape.sdf, &prefix, &mut |n, _, s, _| f(n, s));
    for t in &mut shape.textures {
        f(&t.volume.name, &mut t.volume.selection);
    }
}

/// Calls `f(node, selection)` for every block of `scene`: its shapes' ([`visit_selections_mut`]),
/// then its environment maps'. A map is copied only when its selection changes.
pub(crate) fn visit_scene_selections_mut(
    scene: &mut Scene,
    f: &mut dyn FnMut(&str, &mut BlockValues),
) {
    for shape in &mut scene.shapes {
        visit_selections_mut(shape, f);
    }
    for e in &mut scene.emitters {
        if let Emitter::Envmap { map, .. } = &mut e.emitter {
            let mut selection = map.selection().clone();
            f(&e.name, &mut selection);
            if selection != *map.selection() {
                Arc::make_mut(map).set_selection(selection);
            }
        }
    }
}

impl Sdf {
    /// Whether some grid in the tree has its values selected for differentiation.
    pub fn grid_values_selected(&self) -> bool {
        let mut any = false;
        walk(self, "", &mut |_, _, s, _| {
            any |= *s != BlockValues::Constant
        });
        any
    }

    /// Calls `f` with every grid node's selection (to renumber or clear it).
    pub fn visit_grid_selections_mut(&mut self, f: &mut dyn FnMut(&mut BlockValues)) {
        walk_mut(self, "", &mut |_, _, s, _| f(s));
    }
}

impl Scene {
    /// Every parameter block, shape by shape (its grids in the order of [`Scene::parameters`],
    /// then its material's textures), then the environment maps'.
    pub fn blocks(&self) -> Vec<ParamBlock> {
        let mut out = Vec::new();
        for shape in &self.shapes {
            walk(
                &shape.sdf,
                &root_prefix(&shape.name, &shape.sdf),
                &mut |node, data, _, _| {
                    let [nx, ny, nz] = data.dims;
                    out.push(ParamBlock {
                        kind: BlockKind::Grid,
                        shape_name: shape.name.clone(),
                        node: node.to_string(),
                        name: format!("{node}.values"),
                        shape: vec![nz, ny, nx],
                    });
                },
            );
            for t in &shape.textures {
                let node = &t.volume.name;
                out.push(ParamBlock {
                    kind: BlockKind::Volume,
                    shape_name: shape.name.clone(),
                    node: node.clone(),
                    name: format!("{node}.values"),
                    shape: t.volume.shape(),
                });
            }
        }
        for e in &self.emitters {
            if let Emitter::Envmap { map, .. } = &e.emitter {
                out.push(ParamBlock {
                    kind: BlockKind::Envmap,
                    shape_name: e.name.clone(),
                    node: e.name.clone(),
                    name: format!("{}.values", e.name),
                    shape: map.shape(),
                });
            }
        }
        out
    }

    /// The environment map emitter named `node`, if any.
    fn envmap(&self, node: &str) -> Option<&EnvMap> {
        self.emitters.iter().find_map(|e| match &e.emitter {
            Emitter::Envmap { map, .. } if e.name == node => Some(&**map),
            _ => None,
        })
    }

    /// The kind of the block whose node is `node` (a grid node, a texture or an environment map
    /// emitter), if there is one.
    pub fn block_kind(&self, node: &str) -> Option<BlockKind> {
        (self.blocks().into_iter())
            .find(|b| b.node == node)
            .map(|b| b.kind)
    }

    /// Every grid node's values as a block, in the order of [`Scene::parameters`] (the blocks of
    /// kind [`BlockKind::Grid`]).
    pub fn grid_blocks(&self) -> Vec<ParamBlock> {
        (self.blocks().into_iter())
            .filter(|b| b.kind == BlockKind::Grid)
            .collect()
    }

    /// Every parameter (as [`Scene::parameters`] lists it) and every block: a grid's right after
    /// its node's `level`, a texture's (an environment map's) after its shape's (emitter's) last
    /// parameter (or at the end): the listing of the `params` command.
    pub fn parameter_entries(&self) -> Vec<ParameterEntry> {
        let params = self.parameters();
        let blocks = self.blocks();
        let place = |b: &ParamBlock| {
            let after = match b.kind {
                BlockKind::Grid => {
                    let level = format!("{}.level", b.node);
                    params.iter().position(|(n, _)| *n == level)
                }
                BlockKind::Volume | BlockKind::Envmap => {
                    let prefix = format!("{}.", b.shape_name);
                    params.iter().rposition(|(n, _)| n.starts_with(&prefix))
                }
            };
            after.map_or(params.len(), |i| i + 1)
        };
        let mut out = Vec::new();
        for i in 0..=params.len() {
            for b in blocks.iter().filter(|b| place(b) == i) {
                out.push(ParameterEntry::Grid(b.clone()));
            }
            if let Some((name, value)) = params.get(i) {
                out.push(ParameterEntry::Value(name.clone(), *value));
            }
        }
        out
    }

    /// The block node that `text` names: `NODE`, or its block name `NODE.values`. Any other text is
    /// returned as it is, for the selection to report as unknown.
    pub fn grid_node(&self, text: &str) -> String {
        let blocks = self.blocks();
        (blocks.iter().find(|b| b.name == text))
            .map_or_else(|| text.to_string(), |b| b.node.clone())
    }

    /// Grid node `node`'s values and box.
    fn grid(&self, node: &str) -> Result<(Arc<GridData>, [glam::Vec3; 2])> {
        let mut found = None;
        for shape in &self.shapes {
            walk(
                &shape.sdf,
                &root_prefix(&shape.name, &shape.sdf),
                &mut |n, data, _, bbox| {
                    if n == node {
                        found = Some((data.clone(), bbox));
                    }
                },
            );
        }
        found.ok_or_else(|| self.unknown_grid(node))
    }

    /// The values of grid node `node`. Errors: no grid node of that name (the message lists them).
    pub fn grid_values(&self, node: &str) -> Result<Arc<GridData>> {
        Ok(self.grid(node)?.0)
    }

    /// The values of block `node` (a grid node, a texture or an environment map) in its layout (C
    /// order of its shape). Errors: no block of that name (the message lists them).
    pub fn block_values(&self, node: &str) -> Result<Arc<Vec<f32>>> {
        if let Some(map) = self.envmap(node) {
            return Ok(Arc::new(map.values()));
        }
        for shape in &self.shapes {
            if let Some(t) = shape.textures.iter().find(|t| t.volume.name == node) {
                return Ok(t.volume.values.clone());
            }
        }
        Ok(Arc::new(self.grid_values(node)?.values.clone()))
    }

    /// Replaces the values of block `node` (same layout and count, all finite; a texture's in its
    /// field's range, an environment map's `>= 0`) and recomputes what depends on them (an
    /// environment map's sampling tables).
    pub fn set_block_values(&mut self, node: &str, values: Vec<f32>) -> Result<()> {
        if let Some(old) = self.envmap(node) {
            let map = (old.with_values(&values))
                .map_err(|m| Error::field(format!("{node}.values"), m))?;
            for e in &mut self.emitters {
                if let Emitter::Envmap { map: slot, .. } = &mut e.emitter
                    && e.name == node
                {
                    *slot = Arc::new(map.clone());
                }
            }
            return Ok(());
        }
        let mut texture = None;
        for (i, shape) in self.shapes.iter().enumerate() {
            if let Some(k) = shape.textures.iter().position(|t| t.volume.name == node) {
                texture = Some((i, k));
            }
        }
        let Some((i, k)) = texture else {
            return self.set_grid_values(node, values);
        };
        let t = &self.shapes[i].textures[k];
        let field = t.field.clone();
        let what = format!("{node}.values");
        if values.len() != t.volume.len() {
            return Err(Error::field(
                what,
                format!("needs {} values, got {}", t.volume.len(), values.len()),
            ));
        }
        let range = texture_range(&self.shapes[i].bsdf, t.node, t.key);
        if let Some(j) = values.iter().position(|v| !(range.0..=range.1).contains(v)) {
            return Err(Error::field(
                what,
                format!(
                    "value {} at index {j} is outside [{}, {}] (the range of {field})",
                    values[j], range.0, range.1
                ),
            ));
        }
        self.shapes[i].textures[k].volume.values = Arc::new(values);
        Ok(())
    }

    /// The range of the values of volume texture `node` (its field's) or of environment map `node`
    /// (`[0, f32::MAX]`), `None` for any other name (a grid's).
    pub fn texture_range(&self, node: &str) -> Option<(f32, f32)> {
        if self.envmap(node).is_some() {
            return Some((0.0, f32::MAX));
        }
        self.shapes.iter().find_map(|shape| {
            (shape.textures.iter())
                .find(|t| t.volume.name == node)
                .map(|t| texture_range(&shape.bsdf, t.node, t.key))
        })
    }

    /// The length of grid node `node`'s box diagonal, in the node's own units (a bound for its values
    /// when they are distances).
    pub fn grid_diagonal(&self, node: &str) -> Result<f32> {
        let [lo, hi] = self.grid(node)?.1;
        Ok((hi - lo).length())
    }

    /// The scene seen through `camera`. The shapes' derived data (bounds, Lipschitz bounds, empty
    /// space) does not depend on the camera and is shared, not rebuilt; only the tracer's tolerance,
    /// which follows the camera when no shape is finite, is recomputed.
    pub fn with_camera(&self, camera: crate::camera::Camera) -> Scene {
        let mut scene = self.clone();
        scene.trace.eps = super::base_eps(&scene.shapes, &camera);
        scene.camera = camera;
        scene
    }

    /// Replaces grid node `node`'s samples by `data` (any dimensions; same box) and recomputes what
    /// depends on them. A [`super::Selection`] of the node's gradient block made before a change of
    /// dimensions no longer fits: select again.
    pub fn set_grid(&mut self, node: &str, data: GridData) -> Result<()> {
        self.grid_values(node)?;
        data.validate(&format!("{node}.values"))?;
        let data = Arc::new(data);
        for shape in &mut self.shapes {
            let prefix = root_prefix(&shape.name, &shape.sdf);
            walk_mut(&mut shape.sdf, &prefix, &mut |n, d, _, _| {
                if n == node {
                    *d = data.clone();
                }
            });
        }
        *self = self.refreshed();
        Ok(())
    }

    /// Grid node `node`'s box `[bbox_min, bbox_max]`.
    pub fn grid_box(&self, node: &str) -> Result<[glam::Vec3; 2]> {
        Ok(self.grid(node)?.1)
    }

    /// Replaces the values of grid node `node` (same layout: `values[(z · ny + y) · nx + x]`, as many
    /// as before, all finite) and recomputes what depends on them (bounds, Lipschitz bounds, tracer
    /// tolerance): the next render sees the new surface.
    pub fn set_grid_values(&mut self, node: &str, values: Vec<f32>) -> Result<()> {
        let old = self.grid_values(node)?;
        let data = GridData::new(old.dims, values, &format!("{node}.values"))?;
        let data = Arc::new(data);
        for shape in &mut self.shapes {
            let prefix = root_prefix(&shape.name, &shape.sdf);
            walk_mut(&mut shape.sdf, &prefix, &mut |n, d, _, _| {
                if n == node {
                    *d = data.clone();
                }
            });
        }
        *self = self.refreshed();
        Ok(())
    }

    /// Sets the selection of the blocks named in `selection` (`(node, how)`), every other block's
    /// to constant. Errors: an unknown node, a node given twice, a direction whose length is not the
    /// block's; on error the scene is unchanged.
    pub(crate) fn select_grids(&mut self, selection: &[(String, BlockValues)]) -> Result<()> {
        let blocks = self.blocks();
        for (k, (node, how)) in selection.iter().enumerate() {
            let Some(block) = blocks.iter().find(|b| &b.node == node) else {
                return Err(self.unknown_grid(node));
            };
            if selection[..k].iter().any(|(n, _)| n == node) {
                return Err(Error::field(
                    "grids",
                    format!("grid {node:?} is given twice"),
                ));
            }
            if let BlockValues::Direction { u, .. } = how
                && u.len() != block.len()
            {
                return Err(Error::field(
                    "grid_directions",
                    format!(
                        "the direction of {node:?} has {} values, the block {} (shape {})",
                        u.len(),
                        block.len(),
                        block.shape_text()
                    ),
                ));
            }
        }
        visit_scene_selections_mut(self, &mut |n, s| {
            *s = selection
                .iter()
                .find(|(node, _)| node == n)
                .map_or(BlockValues::Constant, |(_, how)| how.clone());
        });
        Ok(())
    }

    /// The error for an unknown block node: the scene's blocks.
    pub(super) fn unknown_grid(&self, node: &str) -> Error {
        let blocks = self.blocks();
        let textures = blocks.iter().any(|b| b.kind != BlockKind::Grid);
        let envmaps = blocks.iter().any(|b| b.kind == BlockKind::Envmap);
        let nodes: Vec<String> = blocks.into_iter().map(|b| b.node).collect();
        let known = match (nodes.is_empty(), textures, envmaps) {
            (true, _, _) => "the scene has no grid".to_string(),
            (false, false, _) => format!("grid nodes: {}", nodes.join(", ")),
            (false, true, false) => {
                format!("grid nodes and volume textures: {}", nodes.join(", "))
            }
            (false, true, true) => format!(
                "blocks of grid nodes, volume textures and environment maps: {}",
                nodes.join(", ")
            ),
        };
        Error::field("grids", format!("no grid node {node:?} ({known})"))
    }

    /// The scene with its derived data (shape bounds and Lipschitz bounds, tracer tolerance)
    /// recomputed from its shapes; tracer settings other than the tolerance kept.
    pub(super) fn refreshed(&self) -> Scene {
        let shapes = self
            .shapes
            .iter()
            .cloned()
            .map(|s| {
                Shape::translated(s.name, s.sdf, s.bsdf, s.translate).with_textures(s.textures)
            })
            .collect();
        let mut scene = Scene::new(
            self.camera.clone(),
            self.integrator,
            self.spp,
            shapes,
            self.emitters.clone(),
        );
        scene.trace = crate::trace::TraceSettings {
            eps: scene.trace.eps,
            ..self.trace
        };
        scene
    }
}

/// The range of the values of field `key` of material node `node` of `bsdf` ([`crate::bsdf::texture`]).
fn texture_range(bsdf: &crate::bsdf::Bsdf, node: usize, key: &str) -> (f32, f32) {
    let mut ty = "";
    let mut k = 0;
    declare::walk(bsdf, "", &mut |_, n| {
        if k == node {
            ty = declare::Family::kind(n).type_name;
        }
        k += 1;
    });
    crate::bsdf::texture::textured_field(ty, key).map_or((f32::MIN, f32::MAX), |(_, _, r)| r)
}
