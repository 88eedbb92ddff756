//! Target images rendered from a target scene, cached in `DIR/targets/` between runs.

use super::View;
use super::config::OptimizeConfig;
use crate::error::{Error, Result};
use crate::film::Image;
use crate::integrator::{Progress, RenderOptions, render};
use crate::io;
use crate::scene::Scene;
use std::path::Path;

/// Targets rendered from a scene use seeds `seed + TARGET_SEED + k` (view `k`), apart from the seeds of
/// the iterations.
pub const TARGET_SEED: u64 = 0x7A46_E700_0000;
/// The cache key of rendered targets, beside them.
pub const TARGET_KEY: &str = "targets.json";

/// The target images of `views` rendered from `scene` at `spp` samples per pixel, view `k` at seed
/// `seed + k`, each render reporting to a fresh `progress()`.
pub fn render_targets_with(
    scene: &Scene,
    views: &[View],
    spp: u32,
    seed: u64,
    progress: &dyn Fn() -> Progress,
) -> Result<Vec<Image>> {
    let mut images = Vec::with_capacity(views.len());
    for (k, view) in views.iter().enumerate() {
        let scene = view.apply(scene)?;
        let options = RenderOptions {
            spp,
            seed: seed.wrapping_add(k as u64),
            progress: progress(),
        };
        images.push(render(&scene, &options).0);
    }
    Ok(images)
}

/// The seed of the targets rendered from the target scene of `cfg`: view `k` at `seed + k`.
pub fn target_seed(cfg: &OptimizeConfig) -> u64 {
    cfg.settings.seed.wrapping_add(TARGET_SEED)
}

/// FNV-1a, 64 bits: a stable fingerprint of the target scene file for the cache key.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The target images rendered from `scene` (the file `path`) with the views, at `target_spp`: read
/// from `DIR/targets/view_K.exr` when `DIR/targets/targets.json` says they were rendered from the
/// same scene file, views, samples and seed (and they are readable and of the scene's size); else
/// rendered (each render reporting to a fresh `progress()`) and cached there (the key written last,
/// so an interrupted cache is never trusted).
pub fn cached_targets(
    cfg: &OptimizeConfig,
    path: &Path,
    scene: &Scene,
    out: &Path,
    progress: &dyn Fn() -> Progress,
) -> Result<Vec<Image>> {
    let dir = out.join("targets");
    let key_path = dir.join(TARGET_KEY);
    let bytes = std::fs::read(path).map_err(|e| Error::file(path, format!("cannot read: {e}")))?;
    let seed = target_seed(cfg);
    let (width, height) = (cfg.scene.camera.width, cfg.scene.camera.height);
    let views: Vec<String> = cfg.views.iter().map(|v| format!("{v:?}")).collect();
    let key = serde_json::to_string_pretty(&serde_json::json!({
        "scene_fnv1a64": format!("{:016x}", fnv1a(&bytes)),
        "views": views,
        "target_spp": cfg.target_spp,
        "seed": seed,
        "width": width,
        "height": height,
    }))
    .map_err(|e| Error::file(&key_path, e))?;
    let image_path = |k: usize| dir.join(format!("view_{k}.exr"));
    if std::fs::read_to_string(&key_path).is_ok_and(|k| k == key) {
        let cached: Option<Vec<Image>> = (0..cfg.views.len())
            .map(|k| {
                io::read_exr_rgb(&image_path(k))
                    .ok()
                    .filter(|i| (i.width, i.height) == (width, height))
            })
            .collect();
        if let Some(images) = cached {
            return Ok(images);
        }
    }
    let images = render_targets_with(scene, &cfg.views, cfg.target_spp, seed, progress)?;
    std::fs::create_dir_all(&dir).map_err(|e| Error::file(&dir, format!("cannot create: {e}")))?;
    if key_path.exists() {
        std::fs::remove_file(&key_path)
            .map_err(|e| Error::file(&key_path, format!("cannot remove: {e}")))?;
    }
    for (k, image) in images.iter().enumerate() {
        io::write_exr(&image_path(k), width, height, &image.rgb_channels(""))?;
    }
    let tmp = dir.join(format!(".{TARGET_KEY}.{}.tmp", std::process::id()));
    std::fs::write(&tmp, &key)
        .and_then(|_| std::fs::rename(&tmp, &key_path))
        .map_err(|e| Error::file(&key_path, format!("cannot write: {e}")))?;
    Ok(images)
}
