//! The JSON scene format (see docs/scene-format.md): parsed at the edge into the rendering types, with
//! the path of the offending field in every error.
//!
//! serde's derived deserialisers lose the field path in their errors and cannot express "unknown type
//! `spere`, expected one of ..." per node, so the document is read into a [`serde_json::Value`] and
//! walked by hand. Every object declares the keys it accepts before anything is read from it, so a
//! misspelt key is reported as unknown (rather than as a missing correctly spelt one), which gives the
//! strictness of `#[serde(deny_unknown_fields)]`. All validation happens before any rendering type that
//! does work on construction ([`Shape::new`] computes bounds) is built.

use super::integrator_kind::IntegratorKind;
use super::{NamedEmitter, Scene, Shape};
use crate::bsdf::{Bsdf, MaterialTexture, Volume, texture};
use crate::camera::Camera;
use crate::declare::{self, Family, Kind};
use crate::emitter::Emitter;
use crate::error::{Error, FieldPath, Result};
use crate::film::Filter;
use crate::io::json::StrictValue;
use crate::scalar::{Param, Param3};
use crate::sdf::Sdf;
use glam::Vec3;
use serde_json::{Map, Value};
use std::collections::HashMap;
use std::path::Path;

/// Default samples per pixel when the scene gives none.
pub const DEFAULT_SPP: u32 = 64;
/// Default longest path of the path tracer when `max_depth` is absent.
pub const DEFAULT_MAX_DEPTH: u32 = 5;
/// Largest accepted image side, in pixels (guards against typos that would allocate gigabytes).
pub const MAX_IMAGE_SIDE: u64 = 16384;

/// The top-level fields of a scene file, in the order of docs/scene-format.md (also the order
/// [`crate::scene::patch::scene_text`] writes them in).
pub(crate) const SCENE_KEYS: &[&str] = &[
    "description",
    "camera",
    "integrator",
    "spp",
    "shapes",
    "emitters",
];

const INTEGRATOR_TYPES: &[&str] = &["direct", "path"];
const FILTERS: &[&str] = &["tent", "gaussian", "box"];
/// Prefix of the camera's parameter names, so no shape, emitter or node may use it.
const RESERVED_NAME: &str = "camera";

/// Reads and validates a scene file. Relative paths inside it (grids) resolve against its folder.
pub fn load(path: &Path) -> Result<Scene> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::file(path, e))?;
    let base_dir = path.parent().unwrap_or(Path::new("."));
    parse(&text, base_dir).map_err(|e| match e {
        // Syntax errors carry a placeholder name in `parse`; here the real file is known.
        Error::File { path: p, message } if p == JSON_SOURCE => Error::file(path, message),
        e => e,
    })
}

/// Name under which [`parse`] reports JSON syntax errors (it does not know the file).
const JSON_SOURCE: &str = "scene JSON";

/// Parses and validates scene JSON; `base_dir` resolves relative file names.
pub fn parse(json: &str, base_dir: &Path) -> Result<Scene> {
    // serde_json's message is one line and ends with "at line L column C".
    let StrictValue(root) = serde_json::from_str(json).map_err(|e| Error::file(JSON_SOURCE, e))?;
    let mut cx = Context {
        base_dir,
        names: HashMap::new(),
        bsdf_nodes: 0,
        textures: Vec::new(),
    };
    let scene = cx.scene(&root)?;
    Ok(scene.build())
}

/// A validated scene whose shapes are not built yet ([`Shape::new`] evaluates the SDF's bounds, which
/// should only happen once everything is known to be valid).
struct ParsedScene {
    camera: Camera,
    integrator: IntegratorKind,
    spp: u32,
    shapes: Vec<ParsedShape>,
    emitters: Vec<NamedEmitter>,
}

/// A validated shape: name, SDF, material, rigid translation and the material's volume textures.
type ParsedShape = (String, Sdf, Bsdf, Vec3, Vec<MaterialTexture>);

