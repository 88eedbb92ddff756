//! The optimisation file `OPT.json` of `implicit-psdr optimize` (docs/inverse-rendering.md), parsed strictly
//! as scene files are: unknown fields, wrong types and out-of-range values are errors that name the file
//! and the field (`opt.json: views_per_iteration: must be <= 2 (the number of views), got 3`); paths
//! resolve against the file's folder. Everything that can be checked before rendering is checked here:
//! the scenes load, the views are valid cameras, the target images exist, are readable and have the
//! scene's image size, and the parameters and grids to optimise exist.

use super::{AdamOptions, Decay, ResolutionPower, Settings, Terms, View, orbit};
use crate::error::{Error, Result};
use crate::film::Image;
use crate::integrator::{BoundaryBudget, Loss};
use crate::io::json::StrictValue;
use crate::io::read_exr_rgb;
use crate::scene::json::{Obj, describe, number};
use crate::scene::{self, Scene};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Samples per pixel per view per iteration when `spp` is absent.
pub const DEFAULT_SPP: u32 = 16;
/// Adam's step size for named parameters when `learning_rate` is absent.
pub const DEFAULT_LEARNING_RATE: f32 = 0.01;
/// Adam's step size for grid values (scene units, at the starting resolution and iteration 0) when
/// `learning_rate` is absent.
pub const DEFAULT_LEARNING_RATE_GRIDS: f32 = 0.04;
/// The learning rate's decay when `learning_rate_decay` is absent: geometric, whose lower rates from
/// the middle of a run on bring the shape closer to the floor its gradients' noise sets
/// (docs/inverse-rendering.md, "The decay's shape").
pub const DEFAULT_DECAY: Decay = Decay::Exponential {
    final_fraction: DEFAULT_LEARNING_RATE_FINAL,
};
/// The fraction of the learning rate left at the last iteration when `learning_rate_final` is absent.
pub const DEFAULT_LEARNING_RATE_FINAL: f32 = 0.1;
/// How grid steps follow the lattice spacing when `learning_rate_resolution` is absent or `true`
/// ([`ResolutionPower`]): the power 1.
pub const DEFAULT_LEARNING_RATE_RESOLUTION: ResolutionPower = ResolutionPower::Fixed(1.0);
/// Iterations of the learning rate's ramp after each refinement when `learning_rate_warmup` is
/// absent.
pub const DEFAULT_LEARNING_RATE_WARMUP: u32 = 5;
/// The moving average's weight on the past when `ema` is absent.
pub const DEFAULT_EMA: f32 = 0.9;
/// The per-entry gradient clamp (in running RMS of the entry) when `gradient_clamp` is absent.
pub const DEFAULT_GRADIENT_CLAMP: Option<f64> = None;
/// Levels of the loss's image pyramid when `loss_scales` is absent.
pub const DEFAULT_LOSS_SCALES: u32 = 1;
/// Redistancing period of the optimised grids when `redistance_every` is absent.
pub const DEFAULT_REDISTANCE_EVERY: Option<u32> = Some(1);
/// The secondary (shadow) term's boundary samples per pixel, as a fraction of `spp`, when
/// `spp_secondary` is absent: a quarter of a sample per pixel at 16 spp. On the race's and the
/// bunny's shapes at 61³ that term is 0.06% and 1.5% of the gradient's variance at `diff`'s
/// default (`spp/8`) but a quarter of an iteration's time (docs/inverse-rendering.md).
pub const DEFAULT_SECONDARY_SHARE: f32 = 1.0 / 64.0;
/// Samples per pixel of targets rendered from a scene when `target_spp` is absent.
pub const DEFAULT_TARGET_SPP: u32 = 256;
/// Most views an orbit may generate (a guard against typos).
pub const MAX_VIEWS: u64 = 4096;

/// The fields of `OPT.json`.
const FIELDS: &[&str] = &[
    "description",
    "scene",
    "target",
    "views",
    "optimize",
    "iterations",
    "spp",
    "loss",
    "learning_rate",
    "learning_rate_decay",
    "learning_rate_final",
    "learning_rate_resolution",
    "learning_rate_warmup",
    "adam",
    "gradient_clamp",
    "ema",
    "loss_scales",
    "image_scale",
    "views_per_iteration",
    "seed",
    "target_spp",
    "snapshot_every",
    "upsample_at",
    "redistance_every",
    "laplacian",
    "terms",
    "spp_primary",
    "spp_secondary",
    "reference_mesh",
];
const LOSSES: &[&str] = &["l2", "l1"];
const TERMS: &[&str] = &["complete", "interior"];
const DECAYS: &[&str] = &["none", "cosine", "exponential"];

