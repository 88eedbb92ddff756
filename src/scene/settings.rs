//! Settings that are not parameters (the image size, the samples per pixel, the integrator and its
//! `max_depth`), changed by name as the command line's `--set camera.width=32` does.
//!
//! A setting changes the scene document before it is parsed, so a new value is checked by the same
//! rules, and with the same messages, as the file's own (`camera.width: must be an integer in [1,
//! 16384], got 0`).

use super::Scene;
use super::json;
use crate::error::{Error, Result};
use crate::io::json::StrictValue;
use serde_json::{Map, Value};
use std::path::Path;

/// The names of the settings, each the path of its field in the scene file (`integrator` is the
/// integrator's `type`; `max_depth` is accepted for `integrator.max_depth`).
pub const SETTINGS: &[&str] = &[
    "camera.width",
    "camera.height",
    "spp",
    "integrator",
    "integrator.max_depth",
];

/// Whether `name` is a setting (see [`SETTINGS`]) rather than a parameter.
pub fn is_setting(name: &str) -> bool {
    name == "max_depth" || SETTINGS.contains(&name)
}

/// Reads the scene file at `path` with each `(name, value)` of `settings` in place of the file's
/// value (the integrator's type first, then in order), and validates it as [`super::load`] does. A value is read as JSON when it is
/// JSON (`32`, `0.5`) and as a string otherwise (`path`), so the file's rules judge its type too.
/// Changing `integrator` drops the old integrator's fields; a `max_depth` for a file without an
/// integrator asks for the path tracer (the default integrator, `direct`, has no depth).
///
/// Errors: a name that is not a setting (field `name`), and whatever the file's rules say of the new
/// document.
pub fn load_with_settings(path: &Path, settings: &[(String, String)]) -> Result<Scene> {
    if settings.is_empty() {
        return json::load(path);
    }
    let text = std::fs::read_to_string(path).map_err(|e| Error::file(path, e))?;
    let StrictValue(mut doc) = serde_json::from_str(&text).map_err(|e| Error::file(path, e))?;
    // The integrator's type first, so that a depth given before it is not dropped with the old
    // integrator's fields.
    let (kinds, others): (Vec<_>, Vec<_>) = settings.iter().partition(|(n, _)| n == "integrator");
    for (name, value) in kinds.into_iter().chain(others) {
        set(&mut doc, name, value)?;
    }
    let base_dir = path.parent().unwrap_or(Path::new("."));
    json::parse(&doc.to_string(), base_dir)
}

/// Writes one setting into the document (leaving its validation to the parser).
fn set(doc: &mut Value, name: &str, text: &str) -> Result<()> {
    let value = serde_json::from_str::<Value>(text).unwrap_or_else(|_| Value::String(text.into()));
    let Value::Object(root) = doc else {
        // Not an object: the parser names the problem.
        return Ok(());
    };
    match name {
        "camera.width" | "camera.height" => {
            if let Some(camera) = object(root, "camera") {
                camera.insert(name["camera.".len()..].to_string(), value);
            }
        }
        "spp" => {
            root.insert("spp".into(), value);
        }
        "integrator" => {
            root.insert(
                "integrator".into(),
                Value::Object(Map::from_iter([("type".into(), value)])),
            );
        }
        "integrator.max_depth" | "max_depth" => {
            if let Some(integrator) = object(root, "integrator") {
                // The default integrator has no depth: a depth asks for the path tracer.
                let kind = integrator.entry("type").or_insert_with(|| "path".into());
                if kind == "direct" {
                    return Err(Error::field(
                        "integrator.max_depth",
                        "the direct integrator has no max_depth (set integrator to path)",
                    ));
                }
                integrator.insert("max_depth".into(), value);
            }
        }
        _ => {
            return Err(Error::field(
                "name",
                format!(
                    "{name:?} is not a setting (settings: {})",
                    SETTINGS.join(", ")
                ),
            ));
        }
    }
    Ok(())
}

/// The object at `root[key]`, created if missing (`None` if it is something else: the parser names
/// the problem).
fn object<'a>(root: &'a mut Map<String, Value>, key: &str) -> Option<&'a mut Map<String, Value>> {
    root.entry(key)
        .or_insert_with(|| Value::Object(Map::new()))
        .as_object_mut()
}
