//! Writes the many-shape benchmark's scene: the default scene with its ball replaced by `N` random
//! balls of radius 0.1, 256×256, 16 spp.
//!
//! `cargo run --release --example many_balls -- N OUT.json [SEED]`, then
//! `implicit-psdr render OUT.json`.

#[path = "../benches/scenes/many_balls.rs"]
mod scene;

use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: many_balls N OUT.json [SEED]";
    let (Some(n), Some(out)) = (args.first(), args.get(1)) else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let Ok(n) = n.parse::<usize>() else {
        eprintln!("N: not a count, got {n:?} ({usage})");
        return ExitCode::from(2);
    };
    let seed = match args.get(2).map(|s| s.parse::<u64>()) {
        None => 1,
        Some(Ok(s)) => s,
        Some(Err(_)) => {
            eprintln!("SEED: not an integer, got {:?} ({usage})", args[2]);
            return ExitCode::from(2);
        }
    };
    if let Err(e) = std::fs::write(out, scene::many_balls(n, seed)) {
        eprintln!("{out}: {e}");
        return ExitCode::from(2);
    }
    ExitCode::SUCCESS
}
