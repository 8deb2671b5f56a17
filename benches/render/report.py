"""Prints the render benchmark's table from the JSON files run.sh wrote.

Files are named `r{round}-mvgrasp-{backend}.json` (from `bench_render --json`) and
`r{round}-pyrender-{platform}.json` (from `bench_pyrender.py --json`). Views per second are the
median over rounds of each run's median call; a ratio is taken within each round (both
renderers measured minutes apart at most, under the same load) and then its median is shown.
"""

from __future__ import annotations

import json
import re
import statistics
import sys
from collections import defaultdict
from pathlib import Path

TARGET_RATIO = 5.0
NAME = re.compile(r"r(\d+)-(mvgrasp|pyrender)-(\w+)\.json")
# Like-for-like output: RGB + depth + mask; pyrender needs a second (SEG) pass for the mask.
PEER_MODE = "rgb+depth+seg"


def driver(adapter: str, backend: str) -> str:
    name = adapter.split(" (")[0]
    if backend == "vulkan" and name == "llvmpipe":
        return "lavapipe"  # Mesa's Vulkan CPU driver names its device llvmpipe
    return name


def load(folder: Path) -> dict[tuple[str, str], dict[int, dict]]:
    runs: dict[tuple[str, str], dict[int, dict]] = defaultdict(dict)
    for path in sorted(folder.glob("r*-*.json")):
        match = NAME.fullmatch(path.name)
        if match is None or path.stat().st_size == 0:
            continue
        runs[(match[2], match[3])][int(match[1])] = json.loads(path.read_text())
    return runs


def rows(runs: dict) -> list[dict]:
    """One row per renderer, backend and output set: name, backend, views/s per round."""
    out = []
    for (renderer, backend), by_round in sorted(runs.items()):
        first = next(iter(by_round.values()))
        if renderer == "mvgrasp":
            out.append(
                {
                    "name": "mvgrasp rgb+depth+mask",
                    "backend": f"{backend} ({driver(first['adapter'], backend)})",
                    "platform": None,
                    "vps": {r: run["views_per_s"] for r, run in by_round.items()},
                }
            )
            continue
        for mode in (PEER_MODE, "rgb+depth"):
            out.append(
                {
                    "name": f"pyrender {mode}",
                    "backend": f"{backend} ({driver(first['gl_renderer'], backend)})",
                    "platform": backend if mode == PEER_MODE else None,
                    "vps": {r: run[mode]["views_per_s"] for r, run in by_round.items()},
                }
            )
    return out


def ratio(row: dict, peer: dict) -> float | None:
    """Median over the rounds both ran in of row's views/s over the peer's."""
    rounds = sorted(set(row["vps"]) & set(peer["vps"]))
    if not rounds:
        return None
    return statistics.median(row["vps"][r] / peer["vps"][r] for r in rounds)


def main() -> int:
    folder = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parent / "out"
    runs = load(folder)
    if not runs:
        print(f"error: no results in {folder}", file=sys.stderr)
        return 2
    table = rows(runs)
    peers = [row for row in table if row["platform"] is not None]
    header = f"{'renderer':<24} {'backend':<20} {'views/s':>8} {'ms/view':>8} {'range views/s':>15}"
    header += "".join(f" {'x pyrender ' + p['platform']:>18}" for p in peers)
    print(header)
    for row in table:
        values = list(row["vps"].values())
        median = statistics.median(values)
        line = f"{row['name']:<24} {row['backend']:<20} {median:8.1f} {1e3 / median:8.2f}"
        line += f" {min(values):7.1f}..{max(values):<6.1f}"
        for peer in peers:
            r = ratio(row, peer)
            line += f" {'-' if r is None else f'{r:.2f}x':>18}"
        print(line)

    rounds = max(len(row["vps"]) for row in table)
    first = next(iter(next(iter(runs.values())).values()))
    print(
        f"\n{first['views']} views of {first['width']}x{first['height']} per call, "
        f"{first['triangles']} triangles, median call of {first['repeats']} after a warm-up, "
        f"median over {rounds} round(s); ratios paired within each round."
    )
    for (renderer, backend), by_round in sorted(runs.items()):
        run = next(iter(by_round.values()))
        if renderer == "mvgrasp":
            print(f"mvgrasp {backend}: {run['adapter']}")
        else:
            print(f"pyrender {run['pyrender_version']} {backend}: GL_RENDERER {run['gl_renderer']}")
        for _, run in sorted(by_round.items()):
            agreement = run.get("depth_agreement_view0")
            if agreement is not None:
                print(
                    f"  depth agreement with mvgrasp, view 0: "
                    f"{agreement['within_1mm_of_both']:.2%} of the pixels both draw within 1 mm "
                    f"({agreement['pixels_both']} px; median |diff| "
                    f"{agreement['median_abs_diff_m'] * 1e6:.2f} um), "
                    f"silhouette IoU {agreement['silhouette_iou']:.4f}"
                )

    if "egl" in [backend for _, backend in runs]:
        print(
            "note: pyrender 0.1.45 draws into a 4x multisampled framebuffer on EGL (then resolves"
            " it), and single-sampled on OSMesa, as mvgrasp does."
        )
    mvgrasp_rows = [row for row in table if row["name"].startswith("mvgrasp")]
    if mvgrasp_rows and peers:
        best = max(mvgrasp_rows, key=lambda row: statistics.median(row["vps"].values()))
        for peer in peers:
            r = ratio(best, peer)
            if r is None:
                continue
            verdict = "met" if r >= TARGET_RATIO else "NOT met"
            print(
                f"mvgrasp {best['backend']} vs pyrender {PEER_MODE} on {peer['backend']}: "
                f"{r:.2f}x (target {TARGET_RATIO:.0f}x: {verdict})"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
