//! The parameter registry: every numeric scene value has a name `<name>.<field>` (`.x/.y/.z` for vectors,
//! `.r/.g/.b` for colours), can be listed, selected for differentiation (given a derivative slot) and set
//! (for finite differences).

use super::Scene;
use crate::error::Result;

impl Scene {
    /// Every parameter with its current value, in a stable order (camera, shapes, emitters).
    pub fn parameters(&self) -> Vec<(String, f32)> {
        todo!("params: parameters")
    }

    /// Differentiates with respect to `names`: `names[k]` gets derivative slot `k`, every other parameter
    /// none. An unknown name is an error listing near matches.
    pub fn select_parameters(&mut self, names: &[String]) -> Result<()> {
        let _ = names;
        todo!("params: select_parameters")
    }

    /// A copy of the scene with parameter `name` set to `value`, its derived data (bounds, Lipschitz
    /// bounds, tracer tolerance) recomputed. Errors: unknown name; a value the field does not accept.
    pub fn with_parameter(&self, name: &str, value: f32) -> Result<Scene> {
        let _ = (name, value);
        todo!("params: with_parameter")
    }
}
