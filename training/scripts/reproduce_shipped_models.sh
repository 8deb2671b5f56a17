#!/usr/bin/env bash
# Reproduces the shipped networks of models/ from a clean clone: the grasp and RGB-D datasets
# they were trained on (training/configs/datasets/, `render`), the five training runs
# (training/configs/), the exports copied into models/ and the torch-parity fixtures of the
# Rust tests rewritten, then the fused planner's ranker (training/scripts/fit_ranker.py) and both
# planners' chance to hold (training/scripts/fit_probability.py).
#
#   training/scripts/reproduce_shipped_models.sh            # about five hours on a 2-core CPU
#   QUICK=1 training/scripts/reproduce_shipped_models.sh    # minutes: 1 object per category,
#                                                           # 1 epoch, into a scratch folder;
#                                                           # models/ is left alone
#
# Needs cargo, and a Python with the training package's dependencies (torch, numpy, safetensors,
# matplotlib; `.ci/run` makes such a .venv): PYTHON, else .venv/bin/python, else python3.
# Datasets go where the training configs expect them (../datasets beside the repository), runs
# to ../runs; with QUICK=1 both go under a temporary folder. The test split (the real meshes of
# ../shared/data/meshes, or $MVGRASP_SHARED_DATA/meshes, outside random_urdfs) is made when
# that folder is there; it only adds test figures to the reports, never chooses weights.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$root"
python=${PYTHON:-}
if [[ -z $python ]]; then
    if [[ -x .venv/bin/python ]]; then python=.venv/bin/python; else python=python3; fi
fi
shared=${MVGRASP_SHARED_DATA:-$root/../shared/data}
# The training package from this checkout, installed or not.
export PYTHONPATH="$root/training${PYTHONPATH:+:$PYTHONPATH}"
quick=${QUICK:-0}

if [[ $quick == 1 ]]; then
    work=$(mktemp -d)
    data=$work/datasets
    runs=$work/runs
    per_category=1
else
    data=$root/../datasets
    runs=$root/../runs
    per_category=20
fi
echo "datasets: $data; runs: $runs; python: $python"

cargo build --release --quiet --bin grasp_dataset
generator=target/release/grasp_dataset

