//! The parameter registry: every numeric scene value has a name `<name>.<field>` (`.x/.y/.z` for vectors,
//! `.r/.g/.b` for colours), can be listed, selected for differentiation (given a derivative slot) and set
//! (for finite differences).
//!
//! The naming scheme and the order are documented on [`Scene::parameters`].

use super::Scene;
use crate::declare;
use crate::error::{Error, FieldPath, Result, XYZ};
use crate::scalar::Param;
use crate::sdf::Sdf;

/// How many near matches an unknown-name error lists.
const MAX_SUGGESTIONS: usize = 3;

/// The prefix of the unnamed root node of shape `shape` (see [`Scene::parameters`]).
pub(super) fn root_prefix(shape: &str, sdf: &Sdf) -> String {
    match sdf {
        Sdf::Transform { .. } => format!("{shape}.sdf"),
        _ => shape.to_string(),
    }
}

/// Whether parameter `name` belongs to a material field that a volume texture stands in for.
fn textured(textures: &[crate::bsdf::MaterialTexture], name: &str) -> bool {
    textures.iter().any(|t| {
        name.strip_prefix(t.field.as_str())
            .is_some_and(|rest| rest.is_empty() || rest.starts_with('.'))
    })
}

/// Generates the walk over every parameter of a scene in the order of [`Scene::parameters`] (camera,
/// then each shape's translation, sdf tree and material, then the emitters), for shared or mutable
/// access: the same walk written once keeps the names of [`Scene::parameters`] and
/// [`Scene::with_parameter`] identical by construction.
macro_rules! scene_walk {
    ($walk:ident, $sdf:ident, $params:ident $(, $m:tt)?) => {
        fn $walk(scene: &$($m)? Scene, f: &mut dyn FnMut(&str, &$($m)? Param)) {
            let camera = &$($m)? scene.camera;
            for (field, v) in [("origin", &$($m)? camera.origin), ("target", &$($m)? camera.target), ("up", &$($m)? camera.up)] {
                for (c, p) in XYZ.iter().zip(&$($m)? v.c) {
                    f(&format!("camera.{field}.{c}"), p);
                }
            }
            f("camera.fov_y", &$($m)? camera.fov_y);
            for s in &$($m)? scene.shapes {
                let name = &s.name;
                for (c, p) in XYZ.iter().zip(&$($m)? s.translate.c) {
                    f(&format!("{name}.translate.{c}"), p);
                }
                let root = root_prefix(name, &s.sdf);
                s.sdf.$sdf(&root, f);
                // A field given by a volume texture has no number parameters (its texels are a block).
                let textures = &s.textures;
                declare::$params(&$($m)? s.bsdf, name, &mut |n, p| {
                    if !textured(textures, n) {
                        f(n, p)
                    }
                });
            }
            for e in &$($m)? scene.emitters {
                declare::$params(&$($m)? e.emitter, &e.name, f);
            }
        }
    };
}
scene_walk!(scene_params, visit_params, params);
scene_walk!(scene_params_mut, visit_params_mut, params_mut, mut);

impl Sdf {
    /// Calls `f` with the full name and value of every parameter in the tree under this node, whose
    /// prefix is `prefix` (a named node uses its own name instead; see [`Scene::parameters`] for
    /// the scheme).
    pub fn visit_params(&self, prefix: &str, f: &mut dyn FnMut(&str, &Param)) {
        declare::params(self, prefix, f);
    }

    /// [`Sdf::visit_params`] with mutable access (to set values or slots). Derived data (a shape's
    /// bounds) is not updated.
    pub fn visit_params_mut(&mut self, prefix: &str, f: &mut dyn FnMut(&str, &mut Param)) {
        declare::params_mut(self, prefix, f);
    }
}

impl Scene {
    /// Calls `f` with the full name and value of every parameter (see [`Scene::parameters`] for the
    /// names), in the order of [`Scene::parameters`].
    pub fn visit_params(&self, f: &mut dyn FnMut(&str, &Param)) {
        scene_params(self, f);
    }

    /// [`Scene::visit_params`] with mutable access. Changing a value this way does not update derived
    /// data (bounds, Lipschitz bounds, tolerance): use [`Scene::with_parameter`] for that. Setting slots
    /// is what [`super::Selection::apply`] does.
    pub fn visit_params_mut(&mut self, f: &mut dyn FnMut(&str, &mut Param)) {
        scene_params_mut(self, f);
    }