/// What the optimisation should match.
#[derive(Clone, Debug)]
pub enum Target {
    /// Images rendered from a scene with the same views, at [`OptimizeConfig::target_spp`].
    Scene {
        /// The target scene file.
        path: PathBuf,
        /// The target scene.
        scene: Box<Scene>,
    },
    /// One image per view, in the order of the views (read and checked).
    Images {
        /// The EXR files.
        paths: Vec<PathBuf>,
        /// Their images, of the scene's size.
        images: Vec<Image>,
    },
}

/// A checked `OPT.json`: the starting scene, the views, the target and the settings.
#[derive(Clone, Debug)]
pub struct OptimizeConfig {
    /// The `OPT.json` file.
    pub path: PathBuf,
    /// The starting scene's file.
    pub scene_path: PathBuf,
    /// The starting scene's JSON document (to write the result back with
    /// [`crate::scene::patch::patched_scene_json`]).
    pub scene_json: Value,
    /// The starting scene.
    pub scene: Scene,
    /// The target.
    pub target: Target,
    /// The views.
    pub views: Vec<View>,
    /// The library's settings (grid nodes as [`Scene::grid_blocks`] names them).
    pub settings: Settings,
    /// Samples per pixel of targets rendered from a scene.
    pub target_spp: u32,
    /// Write a snapshot of the views every this many iterations (`None`: only at the end).
    pub snapshot_every: Option<u32>,
    /// The mesh that the optimised shapes are measured against every iteration (`reference_mesh`).
    pub reference_mesh: Option<ReferenceMesh>,
}

/// `reference_mesh`: a triangle mesh in the scene's coordinates, read and checked.
#[derive(Clone, Debug)]
pub struct ReferenceMesh {
    /// The file.
    pub path: PathBuf,
    /// Its triangles.
    pub mesh: crate::mesh::TriangleMesh,
}

impl OptimizeConfig {
    /// What cannot show in any of the run's views ([`Scene::reach_warnings_in_views`]), one line each:
    /// shapes outside every view, rectangle emitters that light nothing any view sees. A view whose
    /// camera is invalid is left to the run's own error.
    pub fn reach_warnings(&self) -> Vec<String> {
        let views: Vec<Scene> = (self.views.iter())
            .filter_map(|v| v.apply(&self.scene).ok())
            .collect();
        if views.is_empty() {
            return Vec::new();
        }
        self.scene.reach_warnings_in_views(&views)
    }

    /// Reads and checks `OPT.json` (and the scenes and images it names). Errors are one line naming the
    /// file and the field: `opt.json: optimize.params[0]: no parameter "ball.radus"; did you mean
    /// ball.radius? ...`; an error inside a scene file names that file and its field.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::file(path, e))?;
        // A bare file name has the empty parent: names resolve against the current folder as given.
        let base_dir = path.parent().unwrap_or(Path::new(""));
        let StrictValue(root) = serde_json::from_str(&text).map_err(|e| Error::file(path, e))?;
        Self::from_value(&root, base_dir, path)
    }

    /// Checks the document of an `OPT.json` that is not a file (a Python dict, say): its file names
    /// resolve against `base_dir`, and `name` stands for the file in errors (`name: iterations: must
    /// be >= 1, got 0`) and as [`OptimizeConfig::path`].
    pub fn from_value(root: &Value, base_dir: &Path, name: &Path) -> Result<Self> {
        parse(root, base_dir, name).map_err(|e| match e {
            Error::Field { field, message } => Error::file(name, format!("{field}: {message}")),
            e => e,
        })
    }
}