impl ParsedScene {
    fn build(self) -> Scene {
        let shapes = self
            .shapes
            .into_iter()
            .map(|(name, sdf, bsdf, translate, textures)| {
                Shape::translated(name, sdf, bsdf, translate.into()).with_textures(textures)
            })
            .collect();
        Scene::new(
            self.camera,
            self.integrator,
            self.spp,
            shapes,
            self.emitters,
        )
    }
}

/// State shared by the whole walk.
struct Context<'a> {
    base_dir: &'a Path,
    /// Every name seen so far (shapes, emitters, sdf nodes: one namespace, because later parameter
    /// names are `<name>.<field>`), with the path that defined it.
    names: HashMap<String, String>,
    /// Material nodes of the current shape read so far (depth-first), the index of the next.
    bsdf_nodes: usize,
    /// The volume textures of the current shape's material: (node, field key, texture).
    textures: Vec<(usize, &'static str, Volume)>,
}

pub(crate) fn join(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    }
}

/// A short description of a JSON value for error messages.
pub(crate) fn describe(v: &Value) -> String {
    match v {
        Value::Null => "null".into(),
        Value::Bool(b) => format!("boolean {b}"),
        Value::Number(n) => format!("number {n}"),
        Value::String(s) => format!("string {s:?}"),
        Value::Array(a) => format!("an array of {} elements", a.len()),
        Value::Object(_) => "an object".into(),
    }
}

/// A JSON object being read: its path and the keys it accepts.
pub(crate) struct Obj<'a> {
    pub(crate) path: String,
    map: &'a Map<String, Value>,
}

impl<'a> Obj<'a> {
    /// Checks that `v` is an object whose keys are all in `allowed`.
    pub(crate) fn new(v: &'a Value, path: String, allowed: &[&str]) -> Result<Self> {
        let Value::Object(map) = v else {
            let at = if path.is_empty() {
                "scene".into()
            } else {
                path
            };
            return Err(Error::field(
                at,
                format!("expected an object, got {}", describe(v)),
            ));
        };
        for key in map.keys() {
            if !allowed.contains(&key.as_str()) {
                return Err(Error::field(
                    join(&path, key),
                    format!("unknown field, expected one of {}", allowed.join(", ")),
                ));
            }
        }
        Ok(Self { path, map })
    }

    /// Reads the string tag `key` of `v` (an object) and checks it against `types`; returns the tag.
    pub(crate) fn tag(v: &'a Value, path: &str, key: &str, types: &[&str]) -> Result<&'a str> {
        let Value::Object(map) = v else {
            return Err(Error::field(
                path,
                format!("expected an object, got {}", describe(v)),
            ));
        };
        let field = join(path, key);
        let Some(t) = map.get(key) else {
            return Err(Error::field(
                field,
                format!("missing, expected one of {}", types.join(", ")),
            ));
        };
        let Value::String(t) = t else {
            return Err(Error::field(
                field,
                format!("expected a string, got {}", describe(t)),
            ));
        };
        if types.contains(&t.as_str()) {
            Ok(t)
        } else {
            Err(Error::field(
                field,
                format!("unknown type {t:?}, expected one of {}", types.join(", ")),
            ))
        }
    }

    pub(crate) fn at(&self, key: &str) -> String {
        join(&self.path, key)
    }

    pub(crate) fn get(&self, key: &str) -> Option<&'a Value> {
        self.map.get(key)
    }

