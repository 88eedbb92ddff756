#!/usr/bin/env bash
# The reconstruction of a scanned shape (docs/inverse-rendering.md, "A scanned shape"): runs opt.json (the
# complete gradient) and interior.json (its interior term alone) one after the other on an otherwise idle
# machine, then draws the metrics against the mesh over seconds (docs/images/bunny_progress.png) and the
# reference beside both reconstructions (docs/images/bunny.png), and prints the table.
# Usage, from the repository's root: scenes/inverse/bunny/run.sh [OUT_DIR]
set -euo pipefail
out=${1:-bunny_out}
cargo build --release --quiet --bin implicit-psdr --example scan_figure
./target/release/implicit-psdr optimize scenes/inverse/bunny/opt.json --out "$out/complete"
./target/release/implicit-psdr optimize scenes/inverse/bunny/interior.json --out "$out/interior"
./target/release/examples/scan_figure scenes/inverse/bunny/show.json "$out/complete" "$out/interior" \
  docs/images/bunny_progress.png docs/images/bunny.png
