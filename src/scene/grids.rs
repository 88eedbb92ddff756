//! Grid values as parameter blocks: the samples of every grid node are one block named
//! `<node>.values` (`<node>` the node's prefix of [`Scene::parameters`], e.g. `blob.values`), listed once
//! with its shape rather than value by value, selected as a whole for differentiation (a forward-mode
//! direction or a reverse-mode gradient block) and replaceable in memory between renders.

use super::params::root_prefix;
use super::{Scene, Shape};
use crate::declare;
use crate::error::{Error, Result};
use crate::scalar::BlockValues;
use crate::sdf::{GridData, Sdf};
use std::sync::Arc;

/// One grid node's values as a parameter block.
#[derive(Clone, Debug, PartialEq)]
pub struct GridBlock {
    /// The shape the node belongs to.
    pub shape_name: String,
    /// The node's prefix (`blob`): what `--grid` and `--grid-direction` take.
    pub node: String,
    /// The block's name, `<node>.values`.
    pub name: String,
    /// The `.npy` shape of the values, `[nz, ny, nx]`.
    pub shape: [usize; 3],
}

impl GridBlock {
    /// Number of values.
    pub fn len(&self) -> usize {
        self.shape.iter().product()
    }
    /// Whether the block has no values (never, for a valid grid).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// One entry of the parameter listing ([`Scene::parameter_entries`]).
#[derive(Clone, Debug, PartialEq)]
pub enum ParameterEntry {
    /// A parameter and its current value (as [`Scene::parameters`] lists it).
    Value(String, f32),
    /// A grid node's values, as one block.
    Grid(GridBlock),
}

/// A forward-mode direction for a grid node's values ([`Scene::select_with_grid_directions`]): a
/// perturbation of each value.
#[derive(Clone, Debug, PartialEq)]
pub struct GridDirection {
    /// The grid node, as `NODE` or its block name `NODE.values`.
    pub node: String,
    /// The shape of `values`, `[nz, ny, nx]` (checked against the grid's).
    pub shape: [usize; 3],
    /// The perturbation of each value, in the grid's layout (`(z · ny + y) · nx + x`).
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
    /// Every grid node's values as a block, in the order of [`Scene::parameters`].
    pub fn grid_blocks(&self) -> Vec<GridBlock> {
        let mut out = Vec::new();
        for shape in &self.shapes {
            walk(
                &shape.sdf,
                &root_prefix(&shape.name, &shape.sdf),
                &mut |node, data, _, _| {
                    let [nx, ny, nz] = data.dims;
                    out.push(GridBlock {
                        shape_name: shape.name.clone(),
                        node: node.to_string(),
                        name: format!("{node}.values"),
                        shape: [nz, ny, nx],
                    });
                },
            );
        }
        out
    }

    /// Every parameter (as [`Scene::parameters`] lists them) and every grid block, each grid's block
    /// right after its node's `level` (or at the end): the listing of the `params` command.
    pub fn parameter_entries(&self) -> Vec<ParameterEntry> {
        let params = self.parameters();
        let blocks = self.grid_blocks();
        let place = |b: &GridBlock| {
            let level = format!("{}.level", b.node);
            (params.iter().position(|(n, _)| *n == level)).map_or(params.len(), |i| i + 1)
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

    /// The grid node that `text` names: `NODE`, or its block name `NODE.values`. Any other text is
    /// returned as it is, for the selection to report as unknown.
    pub fn grid_node(&self, text: &str) -> String {
        let blocks = self.grid_blocks();
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

    /// The length of grid node `node`'s box diagonal, in the node's own units (a bound for its values
    /// when they are distances).
    pub fn grid_diagonal(&self, node: &str) -> Result<f32> {
        let [lo, hi] = self.grid(node)?.1;
        Ok((hi - lo).length())
    }

    /// The scene seen through `camera` (derived data recomputed).
    pub fn with_camera(&self, camera: crate::camera::Camera) -> Scene {
        let mut scene = self.clone();
        scene.camera = camera;
        scene.refreshed()
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

    /// Sets the selection of the grid nodes named in `selection` (`(node, how)`), every other grid's
    /// to constant. Errors: an unknown node, a node given twice, a direction whose length is not the
    /// grid's; on error the scene is unchanged.
    pub(crate) fn select_grids(&mut self, selection: &[(String, BlockValues)]) -> Result<()> {
        let blocks = self.grid_blocks();
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
                        "the direction of grid {node:?} has {} values, the grid {} (shape {:?})",
                        u.len(),
                        block.len(),
                        block.shape
                    ),
                ));
            }
        }
        for shape in &mut self.shapes {
            let prefix = root_prefix(&shape.name, &shape.sdf);
            walk_mut(&mut shape.sdf, &prefix, &mut |n, _, s, _| {
                *s = selection
                    .iter()
                    .find(|(node, _)| node == n)
                    .map_or(BlockValues::Constant, |(_, how)| how.clone());
            });
        }
        Ok(())
    }

    /// The error for an unknown grid node: the scene's grid nodes.
    pub(super) fn unknown_grid(&self, node: &str) -> Error {
        let nodes: Vec<String> = self.grid_blocks().into_iter().map(|b| b.node).collect();
        let known = if nodes.is_empty() {
            "the scene has no grid".to_string()
        } else {
            format!("grid nodes: {}", nodes.join(", "))
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
            .map(|s| Shape::translated(s.name, s.sdf, s.bsdf, s.translate).with_textures(s.textures))
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
