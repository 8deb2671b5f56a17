"""Depth from real RGB photographs against the sensor's depth: every predictor of
``plan --rgb`` (the plane-sweep baseline, the multi-view stereo network, the Learnt Stereo
Machine) on the calibrated views of ``../shared/data/real_rgb/apc_shelf_bin`` (15 photographs of
a shelf bin with the RGB-D sensor's aligned depth and object labels), with the object labels as
masks, scored on the objects' pixels where the sensor has depth.

    python scripts/real_rgb_depth_eval.py [--folder DIR] [--views 2 5 15]

Needs the mvgrasp wheel (``scripts/test.sh`` installs it). Prints a markdown table: per
predictor and view count, over the first N views (each view a reference, all N scored), the
median and mean absolute error (mm), the share within 5 mm, the share of the scored pixels
predicted (non-zero), and the prediction's seconds.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import mvgrasp
import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--folder",
        type=Path,
        default=ROOT.parent / "shared" / "data" / "real_rgb" / "apc_shelf_bin",
    )
    parser.add_argument("--views", type=int, nargs="+", default=[2, 5, 15])
    parser.add_argument("--methods", nargs="+", default=["baseline", "mvs", "lsm"])
    args = parser.parse_args()
    if not args.folder.is_dir():
        print(f"{args.folder}: no such folder (the shared real data)", file=sys.stderr)
        return 2
    data = mvgrasp.read_rgbd_folder(args.folder)
    rgb, truth, k, pose = (
        data["rgb"],
        data["depth"],
        data["k"],
        data["world_from_camera"],
    )
    masks = data["mask"]
    if masks is None:
        print(f"{args.folder}: no masks", file=sys.stderr)
        return 2
    print(f"{args.folder}: {len(rgb)} views, {rgb.shape[2]} x {rgb.shape[1]}")
    print(
        "| method | views | median (mm) | mean (mm) | within 5 mm | predicted | seconds |"
    )
    print("|---|---|---|---|---|---|---|")
    for n in args.views:
        n = min(n, len(rgb))
        for method in args.methods:
            started = time.perf_counter()
            try:
                depth = mvgrasp.predict_depth(
                    list(rgb[:n]), list(k[:n]), list(pose[:n]), masks=list(masks[:n]),
                    depth_from=method,
                )  # fmt: skip
            except Exception as error:  # noqa: BLE001 (reported as the row)
                print(f"| {method} | {n} | failed: {error} | | | | |")
                continue
            seconds = time.perf_counter() - started
            scored = masks[:n] & (truth[:n] > 0)
            predicted = scored & (depth > 0)
            errors = np.abs(depth[predicted] - truth[:n][predicted]) * 1e3
            print(
                f"| {method} | {n} | {np.median(errors):.1f} | {errors.mean():.1f} | "
                f"{100 * (errors <= 5).sum() / max(scored.sum(), 1):.0f}% | "
                f"{100 * predicted.sum() / max(scored.sum(), 1):.0f}% | {seconds:.2f} |",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
