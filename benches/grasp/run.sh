#!/usr/bin/env bash
# The grasp-analysis benchmark: antipodal candidates, robust-quality evaluations (25 samples)
# and physics trials per second on this machine, one thread and all threads, on the built-in
# mug and on YCB/Dex-Net meshes from shared/ beside the repository when it is there.
#
#   benches/grasp/run.sh
#
# No peer runs beside it: Dex-Net's Python sampler needs Python 2-era dependencies (meshpy,
# a compiled SDF pipeline) that do not install here; the issue's targets are absolute (1,000
# robust evaluations/s and 50 physics trials/s on 2 cores).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
data="$root/../shared/data/meshes"
meshes=()
for m in ycb/meshes/006_mustard_bottle_textured.obj dexnet/test/models/bar_clamp.obj; do
    [[ -f "$data/$m" ]] && meshes+=("$data/$m")
done
cd "$root"
cargo run --release --quiet -p mvgrasp-grasp --example bench_grasp -- "${meshes[@]}"
