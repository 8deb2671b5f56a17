#!/usr/bin/env bash
# The sweep refiner benchmark: the network in the Rust runtime against torch (same weights,
# inputs and threads, in the same run), and the whole prediction `plan --rgb` makes with it
# beside the plane sweep alone, for 2, 3, 5 and 9 views on 1 and 2 threads. Prints a table.
#
#   benches/sweep_refiner/run.sh [--model MODEL.json] [--threads 1 2] [--views 2 3 5 9]
#
# Needs the repository's .venv (made by .ci/run: torch, the training package) with the wheel
# installed (scripts/test.sh installs it). See bench.py for what is timed.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py=python3
[[ -x "$root/.venv/bin/python" ]] && py="$root/.venv/bin/python"

echo "== building the bench_sweep_refiner and sweep_refiner_data examples (release)"
(cd "$root" && cargo build --release --quiet -p mvgrasp-infer --example bench_sweep_refiner \
    && cargo build --release --quiet --example sweep_refiner_data)
target="${CARGO_TARGET_DIR:-$root/target}/release/examples"
PYTHONPATH="$root/training${PYTHONPATH:+:$PYTHONPATH}" "$py" "$here/bench.py" \
    --bench "$target/bench_sweep_refiner" --features "$target/sweep_refiner_data" "$@"