    /// Every parameter with its current value, in a stable order (camera, shapes, emitters).
    ///
    /// ## Names
    ///
    /// Names use only ASCII letters, digits, `_`, `-` and `.` (no brackets or spaces, so they need no quoting
    /// in a shell). Object names (shapes, emitters, named sdf nodes) share one namespace and contain no dot,
    /// so the names below are unique.
    ///
    /// - Camera: `camera.origin.x|y|z`, `camera.target.x|y|z`, `camera.up.x|y|z`, `camera.fov_y` (degrees;
    ///   `camera` is a reserved object name). `up` is kept as given (the frame is built from it by
    ///   Gram–Schmidt), so its components are parameters although only its direction matters.
    /// - Shape `s`: `s.translate.x|y|z` (the rigid translation of the whole shape, grids included) and
    ///   `s.albedo.r|g|b` (its diffuse BSDF).
    /// - The shape's sdf tree. Every node has a *prefix* and its fields are `<prefix>.<field>`:
    ///   - a node with a `name` in the scene file has that name as its prefix (`{"type": "torus", "name":
    ///     "ring", ...}` gives `ring.major_radius`), wherever it sits in the tree;
    ///   - the unnamed root node has the shape's name as its prefix (`ball.radius`, `ball.center.x`), except
    ///     an unnamed root *transform*, whose `translate` would collide with the shape's own: its prefix is
    ///     `s.sdf` (`ring.sdf.translate.x`, `ring.sdf.angle`);
    ///   - an unnamed child has its parent's prefix followed by its place, as in the JSON path with the
    ///     index written as a component: `<parent>.children.<i>` for unions, intersections, differences and
    ///     smooth unions (`blob.children.1.radius`), `<parent>.child` for a transform
    ///     (`ring.sdf.child.major_radius`).
    /// - Node fields: sphere `center`, `radius`; box `center`, `half_size`, `rounding`; torus `center`,
    ///   `major_radius`, `minor_radius`; cylinder `center`, `radius`, `half_height`, `rounding`; capsule `a`,
    ///   `b`, `radius`; plane `offset`; smooth union `k`; transform `translate`, `angle` (degrees, present
    ///   even when the file gives no rotation: it rotates about the default `+y` axis), `scale`. Union,
    ///   intersection and difference have no fields; a grid has `level`. A grid's samples are not listed
    ///   here one by one: they are one block `<prefix>.values` ([`Scene::grid_blocks`]).
    /// - A material field given by a volume texture has no parameters of its own: the texture's texels
    ///   are one block `<texture name>.values` ([`Scene::blocks`]).
    /// - Emitter `e`: rectangle `e.center.x|y|z`, `e.size.x|y` (the edge lengths along `u` and along
    ///   `v = normal × u`: the components of the two-element `size` array, named like any vector's),
    ///   `e.radiance.r|g|b`; sphere `e.center.*`, `e.radius`, `e.radiance.*`; constant `e.radiance.*`
    ///   (`sky.radiance.g`).
    ///
    /// Unit directions (a torus's or cylinder's `axis`, a plane's or rectangle's `normal`, a rectangle's `u`,
    /// a transform's rotation `axis`) are not parameters: they are normalised on input, so a change of one
    /// component is not a change of the surface along that component alone (its derivative would need the
    /// normalisation's projection, and a finite difference would leave the unit sphere). The grid's box is not
    /// one either (its samples are, as a block). Image size, filter, spp and integrator settings are not numbers
    /// of the scene's geometry or light.
    ///
    /// ## Order
    ///
    /// Camera, then shapes (translate, sdf tree depth-first in file order, albedo),
    /// then emitters, each in file order: stable across runs and file round trips.
    pub fn parameters(&self) -> Vec<(String, f32)> {
        let mut out = Vec::new();
        self.visit_params(&mut |name, p| out.push((name.to_string(), p.value)));
        out
    }

    /// The current value of parameter `name`; an unknown name is an error listing near matches.
    pub fn parameter(&self, name: &str) -> Result<f32> {
        let mut found = None;
        self.visit_params(&mut |n, p| {
            if n == name {
                found = Some(p.value);
            }
        });
        found.ok_or_else(|| self.unknown(name))
    }

    /// Differentiates with respect to `names`: `names[k]` gets derivative slot `k`, every other parameter
    /// none. An unknown name is an error listing near matches, and so is a name given twice; on error the
    /// scene is unchanged.
    pub(crate) fn select_parameters(&mut self, names: &[String]) -> Result<()> {
        for (k, name) in names.iter().enumerate() {
            if names[..k].contains(name) {
                return Err(Error::field(
                    "params",
                    format!("parameter {name:?} is given twice"),
                ));
            }
        }
        let mut seen = vec![false; names.len()];
        self.visit_params(&mut |n, _| {
            if let Some(k) = names.iter().position(|x| x == n) {
                seen[k] = true;
            }
        });
        if let Some(k) = seen.iter().position(|s| !s) {
            return Err(self.unknown(&names[k]));
        }
        self.visit_params_mut(&mut |n, p| {
            p.slot = names.iter().position(|x| x == n).map(|k| k as u32);
        });
        Ok(())
    }