    pub(crate) fn req(&self, key: &str) -> Result<&'a Value> {
        self.get(key)
            .ok_or_else(|| Error::field(self.at(key), "missing"))
    }

    pub(crate) fn f32(&self, key: &str) -> Result<f32> {
        number(self.req(key)?, &self.at(key))
    }

    pub(crate) fn opt_f32(&self, key: &str) -> Result<Option<f32>> {
        self.get(key).map(|v| number(v, &self.at(key))).transpose()
    }

    pub(crate) fn vec3(&self, key: &str) -> Result<Vec3> {
        vec3(self.req(key)?, &self.at(key))
    }

    pub(crate) fn opt_vec3(&self, key: &str) -> Result<Option<Vec3>> {
        self.get(key).map(|v| vec3(v, &self.at(key))).transpose()
    }

    /// A non-zero vector, normalised.
    pub(crate) fn direction(&self, key: &str) -> Result<Vec3> {
        let v = self.vec3(key)?;
        v.try_normalize().ok_or_else(|| {
            Error::field(
                self.at(key),
                format!("must be a non-zero vector, got {}", fmt3(v)),
            )
        })
    }

    pub(crate) fn string(&self, key: &str) -> Result<&'a str> {
        let v = self.req(key)?;
        v.as_str().ok_or_else(|| {
            Error::field(
                self.at(key),
                format!("expected a string, got {}", describe(v)),
            )
        })
    }

    pub(crate) fn opt_string(&self, key: &str) -> Result<Option<&'a str>> {
        match self.get(key) {
            None => Ok(None),
            Some(_) => self.string(key).map(Some),
        }
    }

    /// An integer in `[min, max]`.
    pub(crate) fn opt_int(&self, key: &str, min: u64, max: u64) -> Result<Option<u32>> {
        let Some(v) = self.get(key) else {
            return Ok(None);
        };
        let bad = |what: String| Error::field(self.at(key), what);
        match v {
            Value::Number(n) => match (n.as_u64(), n.as_i64()) {
                (Some(i), _) if (min..=max).contains(&i) => Ok(Some(i as u32)),
                (Some(i), _) if i > max => Err(bad(format!("must be <= {max}, got {n}"))),
                (Some(_), _) | (None, Some(_)) => Err(bad(format!("must be >= {min}, got {n}"))),
                (None, None) => Err(bad(format!("must be an integer, got {n}"))),
            },
            other => Err(bad(format!("expected an integer, got {}", describe(other)))),
        }
    }

    pub(crate) fn array(&self, key: &str) -> Result<&'a [Value]> {
        let v = self.req(key)?;
        match v {
            Value::Array(a) => Ok(a),
            other => Err(Error::field(
                self.at(key),
                format!("expected an array, got {}", describe(other)),
            )),
        }
    }

    pub(crate) fn opt_array(&self, key: &str) -> Result<&'a [Value]> {
        match self.get(key) {
            None => Ok(&[]),
            Some(_) => self.array(key),
        }
    }
}

/// A finite JSON number that fits an `f32`.
pub(crate) fn number(v: &Value, path: &str) -> Result<f32> {
    let Value::Number(n) = v else {
        return Err(Error::field(
            path,
            format!("expected a number, got {}", describe(v)),
        ));
    };
    // Without serde_json's `arbitrary_precision`, every JSON number converts to f64 (1e999 is already
    // a syntax error "number out of range"); values beyond f32's range become infinite here.
    let x = n.as_f64().unwrap_or(f64::NAN) as f32;
    if x.is_finite() {
        Ok(x)
    } else {
        Err(Error::field(
            path,
            format!("must be a finite number within f32 range, got {n}"),
        ))
    }
}

pub(crate) fn vec3(v: &Value, path: &str) -> Result<Vec3> {
    match v {
        Value::Array(a) if a.len() == 3 => Ok(Vec3::new(
            number(&a[0], &format!("{path}[0]"))?,
            number(&a[1], &format!("{path}[1]"))?,
            number(&a[2], &format!("{path}[2]"))?,
        )),
        other => Err(Error::field(
            path,
            format!("expected an array of 3 numbers, got {}", describe(other)),
        )),
    }
}

fn fmt3(v: Vec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}

/// The first of the broken rules a type's `validate` reports (in its order), as the parse error. The
/// rules live on the types because parameter updates check them too.
fn valid(broken: Vec<Error>) -> Result<()> {
    broken.into_iter().next().map_or(Ok(()), Err)
}

