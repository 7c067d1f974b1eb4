#!/usr/bin/env bash
# Instruction counts (valgrind callgrind) of find_loops on the 2.1 h urban drive (75,600 poses,
# γ = 40 m), one thread: a figure that does not depend on the machine's load. Appends a line to
# benches/callgrind/counts.tsv: date, commit, instructions of find_loops.
# Counts the whole process twice — generating the drive only, then generating and finding loops —
# and subtracts, so inlining and threads cannot hide any of the engine's work.
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release --quiet --example drive -p loops-core
drive="${CARGO_TARGET_DIR:-target}/release/examples/drive"
count() {
  RAYON_NUM_THREADS=1 EUCLIDEAN_ONLY=1 "$@" valgrind --tool=callgrind --callgrind-out-file=/dev/null \
    "$drive" 2.1 40 1000 2>&1 | sed -n 's/.*Collected : \([0-9]*\).*/\1/p'
}
base=$(count env GENERATE_ONLY=1)
full=$(count env)
engine=$((full - base))
line="$(date -u +%Y-%m-%d)	$(git describe --always --dirty)	$engine"
echo "$line" | tee -a benches/callgrind/counts.tsv
