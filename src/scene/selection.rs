//! What a derivative pass differentiates, as a value: named parameters and, for grids, a forward-mode
//! direction of the values or their reverse-mode gradient block. A [`Selection`] is made from a scene
//! ([`Scene::select`], [`Scene::select_with_grid_directions`],
//! [`crate::integrator::GradientLayout::select`]), checked against it, and handed to the estimators
//! with the scene to differentiate; the scene itself carries no selection.
//!
//! Inside an estimator the selection is applied to a copy of the scene ([`Selection::apply`]): each
//! selected [`crate::Param`] gets its derivative slot and each selected grid its
//! [`BlockValues`], which the scalar type lifts when the scene is evaluated
//! ([`crate::scalar::Scalar::lift`]).

use super::{GridDirection, ParamBlock, Scene};
use crate::error::{Error, Result};
use crate::scalar::BlockValues;

/// Selected grid nodes and how their values are differentiated.
pub(crate) type GridChoices = Vec<(String, BlockValues)>;

/// The parameters and grid values a derivative pass differentiates (module docs). Forward mode: slot
/// `k` is `names()[k]`, the named parameters first, then one slot per grid direction. Reverse mode
/// ([`crate::integrator::GradientLayout`]): the grids' values are gradient blocks after the named
/// parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Selection {
    /// The named parameters, in slot order.
    params: Vec<String>,
    /// The selected grid nodes and how their values are differentiated; every other grid is constant.
    grids: GridChoices,
    /// The derivatives' names, one per forward-mode slot: `params`, then each direction's block name
    /// (`NODE.values`).
    names: Vec<String>,
}

impl Selection {
    /// The selection of `params` and of `grids` in `scene`, checked by applying it once. Errors as
    /// [`Selection::apply`].
    pub(crate) fn new(
        scene: &Scene,
        params: Vec<String>,
        grids: GridChoices,
        names: Vec<String>,
    ) -> Result<Self> {
        let selection = Self {
            params,
            grids,
            names,
        };
        selection.apply(scene)?;
        Ok(selection)
    }

    /// The names of the forward-mode derivatives, in slot order: the named parameters, then the grid
    /// blocks (`NODE.values`) of the directions.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The named parameters, in slot (or gradient entry) order.
    pub fn params(&self) -> &[String] {
        &self.params
    }

    /// Number of forward-mode derivatives (named parameters and grid directions).
    pub fn len(&self) -> usize {
        self.names.len()
    }

    /// Whether nothing is selected.
    pub fn is_empty(&self) -> bool {
        self.names.is_empty() && self.grids.is_empty()
    }

    /// A copy of `scene` with this selection's derivative slots and grid selections set, every other
    /// parameter and grid constant. Errors: a parameter or grid node `scene` does not have (the message
    /// lists near matches), a name given twice, a grid direction whose length is not its grid's.
    pub fn apply(&self, scene: &Scene) -> Result<Scene> {
        let mut selected = scene.clone();
        selected.select_parameters(&self.params)?;
        selected.select_grids(&self.grids)?;
        Ok(selected)
    }
}

impl Scene {
    /// Differentiates with respect to the parameters `params` (names as [`Scene::parameters`] lists
    /// them): `params[k]` is derivative `k`. Errors: an unknown name (listing near matches), a name
    /// given twice.
    pub fn select<S: AsRef<str>>(&self, params: &[S]) -> Result<Selection> {
        self.select_with_grid_directions(params, &[])
    }

    /// [`Scene::select`] plus, for each of `directions`, the derivative along a perturbation of a grid
    /// node's values, in the slots after the named parameters (named by the grid's block,
    /// `NODE.values`). Errors (on the field `grid_directions`): an unknown or repeated node, a
    /// direction whose shape is not the grid's (naming its source and both shapes).
    pub fn select_with_grid_directions<S: AsRef<str>>(
        &self,
        params: &[S],
        directions: &[GridDirection],
    ) -> Result<Selection> {
        let params: Vec<String> = params.iter().map(|p| p.as_ref().to_string()).collect();
        let (grids, blocks) = self.grid_directions(params.len(), directions)?;
        let mut names = params.clone();
        names.extend(blocks);
        Selection::new(self, params, grids, names)
    }

    /// The grid selections of forward-mode `directions` in slots `first_slot`, `first_slot + 1`, ...,
    /// and their blocks' names. Errors as [`Scene::select_with_grid_directions`].
    fn grid_directions(
        &self,
        first_slot: usize,
        directions: &[GridDirection],
    ) -> Result<(GridChoices, Vec<String>)> {
        let blocks = self.blocks();
        let mut selection: GridChoices = Vec::new();
        let mut names = Vec::new();
        for (k, direction) in directions.iter().enumerate() {
            let node = self.grid_node(&direction.node);
            let Some(block) = blocks.iter().find(|b| b.node == node) else {
                return Err(match self.unknown_grid(&node) {
                    Error::Field { message, .. } => Error::field("grid_directions", message),
                    e => e,
                });
            };
            if selection.iter().any(|(n, _)| *n == node) {
                return Err(Error::field(
                    "grid_directions",
                    format!("grid {node:?} is given twice"),
                ));
            }
            if direction.shape != block.shape {
                let given = ParamBlock {
                    shape: direction.shape.clone(),
                    ..block.clone()
                };
                let what = block.kind.describe();
                return Err(Error::file(
                    &direction.source,
                    format!(
                        "shape {}, but {what} {node:?} has shape {} (a direction has one value per \
                         value of the block)",
                        given.shape_text(),
                        block.shape_text()
                    ),
                ));
            }
            let slot = (first_slot + k) as u32;
            let u = direction.values.clone();
            selection.push((node, BlockValues::Direction { slot, u }));
            names.push(block.name.clone());
        }
        Ok((selection, names))
    }
}