/// Parses the document `root` of `OPT.json` (read from `path`, whose folder is `base_dir`). Errors
/// about its own fields are field errors; errors inside a scene or an image name that file.
fn parse(root: &Value, base_dir: &Path, path: &Path) -> Result<OptimizeConfig> {
    if !root.is_object() {
        return Err(Error::file(
            path,
            format!("expected a JSON object, got {}", describe(root)),
        ));
    }
    let o = Obj::new(root, String::new(), FIELDS)?;
    o.opt_string("description")?;
    for key in ["scene", "target", "views", "optimize", "iterations"] {
        o.req(key)?;
    }

    let scene_path = file(&o, "scene", base_dir)?;
    let (scene, scene_json) = load_scene(&scene_path)?;
    let views = views(o.req("views")?, &scene)?;
    let target = target(&o, base_dir, &scene, views.len())?;
    let (params, grids) = selection(o.req("optimize")?, &scene)?;

    let iterations = o
        .opt_int("iterations", 1, u32::MAX as u64)?
        .expect("checked above");
    let spp = o.opt_int("spp", 1, u32::MAX as u64)?.unwrap_or(DEFAULT_SPP);
    let loss = match choice(&o, "loss", LOSSES)? {
        None | Some("l2") => Loss::L2,
        Some(_) => Loss::L1,
    };
    let (learning_rate_grids, learning_rate_params) = learning_rates(&o)?;
    let learning_rate_decay = decay(&o)?;
    let learning_rate_resolution = match o.get("learning_rate_resolution") {
        None => DEFAULT_LEARNING_RATE_RESOLUTION,
        Some(Value::String(s)) if s == "auto" => ResolutionPower::Auto,
        Some(Value::Bool(true)) => DEFAULT_LEARNING_RATE_RESOLUTION,
        Some(Value::Bool(false)) => ResolutionPower::Fixed(0.0),
        Some(v) => match v.as_f64() {
            Some(p) if (0.0..=8.0).contains(&p) => ResolutionPower::Fixed(p as f32),
            _ => {
                return Err(Error::field(
                    o.at("learning_rate_resolution"),
                    format!(
                        "expected \"auto\", true, false or a power in [0, 8], got {}",
                        describe(v)
                    ),
                ));
            }
        },
    };
    let learning_rate_warmup = o
        .opt_int("learning_rate_warmup", 0, u32::MAX as u64)?
        .unwrap_or(DEFAULT_LEARNING_RATE_WARMUP);
    let adam = adam_options(&o)?;
    let ema = match o.opt_f32("ema")? {
        None => DEFAULT_EMA,
        Some(b) if (0.0..1.0).contains(&b) => b,
        Some(b) => {
            return Err(Error::field(
                o.at("ema"),
                format!("must be in [0, 1), got {b}"),
            ));
        }
    };
    let loss_scales = o
        .opt_int("loss_scales", 1, 16)?
        .unwrap_or(DEFAULT_LOSS_SCALES);
    let views_per_iteration = match o.opt_int("views_per_iteration", 1, u32::MAX as u64)? {
        Some(k) if k as usize > views.len() => {
            return Err(Error::field(
                o.at("views_per_iteration"),
                format!("must be <= {} (the number of views), got {k}", views.len()),
            ));
        }
        k => k.map(|k| k as usize),
    };
    let seed = seed(&o)?;
    let target_spp = (o.opt_int("target_spp", 1, u32::MAX as u64)?).unwrap_or(DEFAULT_TARGET_SPP);
    let snapshot_every = o.opt_int("snapshot_every", 1, u32::MAX as u64)?;
    let terms = match choice(&o, "terms", TERMS)? {
        None | Some("complete") => Terms::Complete,
        Some(_) => Terms::Interior,
    };
    let boundary = BoundaryBudget {
        primary_spp: budget(&o, "spp_primary")?,
        secondary_spp: Some(
            budget(&o, "spp_secondary")?.unwrap_or(spp as f32 * DEFAULT_SECONDARY_SHARE),
        ),
    };

    // Grid options: only with grids to optimise.
    let upsample_at = upsample_at(&o, iterations)?;
    let redistance_every = match o.get("redistance_every") {
        None => DEFAULT_REDISTANCE_EVERY,
        Some(_) => o
            .opt_int("redistance_every", 0, u32::MAX as u64)?
            .filter(|&k| k > 0),
    };
    let laplacian = match o.opt_f32("laplacian")? {
        None => 0.0,
        Some(w) if w >= 0.0 => w,
        Some(w) => {
            return Err(Error::field(
                o.at("laplacian"),
                format!("must be >= 0, got {w}"),
            ));
        }
    };
    let image_scale = super::resolution::parse(
        &o,
        upsample_at.len() + 1,
        !grids.is_empty(),
        super::resolution::default_scale(&scene, &grids),
        (scene.camera.width, scene.camera.height),
    )?;
    if grids.is_empty() {
        let set = [
            ("upsample_at", !upsample_at.is_empty()),
            ("redistance_every", o.get("redistance_every").is_some()),
            (
                "learning_rate_resolution",
                o.get("learning_rate_resolution").is_some(),
            ),
            ("laplacian", laplacian != 0.0),
            (
                "learning_rate_warmup",
                o.get("learning_rate_warmup").is_some(),
            ),
        ];
        if let Some((key, _)) = set.iter().find(|(_, s)| *s) {
            return Err(Error::field(
                *key,
                "is a grid option, but optimize.grids names no grid",
            ));
        }
    }

    let reference_mesh = match o.get("reference_mesh") {
        None => None,
        Some(v) => {
            let field = o.at("reference_mesh");
            let path = file_at(v, &field, base_dir)?;
            let mesh =
                crate::io::read_mesh(&path).map_err(|e| Error::field(&field, e.to_string()))?;
            if super::optimized_shapes(&scene, &params, &grids).is_empty() {
                return Err(Error::field(
                    field,
                    "the optimisation changes no shape (optimize names no grid and no parameter \
                     of a shape) to measure against the mesh",
                ));
            }
            Some(ReferenceMesh { path, mesh })
        }
    };

    let config = OptimizeConfig {
        path: path.to_path_buf(),
        scene_path,
        scene_json,
        scene,
        target,
        views,
        settings: Settings {
            params,
            grids,
            iterations,
            spp,
            loss,
            learning_rate_grids,
            learning_rate_params,
            learning_rate_decay,
            learning_rate_resolution,
            learning_rate_warmup,
            adam,
            ema,
            loss_scales,
            image_scale,
            views_per_iteration,
            seed,
            terms,
            boundary,
            upsample_at,
            redistance_every,
            laplacian,
        },
        target_spp,
        snapshot_every,
        reference_mesh,
    };
    Ok(config)
}

