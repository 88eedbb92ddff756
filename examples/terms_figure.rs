//! The picture of the derivative's terms in docs/derivatives.md: for one parameter of a scene, a row of
//! panels `image | interior | primary | secondary | total | fd`, each under its title, the derivative panels
//! on one symmetric colour scale (blue negative, white zero, red positive; the scale of the `fd` panel)
//! shown by a colour bar under each, written as a PNG.
//!
//! `cargo run --release --example terms_figure -- SCENE.json PARAM OUT.png [SIZE] [SPP]`
//! (defaults: 128 px wide, 256 spp; `fd` at 8× the spp with `h = 0.01·max(|P|, 1)`).

use implicit_psdr::film::colormap::{derivative_panel, diverging, srgb_decode};
use implicit_psdr::film::figure::{Column, compose};
use implicit_psdr::film::{Image, write_png};
use implicit_psdr::integrator::RenderOptions;
use implicit_psdr::integrator::fd::finite_difference;
use implicit_psdr::integrator::{BoundaryBudget, DiffOptions, render_derivatives};
use implicit_psdr::scene::load;
use std::path::Path;

/// A derivative panel on a given scale (mean of the three channels, as [`derivative_panel`]).
fn panel(derivative: &Image, scale: f32) -> Image {
    let mut out = Image::new(derivative.width, derivative.height);
    for (o, p) in out
        .rgb
        .chunks_exact_mut(3)
        .zip(derivative.rgb.chunks_exact(3))
    {
        let srgb = diverging((p[0] + p[1] + p[2]) / 3.0 / scale);
        for (c, s) in o.iter_mut().zip(srgb) {
            *c = srgb_decode(s);
        }
    }
    out
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(scene_path), Some(param), Some(out)) = (args.first(), args.get(1), args.get(2))
    else {
        return Err("usage: terms_figure SCENE.json PARAM OUT.png [SIZE] [SPP]".into());
    };
    let size: u32 = args.get(3).map_or(Ok(128), |s| s.parse())?;
    let spp: u32 = args.get(4).map_or(Ok(256), |s| s.parse())?;
    let mut scene = load(Path::new(scene_path))?;
    let aspect = scene.camera.height as f32 / scene.camera.width as f32;
    scene.camera.width = size;
    scene.camera.height = ((size as f32 * aspect).round() as u32).max(1);
    let selection = scene.select(std::slice::from_ref(param))?;
    // Four times `diff`'s default boundary budgets: the figure should show each term clearly.
    let (bp, bs) = BoundaryBudget::default().resolve(spp);
    let options = DiffOptions {
        render: RenderOptions {
            spp,
            seed: 1,
            progress: Default::default(),
        },
        boundary: BoundaryBudget {
            primary_spp: Some(4.0 * bp),
            secondary_spp: Some(4.0 * bs),
        },
        ..DiffOptions::default()
    };
    let d = render_derivatives(&scene, &selection, &options)?;
    let value = scene
        .parameters()
        .into_iter()
        .find(|(n, _)| n == param)
        .map_or(1.0, |(_, v)| v);
    let fd = finite_difference(
        &scene,
        param,
        0.01 * value.abs().max(1.0),
        &RenderOptions {
            spp: 8 * spp,
            seed: 2,
            progress: Default::default(),
        },
    )?;
    let (_, scale) = derivative_panel(&fd);
    let total = d.total().remove(0);
    let mut columns = vec![Column {
        title: "image".into(),
        panel: d.image.clone(),
        scale: None,
    }];
    for (title, derivative) in [
        ("interior", &d.interior[0]),
        ("primary", &d.primary[0]),
        ("secondary", &d.secondary[0]),
        ("total", &total),
        ("fd", &fd),
    ] {
        columns.push(Column {
            title: title.into(),
            panel: panel(derivative, scale),
            scale: Some(scale),
        });
    }
    let row = compose(&columns, true)?;
    write_png(Path::new(out), row.width, row.height, &row.rgb)?;
    println!(
        "{out}: image | interior | primary | secondary | total | fd for {param}; colour scale ±{scale:.3e}"
    );
    Ok(())
}
