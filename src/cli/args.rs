//! The command line: subcommands, their arguments and help texts, and the parsers of argument values.

use crate::integrator::VelocityField;
use crate::integrator::{Loss, Normalization};
use crate::scene::settings;
use clap::{ArgGroup, Args, Parser, Subcommand};
use std::path::PathBuf;

/// Physically based rendering of implicit surfaces.
#[derive(Parser, Debug)]
#[command(version, about)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
}

/// The scene and how to sample it, shared by the rendering commands.
#[derive(Args, Debug)]
pub(crate) struct SceneArgs {
    /// The scene file (JSON, see docs/scene-format.md).
    pub(crate) scene: PathBuf,
    /// Samples per pixel (default: the scene's `spp`).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) spp: Option<u32>,
    /// Seed of the deterministic sampler.
    #[arg(long, default_value_t = 0)]
    pub(crate) seed: u64,
    /// Override a parameter listed by `params` (repeatable), e.g. `--set ball.radius=0.8`, or a
    /// setting: camera.width, camera.height, spp, integrator (direct or path), integrator.max_depth.
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = assignment)]
    pub(crate) set: Vec<(String, String)>,
}

/// Output files of the rendering commands; the defaults are `<command>.exr` and `<command>.png`.
#[derive(Args, Debug)]
pub(crate) struct OutputArgs {
    /// Output EXR file (`.exr`; a missing folder is created) [default: <command>.exr, e.g. out.exr for
    /// render].
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// Output PNG file (`.png`) [default: <command>.png, e.g. out.png for render].
    #[arg(long)]
    pub(crate) png: Option<PathBuf>,
}

#[derive(Subcommand, Debug)]
pub(crate) enum Command {
    /// Render a scene to an EXR (linear float32 R, G, B) and a PNG (8-bit sRGB, clamped).
    Render {
        #[command(flatten)]
        scene: SceneArgs,
        #[command(flatten)]
        outputs: OutputArgs,
    },
    /// Sample one shape's SDF, or a triangle mesh's signed distance (--mesh), over its bounds (padded)
    /// into a grid and write it as a float32 .npy of shape [nz, ny, nx].
    Bake(BakeArgs),
    /// Extract one shape's surface (a grid's at its level) as a closed triangle mesh by dual
    /// contouring (sharp edges kept sharp, vertices on the surface, normals from the gradient), in
    /// scene coordinates, to a binary PLY or an OBJ (by the extension).
    Mesh(MeshArgs),
    /// List every differentiable parameter of a scene with its value, one `name value` per line
    /// (angles in degrees, so derivatives with respect to them are per degree), and each grid node's
    /// values once, after the node's `level`, as `NODE.values [nz, ny, nx] (N values; ...)` (the
    /// names `grad --grid` and `diff --grid-direction` take: NODE, or NODE.values).
    Params {
        /// The scene file.
        scene: PathBuf,
    },
    /// Render the image and its derivatives with respect to scene parameters (forward mode) to an EXR
    /// (`R`, `G`, `B`, and `d.P.R`, `d.P.G`, `d.P.B` per parameter P) and a PNG (the image beside one
    /// colour-mapped panel per derivative).
    Diff(DiffArgs),
    /// The loss of the image against a target EXR and its gradient (reverse mode) with respect to
    /// scene parameters and grid values, to a JSON file (the loss and one number per parameter) and one
    /// float32 .npy per grid (the gradient of each value, shape [nz, ny, nx]).
    Grad(GradArgs),
    /// Central finite differences of the image with respect to parameters, with common random numbers
    /// (the same samples at P + h and P − h), to an EXR (`R`, `G`, `B`, and `d.P.R|G|B` per parameter
    /// P) and a PNG.
    Fd(FdArgs),
    /// Inverse rendering: optimise scene parameters and grid values so that renders from several
    /// views match target images, as OPT.json describes (see docs/inverse-rendering.md). Writes into
    /// --out: progress.csv, loss.png, views.png (per view: target | current), NODE.npy per optimised grid and
    /// result.json (the optimised scene).
    Optimize(OptimizeArgs),
    /// Speed against error: runs each estimator at spp 1, 2, 4, ... (two seeds per point) until its
    /// share of the budget is spent, measures each run against a reference, and writes into --out
    /// report.csv (one row per run), report.md (time to 10%, 5%, 2% blurred error, bias floors,
    /// fd / complete) and report.png + report.svg (log-log error against seconds per parameter).
    Report(ReportArgs),
    /// Compare the derivative channels of two EXR files (B is the reference): relative L2 error, raw and
    /// after a 5x5 box blur, sums, sums of absolute values and correlation.
    Compare {
        /// The EXR file to check.
        a: PathBuf,
        /// The reference EXR file.
        b: PathBuf,
        /// Compare only the channels whose names start with PREFIX (default: every channel starting
        /// with `d`).
        #[arg(long, value_name = "PREFIX")]
        channel: Option<String>,
    },
}

