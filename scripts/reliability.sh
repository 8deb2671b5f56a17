#!/usr/bin/env bash
# scripts/reliability.sh: the long reliability pass, whose tables fill the README's reliability
# section and docs/reliability.md. Three parts, each printing a markdown table:
#   1. fuzz: every fuzz target of crates/fuzz for FUZZ_SECONDS (default 600) in its own process
#      (`mvgrasp-fuzz run`); findings are saved under target/fuzz/<target>/.
#   2. load: 10,000 plans on one planner and 1/2/4 threads planning at once, from Rust
#      (examples/bench_load.rs) and from Python (scripts/bench_load.py, the wheel installed).
#   3. kill: kill -9 at random moments, 10 times per job, resume, compare bytes
#      (scripts/kill_resume.py: dataset generation from the CLI, Python and Ray, RGB-D
#      rendering, training, evaluate).
#
# Usage: scripts/reliability.sh [fuzz] [load] [kill]   (default: all three)
# Environment: FUZZ_SECONDS (per target), PLANS (default 10000), KILLS (default 10), PYTHON
# (default .venv/bin/python when present, else python3), DATA (default ../shared/data).
# About 4 hours on a 2-core machine with the defaults (fuzz 24 x 10 min, load 20 min,
# kill 40 min). Run it from a checkout with the wheel and training/ installed (.ci/run makes
# such a .venv).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

FUZZ_SECONDS=${FUZZ_SECONDS:-600}
PLANS=${PLANS:-10000}
KILLS=${KILLS:-10}
DATA=${DATA:-../shared/data}
if [[ -z ${PYTHON:-} ]]; then
    if [[ -x .venv/bin/python ]]; then PYTHON=.venv/bin/python; else PYTHON=python3; fi
fi
parts=("$@")
[[ ${#parts[@]} -gt 0 ]] || parts=(fuzz load kill)

cargo build --release --bins -p mvgrasp -p mvgrasp-fuzz --example bench_load

status=0
for part in "${parts[@]}"; do
    case $part in
    fuzz)
        echo "## Fuzzing: $FUZZ_SECONDS s per target ($(date -u +%F))"
        target/release/mvgrasp-fuzz run --seconds "$FUZZ_SECONDS" --out target/fuzz || status=1
        ;;
    load)
        echo "## Under load, Rust ($(date -u +%F))"
        target/release/examples/bench_load --plans "$PLANS" --data "$DATA" || status=1
        echo "## Under load, Python"
        "$PYTHON" scripts/bench_load.py --plans "$PLANS" --data "$DATA" || status=1
        ;;
    kill)
        echo "## Kill -9 and resume: $KILLS kills per job ($(date -u +%F))"
        "$PYTHON" scripts/kill_resume.py --kills "$KILLS" --bin-dir target/release || status=1
        ;;
    *)
        echo "scripts/reliability.sh: unknown part $part (fuzz, load, kill)" >&2
        exit 2
        ;;
    esac
done
exit $status
