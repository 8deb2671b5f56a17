"""Depth from RGB views by the refined plane sweep, timed: the refiner network in the Rust
runtime and in torch (the same exported weights, the same inputs, the same thread count, in the
same run), then the whole prediction as ``plan --rgb`` makes it (the wheel's ``predict_depth``:
the sweep, the features, the network) beside the sweep alone, for 2, 3, 5 and 9 views (the
first top-down).

    benches/sweep_refiner/run.sh        # builds the Rust side, then runs this

The network's inputs: the views of sweep_refiner_data samples made into a temporary folder
(the features of real sweeps; their boxes are what a view of an object 0.4 to 0.8 m away
gives). The whole prediction: the test views of a mug rendered by the wheel, 0.5 m away. Per
view count and thread count: the median of at least 5 passes after 2 warm-up passes of each
runtime, each whole prediction in a fresh process whose rayon pool has that many threads. The
corrections' mean of each runtime is printed beside, a check that they agree.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import mvgrasp
import numpy as np
import torch
from safetensors.torch import save_file

from mvgrasp_training.export import load_sweep_refiner
from mvgrasp_training.sweep_refiner import FEATURES

ROOT = Path(__file__).resolve().parents[2]

FULL = """
import json, sys, time
import mvgrasp
data = mvgrasp.read_rgbd_folder(sys.argv[1])
n, method = int(sys.argv[2]), sys.argv[3]
args = ([i for i in data["rgb"][:n]], [k for k in data["k"][:n].astype("float64")],
        [p for p in data["world_from_camera"][:n].astype("float64")])
masks = [m for m in data["mask"][:n]]
times = []
for i in range(7):
    t = time.perf_counter()
    mvgrasp.predict_depth(*args, masks=masks, depth_from=method)
    times.append(time.perf_counter() - t)
print(json.dumps(sorted(times[2:])[len(times[2:]) // 2]))
"""


def median_time(call, calls: int = 5) -> float:
    call()
    call()
    times = []
    for _ in range(calls):
        started = time.perf_counter()
        call()
        times.append(time.perf_counter() - started)
    return sorted(times)[len(times) // 2]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--bench", type=Path, required=True, help="the bench_sweep_refiner example")
    parser.add_argument("--features", type=Path, required=True, help="the sweep_refiner_data example")
    parser.add_argument("--model", type=Path, default=ROOT / "models" / "sweep_refiner_small.json")
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--views", type=int, nargs="+", default=[2, 3, 5, 9])
    args = parser.parse_args()

    scratch = Path(tempfile.mkdtemp(prefix="bench_sweep_refiner_"))
    # Every sample's views are written (views_per_sample 9): boxes of views around one object.
    subprocess.run(
        [str(args.features), "--out", str(scratch / "samples"), "--samples", "6",
         "--views-per-sample", "9"],
        check=True, capture_output=True,
    )  # fmt: skip
    boxes = [
        torch.from_numpy(np.load(path)[None, : len(FEATURES)].copy())
        for path in sorted((scratch / "samples").glob("*.npy"))
    ]
    mvgrasp.generate_rgbd_dataset(scratch / "data", categories=["mug"], per_category=1)
    folder = scratch / "data" / "mug_000" / "test"
    net, _ = load_sweep_refiner(args.model)
    print(f"model: {args.model}; {len(boxes)} view boxes of sweep_refiner_data samples,")
    print(f"median {int(np.median([b.shape[-1] * b.shape[-2] for b in boxes]))} pixels a box")
    print()
    print(
        "| views | threads | Rust refiner (ms) | torch refiner (ms) | Rust / torch | "
        "plan --rgb refined, full prediction (ms) | plane sweep alone (ms) | "
        "mean correction Rust / torch (mm) |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for views in args.views:
        chosen = [boxes[i % len(boxes)] for i in range(views)]
        for threads in args.threads:
            inputs = scratch / f"inputs_{views}.safetensors"
            save_file({f"features.{i}": b for i, b in enumerate(chosen)}, str(inputs))
            env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
            rust = json.loads(
                subprocess.run(
                    [str(args.bench), str(args.model), str(inputs), "--threads", str(threads)],
                    check=True, capture_output=True, text=True, env=env,
                ).stdout
            )  # fmt: skip
            torch.set_num_threads(threads)

            def pass_(chosen=chosen) -> float:
                total, count = 0.0, 0
                with torch.no_grad():
                    for b in chosen:
                        correction, _ = net(b)
                        total += float(correction.double().sum())
                        count += correction.numel()
                return total / count

            torch_s = median_time(pass_)
            torch_mean = pass_()

            def full(method: str, env=env, views=views) -> float:
                out = subprocess.run(
                    [sys.executable, "-c", FULL, str(folder), str(views), method],
                    check=True, capture_output=True, text=True, env=env,
                )  # fmt: skip
                return json.loads(out.stdout)

            print(
                f"| {views} | {threads} | {1e3 * rust['median_s']:.0f} | {1e3 * torch_s:.0f} | "
                f"{rust['median_s'] / torch_s:.2f} | {1e3 * full('refined'):.0f} | "
                f"{1e3 * full('baseline'):.0f} | "
                f"{1e3 * rust['mean_correction_m']:.4f} / {1e3 * torch_mean:.4f} |",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
