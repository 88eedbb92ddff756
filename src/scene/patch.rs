//! Writing a scene back to its JSON: the original document with every parameter's current value written
//! where the scene file keeps it, and grid nodes pointed at other `.npy` files (what `optimize` writes
//! as `result.json`).
//!
//! The walk mirrors the naming scheme of [`Scene::parameters`] on the JSON document: a parameter
//! `<prefix>.<field>` lives in field `<field>` of the node whose prefix is `<prefix>` (a node's `name`,
//! else its parent's prefix followed by `children.<i>` or `child`, the root's being the shape's name or
//! `<shape>.sdf` for an unnamed root transform, as `root_prefix` has it), vector components in array elements, a transform's
//! `angle` in `rotate.angle`. Fields that the file leaves out (a shape's `translate`, a rounding, a
//! transform's `translate`, `rotate` or `scale`, a grid's `level`) are added only when the value differs
//! from the default the parser would use; everything else in the document (descriptions, unit
//! directions, image size, integrator) is kept as it is.

use super::Scene;
use super::json::SCENE_KEYS;
use crate::bsdf::Bsdf;
use crate::declare::{self, Family};
use crate::emitter::Emitter;
use crate::error::{Error, Result};
use crate::sdf::Sdf;
use serde_json::{Map, Number, Value};
use std::collections::HashMap;

/// The scene JSON `original` (the document `scene` was parsed from) with every parameter value of
/// `scene` written in place and the `file` of each grid node named in `grid_files` (`(node, file)`,
/// `node` as [`Scene::grid_blocks`] names it) replaced by `file`, as given: a relative file name resolves
/// against the folder the patched document is written to, so name it from there.
///
/// Errors (the document is not this scene's): a parameter of `scene` with no place in the document, a
/// parameter of the document that `scene` lacks, a grid node not in the document, a non-finite value.
pub fn patched_scene_json(
    original: &Value,
    scene: &Scene,
    grid_files: &[(String, String)],
) -> Result<Value> {
    let mut doc = original.clone();
    let mut walk = Walk {
        values: Some(scene.parameters().into_iter().collect()),
        new_files: grid_files,
        replaced: vec![false; grid_files.len()],
        files: Vec::new(),
    };
    walk.scene(&mut doc)?;
    if let Some((name, _)) = walk.values.as_ref().and_then(|v| v.iter().next()) {
        return Err(Error::field(
            name.clone(),
            "the scene's parameter has no place in the scene JSON (not the scene's document)",
        ));
    }
    if let Some(k) = walk.replaced.iter().position(|r| !r) {
        let nodes: Vec<&str> = walk.files.iter().map(|(n, _)| n.as_str()).collect();
        return Err(Error::field(
            grid_files[k].0.clone(),
            format!(
                "no grid node of that name in the scene JSON (grid nodes: {})",
                if nodes.is_empty() {
                    "none".to_string()
                } else {
                    nodes.join(", ")
                }
            ),
        ));
    }
    Ok(doc)
}

/// Every grid node of a scene JSON document with its `file` as written (relative to the document's
/// folder unless absolute), in the order of [`Scene::grid_blocks`].
pub fn grid_files(original: &Value) -> Result<Vec<(String, String)>> {
    let mut doc = original.clone();
    let mut walk = Walk {
        values: None,
        new_files: &[],
        replaced: Vec::new(),
        files: Vec::new(),
    };
    walk.scene(&mut doc)?;
    Ok(walk.files)
}

/// The walk over a scene document.
struct Walk<'a> {
    /// Parameter values still to write (`None`: only list the grid files); each is removed when
    /// written.
    values: Option<HashMap<String, f32>>,
    /// Grid files to set, `(node, file)`.
    new_files: &'a [(String, String)],
    /// Which of `new_files` were set.
    replaced: Vec<bool>,
    /// Grid nodes found, with their original files.
    files: Vec<(String, String)>,
}

const XYZ: &[&str] = &["x", "y", "z"];

/// The object at `path`, or an error (the document was parsed once, so this means it is not a scene).
fn object<'v>(v: &'v mut Value, path: &str) -> Result<&'v mut Map<String, Value>> {
    v.as_object_mut()
        .ok_or_else(|| Error::field(path, "expected an object in the scene JSON"))
}

