//! The `params` command: every parameter of a scene with its value, and each grid's block of values.

use crate::cli::{load_scene, write_stdout};
use crate::scene::{ParameterEntry, Scene};
use anyhow::Result;
use std::fmt::Write as _;
use std::path::Path;

pub(crate) fn params(scene: &Path) -> Result<()> {
    write_stdout(format_args!("{}", parameter_list(&load_scene(scene)?)))
}

/// What `params` prints: every parameter as `name value`, and each grid node's values once, as
/// `NODE.values [nz, ny, nx] (N values; ...)`, after the node's `level` (or at the end), and each
/// volume texture's texels as `NAME.values [nz, ny, nx, 3]` (or `[nz, ny, nx]`) after its shape's
/// parameters, and each environment map's as `NAME.values [H, W, 3]` after its emitter's.
fn parameter_list(scene: &Scene) -> String {
    let mut out = String::new();
    for entry in scene.parameter_entries() {
        let _ = match entry {
            ParameterEntry::Value(name, value) => writeln!(out, "{name} {value}"),
            ParameterEntry::Grid(b) => {
                let node = &b.node;
                writeln!(
                    out,
                    "{} {} ({} values; select with --grid {node} or --grid-direction {node}=U.npy)",
                    b.name,
                    b.shape_text(),
                    b.len()
                )
            }
        };
    }
    out
}
