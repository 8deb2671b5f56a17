#!/usr/bin/env python3
"""Plans on gqcnn's ten real single-object Primesense images with `plan --depth` (the camera's
pose withheld), without and with each image's mask, and draws the overlays side by side: the
top row without masks, the bottom row with them, each tile cropped around the object. With
`--clutter`, on its 15 clutter images instead (10 PhoXi bins, 5 Primesense piles), without
masks and with the camera's pose, each tile titled with the best grasp's quality.

Usage: scripts/real_depth_overlays.py [--data ../shared/data] [--plan target/release/plan]
           [--out docs/real_depth_primesense.png] [--clutter]
Needs numpy and matplotlib (a documentation tool, not part of the tests).
"""

import argparse
import json
import subprocess
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

HALF = 90  # crop half side, pixels


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=Path("../shared/data"))
    parser.add_argument("--plan", type=Path, default=Path("target/release/plan"))
    parser.add_argument("--out", type=Path, default=Path("docs/real_depth_primesense.png"))
    parser.add_argument("--clutter", action="store_true", help="the 15 clutter images")
    args = parser.parse_args()
    root = args.data / "real_depth/gqcnn/data"
    if args.clutter:
        clutter(args, root)
        return
    images = root / "examples/single_object/primesense"
    intr = root / "calib/primesense/primesense.intr"
    fig, axes = plt.subplots(2, 10, figsize=(20, 4.6))
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(10):
            mask_path = images / f"segmask_{i}.png"
            mask = mpimg.imread(mask_path) > 0
            rows, cols = np.nonzero(mask if mask.ndim == 2 else mask[..., 0])
            cy, cx = int(rows.mean()), int(cols.mean())
            for row, with_mask in enumerate([False, True]):
                out = Path(tmp) / f"{i}_{row}"
                command = [str(args.plan), "--depth", str(images / f"depth_{i}.npy")]
                command += ["--intrinsics", str(intr), "--out", str(out)]
                if with_mask:
                    command += ["--mask", str(mask_path)]
                subprocess.run(command, check=True, capture_output=True)
                overlay = mpimg.imread(out / "overlay_0.png")
                h, w = overlay.shape[:2]
                top, left = min(max(cy - HALF, 0), h - 2 * HALF), min(max(cx - HALF, 0), w - 2 * HALF)
                ax = axes[row][i]
                ax.imshow(overlay[top : top + 2 * HALF, left : left + 2 * HALF])
                ax.set_xticks([])
                ax.set_yticks([])
                if row == 0:
                    ax.set_title(f"image {i}", fontsize=10)
        axes[0][0].set_ylabel("no mask", fontsize=11)
        axes[1][0].set_ylabel("mask", fontsize=11)
    fig.suptitle(
        "plan --depth on gqcnn's real Primesense images, camera pose withheld "
        "(green: the best grasp; blue, orange, purple, cyan: the next four)",
        fontsize=12,
    )
    fig.tight_layout()
    fig.savefig(args.out, dpi=80)


def clutter(args: argparse.Namespace, root: Path) -> None:
    """The 15 clutter images without masks, with the camera's pose, in three rows."""
    sets = [
        ("phoxi/dex-net_4.0", "phoxi/phoxi.intr", "phoxi/phoxi_to_world.tf"),
        ("phoxi/fcgqcnn", "phoxi/phoxi.intr", "phoxi/phoxi_to_world.tf"),
        ("primesense", "primesense/primesense.intr", "primesense/primesense.tf"),
    ]
    fig, axes = plt.subplots(3, 5, figsize=(20, 9.6))
    with tempfile.TemporaryDirectory() as tmp:
        for row, (folder, intr, pose) in enumerate(sets):
            for i in range(5):
                images = root / "examples/clutter" / folder
                out = Path(tmp) / f"{row}_{i}"
                command = [str(args.plan), "--depth", str(images / f"depth_{i}.npy")]
                command += ["--intrinsics", str(root / "calib" / intr)]
                command += ["--camera-pose", str(root / "calib" / pose), "--out", str(out)]
                subprocess.run(command, check=True, capture_output=True)
                grasps = json.loads((out / "grasps.json").read_text())["grasps"]
                overlay = mpimg.imread(out / "overlay_0.png")
                ax = axes[row][i]
                ax.imshow(overlay)
                ax.set_xticks([])
                ax.set_yticks([])
                quality = f"quality {grasps[0]['quality']:.2f}" if grasps else "no grasp"
                ax.set_title(f"{folder} {i}: {quality}", fontsize=10)
    fig.suptitle(
        "plan --depth on gqcnn's real clutter images, no mask, the camera's pose given "
        "(green: the best grasp; blue, orange, purple, cyan: the next four)",
        fontsize=12,
    )
    fig.tight_layout()
    fig.savefig(args.out, dpi=45)


if __name__ == "__main__":
    main()
