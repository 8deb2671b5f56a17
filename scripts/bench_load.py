"""The planner as a long-lived object under load, from Python (`examples/bench_load.rs` measures
the same in Rust): one `mvgrasp.Planner`, one depth image planned on again and again.

1. `--plans N` plans one after the other, the process's resident memory (VmRSS of
   /proc/self/status) sampled every N/20 plans: printed at the start, after the warm-up (the
   first 5%) and at the end, with the growth after the warm-up; and whether every plan gave the
   first one's grasps.
2. `--thread-plans M` plans shared by 1, 2 and 4 Python threads (a ThreadPoolExecutor, one
   Planner): a markdown table of plans/s, p50 and p99 latency, and whether every grasp equals
   the single-thread one (the same seed and image give the same `grasps.json` bytes). The plans
   overlap only because the GIL is released while one runs.

Usage (the mvgrasp wheel installed):

    python scripts/bench_load.py [--plans 10000] [--threads 1 2 4] [--thread-plans 400]
                                 [--data ../shared/data]

The image is gqcnn's real Primesense `depth_0.npy` under `DATA/real_depth` when it is there,
else a synthetic 4 x 6 cm box on a table 0.7 m below a Primesense (the wheel's tests' box).
"""

from __future__ import annotations

import argparse
import os
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

import mvgrasp

REPO = Path(__file__).resolve().parents[1]


def rss_mib() -> float:
    """The process's resident memory, MiB (0 where /proc is missing)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return 0.0


def depth_image(data: Path) -> tuple[str, np.ndarray, mvgrasp.Camera]:
    """The real Primesense image and its camera, or the synthetic box on a table."""
    root = data / "real_depth/gqcnn/data"
    depth_path = root / "examples/single_object/primesense/depth_0.npy"
    intr = root / "calib/primesense/primesense.intr"
    if depth_path.is_file() and intr.is_file():
        depth = np.load(depth_path)
        return f"{depth_path} (real Primesense)", depth, mvgrasp.Camera.from_intr_file(intr)
    camera = mvgrasp.Camera.preset("primesense")
    fx, cx, cy = camera.k[0, 0], camera.k[0, 2], camera.k[1, 2]
    v, u = np.mgrid[0 : camera.height, 0 : camera.width].astype(np.float32)
    x, y = (u - cx) * 0.65 / fx, (v - cy) * 0.65 / fx
    depth = np.full((camera.height, camera.width), 0.7, dtype=np.float32)
    depth[(np.abs(x) < 0.02) & (np.abs(y) < 0.03)] = 0.65
    return "a synthetic box on a table (640 x 480)", depth, camera


def quantile_ms(sorted_s: list[float], q: float) -> float:
    """The `q`-quantile of sorted seconds, nearest rank, in milliseconds."""
    rank = min(max(int(np.ceil(q * len(sorted_s))), 1), len(sorted_s))
    return 1000.0 * sorted_s[rank - 1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    add = parser.add_argument
    add("--plans", type=int, default=10_000, help="plans in a row for the memory measurement")
    add("--threads", type=int, nargs="+", default=[1, 2, 4], help="the table's thread counts")
    add("--thread-plans", type=int, default=400, help="plans per row of the table, all threads")
    default_data = os.environ.get("MVGRASP_SHARED_DATA", str(REPO.parent / "shared" / "data"))
    add("--data", type=Path, default=Path(default_data), help="the shared data folder")
    args = parser.parse_args()
    if args.plans < 1 or args.thread_plans < 1 or min(args.threads) < 1:
        parser.error("--plans, --thread-plans and --threads: at least 1")

    source, depth, camera = depth_image(args.data)
    planner = mvgrasp.Planner()
    print(f"image: {source}; {os.cpu_count()} cores; mvgrasp {mvgrasp.__version__}")

    # 1. Memory over many plans one after the other.
    n = args.plans
    every = max(n // 20, 1)
    warm_up = max(n // 20, 1)
    rss_start = rss_mib()
    reference = planner.plan(depth, camera).grasps_json
    rss_warm, samples, differing = rss_start, [], 0
    started = time.perf_counter()
    for i in range(1, n + 1):
        if planner.plan(depth, camera).grasps_json != reference:
            differing += 1
        if i == warm_up:
            rss_warm = rss_mib()
        if i % every == 0 or i == n:
            samples.append(rss_mib())
    elapsed = time.perf_counter() - started
    rss_end = rss_mib()
    peak = max([rss_warm, *samples])
    print(f"\n{n} plans one after the other in {elapsed:.1f} s ({1000 * elapsed / n:.1f} ms each)")
    print(f"RSS every {every} plans, MiB: " + " ".join(f"{r:.0f}" for r in samples))
    print(
        f"RSS: start {rss_start:.1f} MiB, after warm-up ({warm_up} plans) {rss_warm:.1f} MiB, "
        f"end {rss_end:.1f} MiB (peak after warm-up {peak:.1f}); growth after warm-up "
        f"{rss_end - rss_warm:+.1f} MiB"
    )
    same = "yes" if differing == 0 else f"no ({differing} of {n} differ)"
    print(f"every plan gave the first one's grasps: {same}")

    # 2. Throughput and latency with 1, 2, 4 threads sharing the planner.
    def one_plan(_: int) -> tuple[float, bool]:
        t0 = time.perf_counter()
        text = planner.plan(depth, camera).grasps_json
        return time.perf_counter() - t0, text == reference

    print(f"\n{args.thread_plans} plans per row, shared by the threads (ThreadPoolExecutor)")
    print()
    print("| threads | plans/s | p50 ms | p99 ms | same grasps as one thread |")
    print("|---|---|---|---|---|")
    for threads in args.threads:
        with ThreadPoolExecutor(max_workers=threads) as pool:
            started = time.perf_counter()
            results = list(pool.map(one_plan, range(args.thread_plans)))
            wall = time.perf_counter() - started
        latencies = sorted(r[0] for r in results)
        differing = sum(not r[1] for r in results)
        same = "yes" if differing == 0 else f"no ({differing} differ)"
        print(
            f"| {threads} | {len(results) / wall:.1f} | {quantile_ms(latencies, 0.5):.1f} | "
            f"{quantile_ms(latencies, 0.99):.1f} | {same} |"
        )


if __name__ == "__main__":
    main()