/// The boundary samples per pixel in field `key` of `o`, if present: a finite number ≥ 0.
fn budget(o: &Obj, key: &str) -> Result<Option<f32>> {
    match o.opt_f32(key)? {
        Some(r) if !(r.is_finite() && r >= 0.0) => Err(Error::field(
            o.at(key),
            format!("must be a finite number >= 0, got {r}"),
        )),
        r => Ok(r),
    }
}

/// The file named by string field `key` of `o`, resolved against `base_dir`; it must exist.
fn file(o: &Obj, key: &str, base_dir: &Path) -> Result<PathBuf> {
    file_at(o.req(key)?, &o.at(key), base_dir)
}

/// The file named by the string `v` (at field `field`), resolved against `base_dir`; it must exist.
fn file_at(v: &Value, field: &str, base_dir: &Path) -> Result<PathBuf> {
    let Value::String(name) = v else {
        return Err(Error::field(
            field,
            format!("expected a file name, got {}", describe(v)),
        ));
    };
    if name.is_empty() {
        return Err(Error::field(field, "expected a file name, got \"\""));
    }
    let path = base_dir.join(name);
    if !path.is_file() {
        return Err(Error::field(
            field,
            format!("file {} not found", path.display()),
        ));
    }
    Ok(path)
}

/// A scene and its JSON document; errors name the scene file.
fn load_scene(path: &Path) -> Result<(Scene, Value)> {
    let in_file = |e| match e {
        Error::Field { field, message } => Error::file(path, format!("{field}: {message}")),
        e => e,
    };
    let scene = scene::load(path).map_err(in_file)?;
    let text = std::fs::read_to_string(path).map_err(|e| Error::file(path, e))?;
    let json = serde_json::from_str(&text).map_err(|e| Error::file(path, e))?;
    Ok((scene, json))
}

/// String field `key`, one of `options` (absent: `None`).
fn choice<'a>(o: &Obj<'a>, key: &str, options: &[&str]) -> Result<Option<&'a str>> {
    match o.opt_string(key)? {
        Some(s) if !options.contains(&s) => Err(Error::field(
            o.at(key),
            format!(
                "unknown {key} {s:?}, expected one of {}",
                options.join(", ")
            ),
        )),
        s => Ok(s),
    }
}

/// A finite number > 0 at `field`.
fn positive(v: &Value, field: &str) -> Result<f32> {
    let x = number(v, field)?;
    if x > 0.0 {
        Ok(x)
    } else {
        Err(Error::field(field, format!("must be > 0, got {x}")))
    }
}

