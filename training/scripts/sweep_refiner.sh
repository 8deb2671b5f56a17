#!/usr/bin/env bash
# The sweep refiner (models/sweep_refiner_small) from a clean clone: its samples
# (examples/sweep_refiner_data.rs: built-in objects of library seed 2 under random camera rigs,
# the plane sweep run on each), then its training run (training/configs/sweep_refiner_small.toml),
# exported. Both steps resume where an interrupted run stopped. PHOTO_SHARE=0.75 renders that
# share of the samples with the photographic look (mvgrasp::scene::photoreal: textures, gloss,
# room lights and shadows, backgrounds, sensor noise, blur, JPEG) into their own folder
# (../datasets/sweep_refiner_photo) and run (../runs/sweep_refiner_small_photo); the shipped weights
# are the default's (PHOTO_SHARE=0).
#
#   training/scripts/sweep_refiner.sh            # ~25 min of samples + ~45 min of training (2 cores)
#   QUICK=1 training/scripts/sweep_refiner.sh    # a minute: 8 samples, 1 short epoch, scratch folder
#   INSTALL=1 training/scripts/sweep_refiner.sh  # then copy the export into models/
#
# PYTHON, else .venv/bin/python, else python3 (torch, numpy, safetensors, matplotlib). Samples
# go to ../datasets/sweep_refiner and the run to ../runs/sweep_refiner_small beside the
# repository (QUICK=1: a temporary folder).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$root"
python=${PYTHON:-}
if [[ -z $python ]]; then
    if [[ -x .venv/bin/python ]]; then python=.venv/bin/python; else python=python3; fi
fi
export PYTHONPATH="$root/training${PYTHONPATH:+:$PYTHONPATH}"
photo_share=${PHOTO_SHARE:-0}
suffix=""
if [[ $photo_share != 0 ]]; then suffix=_photo; fi
if [[ ${QUICK:-0} == 1 ]]; then
    work=$(mktemp -d)
    data=$work/datasets/sweep_refiner$suffix
    runs=$work/runs
    samples=8
    edits=(-e "s|^epochs = .*|epochs = 1|" -e "s|^samples_per_epoch = .*|samples_per_epoch = 32|")
else
    data=$root/../datasets/sweep_refiner$suffix
    runs=$root/../runs
    samples=1000
    edits=()
fi
mkdir -p "$runs"
cargo build --release --quiet --example sweep_refiner_data
target/release/examples/sweep_refiner_data --out "$data" --samples "$samples" --photo-share "$photo_share"
run=$runs/sweep_refiner_small$suffix
config=$run.toml
sed "${edits[@]}" -e "s|^dataset_dir = .*|dataset_dir = \"$data\"|" \
    training/configs/sweep_refiner_small.toml > "$config"
"$python" -m mvgrasp_training.train_sweep_refiner "$config" --out "$run" \
    --export "$run/sweep_refiner_small"
if [[ ${INSTALL:-0} == 1 && ${QUICK:-0} != 1 ]]; then
    cp "$run/sweep_refiner_small.json" "$run/sweep_refiner_small.safetensors" models/
    cp "$run/learning_curve.png" models/sweep_refiner_small.png
    echo "models/sweep_refiner_small rewritten; next: cargo test, then re-measure docs/depth-from-rgb.md"
fi
