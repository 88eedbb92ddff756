//! Bit-for-bit regression of the tool's outputs: the example scenes (copies frozen in
//! `tests/data/regression/`, so that editing `scenes/` does not move this test) rendered and
//! differentiated through the command line, every EXR channel hashed (FNV-1a over channel names and
//! `f32` bit patterns, zeros counted without their sign) and compared with the hashes stored in `tests/data/regression/hashes.txt`.
//!
//! A restructuring of the code must leave every hash unchanged. A change that is meant to alter
//! outputs re-blesses the file (`REGRESSION_BLESS=1 cargo test --release --test regression`) and says
//! so in its commit message.

mod common;

use common::{run, workdir};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// `(case name, arguments after the scene path)`; each case writes `out.exr` in its own folder.
const CASES: &[(&str, &str, &[&str])] = &[
    (
        "render_sphere_floor",
        "sphere_floor.json",
        &["render", "--spp", "4"],
    ),
    ("render_csg", "csg.json", &["render", "--spp", "2"]),
    (
        "render_environment",
        "environment.json",
        &["render", "--spp", "4"],
    ),
    ("render_grid", "grid.json", &["render", "--spp", "2"]),
    ("render_lights", "lights.json", &["render", "--spp", "2"]),
    (
        "diff_lights",
        "lights.json",
        &[
            "diff",
            "--terms",
            "--spp",
            "2",
            "--param",
            "ball.center.x",
            "--param",
            "bulb.position.y",
            "--param",
            "sun.direction.x",
        ],
    ),
    (
        "diff_sphere_floor",
        "sphere_floor.json",
        &[
            "diff",
            "--terms",
            "--spp",
            "8",
            "--param",
            "ball.radius",
            "--param",
            "light.center.x",
            "--param",
            "camera.fov_y",
        ],
    ),
    (
        "diff_sphere_floor_fixed",
        "sphere_floor.json",
        &[
            "diff",
            "--terms",
            "--spp",
            "4",
            "--normalization",
            "fixed",
            "--param",
            "ball.center.x",
        ],
    ),
    (
        "diff_csg_path",
        "csg.json",
        &[
            "diff",
            "--terms",
            "--spp",
            "2",
            "--param",
            "blob.k",
            "--param",
            "ring.sdf.angle",
        ],
    ),
    (
        "diff_environment",
        "environment.json",
        &[
            "diff",
            "--terms",
            "--spp",
            "4",
            "--param",
            "donut.major_radius",
            "--param",
            "sky.radiance.r",
        ],
    ),
    (
        "diff_grid",
        "grid.json",
        &[
            "diff",
            "--terms",
            "--spp",
            "4",
            "--param",
            "baked_blob.sdf.translate.x",
            "--param",
            "baked_blob.sdf.child.level",
        ],
    ),
];

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/regression")
}

/// FNV-1a (64 bit) over every channel's name and values, channels in the file's order.
fn hash_exr(path: &Path) -> u64 {
    let (w, h, channels) = implicit_psdr::film::read_exr(path).unwrap();
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    let mut eat = |bytes: &[u8]| {
        for b in bytes {
            hash ^= *b as u64;
            hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    eat(&w.to_le_bytes());
    eat(&h.to_le_bytes());
    for (name, values) in &channels {
        eat(name.as_bytes());
        for v in values {
            // +0 and −0 are the same number: a derivative read out as `a − b·c` instead of the dual
            // type's `a − (b·c + 0·d)` may flip the sign of a zero and nothing else.
            eat(&(v + 0.0).to_bits().to_le_bytes());
        }
    }
    hash
}

fn stored_hashes() -> BTreeMap<String, String> {
    let text = std::fs::read_to_string(data_dir().join("hashes.txt")).unwrap_or_default();
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .filter_map(|l| {
            let mut parts = l.split_whitespace();
            Some((parts.next()?.to_string(), parts.next()?.to_string()))
        })
        .collect()
}

#[test]
fn outputs_are_unchanged_bit_for_bit() {
    let dir = workdir("regression", "cases");
    let mut computed = BTreeMap::new();
    for (name, scene, args) in CASES {
        let scene = data_dir().join(scene);
        let mut full: Vec<&str> = vec![args[0], scene.to_str().unwrap()];
        full.extend_from_slice(&args[1..]);
        let out = format!("{name}.exr");
        let png = format!("{name}.png");
        full.extend_from_slice(&["--out", &out, "--png", &png]);
        let result = run(&dir, &full);
        assert!(
            result.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&result.stderr)
        );
        computed.insert(
            name.to_string(),
            format!("{:016x}", hash_exr(&dir.join(&out))),
        );
    }
    if std::env::var_os("REGRESSION_BLESS").is_some() {
        let mut text = String::from(
            "# FNV-1a hashes of the EXR channels of tests/regression.rs's cases (see its docs).\n",
        );
        for (name, hash) in &computed {
            text.push_str(&format!("{name} {hash}\n"));
        }
        std::fs::write(data_dir().join("hashes.txt"), text).unwrap();
        return;
    }
    let stored = stored_hashes();
    let mismatches: Vec<String> = computed
        .iter()
        .filter(|(name, hash)| stored.get(*name) != Some(hash))
        .map(|(name, hash)| format!("{name}: {hash}, stored {:?}", stored.get(name)))
        .collect();
    assert!(mismatches.is_empty(), "changed outputs: {mismatches:#?}");
    let _ = std::fs::remove_dir_all(&dir);
}