/// `learning_rate`: one number for both, or `{"grids": x, "params": y}` (each defaults to
/// [`DEFAULT_LEARNING_RATE_GRIDS`] and [`DEFAULT_LEARNING_RATE`]). Returns `(grids, params)`.
fn learning_rates(o: &Obj) -> Result<(f32, f32)> {
    let field = o.at("learning_rate");
    match o.get("learning_rate") {
        None => Ok((DEFAULT_LEARNING_RATE_GRIDS, DEFAULT_LEARNING_RATE)),
        Some(v @ Value::Number(_)) => {
            let x = positive(v, &field)?;
            Ok((x, x))
        }
        Some(v @ Value::Object(_)) => {
            let r = Obj::new(v, field, &["grids", "params"])?;
            let rate = |key: &str, default: f32| {
                r.get(key).map_or(Ok(default), |v| positive(v, &r.at(key)))
            };
            Ok((
                rate("grids", DEFAULT_LEARNING_RATE_GRIDS)?,
                rate("params", DEFAULT_LEARNING_RATE)?,
            ))
        }
        Some(v) => Err(Error::field(
            field,
            format!(
                "expected a number or an object {{\"grids\": x, \"params\": y}}, got {}",
                describe(v)
            ),
        )),
    }
}

/// `learning_rate_decay` (`"none"`, `"cosine"` or `"exponential"`) and `learning_rate_final` (the
/// fraction of the rate left at the last iteration, in `(0, 1]`).
fn decay(o: &Obj) -> Result<Decay> {
    let final_fraction = match o.opt_f32("learning_rate_final")? {
        None => DEFAULT_LEARNING_RATE_FINAL,
        Some(f) if f > 0.0 && f <= 1.0 => f,
        Some(f) => {
            return Err(Error::field(
                o.at("learning_rate_final"),
                format!("must be in (0, 1], got {f}"),
            ));
        }
    };
    Ok(match choice(o, "learning_rate_decay", DECAYS)? {
        None => match DEFAULT_DECAY {
            Decay::None => Decay::None,
            Decay::Cosine { .. } => Decay::Cosine { final_fraction },
            Decay::Exponential { .. } => Decay::Exponential { final_fraction },
        },
        Some("none") => Decay::None,
        Some("cosine") => Decay::Cosine { final_fraction },
        Some(_) => Decay::Exponential { final_fraction },
    })
}

/// `adam` (`{"beta1": b1, "beta2": b2, "epsilon": e}`, each optional) and `gradient_clamp` (a number
/// > 0, or 0 for none).
fn adam_options(o: &Obj) -> Result<AdamOptions> {
    let mut options = AdamOptions {
        clamp: DEFAULT_GRADIENT_CLAMP,
        ..AdamOptions::default()
    };
    match o.opt_f32("gradient_clamp")? {
        None => {}
        Some(0.0) => options.clamp = None,
        Some(k) if k > 0.0 => options.clamp = Some(k as f64),
        Some(k) => {
            return Err(Error::field(
                o.at("gradient_clamp"),
                format!("must be >= 0, got {k}"),
            ));
        }
    }
    let Some(v) = o.get("adam") else {
        return Ok(options);
    };
    let a = Obj::new(v, o.at("adam"), &["beta1", "beta2", "epsilon"])?;
    for (key, slot) in [("beta1", &mut options.beta1), ("beta2", &mut options.beta2)] {
        match a.opt_f32(key)? {
            None => {}
            Some(b) if (0.0..1.0).contains(&b) => *slot = b as f64,
            Some(b) => {
                return Err(Error::field(
                    a.at(key),
                    format!("must be in [0, 1), got {b}"),
                ));
            }
        }
    }
    if let Some(v) = a.get("epsilon") {
        options.epsilon = positive(v, &a.at("epsilon"))? as f64;
    }
    Ok(options)
}

/// `seed`: an integer in `[0, 2^64)` (default 0).
fn seed(o: &Obj) -> Result<u64> {
    match o.get("seed") {
        None => Ok(0),
        Some(Value::Number(n)) => n.as_u64().ok_or_else(|| {
            Error::field(
                o.at("seed"),
                format!("must be an integer in [0, 2^64), got {n}"),
            )
        }),
        Some(v) => Err(Error::field(
            o.at("seed"),
            format!("expected an integer, got {}", describe(v)),
        )),
    }
}

