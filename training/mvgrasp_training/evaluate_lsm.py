"""Depth from RGB, the LSM beside the classical baseline, on the same views (the seed paper's
Table 1 layout).

    python -m mvgrasp_training.evaluate_lsm RUN/best.pt DATASET [--views 3 5 9]

For every object of a ``render`` dataset (objects the LSM never saw), its 10 test views (novel
colours, the first top-down): the first N views go in, each method predicts their depth, and
the prediction is compared with the rendered depth over the object's pixels at the images' full
resolution (the LSM's depth upsampled bilinearly). Per method and N, for the top-down view and
over all N views: the mean absolute error of the predicted pixels (mm), the share predicted, the
shares within 2 and 5 mm (of all object pixels), the normalised error (MAE over the mean true
depth) and the seconds per prediction (the same threads for both). The baseline is the Rust
core's, through the wheel (``mvgrasp.predict_depth``).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
import torch
from torch.nn import functional as F

import mvgrasp
from mvgrasp_training.lsm import LSM, LsmArchitecture, scale_intrinsics


class Tally:
    """Sums over object pixels."""

    def __init__(self) -> None:
        self.pixels = self.predicted = self.within_2 = self.within_5 = 0
        self.error_m = self.depth_m = 0.0

    def add(self, predicted: np.ndarray, truth: np.ndarray, mask: np.ndarray) -> None:
        where = mask & (truth > 0)
        p, t = predicted[where], truth[where]
        self.pixels += int(where.sum())
        self.depth_m += float(t.sum())
        known = p > 0
        e = np.abs(p[known] - t[known])
        self.predicted += int(known.sum())
        self.error_m += float(e.sum())
        self.within_2 += int((e <= 2e-3).sum())
        self.within_5 += int((e <= 5e-3).sum())

    def row(self) -> str:
        n = max(self.pixels, 1)
        mae = self.error_m / max(self.predicted, 1)
        return (
            f"{1e3 * mae:.2f} | {100 * self.predicted / n:.0f}% | {100 * self.within_2 / n:.0f}% | "
            f"{100 * self.within_5 / n:.0f}% | {mae / (self.depth_m / n):.4f}"
        )


def load_checkpoint(path: Path) -> LSM:
    """A training run's weights (``RUN/best.pt``)."""
    state = torch.load(path, weights_only=False)
    net = LSM(LsmArchitecture(**state["arch"]))
    net.load_state_dict(state["model"])
    return net.eval()


def lsm_depth(net: LSM, folder: dict, n: int) -> np.ndarray:
    """The LSM's depth of the first ``n`` views at full resolution (V, H, W)."""
    arch = net.arch
    rgb = torch.from_numpy(folder["rgb"][:n]).permute(0, 3, 1, 2).float() / 255.0
    h, w = rgb.shape[-2:]
    small = F.interpolate(rgb, size=(arch.image_height, arch.image_width), mode="area")
    k = scale_intrinsics(
        torch.from_numpy(folder["k"][:n]), arch.image_width / w, arch.image_height / h
    ).float()
    pose = torch.linalg.inv(torch.from_numpy(folder["world_from_camera"][:n])).float()
    with torch.no_grad():
        depth = net(small[None], k[None], pose[None])[0]
    full = F.interpolate(depth[:, None], size=(h, w), mode="bilinear", align_corners=False)
    return full[:, 0].numpy()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("weights", type=Path)
    parser.add_argument("dataset", type=Path)
    parser.add_argument("--views", type=int, nargs="+", default=[3, 5, 9])
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args(argv)
    torch.set_num_threads(args.threads)
    net = load_checkpoint(args.weights)
    names = json.loads((args.dataset / "dataset.json").read_text())["objects"]
    methods = ("LSM", "baseline")
    tallies = {(m, n, s): Tally() for m in methods for n in args.views for s in ("top", "all")}
    seconds = {(m, n): 0.0 for m in methods for n in args.views}
    for name in names:
        folder = mvgrasp.read_rgbd_folder(args.dataset / name / "test")
        truth, mask = folder["depth"], folder["mask"]
        for n in args.views:
            started = time.perf_counter()
            predicted = {"LSM": lsm_depth(net, folder, n)}
            seconds[("LSM", n)] += time.perf_counter() - started
            started = time.perf_counter()
            predicted["baseline"] = mvgrasp.predict_depth(
                list(folder["rgb"][:n]),
                list(folder["k"][:n]),
                list(folder["world_from_camera"][:n]),
                masks=list(mask[:n]),
                depth_from="baseline",
            )
            seconds[("baseline", n)] += time.perf_counter() - started
            for m in methods:
                for v in range(n):
                    if v == 0:
                        tallies[(m, n, "top")].add(predicted[m][v], truth[v], mask[v])
                    tallies[(m, n, "all")].add(predicted[m][v], truth[v], mask[v])
        print(".", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    print(f"{len(names)} objects of {args.dataset}, the LSM of {args.weights}")
    print("| method | input views | views scored | MAE (mm) | predicted | within 2 mm | "
          "within 5 mm | normalised | time (s) |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|")
    for n in args.views:
        for m in methods:
            for s, label in (("top", "top-down"), ("all", "all")):
                t = seconds[(m, n)] / max(len(names), 1)
                print(f"| {m} | {n} | {label} | {tallies[(m, n, s)].row()} | {t:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