#[derive(Args, Debug)]
#[command(group(ArgGroup::new("source").required(true).args(["scene", "mesh"])))]
pub(crate) struct BakeArgs {
    /// The scene file holding the shape (with --shape).
    #[arg(requires = "shape")]
    pub(crate) scene: Option<PathBuf>,
    /// Name of the shape to bake.
    #[arg(long, requires = "scene")]
    pub(crate) shape: Option<String>,
    /// Bake a triangle mesh instead of a shape: its signed distance (exact distance to the
    /// triangles; inside where the generalised winding number is at least 1/2), from a .obj, .ply,
    /// .stl or .off file.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["scene", "shape"])]
    pub(crate) mesh: Option<PathBuf>,
    /// Samples along the longest edge of the box (4 to 512); the other axes get near-cubic cells.
    #[arg(long, value_parser = clap::value_parser!(u32).range(4..=512))]
    pub(crate) res: u32,
    /// Output .npy file.
    #[arg(long)]
    pub(crate) out: PathBuf,
    /// The box's margin on every side, as a fraction of the longest edge of the shape's (or mesh's)
    /// bounds (a number >= 0).
    #[arg(long, value_name = "P", default_value_t = crate::sdf::BAKE_PADDING,
          allow_negative_numbers = true, value_parser = non_negative_f32)]
    pub(crate) padding: f32,
}

#[derive(Args, Debug)]
pub(crate) struct MeshArgs {
    /// The scene file holding the shape.
    pub(crate) scene: PathBuf,
    /// Name of the shape.
    #[arg(long)]
    pub(crate) shape: String,
    /// Lattice points along the longest side of the shape's box (4 to 1024); cells are near-cubic.
    #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(4..=1024))]
    pub(crate) res: u32,
    /// Output mesh, `.ply` (binary) or `.obj` [default: SHAPE.ply].
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
}

/// How a derivative is estimated besides the samples of the image, shared by `diff` and `grad`.
#[derive(Args, Debug)]
pub(crate) struct EstimatorArgs {
    /// Boundary samples per pixel for the secondary (shadow) term, a number >= 0 that may be
    /// fractional (0.25: one sample per four pixels); 0 skips it [default: spp/8, rounded up].
    #[arg(long, allow_negative_numbers = true, value_parser = non_negative_f32)]
    pub(crate) spp_secondary: Option<f32>,
    /// Silhouette-curve samples per pixel for the primary (silhouette) term, a number >= 0 that may
    /// be fractional; 0 skips it [default: spp/32, rounded up].
    #[arg(long, allow_negative_numbers = true, value_parser = non_negative_f32)]
    pub(crate) spp_primary: Option<f32>,
    /// Pixel normalisation: `differentiable` (F / W, both differentiated: lower error) or `fixed`
    /// (the filter-weight sum is a constant).
    #[arg(long, default_value = "differentiable")]
    pub(crate) normalization: Normalization,
    /// How surface points move with the parameters (same derivative, different noise): `auto` (a
    /// shape's known motion where its curvature radius is below a pixel, e.g. a thin torus or a tight
    /// smooth union; the normal field elsewhere), `normal` (along the normal everywhere) or `carried`
    /// (the known motion wherever there is one).
    #[arg(long, default_value = "auto")]
    pub(crate) velocity_field: VelocityField,
}

#[derive(Args, Debug)]
#[command(group(ArgGroup::new("selection").required(true).multiple(true)))]
pub(crate) struct DiffArgs {
    #[command(flatten)]
    pub(crate) scene: SceneArgs,
    /// A parameter to differentiate with respect to (repeat for several; see `params`).
    #[arg(long = "param", value_name = "P", group = "selection")]
    pub(crate) params: Vec<String>,
    /// Differentiate with respect to grid NODE's values along the direction U (a float32 .npy of the
    /// grid's shape [nz, ny, nx]; repeatable): channels `d.NODE.values.R|G|B`, after the `--param`s.
    #[arg(long = "grid-direction", value_name = "NODE=U.npy", value_parser = grid_direction,
          group = "selection")]
    pub(crate) grid_directions: Vec<(String, PathBuf)>,
    /// Also write each term of the derivative (`d_interior.P.R|G|B`, `d_primary.P.R|G|B`,
    /// `d_secondary.P.R|G|B`; they sum to `d.P`).
    #[arg(long)]
    pub(crate) terms: bool,
    #[command(flatten)]
    pub(crate) estimator: EstimatorArgs,
    #[command(flatten)]
    pub(crate) outputs: OutputArgs,
}

