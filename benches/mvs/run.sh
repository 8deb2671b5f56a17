#!/usr/bin/env bash
# The learned multi-view stereo benchmark: the network in the Rust runtime against torch (same
# weights, inputs and threads, in the same run), the whole prediction `plan --rgb` makes with
# it, and the classical baseline, for 2, 3, 5 and 9 views on 1 and 2 threads. Prints a table.
#
#   benches/mvs/run.sh [--model MODEL.json] [--folder DATASET/OBJECT/test] [--threads 1 2]
#
# Needs the repository's .venv (made by .ci/run: torch, the training package) with the wheel
# installed (scripts/test.sh installs it). See bench.py for what is timed.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py=python3
[[ -x "$root/.venv/bin/python" ]] && py="$root/.venv/bin/python"

echo "== building the bench_mvs example (release)"
(cd "$root" && cargo build --release --quiet -p mvgrasp-infer --example bench_mvs)
bench="${CARGO_TARGET_DIR:-$root/target}/release/examples/bench_mvs"
PYTHONPATH="$root/training${PYTHONPATH:+:$PYTHONPATH}" "$py" "$here/bench.py" --bench "$bench" "$@"
