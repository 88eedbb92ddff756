//! The scene of the many-shape benchmark: the default scene (`scenes/sphere_floor.json`) with its ball
//! replaced by `n` small balls at random places above the floor, at 256×256 and 16 spp.
//!
//! Shared by `benches/bvh.rs` and `examples/many_balls.rs` (which writes it to a file).

/// Radius of every ball.
pub const RADIUS: f64 = 0.1;

/// The scene file's text: `n` balls of radius [`RADIUS`] named `ball0`, `ball1`, …, centres uniform
/// in `[-1.5, 1.5] × [-1.4, 1.5] × [-1.5, 1.5]` (the floor's top is at `y = −1.5`), drawn from `seed`;
/// the default scene's floor, light and camera; 256×256, 16 spp, `direct`.
pub fn many_balls(n: usize, seed: u64) -> String {
    let base = include_str!("../../scenes/sphere_floor.json");
    let mut doc: serde_json::Value = serde_json::from_str(base).expect("the default scene is JSON");
    let mut state = seed;
    // SplitMix64: a fixed sequence per seed, whatever the platform.
    let mut uniform = move || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    };
    // Rounded to a thousandth: the file reads as written.
    let mut at = |lo: f64, hi: f64| ((lo + (hi - lo) * uniform()) * 1000.0).round() / 1000.0;
    let balls: Vec<serde_json::Value> = (0..n)
        .map(|i| {
            let c = [at(-1.5, 1.5), at(-1.4, 1.5), at(-1.5, 1.5)];
            serde_json::json!({
                "name": format!("ball{i}"),
                "sdf": {"type": "sphere", "center": c, "radius": RADIUS},
                "bsdf": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}
            })
        })
        .collect();
    let shapes = doc["shapes"]
        .as_array_mut()
        .expect("the default scene has shapes");
    shapes.retain(|s| s["name"] != "ball");
    shapes.splice(0..0, balls);
    doc["description"] =
        format!("The default scene with {n} random balls of radius {RADIUS}.").into();
    doc["camera"]["width"] = 256.into();
    doc["camera"]["height"] = 256.into();
    doc["spp"] = 16.into();
    serde_json::to_string_pretty(&doc).expect("a JSON value prints")
}
