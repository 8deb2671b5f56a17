#!/usr/bin/env bash
# The depth-from-RGB benchmark: the Learnt Stereo Machine in the Rust runtime against torch
# (same weights, inputs and threads, in the same run), the whole prediction `plan --rgb` makes,
# and the classical baseline, for 1, 3, 5 and 9 views on 1 and 2 threads. Prints a table.
#
#   benches/lsm/run.sh [--model MODEL.json] [--folder DATASET/OBJECT/test] [--threads 1 2]
#
# Needs the repository's .venv (made by .ci/run: torch, the training package) with the wheel
# installed (scripts/test.sh installs it). See bench.py for what is timed.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py=python3
[[ -x "$root/.venv/bin/python" ]] && py="$root/.venv/bin/python"

echo "== building the bench_lsm example (release)"
(cd "$root" && cargo build --release --quiet -p mvgrasp-infer --example bench_lsm)
bench="${CARGO_TARGET_DIR:-$root/target}/release/examples/bench_lsm"
PYTHONPATH="$root/training${PYTHONPATH:+:$PYTHONPATH}" "$py" "$here/bench.py" --bench "$bench" "$@"
