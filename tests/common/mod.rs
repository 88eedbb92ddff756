//! Helpers shared by the integration tests that run the command-line tool or write input files.

// Each test crate uses a different subset of these helpers.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The tool under test.
pub const BIN: &str = env!("CARGO_BIN_EXE_implicit-psdr");

/// A fresh, empty working folder for one test (`prefix` keeps test crates apart).
pub fn workdir(prefix: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("psdr-{prefix}-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs the tool with `args` in `dir`.
pub fn run(dir: &Path, args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run implicit-psdr")
}

/// A successful run: its stdout (the failure message shows stderr).
#[track_caller]
pub fn assert_success(out: &Output) -> String {
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// A clean failure: exit code 2 and exactly one line `error: ...` on stderr mentioning `expected`.
#[track_caller]
pub fn assert_failure(out: &Output, expected: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {stderr}");
    assert!(stderr.starts_with("error: "), "stderr: {stderr:?}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "stderr: {stderr:?}");
    assert!(stderr.contains(expected), "{stderr:?} lacks {expected:?}");
    assert!(!stderr.contains("panicked"), "stderr: {stderr:?}");
}

/// Files in `dir` other than the inputs named, sorted.
pub fn outputs(dir: &Path, inputs: &[&str]) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !inputs.contains(&n.as_str()))
        .collect();
    names.sort();
    names
}

/// A version-1 `.npy` file with the given dtype descriptor, shape and raw little-endian data.
pub fn npy_bytes(descr: &str, shape: &[usize], data: &[u8]) -> Vec<u8> {
    let dims: Vec<String> = shape.iter().map(|n| n.to_string()).collect();
    let shape_str = match shape {
        [n] => format!("({n},)"),
        _ => format!("({})", dims.join(", ")),
    };
    let mut header =
        format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape_str}, }}");
    // Pad so that magic (6) + version (2) + length (2) + header is a multiple of 64, ending in '\n'.
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    bytes.extend_from_slice(data);
    bytes
}

/// Deterministic xorshift64* generator: tests must not depend on a seed that changes between runs.
pub struct Rng(u64);

impl Rng {
    /// A generator from any seed (0 included).
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in `[0, 1)` with 24 random bits.
    pub fn f32(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
    /// Uniform in `[0, 1)` with 53 random bits.
    pub fn f64(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in the box `[lo, hi]`.
    pub fn in_box(&mut self, lo: glam::Vec3, hi: glam::Vec3) -> glam::Vec3 {
        lo + (hi - lo) * glam::Vec3::new(self.f32(), self.f32(), self.f32())
    }
}

/// A small deterministic generator (SplitMix64) of uniform numbers in `[0, 1)`, points in a cube and
/// directions, seeded by its state.
pub struct SplitMix(pub u64);

impl SplitMix {
    /// Uniform in `[0, 1)` with 24 random bits.
    pub fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 40) as f32 / (1u32 << 24) as f32
    }
    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next()
    }
    /// Uniform in the cube `[−half, half)³`.
    pub fn point(&mut self, half: f32) -> glam::Vec3 {
        glam::Vec3::new(
            self.range(-half, half),
            self.range(-half, half),
            self.range(-half, half),
        )
    }
    /// A uniform unit vector (rejection from the unit ball).
    pub fn direction(&mut self) -> glam::Vec3 {
        loop {
            let v = self.point(1.0);
            if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }
}

pub mod chi2;
pub mod deriv;
pub mod hard_scenes;

/// The default scene (`scenes/sphere_floor.json`) at 16×16 pixels and 4 spp, changed by `edit`, written
/// to `dir/name`: a scene the command-line tests run in well under a second.
pub fn write_small_scene(dir: &Path, name: &str, edit: impl FnOnce(&mut serde_json::Value)) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/sphere_floor.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    v["camera"]["width"] = 16.into();
    v["camera"]["height"] = 16.into();
    v["spp"] = 4.into();
    edit(&mut v);
    std::fs::write(dir.join(name), v.to_string()).unwrap();
}