test_meshes=()
if [[ -d $shared/meshes && $quick != 1 ]]; then
    for folder in "$shared"/meshes/*; do
        [[ -d $folder ]] || continue
        if [[ $(basename "$folder") == pybullet ]]; then
            for sub in "$folder"/*; do
                [[ $(basename "$sub") == random_urdfs ]] && continue
                [[ -d $sub || $sub == *.obj || $sub == *.urdf || $sub == *.stl ]] && test_meshes+=(--mesh "$sub")
            done
        else
            test_meshes+=(--mesh "$folder")
        fi
    done
fi

# The datasets: the top-down one (20 objects per category, library seed 0) and the large
# multi-view one (60 per category, library seed 1: no evaluation object among them).
for kind in topdown multiview_large; do
    config=training/configs/datasets/$kind.toml
    if [[ $kind == topdown ]]; then
        objects=(--per-category "$per_category")
    else
        objects=(--per-category "$((per_category * 3))" --library-seed 1)
    fi
    "$generator" --quiet "${objects[@]}" --config "$config" --out "$data/$kind/train"
    if [[ ${#test_meshes[@]} -gt 0 ]]; then
        "$generator" --quiet --config "$config" "${test_meshes[@]}" --out "$data/$kind/test"
    fi
done

# The training configs, with the dataset folder (and for QUICK=1 the epochs) of this run.
for name in gqcnn_small_topdown gqcnn_small_multiview; do
    kind=${name#gqcnn_small_}
    [[ $kind == multiview ]] && kind=multiview_large
    config=$runs/$name.toml
    mkdir -p "$runs"
    edits=(-e "s|^dataset_dir = .*|dataset_dir = \"$data/$kind/train\"|")
    [[ $quick == 1 ]] && edits+=(-e "s|^epochs = .*|epochs = 1|")
    sed "${edits[@]}" "training/configs/$name.toml" > "$config"
    test_args=()
    [[ -d $data/$kind/test ]] && test_args=(--test-dataset "$data/$kind/test")
    "$python" -m mvgrasp_training.train "$config" --out "$runs/$name" "${test_args[@]}" \
        > "$runs/$name.log" 2>&1 &
done
wait
for name in gqcnn_small_topdown gqcnn_small_multiview; do
    [[ -f $runs/$name/$name.json ]] || { echo "training $name failed: see $runs/$name.log" >&2; exit 1; }
done

# The Learnt Stereo Machine: the RGB-D dataset of `render` (20 objects per category, library
# seed 2: other shapes than the grasp datasets' and the evaluation's), then its run (about an
# hour and a half here on its own), exported for the Rust runtime.
cargo build --release --quiet --bin render
target/release/render --quiet --per-category "$per_category" --library-seed 2 --out "$data/lsm"
config=$runs/lsm_small.toml
edits=(-e "s|^dataset_dir = .*|dataset_dir = \"$data/lsm\"|")
[[ $quick == 1 ]] && edits+=(-e "s|^epochs = .*|epochs = 1|" -e "s|^samples_per_epoch = .*|samples_per_epoch = 8|")
sed "${edits[@]}" training/configs/lsm_small.toml > "$config"
"$python" -m mvgrasp_training.train_lsm "$config" --out "$runs/lsm_small" \
    --export "$runs/lsm_small/lsm_small" > "$runs/lsm_small.log" 2>&1 \
    || { echo "training lsm_small failed: see $runs/lsm_small.log" >&2; exit 1; }

# The learned multi-view stereo network on the same RGB-D dataset (about an hour here on its
# own), exported for the Rust runtime.
config=$runs/mvs_small.toml
sed "${edits[@]}" training/configs/mvs_small.toml > "$config"
"$python" -m mvgrasp_training.train_mvs "$config" --out "$runs/mvs_small" \
    --export "$runs/mvs_small/mvs_small" > "$runs/mvs_small.log" 2>&1 \
    || { echo "training mvs_small failed: see $runs/mvs_small.log" >&2; exit 1; }

# The plane sweep's learned refinement: its own samples (sweeps of random camera rigs) and
# run, by its script (about 25 minutes of samples and 30 of training here on its own; its data
# and run go to ../datasets and ../runs, the same folders as here, or a scratch folder of its
# own with QUICK=1).
QUICK=$quick training/scripts/sweep_refiner.sh > "$runs/sweep_refiner_small.log" 2>&1 \
    || { echo "training sweep_refiner_small failed: see $runs/sweep_refiner_small.log" >&2; exit 1; }

ranker_out=$runs/ranker_fused.json
if [[ $quick != 1 ]]; then
    for name in gqcnn_small_topdown gqcnn_small_multiview; do
        cp "$runs/$name/$name.json" "$runs/$name/$name.safetensors" models/
        cp "$runs/$name/learning_curve.png" "models/$name.png"
    done
    cp "$runs/lsm_small/lsm_small.json" "$runs/lsm_small/lsm_small.safetensors" models/
    cp "$runs/lsm_small/learning_curve.png" models/lsm_small.png
    cp "$runs/mvs_small/mvs_small.json" "$runs/mvs_small/mvs_small.safetensors" models/
    cp "$runs/mvs_small/learning_curve.png" models/mvs_small.png
    cp "$runs/sweep_refiner_small/sweep_refiner_small.json" \
        "$runs/sweep_refiner_small/sweep_refiner_small.safetensors" models/
    cp "$runs/sweep_refiner_small/learning_curve.png" models/sweep_refiner_small.png
    "$python" training/scripts/make_parity_fixtures.py
    ranker_out=models/ranker_fused.json
fi

# The fused planner's ranker: the planner (with the networks now compiled into ranker_data) on
# built-in objects 60 to 69 of each category (past every training and evaluation index), every
# re-scored candidate tried in physics, and a logistic model of the outcome fitted to them; the
# development set (objects 50 to 54) is made the same way and reported beside the fit. About
# ten minutes here; an interrupted run keeps its finished objects.
cargo build --release --quiet --bin ranker_data
mkdir -p "$data/ranker"
for set in "fit builtin:60 $((per_category / 2))" "dev dev $((per_category / 4))"; do
    read -r name objects count <<< "$set"
    (( count >= 1 )) || count=1
    target/release/ranker_data --out "$data/ranker/$name" --set "$objects" \
        --per-category "$count" > "$runs/ranker_$name.log" 2>&1
done
"$python" training/scripts/fit_ranker.py "$data/ranker/fit/rescored.jsonl" \
    --validate "$data/ranker/dev/rescored.jsonl" --out "$ranker_out"

# The chance to hold (training/scripts/fit_probability.py), a logistic map of each planner's
# quality to the trial's outcome, every resting pose, seeds 0 to 2, with the networks and the
# ranker now compiled into evaluate: the top-down GQ-CNN (the default run with --no-fuse, and on
# rendered depth) over the development set (built-in objects 50 to 54 of each category), about
# 20 minutes here; the multi-view planner (the default run, and on rendered depth) over the
# same objects and the real development set (every 20th of pybullet's random_urdfs in the shared
# meshes, when present), about 20 minutes.
topdown_out=$runs/probability_topdown.json
fused_out=$runs/probability_fused.json
if [[ $quick == 0 ]]; then
    topdown_out=models/probability_topdown.json
    fused_out=models/probability_fused.json
fi
probability_seeds=0,1,2
min_grasps=20
dev_real_meshes=0
if [[ $quick == 1 ]]; then probability_seeds=0; min_grasps=2; dev_real_meshes=2; fi
cargo build --release --quiet --bin evaluate
dev_per_category=$(( per_category / 4 > 0 ? per_category / 4 : 1 ))
rm -rf "$runs/probability_dev" "$runs/probability_fused_dev"
target/release/evaluate --out "$runs/probability_dev" --set dev \
    --per-category "$dev_per_category" \
    --seeds "$probability_seeds" --all-poses --policy rgb --policy depth --suite grasps --plain \
    > "$runs/probability_dev.log"
"$python" training/scripts/fit_probability.py "$runs/probability_dev/records.jsonl" \
    --planner topdown --out "$topdown_out" --min-grasps "$min_grasps"
target/release/evaluate --out "$runs/probability_fused_dev" --set dev --set dev-real \
    --per-category "$dev_per_category" --max-meshes "$dev_real_meshes" \
    --seeds "$probability_seeds" --all-poses --policy rgb-fused --policy depth-fused \
    --suite grasps --plain > "$runs/probability_fused_dev.log"
"$python" training/scripts/fit_probability.py "$runs/probability_fused_dev/records.jsonl" \
    --planner fused --out "$fused_out" --min-grasps "$min_grasps"

if [[ $quick == 1 ]]; then
    echo "QUICK=1: exports in $runs (models/ unchanged)"
    exit 0
fi
echo "models/ rewritten; next: cargo test (parity with torch), then re-measure models/README.md and the report (cargo run --release --bin evaluate)"