impl Context<'_> {
    /// Registers a name (shape, emitter or sdf node) defined at `path`.
    fn name(&mut self, name: &str, path: String) -> Result<()> {
        let valid = !name.is_empty()
            && name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
        if !valid {
            return Err(Error::field(
                path,
                format!(
                    "names must be non-empty and use only ASCII letters, digits, '_' and '-', got {name:?}"
                ),
            ));
        }
        if name == RESERVED_NAME {
            return Err(Error::field(
                path,
                format!(
                    "the name {name:?} is reserved for the camera's parameters ({name}.origin.x, ...)"
                ),
            ));
        }
        if let Some(first) = self.names.get(name) {
            return Err(Error::field(
                path,
                format!("duplicate name {name:?} (already used by {first})"),
            ));
        }
        self.names.insert(name.to_string(), path);
        Ok(())
    }

    fn scene(&mut self, root: &Value) -> Result<ParsedScene> {
        let o = Obj::new(root, String::new(), SCENE_KEYS)?;
        o.opt_string("description")?;
        let camera = camera(o.req("camera")?, "camera")?;
        let integrator = match o.get("integrator") {
            None => IntegratorKind::Direct,
            Some(v) => integrator(v, "integrator")?,
        };
        let spp = o.opt_int("spp", 1, u32::MAX as u64)?.unwrap_or(DEFAULT_SPP);

        let mut shapes = Vec::new();
        for (i, v) in o.opt_array("shapes")?.iter().enumerate() {
            shapes.push(self.shape(v, format!("shapes[{i}]"))?);
        }
        let mut emitters = Vec::new();
        let mut environment: Option<String> = None;
        for (i, v) in o.opt_array("emitters")?.iter().enumerate() {
            let path = format!("emitters[{i}]");
            let e = self.emitter(v, &path)?;
            if e.emitter.is_infinite() {
                if let Some(first) = &environment {
                    return Err(Error::field(
                        join(&path, "type"),
                        format!(
                            "at most one environment emitter is allowed, {first} is one already"
                        ),
                    ));
                }
                environment = Some(path);
            }
            emitters.push(e);
        }
        Ok(ParsedScene {
            camera,
            integrator,
            spp,
            shapes,
            emitters,
        })
    }

    fn shape(&mut self, v: &Value, path: String) -> Result<ParsedShape> {
        let o = Obj::new(v, path, &["name", "sdf", "bsdf", "translate"])?;
        let name = o.string("name")?;
        self.name(name, o.at("name"))?;
        // Transforms keep the sine and cosine of their angles, computed once the whole tree is read.
        let sdf = self.sdf(o.req("sdf")?, &o.at("sdf"))?.refreshed();
        self.bsdf_nodes = 0;
        self.textures.clear();
        let bsdf = self.bsdf(o.req("bsdf")?, &o.at("bsdf"))?;
        let textures = material_textures(&bsdf, name, std::mem::take(&mut self.textures));
        let translate = o.opt_vec3("translate")?.unwrap_or(Vec3::ZERO);
        Ok((name.to_string(), sdf, bsdf, translate, textures))
    }

    fn sdf(&mut self, v: &Value, path: &str) -> Result<Sdf> {
        let kind = kind_of::<Sdf>(v, path)?;
        // Every node accepts "type" and "name" besides its own fields.
        let o = Obj::new(v, path.to_string(), &keys(kind, &["type", "name"]))?;
        let name = o.opt_string("name")?;
        if let Some(name) = name {
            self.name(name, o.at("name"))?;
        }
        let mut node = (kind.blank)();
        self.fields(kind, &o, &mut node, Self::sdf)?;
        // The name is kept (as a wrapper that delegates everything) because parameter names key on it.
        Ok(match name {
            Some(name) => Sdf::named(name, node),
            None => node,
        })
    }

    fn emitter(&mut self, v: &Value, path: &str) -> Result<NamedEmitter> {
        let kind = kind_of::<Emitter>(v, path)?;
        let o = Obj::new(v, path.to_string(), &keys(kind, &["type", "name"]))?;
        let name = o.string("name")?;
        self.name(name, o.at("name"))?;
        let mut emitter = (kind.blank)();
        self.fields(kind, &o, &mut emitter, |_, _, _| {
            unreachable!("emitters have no child nodes")
        })?;
        Ok(NamedEmitter {
            name: name.to_string(),
            emitter,
        })
    }

    fn bsdf(&mut self, v: &Value, path: &str) -> Result<Bsdf> {
        let kind = kind_of::<Bsdf>(v, path)?;
        let node = self.bsdf_nodes;
        self.bsdf_nodes += 1;
        // A field given as a volume texture: the texture is read here, and a valid constant (its
        // first texel) stands in for the field so that the declaration reads the node as usual.
        let mut with_constants = None;
        for field in kind.fields {
            let Some((key, channels, range)) = texture::textured_field(kind.type_name, field.key)
            else {
                continue;
            };
            let Some(tex @ Value::Object(_)) = v.get(key) else {
                continue;
            };
            let volume = self.volume(tex, &join(path, key), channels, range)?;
            let first = &volume.values[..channels];
            let constant = if channels == 3 {
                serde_json::json!(first)
            } else {
                serde_json::json!(first[0])
            };
            let copy = with_constants.get_or_insert_with(|| v.clone());
            copy[key] = constant;
            self.textures.push((node, key, volume));
        }
        let v = with_constants.as_ref().unwrap_or(v);
        let o = Obj::new(v, path.to_string(), &keys(kind, &["type"]))?;
        let mut bsdf = (kind.blank)();
        self.fields(kind, &o, &mut bsdf, Self::bsdf)?;
        Ok(bsdf)
    }

    /// A volume texture `{"type": "volume", "name", "file", "bbox_min", "bbox_max"}` at `path` for a
    /// field of `channels` values in `range`: the file read and checked.
    fn volume(
        &mut self,
        v: &Value,
        path: &str,
        channels: usize,
        range: (f32, f32),
    ) -> Result<Volume> {
        Obj::tag(v, path, "type", &["volume"])?;
        let o = Obj::new(
            v,
            path.to_string(),
            &["type", "name", "file", "bbox_min", "bbox_max"],
        )?;
        let name = o.string("name")?;
        self.name(name, o.at("name"))?;
        let bbox_min = o.vec3("bbox_min")?;
        let bbox_max = o.vec3("bbox_max")?;
        if !bbox_max.cmpgt(bbox_min).all() {
            return Err(Error::field(
                o.at("bbox_max"),
                format!(
                    "must exceed bbox_min {} in every component, got {}",
                    fmt3(bbox_min),
                    fmt3(bbox_max)
                ),
            ));
        }
        let file = self.base_dir.join(o.string("file")?);
        if !file.is_file() {
            return Err(Error::field(
                path,
                format!("volume file {} not found", file.display()),
            ));
        }
        let fail = |message: String| {
            Error::field(path, format!("volume file {}: {message}", file.display()))
        };
        let array = crate::io::read_npy_array(&file).map_err(|e| match e {
            Error::File { message, .. } => fail(message),
            e => fail(e.to_string()),
        })?;
        Volume::from_array(
            name,
            &array.shape,
            array.values,
            channels,
            range,
            [bbox_min, bbox_max],
        )
        .map_err(fail)
    }

    /// Reads the fields `kind` declares from `o` (its keys already checked) into `node`, in the
    /// declaration's order, then checks the node's rules. `child` reads a child node.
    fn fields<N: Family>(
        &mut self,
        kind: &Kind<N>,
        o: &Obj,
        node: &mut N,
        child: fn(&mut Self, &Value, &str) -> Result<N>,
    ) -> Result<()> {
        for field in kind.fields {
            let key = field.key;
            match &field.value {
                declare::Value::Number {
                    access, default, ..
                } => {
                    let v = match default {
                        Some(d) => o.opt_f32(key)?.unwrap_or(*d),
                        None => o.f32(key)?,
                    };
                    *(access.get_mut)(node) = Param::new(v);
                }
                declare::Value::Vector {
                    access, default, ..
                } => {
                    let v = match default {
                        Some(d) => o.opt_vec3(key)?.unwrap_or(Vec3::splat(*d)),
                        None => o.vec3(key)?,
                    };
                    *(access.get_mut)(node) = Param3::from(v);
                }
                declare::Value::Pair { access, .. } => {
                    let at = o.at(key);
                    let pair = match o.req(key)? {
                        Value::Array(a) if a.len() == 2 => [
                            number(&a[0], &format!("{at}[0]"))?,
                            number(&a[1], &format!("{at}[1]"))?,
                        ],
                        other => {
                            return Err(Error::field(
                                at,
                                format!("expected an array of 2 numbers, got {}", describe(other)),
                            ));
                        }
                    };
                    *(access.get_mut)(node) = pair.map(Param::new);
                }
                declare::Value::Direction { access, after } => {
                    *(access.get_mut)(node) = o.direction(key)?;
                    if let Some(after) = after {
                        after(node).map_err(|m| Error::field(o.at(key), m))?;
                    }
                }
                declare::Value::Fixed { access, after } => {
                    *(access.get_mut)(node) = o.vec3(key)?;
                    if let Some(after) = after {
                        after(node).map_err(|m| Error::field(o.at(key), m))?;
                    }
                }
                declare::Value::Rotation { axis, angle, .. } => {
                    let (a, degrees) = match o.get(key) {
                        None => (Vec3::Y, 0.0),
                        Some(r) => {
                            let r = Obj::new(r, o.at(key), &["axis", "angle"])?;
                            (r.direction("axis")?, r.f32("angle")?)
                        }
                    };
                    *(axis.get_mut)(node) = a;
                    *(angle.get_mut)(node) = Param::new(degrees);
                }
                declare::Value::Child(access) => {
                    *(access.get_mut)(node) = child(self, o.req(key)?, &o.at(key))?;
                }
                declare::Value::Children { access, count } => {
                    let at = o.at(key);
                    let list = o.array(key)?;
                    match count {
                        Some(n) if list.len() != *n => {
                            return Err(Error::field(
                                at,
                                format!("must hold exactly {n} nodes, got {}", list.len()),
                            ));
                        }
                        None if list.is_empty() => {
                            return Err(Error::field(
                                at,
                                "must hold at least one node, got an empty array",
                            ));
                        }
                        _ => {}
                    }
                    let children = (list.iter().enumerate())
                        .map(|(i, c)| child(self, c, &format!("{at}[{i}]")))
                        .collect::<Result<Vec<N>>>()?;
                    *(access.get_mut)(node) = children;
                }
                // Read last, once the other fields are known to be valid (a file can be large).
                declare::Value::File { .. } => {}
            }
        }
        valid(declare::violations(node, FieldPath::Json(&o.path)))?;
        for field in kind.fields {
            if let declare::Value::File { load } = &field.value {
                let key = field.key;
                let at = o.at(key);
                let file = self.base_dir.join(o.string(key)?);
                let what = kind.type_name;
                if !file.is_file() {
                    return Err(Error::field(
                        at,
                        format!("{what} file {} not found", file.display()),
                    ));
                }
                load(node, &file).map_err(|message| {
                    Error::field(at, format!("{what} file {}: {message}", file.display()))
                })?;
            }
        }
        Ok(())
    }
}

