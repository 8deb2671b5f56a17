"""Depth from RGB views, timed: the learned multi-view stereo network in the Rust runtime and in
torch (the same exported weights, the same inputs, the same thread count, in the same run), and
the classical baseline (plane sweep in the visual hull) on the same views, for 2, 3, 5 and 9
views (the first top-down).

    benches/mvs/run.sh        # builds the Rust side, then runs this

The views: the test split of one object of an RGB-D dataset (``render`` output; default the
first object of ../datasets/lsm_eval, else a mug rendered into a temporary folder), read
through the wheel and prepared as the training prepares them (area-averaged to the network's
input size, intrinsics scaled). Per view count and thread count: the median of at least 5 calls
after 2 warm-up calls of each runtime, the network alone (``Mvs::predict`` / ``MVS.forward``),
then the whole prediction as ``plan --rgb`` makes it (the wheel's ``predict_depth``: resizing
in, the network, resizing out and the table plane off the masks) and the baseline's
``predict_depth``, each in a fresh process whose rayon pool has that many threads. The mean
depth of each runtime's prediction is printed beside, a check that they agree.
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
import torch
from safetensors.torch import save_file
from torch.nn import functional as F

from mvgrasp_training.export import load_mvs
from mvgrasp_training.lsm import scale_intrinsics

ROOT = Path(__file__).resolve().parents[2]

FULL = """
import json, os, sys, time
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
    parser.add_argument("--bench", type=Path, required=True, help="the bench_mvs example")
    parser.add_argument("--model", type=Path, default=ROOT / "models" / "mvs_small.json")
    parser.add_argument("--folder", type=Path, help="a dataset's OBJECT/test folder")
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--views", type=int, nargs="+", default=[2, 3, 5, 9])
    args = parser.parse_args()

    scratch = Path(tempfile.mkdtemp(prefix="bench_mvs_"))
    folder = args.folder
    if folder is None:
        default = ROOT.parent / "datasets" / "lsm_eval"
        objects = sorted(p for p in default.glob("*/test") if p.is_dir())
        if objects:
            folder = objects[0]
        else:
            mvgrasp.generate_rgbd_dataset(scratch / "data", categories=["mug"], per_category=1)
            folder = scratch / "data" / "mug_000" / "test"
    net, _ = load_mvs(args.model)
    arch = net.arch
    data = mvgrasp.read_rgbd_folder(folder)
    rgb = torch.from_numpy(data["rgb"]).permute(0, 3, 1, 2).float() / 255.0
    h, w = rgb.shape[-2:]
    images = F.interpolate(rgb, size=(arch.image_height, arch.image_width), mode="area")
    k = scale_intrinsics(
        torch.from_numpy(data["k"]).float(), arch.image_width / w, arch.image_height / h
    )
    pose = torch.linalg.inv(torch.from_numpy(data["world_from_camera"]).double()).float()
    print(f"views of {folder}, {w} x {h}, network input {arch.image_width} x {arch.image_height}")
    print(f"model: {args.model}")
    print()
    print(
        "| views | threads | Rust MVS (ms) | torch MVS (ms) | Rust / torch | plan --rgb MVS, "
        "full prediction (ms) | baseline (ms) | mean depth Rust / torch (m) |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for views in args.views:
        for threads in args.threads:
            inputs = scratch / f"inputs_{views}.safetensors"
            tensors = {
                "images": images[:views].contiguous(),
                "k": k[:views].contiguous(),
                "camera_from_world": pose[:views].contiguous(),
            }
            save_file(tensors, str(inputs))
            env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
            rust = json.loads(
                subprocess.run(
                    [str(args.bench), str(args.model), str(inputs), "--threads", str(threads)],
                    check=True, capture_output=True, text=True, env=env,
                ).stdout
            )  # fmt: skip
            torch.set_num_threads(threads)
            x = (images[:views][None], k[:views][None], pose[:views][None])
            with torch.no_grad():
                torch_s = median_time(lambda x=x: net(*x))
                torch_mean = float(net(*x).depth.double().mean())

            def full(method: str, env=env, views=views) -> float:
                out = subprocess.run(
                    [sys.executable, "-c", FULL, str(folder), str(views), method],
                    check=True, capture_output=True, text=True, env=env,
                )  # fmt: skip
                return json.loads(out.stdout)

            baseline = f"{1e3 * full('baseline'):.0f}"
            print(
                f"| {views} | {threads} | {1e3 * rust['median_s']:.0f} | {1e3 * torch_s:.0f} | "
                f"{rust['median_s'] / torch_s:.2f} | {1e3 * full('mvs'):.0f} | "
                f"{baseline} | "
                f"{rust['mean_depth_m']:.5f} / {torch_mean:.5f} |",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