    /// A copy of the scene with parameter `name` set to `value`, its derived data (bounds, Lipschitz
    /// bounds, tracer tolerance) recomputed. Errors: unknown name; a value the field does not accept.
    ///
    /// The value must be finite and satisfy the scene file's rules for its field (a radius `> 0`, a
    /// rounding in `[0, min half size]`, a torus's major radius above its minor one, an albedo in `[0, 1]`,
    /// a radiance `>= 0`, a valid camera, ...). Only rules that the change breaks are reported: a scene
    /// built in code with some other field out of range can still be changed elsewhere.
    /// The tracer settings other than the tolerance `eps` (which follows the scene's scale as in
    /// [`Scene::new`]) are kept.
    pub fn with_parameter(&self, name: &str, value: f32) -> Result<Scene> {
        if !value.is_finite() {
            return Err(Error::field(
                name,
                format!("must be a finite number, got {value}"),
            ));
        }
        let mut copy = self.clone();
        let mut found = false;
        copy.visit_params_mut(&mut |n, p| {
            if n == name {
                p.value = value;
                found = true;
            }
        });
        if !found {
            return Err(self.unknown(name));
        }
        // Compared by message (field and value), so a rule broken before and after is not reported.
        let before: Vec<String> = self.violations().iter().map(Error::to_string).collect();
        if let Some(v) = copy
            .violations()
            .into_iter()
            .find(|v| !before.contains(&v.to_string()))
        {
            return Err(v);
        }
        Ok(copy.refreshed())
    }

    /// The error for an unknown parameter name, on the field `params` (the registry of
    /// [`Scene::parameters`]; front ends name their own option): near matches by edit distance, or else
    /// names of the same object.
    fn unknown(&self, name: &str) -> Error {
        let names: Vec<String> = self.parameters().into_iter().map(|(n, _)| n).collect();
        let near = near_matches(name, &names);
        let message = if near.is_empty() {
            format!("no parameter {name:?}")
        } else {
            format!("no parameter {name:?}; did you mean {}?", near.join(", "))
        };
        Error::field("params", message)
    }

    /// Every broken field rule of the scene file, as errors naming the parameter (see
    /// [`Scene::with_parameter`]).
    fn violations(&self) -> Vec<Error> {
        let mut out = Vec::new();
        if let Err(e) = self.camera.validate() {
            out.push(match e {
                Error::Field { field, message } => Error::field(format!("camera.{field}"), message),
                e => e,
            });
        }
        for s in &self.shapes {
            sdf_violations(&s.sdf, &root_prefix(&s.name, &s.sdf), &mut out);
            // A blend's children are nodes of their own (`<shape>.bsdfs.<i>`).
            declare::walk(&s.bsdf, &s.name, &mut |p, node| {
                out.extend(node.validate(FieldPath::Param(p)))
            });
        }
        for e in &self.emitters {
            out.extend(e.emitter.validate(FieldPath::Param(&e.name)));
        }
        out
    }
}

/// The scene file's rules ([`Sdf::validate`], which the parser applies too) for every node of the tree
/// under `sdf` (prefix `prefix`), named as parameters.
fn sdf_violations(sdf: &Sdf, prefix: &str, out: &mut Vec<Error>) {
    declare::walk(sdf, prefix, &mut |p, node| {
        out.extend(node.validate(FieldPath::Param(p)))
    });
}

/// Up to [`MAX_SUGGESTIONS`] names close to `name`: by edit distance (at most a third of the name's
/// length, and at least 2), nearest first; failing that, names of the same object (`ball.` for
/// `ball.radios`).
fn near_matches(name: &str, names: &[String]) -> Vec<String> {
    let limit = (name.chars().count() / 3).max(2);
    let mut scored: Vec<(usize, &String)> = names
        .iter()
        .map(|n| (edit_distance(name, n), n))
        .filter(|&(d, _)| d <= limit)
        .collect();
    // Stable: equal distances keep the registry order.
    scored.sort_by_key(|&(d, _)| d);
    let mut out: Vec<String> = scored
        .into_iter()
        .take(MAX_SUGGESTIONS)
        .map(|(_, n)| n.clone())
        .collect();
    if out.is_empty()
        && let Some((object, _)) = name.split_once('.')
    {
        let prefix = format!("{object}.");
        out = names
            .iter()
            .filter(|n| n.starts_with(&prefix))
            .take(MAX_SUGGESTIONS)
            .cloned()
            .collect();
    }
    out
}

/// Levenshtein distance (insertions, deletions, substitutions) between `a` and `b`, by characters.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diag = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let next = (diag + usize::from(ca != cb))
                .min(row[j] + 1)
                .min(row[j + 1] + 1);
            diag = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edit_distance_counts_edits() {
        assert_eq!(edit_distance("ball.radus", "ball.radius"), 1);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("same", "same"), 0);
    }

    #[test]
    fn near_matches_prefer_small_distances_then_fall_back_to_the_object() {
        let names: Vec<String> = ["ball.radius", "ball.center.x", "light.center.y"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        assert_eq!(near_matches("ball.radus", &names), vec!["ball.radius"]);
        assert_eq!(
            near_matches("ball.whatever_it_is", &names),
            vec!["ball.radius", "ball.center.x"]
        );
        assert!(near_matches("zzz", &names).is_empty());
    }
}
