//! The derivative API from Rust: loads a scene, selects parameters, renders the image and the complete
//! derivative of the image with respect to each (interior, primary and secondary terms), prints the
//! sum of each term, and writes `examples-out/derivative.exr` with the channels `diff --terms` writes.
//!
//! `cargo run --release --example derivative_terms -- [SCENE.json] [PARAM ...]`
//! (defaults: `scenes/sphere_floor.json`, `ball.radius` and `light.center.x`).

use implicit_psdr::film::{Image, write_exr};
use implicit_psdr::integrator::{DiffOptions, RenderOptions, render_derivatives};
use implicit_psdr::scene;
use std::path::Path;

fn main() -> implicit_psdr::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene_path = args
        .first()
        .map_or("scenes/sphere_floor.json", String::as_str);
    let params: Vec<String> = if args.len() > 1 {
        args[1..].to_vec()
    } else {
        vec!["ball.radius".into(), "light.center.x".into()]
    };

    let scene = scene::load(Path::new(scene_path))?;
    // Derivative k is parameter k of the list.
    let selection = scene.select(&params)?;
    let options = DiffOptions {
        render: RenderOptions {
            spp: 32,
            seed: 0,
            ..RenderOptions::default()
        },
        // The default pixel normalisation (differentiable) and boundary budgets (spp/32 silhouette
        // and spp/8 shadow samples per pixel).
        ..DiffOptions::default()
    };
    let d = render_derivatives(&scene, &selection, &options)?;

    let sum = |image: &Image| image.rgb.iter().map(|&v| v as f64).sum::<f64>();
    for (k, p) in params.iter().enumerate() {
        println!(
            "d/d{p}: image sum {:+.4e} = interior {:+.4e} + primary {:+.4e} + secondary {:+.4e}",
            sum(&d.total()[k]),
            sum(&d.interior[k]),
            sum(&d.primary[k]),
            sum(&d.secondary[k]),
        );
    }
    println!("{}", d.note(&scene.unsampled_creases()));
    let dir = Path::new("examples-out");
    std::fs::create_dir_all(dir).map_err(|e| implicit_psdr::Error::file(dir, e))?;
    let out = dir.join("derivative.exr");
    write_exr(
        &out,
        d.image.width,
        d.image.height,
        &d.channels(&params, true),
    )?;
    println!("wrote {}", out.display());
    Ok(())
}
