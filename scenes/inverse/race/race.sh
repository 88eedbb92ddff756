#!/usr/bin/env bash
# The race against the reconstruction protocol of Vicini et al. 2022 (docs/inverse-rendering.md,
# "Time to quality"): runs opt.json on an otherwise idle machine, then draws IoU and Chamfer against
# seconds of optimisation beside their figures and prints the table.
# Usage, from the repository's root: scenes/inverse/race/race.sh [OUT_DIR]
set -euo pipefail
out=${1:-race_out}
cargo build --release --quiet
./target/release/implicit-psdr optimize scenes/inverse/race/opt.json --out "$out"
cargo run --release --quiet --example race_figure -- "$out/progress.csv" docs/images/race.png
