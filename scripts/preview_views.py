#!/usr/bin/env python3
"""Draws one object's RGB, depth and mask from a few views of a `render` dataset into one PNG.

Usage: scripts/preview_views.py DATASET/OBJECT --split test --views 0 3 6 --out docs/views.png
Needs numpy and matplotlib (a documentation tool, not part of the tests).
"""

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("object_dir", type=Path)
    parser.add_argument("--split", default="test")
    parser.add_argument("--views", type=int, nargs="+", default=[0, 3, 6])
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    dataset = json.loads((args.object_dir.parent / "dataset.json").read_text())
    units = dataset["depth_png_units_per_m"]
    split = args.object_dir / args.split
    fig, axes = plt.subplots(len(args.views), 3, figsize=(9, 2.4 * len(args.views)), dpi=100)
    for row, view in zip(np.atleast_2d(axes), args.views):
        rgb = mpimg.imread(split / f"{view:03d}_rgb.png")
        # matplotlib reads 16-bit PNGs as floats in [0, 1]: back to metres.
        depth = mpimg.imread(split / f"{view:03d}_depth.png") * 65535.0 / units
        mask = mpimg.imread(split / f"{view:03d}_mask.png") * 255.0
        shown = np.where(depth > 0, depth, np.nan)
        row[0].imshow(rgb)
        image = row[1].imshow(shown, cmap="viridis")
        fig.colorbar(image, ax=row[1], fraction=0.035, label="z (m)")
        row[2].imshow(mask, cmap="tab10", vmin=0, vmax=9, interpolation="nearest")
        for ax, title in zip(row, ("RGB", "depth", "mask (1 object, 2 table)")):
            ax.set_title(f"{args.split} view {view}: {title}", fontsize=8)
            ax.set_axis_off()
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