/// `upsample_at`: increasing iterations in `[1, iterations − 1]` (default none).
fn upsample_at(o: &Obj, iterations: u32) -> Result<Vec<u32>> {
    let field = o.at("upsample_at");
    let mut out: Vec<u32> = Vec::new();
    for (i, v) in o.opt_array("upsample_at")?.iter().enumerate() {
        let at = format!("{field}[{i}]");
        let k = match v {
            Value::Number(n) => n.as_u64(),
            _ => None,
        };
        let Some(k) = k else {
            return Err(Error::field(
                at,
                format!(
                    "expected an iteration (an integer >= 1), got {}",
                    describe(v)
                ),
            ));
        };
        if k < 1 || k >= iterations as u64 {
            return Err(Error::field(
                at,
                format!(
                    "must be an iteration in [1, {}] (iterations is {iterations}), got {k}",
                    iterations.saturating_sub(1)
                ),
            ));
        }
        if let Some(&last) = out.last()
            && k <= last as u64
        {
            return Err(Error::field(
                at,
                format!("must be increasing, got {k} after {last}"),
            ));
        }
        out.push(k as u32);
    }
    Ok(out)
}

/// `views`: a list of cameras or `{"orbit": {...}}`, each checked against the scene's film.
fn views(v: &Value, scene: &Scene) -> Result<Vec<View>> {
    let field = "views";
    let camera = &scene.camera;
    let views = match v {
        Value::Array(list) => {
            if list.is_empty() {
                return Err(Error::field(
                    field,
                    "must hold at least one view, got an empty array",
                ));
            }
            let mut views = Vec::with_capacity(list.len());
            for (i, item) in list.iter().enumerate() {
                let path = format!("{field}[{i}]");
                let c = Obj::new(item, path.clone(), &["origin", "target", "up", "fov_y"])?;
                let view = View {
                    origin: c.vec3("origin")?,
                    target: c.vec3("target")?,
                    up: match c.get("up") {
                        Some(_) => c.direction("up")?,
                        None => camera.up.value(),
                    },
                    fov_y: c.opt_f32("fov_y")?.unwrap_or(camera.fov_y.value),
                };
                check_view(&view, scene, &path)?;
                views.push(view);
            }
            views
        }
        Value::Object(_) => {
            let g = Obj::new(v, field.into(), &["orbit"])?;
            let o = Obj::new(
                g.req("orbit")?,
                g.at("orbit"),
                &["count", "radius", "height", "look_at", "fov_y"],
            )?;
            let count = o
                .opt_int("count", 1, MAX_VIEWS)?
                .ok_or_else(|| Error::field(o.at("count"), "missing"))?;
            let radius = positive(o.req("radius")?, &o.at("radius"))?;
            let heights = match o.get("height") {
                None => vec![0.0],
                Some(Value::Array(list)) if !list.is_empty() => (list.iter().enumerate())
                    .map(|(k, h)| number(h, &format!("{}[{k}]", o.at("height"))))
                    .collect::<Result<Vec<f32>>>()?,
                Some(Value::Array(_)) => {
                    return Err(Error::field(o.at("height"), "an empty list of heights"));
                }
                Some(h) => vec![number(h, &o.at("height"))?],
            };
            let look_at = o.opt_vec3("look_at")?.unwrap_or(glam::Vec3::ZERO);
            let fov_y = o.opt_f32("fov_y")?.unwrap_or(camera.fov_y.value);
            let views = orbit(count as usize, radius, &heights, look_at, fov_y);
            for (k, view) in views.iter().enumerate() {
                check_view(view, scene, &format!("{} (view {k})", o.path))?;
            }
            views
        }
        other => {
            return Err(Error::field(
                field,
                format!(
                    "expected a list of cameras or {{\"orbit\": {{...}}}}, got {}",
                    describe(other)
                ),
            ));
        }
    };
    Ok(views)
}

/// Checks that `view` is a valid camera for the scene's film; errors name `path` and the field.
fn check_view(view: &View, scene: &Scene, path: &str) -> Result<()> {
    view.apply(scene).map(|_| ()).map_err(|e| match e {
        Error::Field { field, message } => Error::field(format!("{path}.{field}"), message),
        e => e,
    })
}