/// The array at `path` (an absent one is empty).
fn array<'v>(v: Option<&'v mut Value>, path: &str) -> Result<&'v mut [Value]> {
    match v {
        None => Ok(&mut []),
        Some(Value::Array(a)) => Ok(a),
        Some(_) => Err(Error::field(path, "expected an array in the scene JSON")),
    }
}

fn string(o: &Map<String, Value>, key: &str, path: &str) -> Result<String> {
    match o.get(key) {
        Some(Value::String(s)) => Ok(s.clone()),
        _ => Err(Error::field(
            format!("{path}.{key}"),
            "expected a string in the scene JSON",
        )),
    }
}

/// The JSON number that reads back as `v`: its shortest decimal form when that parses back to the same
/// `f32` through `f64` (as the scene parser reads numbers), else the exact `f64` of `v`.
pub(crate) fn json_number(v: f32, name: &str) -> Result<Value> {
    if !v.is_finite() {
        return Err(Error::field(name, format!("must be finite, got {v}")));
    }
    let short: Option<Number> = serde_json::from_str(&format!("{v}")).ok();
    let n = short
        .filter(|n| n.as_f64().is_some_and(|x| x as f32 == v))
        .or_else(|| Number::from_f64(v as f64))
        .expect("a finite f32 is a JSON number");
    Ok(Value::Number(n))
}

