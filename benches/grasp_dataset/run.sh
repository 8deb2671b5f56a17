#!/usr/bin/env bash
# The grasp-dataset benchmark: labelled datapoints per hour and peak memory of `grasp_dataset`
# over the built-in library (default 5 objects per category = 50 objects), with the default
# config (top-down cameras, 3 stable poses x 100 axes x 10 views per object, rapier trials on
# 10% of the collision-free datapoints), on one thread and on all threads, from a clean folder.
#
#   benches/grasp_dataset/run.sh [objects per category]
#
# No peer runs beside it: Dex-Net 2.0's dataset generator was never released (gqcnn issues #48,
# #125), so the figure compares with the issue's target (200,000 labelled datapoints an hour on
# 2 cores).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
per_category=${1:-5}
cd "$root"
cargo build --release --quiet --bin grasp_dataset
bin=$root/target/release/grasp_dataset
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
printf '| threads | objects | datapoints | physics trials | seconds | datapoints/hour | peak RSS (MiB) | target |\n'
printf '|---|---|---|---|---|---|---|---|\n'
for threads in 1 "$(nproc)"; do
    out=$work/t$threads
    /usr/bin/time -f '%e %M' -o "$work/time" env RAYON_NUM_THREADS="$threads" \
        "$bin" --quiet --per-category "$per_category" --out "$out" > "$work/log" 2>&1
    read -r seconds kib < "$work/time"
    python3 - "$out/dataset.json" "$threads" "$seconds" "$kib" <<'PY'
import json, sys
manifest = json.load(open(sys.argv[1]))
threads, seconds, kib = sys.argv[2], float(sys.argv[3]), int(sys.argv[4])
t = manifest["totals"]
rate = t["datapoints"] / seconds * 3600
print(f"| {threads} | {len(manifest['objects'])} | {t['datapoints']} | {t['physics_trials']} "
      f"| {seconds:.1f} | {rate:,.0f} | {kib / 1024:.0f} | 200,000 |")
PY
done
