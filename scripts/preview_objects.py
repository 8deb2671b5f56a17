#!/usr/bin/env python3
"""Draws OBJ meshes side by side into one PNG (the README's picture of the object library).

Usage: scripts/preview_objects.py --out docs/objects.png OBJ [OBJ ...]
Needs numpy and matplotlib (a documentation tool, not part of the tests):
    python3 -m venv /tmp/docvenv && /tmp/docvenv/bin/pip install numpy matplotlib
"""

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402


def read_obj(path: Path) -> tuple[np.ndarray, np.ndarray]:
    vertices, faces = [], []
    for line in path.read_text().splitlines():
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            vertices.append([float(x) for x in parts[1:4]])
        elif parts[0] == "f":
            faces.append([int(p.split("/")[0]) - 1 for p in parts[1:4]])
    return np.asarray(vertices), np.asarray(faces)


def draw(ax, vertices: np.ndarray, faces: np.ndarray, title: str) -> None:
    triangles = vertices[faces]
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True) + 1e-12
    light = np.array([0.4, -0.5, 0.77])
    shade = 0.25 + 0.75 * np.clip(normals @ (light / np.linalg.norm(light)), 0, 1)
    colors = np.outer(shade, [0.35, 0.55, 0.85])
    ax.add_collection3d(Poly3DCollection(triangles, facecolors=colors, edgecolors="none"))
    lo, hi = vertices.min(0), vertices.max(0)
    center, half = (lo + hi) / 2, (hi - lo).max() / 2
    for setter, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), center):
        setter(c - half, c + half)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=25, azim=-60)
    ax.set_axis_off()
    size_cm = (hi - lo) * 100
    ax.set_title(f"{title}\n{size_cm[0]:.0f} x {size_cm[1]:.0f} x {size_cm[2]:.0f} cm", fontsize=9)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--columns", type=int, default=5)
    parser.add_argument("meshes", type=Path, nargs="+")
    args = parser.parse_args()
    rows = -(-len(args.meshes) // args.columns)
    fig = plt.figure(figsize=(2.4 * args.columns, 2.6 * rows), dpi=100)
    for i, path in enumerate(args.meshes):
        ax = fig.add_subplot(rows, args.columns, i + 1, projection="3d")
        draw(ax, *read_obj(path), path.stem)
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
