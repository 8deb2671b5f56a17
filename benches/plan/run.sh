#!/usr/bin/env bash
# The planner's latency benchmark on real depth (gqcnn's Primesense images in shared/ beside
# the repository): each stage's median time for 1 view and 5 views, with and without the
# cross-entropy method, and grasps scored per second. Targets: 1 view under 50 ms, 5 views
# under 150 ms. gqcnn itself (TensorFlow 1) does not install here: its published figures are
# printed beside ours, marked as such.
#
#   benches/plan/run.sh [--runs N]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$root"
cargo run --release --quiet --example bench_plan -- --data "${MVGRASP_SHARED_DATA:-$root/../shared/data}" "$@"
