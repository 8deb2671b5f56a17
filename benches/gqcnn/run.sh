#!/usr/bin/env bash
# The GQ-CNN benchmark: grasps scored per second by mvgrasp's CPU runtime (crates/infer,
# `Gqcnn::predict`) against torch (the training code's module, `load_gqcnn`), same exported
# weights, same seeded inputs, same thread count, softmax included in both, in the same run:
# threads 1 and 2, batches 1, 64 and 256 (and 128 for the comparison with Fast-VGQ-CNN's
# published 128 grasps in 12 ms on a CPU, 10,667 grasps/s). torch runs twice: as it comes,
# and with torch.set_flush_denormal(True), since the Rust runtime flushes subnormal weights to
# zero at load (trained weights hold many; each product with one costs x86 a microcode assist).
# Prints a table with the Rust/torch ratio against the faster torch (median over rounds of the
# ratio within each round), and checks that the runtimes gave the same mean probability.
#
#   benches/gqcnn/run.sh [MODEL.json ...]
#
# Models default to models/*.json in the repository root (training exports: NAME.json with
# NAME.safetensors beside it). Environment: ROUNDS (3) rounds, Rust and torch interleaved in
# each so that all see the same load; BENCH_SECONDS (1) timed seconds per batch size (at
# least 5 calls); THREADS ("1 2"); BATCHES ("1,64,128,256"). Python: the repository's .venv
# (made by .ci/run) when present, else python3 with torch and mvgrasp_training importable.
# Writes benches/gqcnn/out/ (git-ignored).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
rounds="${ROUNDS:-3}"
seconds="${BENCH_SECONDS:-1}"
threads_list="${THREADS:-1 2}"
batches="${BATCHES:-1,64,128,256}"
out="$here/out"

if [[ $# -gt 0 ]]; then
    models=("$@")
else
    shopt -s nullglob
    models=("$root"/models/gqcnn_*.json)
    shopt -u nullglob
fi
if [[ ${#models[@]} -eq 0 ]]; then
    echo "error: no models (pass MODEL.json paths, or put exports in $root/models/)" >&2
    exit 2
fi
for m in "${models[@]}"; do
    [[ -f "$m" ]] || { echo "error: model not found: $m" >&2; exit 2; }
done

py=python3
[[ -x "$root/.venv/bin/python" ]] && py="$root/.venv/bin/python"

echo "== building the bench_gqcnn example (release)"
(cd "$root" && cargo build --release --quiet -p mvgrasp-infer --example bench_gqcnn)
bench="${CARGO_TARGET_DIR:-$root/target}/release/examples/bench_gqcnn"

rm -rf "$out"
mkdir -p "$out"
for round in $(seq 1 "$rounds"); do
    echo "== round $round of $rounds"
    for model in "${models[@]}"; do
        for threads in $threads_list; do
            args=("$model" --threads "$threads" --batches "$batches" --seconds "$seconds")
            # One file per round: report.py pairs the runtimes within each round.
            "$bench" "${args[@]}" >> "$out/r$round.jsonl"
            "$py" "$here/bench_torch.py" "${args[@]}" >> "$out/r$round.jsonl"
            "$py" "$here/bench_torch.py" "${args[@]}" --flush-denormal >> "$out/r$round.jsonl"
        done
    done
done

echo
"$py" "$here/report.py" "$out"
