"""Two Python threads planning at once against one plan after the other (the GIL released).

Prints, per kind of plan, the median over ROUNDS of: the time of one plan, of two one after the
other, of two in two threads, and the ratio threads / sequential (1.0 or more if the GIL were
held through the plan; below 1.0 as far as one plan leaves cores idle for the other).

Usage: python benches/python/threads.py   (the mvgrasp wheel installed; ROUNDS=5 by default)
"""

from __future__ import annotations

import os
import statistics
import threading
import time
from pathlib import Path
from typing import Callable

import numpy as np

import mvgrasp

ROUNDS = int(os.environ.get("ROUNDS", "5"))
SHARED = Path(os.environ.get("MVGRASP_SHARED_DATA", Path(__file__).parents[3] / "shared" / "data"))


def timed(call: Callable[[], object]) -> float:
    start = time.perf_counter()
    call()
    return time.perf_counter() - start


def in_two_threads(call: Callable[[], object]) -> None:
    threads = [threading.Thread(target=call) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()


def main() -> None:
    vertices, triangles = mvgrasp.builtin_object("mug", 0)
    work: dict[str, Callable[[], object]] = {
        "plan_mesh (top-down, no physics)": lambda: mvgrasp.Planner().plan_mesh(
            vertices, triangles, physics=False
        ),
        "plan_mesh (fuse, 5 views, no physics)": lambda: mvgrasp.Planner(fuse=True).plan_mesh(
            vertices, triangles, physics=False
        ),
    }
    primesense = SHARED / "real_depth/gqcnn/data/examples/single_object/primesense"
    if primesense.is_dir():
        depth = np.load(primesense / "depth_0.npy")
        camera = mvgrasp.Camera.from_intr_file(
            SHARED / "real_depth/gqcnn/data/calib/primesense/primesense.intr"
        )
        work["plan (real Primesense depth)"] = lambda: mvgrasp.Planner().plan(depth, camera)
    print(f"{os.cpu_count()} cores, medians of {ROUNDS} rounds, seconds")
    print("| plan | one | two, one after the other | two threads | threads / sequential |")
    print("|---|---|---|---|---|")
    for name, call in work.items():
        call()  # renderer and networks loaded
        one, sequential, threads, ratio = [], [], [], []
        for _ in range(ROUNDS):
            one.append(timed(call))
            sequential.append(timed(lambda: (call(), call())))
            threads.append(timed(lambda: in_two_threads(call)))
            ratio.append(threads[-1] / sequential[-1])
        m = statistics.median
        print(f"| {name} | {m(one):.3f} | {m(sequential):.3f} | {m(threads):.3f} | {m(ratio):.2f} |")


if __name__ == "__main__":
    main()