impl Walk<'_> {
    /// Takes the value of parameter `name`; `None` when only listing grids.
    fn take(&mut self, name: &str) -> Result<Option<f32>> {
        let Some(values) = &mut self.values else {
            return Ok(None);
        };
        values.remove(name).map(Some).ok_or_else(|| {
            Error::field(
                name,
                "the scene JSON has this parameter but the scene does not (not the scene's document)",
            )
        })
    }

    /// Writes scalar `<prefix>.<key>` to `o[key]` (added if absent unless equal to `default`).
    fn scalar(
        &mut self,
        o: &mut Map<String, Value>,
        key: &str,
        prefix: &str,
        default: Option<f32>,
    ) -> Result<()> {
        let name = format!("{prefix}.{key}");
        let Some(v) = self.take(&name)? else {
            return Ok(());
        };
        if o.contains_key(key) || default != Some(v) {
            o.insert(key.to_string(), json_number(v, &name)?);
        }
        Ok(())
    }

    /// Writes the components `<prefix>.<key>.<c>` (`c` in `comps`) to the array `o[key]` (added if
    /// absent unless every component equals `default`).
    fn vector(
        &mut self,
        o: &mut Map<String, Value>,
        key: &str,
        prefix: &str,
        comps: &[&str],
        default: Option<f32>,
    ) -> Result<()> {
        let mut values = Vec::with_capacity(comps.len());
        for c in comps {
            let name = format!("{prefix}.{key}.{c}");
            match self.take(&name)? {
                Some(v) => values.push(json_number(v, &name)?),
                None => return Ok(()),
            }
        }
        let is_default = default.is_some_and(|d| {
            values
                .iter()
                .all(|v| v.as_f64().is_some_and(|x| x as f32 == d))
        });
        if o.contains_key(key) || !is_default {
            o.insert(key.to_string(), Value::Array(values));
        }
        Ok(())
    }

    fn scene(&mut self, doc: &mut Value) -> Result<()> {
        let root = object(doc, "scene")?;
        let camera = object(
            root.get_mut("camera")
                .ok_or_else(|| Error::field("camera", "missing in the scene JSON"))?,
            "camera",
        )?;
        for key in ["origin", "target", "up"] {
            self.vector(camera, key, "camera", XYZ, None)?;
        }
        self.scalar(camera, "fov_y", "camera", None)?;

        for (i, shape) in array(root.get_mut("shapes"), "shapes")?
            .iter_mut()
            .enumerate()
        {
            let path = format!("shapes[{i}]");
            let o = object(shape, &path)?;
            let name = string(o, "name", &path)?;
            self.vector(o, "translate", &name, XYZ, Some(0.0))?;
            let sdf_path = format!("{path}.sdf");
            let sdf = o
                .get_mut("sdf")
                .ok_or_else(|| Error::field(&sdf_path, "missing in the scene JSON"))?;
            // The prefix of the root node as `root_prefix` gives it: `<shape>.sdf` for an unnamed
            // transform, else the shape's name (a named root uses its own name, which `sdf` picks up).
            let is_transform = sdf.get("type").and_then(Value::as_str) == Some("transform");
            let root = if is_transform {
                format!("{name}.sdf")
            } else {
                name.clone()
            };
            self.node::<Sdf>(sdf, &root, &sdf_path)?;
            let bsdf_path = format!("{path}.bsdf");
            let bsdf = o
                .get_mut("bsdf")
                .ok_or_else(|| Error::field(&bsdf_path, "missing in the scene JSON"))?;
            self.node::<Bsdf>(bsdf, &name, &bsdf_path)?;
        }

        for (i, emitter) in array(root.get_mut("emitters"), "emitters")?
            .iter_mut()
            .enumerate()
        {
            let path = format!("emitters[{i}]");
            let name = string(object(emitter, &path)?, "name", &path)?;
            self.node::<Emitter>(emitter, &name, &path)?;
        }
        Ok(())
    }

    /// Writes the parameters of the node at `path` (of family `N`, prefix `prefix` unless it has a
    /// name) where its kind's declaration keeps them, and visits its children.
    fn node<N: Family>(&mut self, node: &mut Value, prefix: &str, path: &str) -> Result<()> {
        let o = object(node, path)?;
        let p = match o.get("name") {
            Some(Value::String(name)) => name.clone(),
            _ => prefix.to_string(),
        };
        let p = p.as_str();
        let ty = string(o, "type", path)?;
        let Some(kind) = declare::kind_named::<N>(&ty) else {
            return Err(Error::field(
                format!("{path}.type"),
                format!("unknown type {ty:?} in the scene JSON"),
            ));
        };
        for field in kind.fields {
            let key = field.key;
            // A field given by a volume texture: its file, like a grid's (its texels are a block).
            let number = matches!(
                field.value,
                declare::Value::Number { .. } | declare::Value::Vector { .. }
            );
            if let (true, Some(Value::Object(texture))) = (number, o.get_mut(key)) {
                let at = format!("{path}.{key}");
                let name = string(texture, "name", &at)?;
                let file = string(texture, "file", &at)?;
                self.files.push((name.clone(), file));
                if let Some(k) = self.new_files.iter().position(|(n, _)| *n == name) {
                    texture.insert("file".into(), Value::String(self.new_files[k].1.clone()));
                    self.replaced[k] = true;
                }
                continue;
            }
            match &field.value {
                declare::Value::Number { default, .. } => self.scalar(o, key, p, *default)?,
                declare::Value::Vector {
                    components,
                    default,
                    ..
                } => self.vector(o, key, p, components.names(), *default)?,
                declare::Value::Pair { .. } => self.vector(o, key, p, &declare::PAIR, None)?,
                declare::Value::Rotation { keyed, .. } => {
                    self.rotation_angle(o, key, p, path, *keyed)?
                }
                declare::Value::Child(_) => {
                    let child_path = format!("{path}.{key}");
                    let child = o
                        .get_mut(key)
                        .ok_or_else(|| Error::field(&child_path, "missing in the scene JSON"))?;
                    self.node::<N>(child, &format!("{p}.{key}"), &child_path)?;
                }
                declare::Value::Children { .. } => {
                    let children_path = format!("{path}.{key}");
                    for (i, child) in array(o.get_mut(key), &children_path)?
                        .iter_mut()
                        .enumerate()
                    {
                        self.node::<N>(
                            child,
                            &format!("{p}.{key}.{i}"),
                            &format!("{children_path}[{i}]"),
                        )?;
                    }
                }
                declare::Value::File { .. } => {
                    let file = string(o, key, path)?;
                    self.files.push((p.to_string(), file));
                    if let Some(k) = self.new_files.iter().position(|(n, _)| n == p) {
                        o.insert(key.into(), Value::String(self.new_files[k].1.clone()));
                        self.replaced[k] = true;
                    }
                }
                declare::Value::Direction { .. } | declare::Value::Fixed { .. } => {}
            }
        }
        Ok(())
    }

    /// A rotation's `angle` parameter, kept in `<key>.angle`; without the rotation, a non-zero angle
    /// adds one about the parser's default axis `+y`.
    fn rotation_angle(
        &mut self,
        o: &mut Map<String, Value>,
        key: &str,
        p: &str,
        path: &str,
        keyed: bool,
    ) -> Result<()> {
        let name = declare::rotation_angle_name(p, key, keyed);
        let Some(v) = self.take(&name)? else {
            return Ok(());
        };
        match o.get_mut(key) {
            Some(rotate) => {
                object(rotate, &format!("{path}.{key}"))?
                    .insert("angle".into(), json_number(v, &name)?);
            }
            None if v != 0.0 => {
                let mut rotate = Map::new();
                rotate.insert("axis".into(), serde_json::json!([0, 1, 0]));
                rotate.insert("angle".into(), json_number(v, &name)?);
                o.insert(key.into(), Value::Object(rotate));
            }
            None => {}
        }
        Ok(())
    }
}