/// `target`: `{"scene": FILE}` or `{"images": [FILE, ...]}` (one per view, of the scene's size).
fn target(o: &Obj, base_dir: &Path, scene: &Scene, views: usize) -> Result<Target> {
    let t = Obj::new(o.req("target")?, o.at("target"), &["scene", "images"])?;
    let size = (scene.camera.width, scene.camera.height);
    match (t.get("scene"), t.get("images")) {
        (Some(_), None) => {
            let path = file(&t, "scene", base_dir)?;
            let (target, _) = load_scene(&path)?;
            let got = (target.camera.width, target.camera.height);
            if got != size {
                return Err(Error::field(
                    t.at("scene"),
                    format!(
                        "{}: its image is {}x{}, the scene's {}x{} (the targets must have the \
                         scene's size)",
                        path.display(),
                        got.0,
                        got.1,
                        size.0,
                        size.1
                    ),
                ));
            }
            Ok(Target::Scene {
                path,
                scene: Box::new(target),
            })
        }
        (None, Some(_)) => {
            let list = t.array("images")?;
            if list.len() != views {
                return Err(Error::field(
                    t.at("images"),
                    format!(
                        "{} image{} for {views} view{} (one per view, in the order of views)",
                        list.len(),
                        if list.len() == 1 { "" } else { "s" },
                        if views == 1 { "" } else { "s" },
                    ),
                ));
            }
            let mut paths = Vec::with_capacity(list.len());
            let mut images = Vec::with_capacity(list.len());
            for (k, v) in list.iter().enumerate() {
                let field = format!("{}[{k}]", t.at("images"));
                let path = file_at(v, &field, base_dir)?;
                let image = read_exr_rgb(&path).map_err(|e| {
                    let message = match e {
                        Error::File { message, .. } => message,
                        e => e.to_string(),
                    };
                    Error::field(&field, format!("{}: {message}", path.display()))
                })?;
                if (image.width, image.height) != size {
                    return Err(Error::field(
                        field,
                        format!(
                            "{} is {}x{}, the scene's image {}x{}",
                            path.display(),
                            image.width,
                            image.height,
                            size.0,
                            size.1
                        ),
                    ));
                }
                paths.push(path);
                images.push(image);
            }
            Ok(Target::Images { paths, images })
        }
        _ => Err(Error::field(
            o.at("target"),
            "expected exactly one of {\"scene\": FILE} or {\"images\": [FILE, ...]}",
        )),
    }
}

/// `optimize`: `{"grids": [NODE, ...], "params": [NAME, ...]}`, each known to the scene and given once,
/// at least one in all. Grids may be named `NODE` or `NODE.values`; they are returned as `NODE`.
fn selection(v: &Value, scene: &Scene) -> Result<(Vec<String>, Vec<String>)> {
    let o = Obj::new(v, "optimize".into(), &["grids", "params"])?;
    let strings = |key: &str| -> Result<Vec<(String, String)>> {
        let mut out: Vec<(String, String)> = Vec::new();
        for (i, v) in o.opt_array(key)?.iter().enumerate() {
            let field = format!("{}[{i}]", o.at(key));
            let Value::String(s) = v else {
                return Err(Error::field(
                    field,
                    format!("expected a string, got {}", describe(v)),
                ));
            };
            out.push((field, s.clone()));
        }
        Ok(out)
    };
    // The library names its own options (`--param`, `--grid`) in these errors: name the field instead.
    let at = |field: &str| {
        let field = field.to_string();
        move |e: Error| match e {
            Error::Field { message, .. } => Error::field(field.clone(), message),
            e => e,
        }
    };
    let mut params: Vec<String> = Vec::new();
    for (field, name) in strings("params")? {
        scene.parameter(&name).map_err(at(&field))?;
        if params.contains(&name) {
            return Err(Error::field(
                field,
                format!("parameter {name:?} is given twice"),
            ));
        }
        params.push(name);
    }
    let blocks = scene.blocks();
    let mut grids: Vec<String> = Vec::new();
    for (field, name) in strings("grids")? {
        let node = (blocks.iter().find(|b| b.name == name)).map_or(name, |b| b.node.clone());
        scene.block_values(&node).map_err(at(&field))?;
        if grids.contains(&node) {
            return Err(Error::field(field, format!("grid {node:?} is given twice")));
        }
        grids.push(node);
    }
    if params.is_empty() && grids.is_empty() {
        return Err(Error::field(
            "optimize",
            "nothing to optimise: name grids or params",
        ));
    }
    Ok((params, grids))
}