#[derive(Args, Debug)]
#[command(group(ArgGroup::new("selection").required(true).multiple(true)))]
pub(crate) struct GradArgs {
    #[command(flatten)]
    pub(crate) scene: SceneArgs,
    /// The target image: an EXR with channels R, G, B of the scene's image size.
    #[arg(long, value_name = "T.exr")]
    pub(crate) target: PathBuf,
    /// The loss: `l2` (mean over pixels and R, G, B of (I − T)²) or `l1` (mean of |I − T|). The loss
    /// is that of the image of `--seed`; its gradient is estimated with the samples of seed + 1 (so
    /// that the two are independent).
    #[arg(long, default_value = "l2")]
    pub(crate) loss: Loss,
    /// A parameter to differentiate with respect to (repeat for several; see `params`).
    #[arg(long = "param", value_name = "P", group = "selection")]
    pub(crate) params: Vec<String>,
    /// Differentiate with respect to every value of grid node NODE (repeat for several; `params`
    /// lists them as `NODE.values`).
    #[arg(long = "grid", value_name = "NODE", group = "selection")]
    pub(crate) grids: Vec<String>,
    #[command(flatten)]
    pub(crate) estimator: EstimatorArgs,
    /// Output JSON file: `{"loss", "spp", "seed", "params": {P: dL/dP}, "grids": {NODE: FILE}}`. The
    /// gradient of grid NODE goes beside it to FILE = `<stem>.NODE.values.npy` (float32, shape
    /// [nz, ny, nx]), `<stem>` being this file's name without `.json`: `--out runs/a.json` writes
    /// runs/a.NODE.values.npy, so runs with different names never share a grid file.
    #[arg(long, value_name = "FILE.json", default_value = "grad.json")]
    pub(crate) out: PathBuf,
}

#[derive(Args, Debug)]
pub(crate) struct OptimizeArgs {
    /// The optimisation file (JSON, see docs/inverse-rendering.md); the paths in it are relative to it.
    #[arg(value_name = "OPT.json")]
    pub(crate) config: PathBuf,
    /// Output folder, created if missing. Targets rendered from a scene are cached in DIR/targets/;
    /// a previous run's files are replaced only at the end of a successful run.
    #[arg(long, value_name = "DIR", default_value = "optimize_out")]
    pub(crate) out: PathBuf,
}

#[derive(Args, Debug)]
pub(crate) struct ReportArgs {
    /// The scene file (JSON, see docs/scene-format.md).
    pub(crate) scene: PathBuf,
    /// A parameter to report on (repeat for several; see `params`).
    #[arg(long = "param", value_name = "P", required = true)]
    pub(crate) params: Vec<String>,
    /// Reference derivatives: an EXR of the scene's size with channels d.P.R, d.P.G, d.P.B for every
    /// --param P (e.g. from `diff` at high spp) [default: fd at high spp with half the default step].
    #[arg(long, value_name = "REF.exr")]
    pub(crate) reference: Option<PathBuf>,
    /// Seconds of estimator runs in all, shared evenly between the (parameter, estimator) series and
    /// the image; the references come on top.
    #[arg(long, value_name = "SECONDS", default_value_t = crate::report::DEFAULT_BUDGET,
          allow_negative_numbers = true, value_parser = positive_f64)]
    pub(crate) budget: f64,
    /// Comma-separated estimators: complete, interior, complete-boundary-x4, complete-boundary-div4,
    /// fd, primal [default: all that apply].
    #[arg(long, value_name = "LIST")]
    pub(crate) estimators: Option<String>,
    /// Output folder, created if missing; its report.* files are replaced only when all are written.
    #[arg(long, value_name = "DIR", default_value = "report")]
    pub(crate) out: PathBuf,
}

#[derive(Args, Debug)]
pub(crate) struct FdArgs {
    #[command(flatten)]
    pub(crate) scene: SceneArgs,
    /// A parameter (repeat for several, each a pair of renders with the image's samples; see
    /// `params`).
    #[arg(long = "param", value_name = "P", required = true)]
    pub(crate) params: Vec<String>,
    /// Step, a finite number > 0, for every parameter (default: 0.01 · max(|P|, 1) for each).
    #[arg(long, allow_negative_numbers = true, value_parser = positive_f32)]
    pub(crate) h: Option<f32>,
    #[command(flatten)]
    pub(crate) outputs: OutputArgs,
}

/// `NAME=VALUE`: a parameter with a finite value, or a setting with a value its field's rules judge
/// later (see [`crate::scene::settings`]).
pub(crate) fn assignment(text: &str) -> Result<(String, String), String> {
    let (name, value) = text.split_once('=').ok_or("expected NAME=VALUE")?;
    let (name, value) = (name.trim().to_string(), value.trim().to_string());
    if settings::is_setting(&name) {
        return Ok((name, value));
    }
    match value.parse::<f32>() {
        Ok(v) if v.is_finite() => Ok((name, value)),
        _ => Err(format!("{value:?} is not a finite number")),
    }
}

/// `NODE=FILE`.
pub(crate) fn grid_direction(text: &str) -> Result<(String, PathBuf), String> {
    match text.split_once('=') {
        Some((node, file)) if !node.trim().is_empty() && !file.is_empty() => {
            Ok((node.trim().to_string(), PathBuf::from(file)))
        }
        _ => Err("expected NODE=U.npy".into()),
    }
}

/// A finite number > 0, in double precision.
pub(crate) fn positive_f64(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("expected a finite number > 0, got {text:?}")),
    }
}

/// A finite number >= 0.
pub(crate) fn non_negative_f32(text: &str) -> Result<f32, String> {
    match text.parse::<f32>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("expected a finite number >= 0, got {text:?}")),
    }
}

/// A finite number > 0.
pub(crate) fn positive_f32(text: &str) -> Result<f32, String> {
    match text.parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("expected a finite number > 0, got {text:?}")),
    }
}