/// Keys written first, after the scene's own ([`SCENE_KEYS`]), in this order; the others follow in
/// alphabetical order.
const MEMBER_KEYS_FIRST: &[&str] = &["name", "type"];

/// A scene document as text: indented objects, arrays of numbers on one line (`"center": [0, 1, 0]`),
/// names and types first in every object, ending in a newline.
pub fn scene_text(doc: &Value) -> String {
    let mut out = String::new();
    write_value(doc, 0, &mut out);
    out.push('\n');
    out
}

fn write_value(v: &Value, indent: usize, out: &mut String) {
    let pad = |n: usize| " ".repeat(n);
    match v {
        Value::Object(map) if !map.is_empty() => {
            let mut keys: Vec<&String> = map.keys().collect();
            keys.sort_by_key(|k| {
                let mut first = SCENE_KEYS.iter().chain(MEMBER_KEYS_FIRST);
                let rank = first.position(|o| o == k);
                (rank.unwrap_or(usize::MAX), k.as_str())
            });
            out.push_str("{\n");
            for (i, key) in keys.iter().enumerate() {
                out.push_str(&pad(indent + 2));
                out.push_str(&Value::String(key.to_string()).to_string());
                out.push_str(": ");
                write_value(&map[key.as_str()], indent + 2, out);
                out.push_str(if i + 1 < keys.len() { ",\n" } else { "\n" });
            }
            out.push_str(&pad(indent));
            out.push('}');
        }
        Value::Array(items) if items.iter().any(|i| i.is_object() || i.is_array()) => {
            out.push_str("[\n");
            for (i, item) in items.iter().enumerate() {
                out.push_str(&pad(indent + 2));
                write_value(item, indent + 2, out);
                out.push_str(if i + 1 < items.len() { ",\n" } else { "\n" });
            }
            out.push_str(&pad(indent));
            out.push(']');
        }
        Value::Array(items) => {
            let items: Vec<String> = items.iter().map(Value::to_string).collect();
            out.push('[');
            out.push_str(&items.join(", "));
            out.push(']');
        }
        other => out.push_str(&other.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{load, parse};
    use crate::sdf::{GridData, write_npy};
    use std::path::{Path, PathBuf};

    /// A fresh empty folder for one test.
    fn workdir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("psdr-patch-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn json_of(path: &Path) -> Value {
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
    }

    /// `scene` with every parameter `p` for which `change(name)` holds set to `1.01 p + 0.003` (small
    /// enough to keep every field rule), without any check. The camera's `up` is left alone: the
    /// parser normalises it, so only a unit `up` reads back as written.
    fn modified(scene: &Scene, change: impl Fn(&str) -> bool) -> Scene {
        let mut scene = scene.clone();
        scene.visit_params_mut(&mut |name, p| {
            if change(name) && !name.starts_with("camera.up.") {
                p.value = 1.01 * p.value + 0.003;
            }
        });
        scene
    }

    /// Writes the patched document into `dir` and parses it from there.
    fn round_trip(doc: &Value, dir: &Path) -> Scene {
        let text = scene_text(doc);
        let path = dir.join("result.json");
        std::fs::write(&path, &text).unwrap();
        load(&path).unwrap_or_else(|e| panic!("{e}\n{text}"))
    }

    /// Every parameter of the re-parsed scene equals the patched one, bit for bit, in the same order.
    #[track_caller]
    fn assert_same_parameters(got: &Scene, want: &Scene) {
        let (got, want) = (got.parameters(), want.parameters());
        assert_eq!(got.len(), want.len());
        for ((n, a), (m, b)) in got.iter().zip(&want) {
            assert_eq!(n, m);
            assert_eq!(a.to_bits(), b.to_bits(), "{n}: {a} vs {b}");
        }
    }

    #[test]
    fn example_scenes_round_trip_with_every_parameter_changed() {
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
        let mut names: Vec<PathBuf> = std::fs::read_dir(&scenes)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "json"))
            .collect();
        names.sort();
        assert!(names.len() >= 4, "{names:?}");
        for path in names {
            let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
            let dir = workdir(&stem);
            let scene = load(&path).unwrap();
            let original = json_of(&path);
            // Grid files move next to the result, under a new name.
            let mut files = Vec::new();
            for (node, file) in grid_files(&original).unwrap() {
                let moved = format!("{node}.moved.npy");
                std::fs::copy(scenes.join(&file), dir.join(&moved)).unwrap();
                files.push((node, moved));
            }
            let changed = modified(&scene, |_| true);
            let doc = patched_scene_json(&original, &changed, &files).unwrap();
            let back = round_trip(&doc, &dir);
            assert_same_parameters(&back, &changed);
            for block in scene.grid_blocks() {
                assert_eq!(
                    back.grid_values(&block.node).unwrap(),
                    scene.grid_values(&block.node).unwrap()
                );
            }
            // Unchanged values stay as they were, changed ones are the new ones.
            let half = modified(&scene, |n| n.len() % 2 == 0);
            let doc = patched_scene_json(&original, &half, &files).unwrap();
            assert_same_parameters(&round_trip(&doc, &dir), &half);
            let doc = patched_scene_json(&original, &scene, &files).unwrap();
            assert_same_parameters(&round_trip(&doc, &dir), &scene);
            let _ = std::fs::remove_dir_all(&dir);
        }
    }

    /// Every node type, named and unnamed nodes at every depth, and fields the file leaves out.
    const EVERY_NODE: &str = r#"{
      "camera": {"origin": [0, 3, 6], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 40,
                 "width": 8, "height": 8},
      "shapes": [
        {"name": "a", "sdf": {"type": "union", "children": [
           {"type": "sphere", "center": [0, 0, 0], "radius": 0.5},
           {"type": "box", "center": [1, 0, 0], "half_size": [0.3, 0.4, 0.5]},
           {"name": "cyl", "type": "cylinder", "center": [0, 1, 0], "axis": [0, 1, 0], "radius": 0.3,
            "half_height": 0.4},
           {"type": "smooth_union", "k": 0.2, "children": [
             {"type": "capsule", "a": [0, 0, 0], "b": [0, 1, 0], "radius": 0.2},
             {"type": "torus", "center": [0, 0, 0], "axis": [0, 0, 1], "major_radius": 0.6,
              "minor_radius": 0.1}]},
           {"type": "transform", "child": {"type": "sphere", "center": [0, 0, 0], "radius": 0.3}}
         ]},
         "bsdf": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
        {"name": "b", "translate": [0, 0.5, 0],
         "sdf": {"type": "transform", "translate": [0, 0, 1], "rotate": {"axis": [1, 0, 0], "angle": 30},
                 "scale": 1.5,
                 "child": {"type": "difference", "children": [
                   {"type": "intersection", "children": [
                     {"type": "plane", "normal": [0, 1, 0], "offset": 0.1},
                     {"name": "g", "type": "grid", "file": "g.npy", "bbox_min": [-1, -1, -1],
                      "bbox_max": [1, 1, 1]}]},
                   {"type": "grid", "file": "g.npy", "bbox_min": [-1, -1, -1], "bbox_max": [1, 1, 1],
                    "level": 0.05}]}},
         "bsdf": {"type": "diffuse", "albedo": [0.2, 0.3, 0.4]}},
        {"name": "c", "sdf": {"name": "t", "type": "transform",
                              "child": {"type": "sphere", "center": [0, 0, 0], "radius": 0.4}},
         "bsdf": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}
      ],
      "emitters": [
        {"name": "r", "type": "rectangle", "center": [0, 4, 0], "normal": [0, -1, 0], "u": [1, 0, 0],
         "size": [1, 2], "radiance": [5, 5, 5]},
        {"name": "s", "type": "sphere", "center": [2, 3, 0], "radius": 0.25, "radiance": [3, 3, 3]},
        {"name": "sky", "type": "constant", "radiance": [0.1, 0.1, 0.1]}
      ]
    }"#;

    fn every_node_scene(dir: &Path) -> (Scene, Value) {
        let values: Vec<f32> = (0..64).map(|i| (i % 4) as f32 * 0.25 - 0.4).collect();
        let grid = GridData::new([4, 4, 4], values, "test grid").unwrap();
        write_npy(&dir.join("g.npy"), &grid).unwrap();
        let scene = parse(EVERY_NODE, dir).unwrap();
        (scene, serde_json::from_str(EVERY_NODE).unwrap())
    }

    #[test]
    fn every_node_type_round_trips_and_absent_fields_are_added_only_when_changed() {
        let dir = workdir("every-node");
        let (scene, original) = every_node_scene(&dir);
        let names: Vec<String> = scene.parameters().into_iter().map(|(n, _)| n).collect();
        for expected in [
            "a.children.1.rounding",
            "cyl.rounding",
            "a.children.3.children.1.minor_radius",
            "a.children.4.angle",
            "b.sdf.scale",
            "b.sdf.child.children.0.children.0.offset",
            "g.level",
            "b.sdf.child.children.1.level",
            "t.angle",
            "r.size.y",
            "s.radius",
        ] {
            assert!(
                names.iter().any(|n| n == expected),
                "{expected} in {names:?}"
            );
        }
        let blocks: Vec<String> = scene.grid_blocks().into_iter().map(|b| b.node).collect();
        assert_eq!(blocks, ["g", "b.sdf.child.children.1"]);

        // Unchanged: the document is the original (no defaults written out).
        let same = patched_scene_json(&original, &scene, &[]).unwrap();
        let reparsed: Value = serde_json::from_str(EVERY_NODE).unwrap();
        let numbers_equal = |a: &Value, b: &Value| scene_text(a) == scene_text(b);
        assert!(numbers_equal(&same, &reparsed), "{}", scene_text(&same));

        // Everything changed: absent fields appear, and the values come back.
        let changed = modified(&scene, |_| true);
        let out = dir.join("out");
        std::fs::create_dir_all(&out).unwrap();
        let files = [("g".to_string(), "../g.npy".to_string())];
        let doc = patched_scene_json(&original, &changed, &files).unwrap();
        let transform = &doc["shapes"][0]["sdf"]["children"][4];
        assert_eq!(transform["rotate"]["axis"], serde_json::json!([0, 1, 0]));
        assert!(transform.get("scale").is_some() && transform.get("translate").is_some());
        assert!(doc["shapes"][0]["translate"].is_array());
        assert_eq!(
            doc["shapes"][1]["sdf"]["child"]["children"][0]["children"][1]["file"],
            "../g.npy"
        );
        // The unoptimised grid keeps its file as written (relative to the original folder).
        assert_eq!(
            doc["shapes"][1]["sdf"]["child"]["children"][1]["file"],
            "g.npy"
        );
        std::fs::copy(dir.join("g.npy"), out.join("g.npy")).unwrap();
        assert_same_parameters(&round_trip(&doc, &out), &changed);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn mismatched_documents_and_unknown_grid_nodes_are_errors() {
        let dir = workdir("mismatch");
        let (scene, original) = every_node_scene(&dir);
        let e = patched_scene_json(&original, &scene, &[("nope".into(), "x.npy".into())]);
        let e = e.unwrap_err().to_string();
        assert!(
            e.starts_with("nope: no grid node") && e.contains("g, b.sdf.child.children.1"),
            "{e}"
        );
        let other = load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/sphere_floor.json"));
        let e = patched_scene_json(&original, &other.unwrap(), &[]).unwrap_err();
        assert!(e.to_string().contains("not the scene's document"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn numbers_read_back_exactly() {
        for v in [
            0.1f32,
            1.0 / 3.0,
            1e-30,
            3.4e38,
            -2.5e-8,
            16777217.0,
            0.0,
            -0.0,
        ] {
            let n = json_number(v, "x").unwrap();
            let back = n.as_f64().unwrap() as f32;
            assert_eq!(back, v, "{v} -> {n}");
        }
        assert!(json_number(f32::NAN, "x").is_err());
        assert_eq!(json_number(0.8, "x").unwrap().to_string(), "0.8");
        assert_eq!(json_number(2.0, "x").unwrap().to_string(), "2");
    }
}
