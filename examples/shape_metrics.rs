//! How close a shape in one scene is to the shape of the same name in another: IoU and Chamfer
//! distance as `optimize` reports them (`optimize::metrics::shape_quality`).
//!
//! `cargo run --release --example shape_metrics -- A.json B.json SHAPE`

use implicit_psdr::optimize::metrics::shape_quality;
use implicit_psdr::scene::load;
use std::path::Path;

fn main() -> implicit_psdr::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [a, b, shape] = args.as_slice() else {
        eprintln!("usage: shape_metrics A.json B.json SHAPE");
        std::process::exit(2);
    };
    let (a, b) = (load(Path::new(a))?, load(Path::new(b))?);
    match shape_quality(&a, &b, shape)? {
        Some((iou, chamfer)) => println!("{shape}: IoU {iou:.4}, Chamfer {chamfer:.5}"),
        None => println!("{shape}: not in both scenes (or unbounded)"),
    }
    Ok(())
}