/// The textures read for material `bsdf` of shape `shape` as [`MaterialTexture`]s, each with its
/// field's parameter prefix (the material's nodes in the order of [`declare::walk`], the order they
/// were read in).
fn material_textures(
    bsdf: &Bsdf,
    shape: &str,
    read: Vec<(usize, &'static str, Volume)>,
) -> Vec<MaterialTexture> {
    let mut prefixes = Vec::new();
    declare::walk(bsdf, shape, &mut |prefix, _| {
        prefixes.push(prefix.to_string())
    });
    read.into_iter()
        .map(|(node, key, volume)| MaterialTexture {
            node,
            key,
            field: format!("{}.{key}", prefixes[node]),
            volume,
        })
        .collect()
}

/// The kind named by the `type` of node `v` (an object), or an error listing the family's types.
fn kind_of<N: Family>(v: &Value, path: &str) -> Result<&'static Kind<N>> {
    let ty = Obj::tag(v, path, "type", &declare::type_names::<N>())?;
    Ok(declare::kind_named::<N>(ty).expect("tag checked against the family's types"))
}

/// The keys a node of `kind` accepts: `common` and its fields'.
fn keys<N>(kind: &Kind<N>, common: &[&'static str]) -> Vec<&'static str> {
    (common.iter().copied())
        .chain(kind.fields.iter().map(|f| f.key))
        .collect()
}

fn camera(v: &Value, path: &str) -> Result<Camera> {
    let o = Obj::new(
        v,
        path.to_string(),
        &[
            "origin", "target", "up", "fov_y", "width", "height", "filter",
        ],
    )?;
    let origin = o.vec3("origin")?;
    let target = o.vec3("target")?;
    let up = o.direction("up")?;
    let view = (target - origin).try_normalize().ok_or_else(|| {
        Error::field(
            o.at("target"),
            format!("must differ from origin, got {}", fmt3(target)),
        )
    })?;
    if view.cross(up).length() < 1e-4 {
        return Err(Error::field(
            o.at("up"),
            format!(
                "must not be parallel to the view direction {}, got {}",
                fmt3(view),
                fmt3(up)
            ),
        ));
    }
    let fov_y = o.f32("fov_y")?;
    if !(fov_y > 0.0 && fov_y < 180.0) {
        return Err(Error::field(
            o.at("fov_y"),
            format!("must be in (0, 180) degrees, got {fov_y}"),
        ));
    }
    let side = |key: &str| -> Result<u32> {
        o.opt_int(key, 1, MAX_IMAGE_SIDE)?
            .ok_or_else(|| Error::field(o.at(key), "missing"))
    };
    let width = side("width")?;
    let height = side("height")?;
    let filter = match o.opt_string("filter")? {
        None => Filter::default(),
        Some("tent") => Filter::Tent,
        Some("gaussian") => Filter::Gaussian,
        Some("box") => Filter::Box,
        Some(other) => {
            return Err(Error::field(
                o.at("filter"),
                format!(
                    "unknown filter {other:?}, expected one of {}",
                    FILTERS.join(", ")
                ),
            ));
        }
    };
    let camera = Camera::new(origin, target, up, fov_y, width, height, filter);
    // The checks above name the fields; this catches anything the camera needs that they missed.
    camera.validate().map_err(|e| match e {
        Error::Field { field, message } => Error::field(join(path, &field), message),
        e => e,
    })?;
    Ok(camera)
}

fn integrator(v: &Value, path: &str) -> Result<IntegratorKind> {
    let ty = Obj::tag(v, path, "type", INTEGRATOR_TYPES)?;
    Ok(match ty {
        "direct" => {
            Obj::new(v, path.to_string(), &["type"])?;
            IntegratorKind::Direct
        }
        "path" => {
            let o = Obj::new(v, path.to_string(), &["type", "max_depth"])?;
            let max_depth = o
                .opt_int("max_depth", 1, 1024)?
                .unwrap_or(DEFAULT_MAX_DEPTH);
            IntegratorKind::Path { max_depth }
        }
        _ => unreachable!("tag checked against INTEGRATOR_TYPES"),
    })
}
