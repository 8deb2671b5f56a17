"""Heavy calls release the GIL: a Python thread keeps running while they work.

A counter thread spins in Python; the main thread makes one heavy call. With the GIL held for
the whole call the counter stands still (at most one switch interval, 5 ms, of counting before
the call starts); with it released the counter runs for the whole call. And two plans in two
threads finish sooner than one after the other: each plan spreads over the cores only in
parts (scoring, sampling), so the other's serial parts fill the gaps, which they could not
with the GIL held.
"""

from __future__ import annotations

import threading
import time
from typing import Callable

import numpy as np

import mvgrasp
from test_planning import PRIMESENSE_K, box_on_table


def python_time_during(call: Callable[[], object]) -> float:
    """The share of `call`'s wall time in which another Python thread ran."""
    count = 0
    stop = threading.Event()

    def spin() -> None:
        nonlocal count
        while not stop.is_set():
            count += 1

    thread = threading.Thread(target=spin)
    thread.start()
    time.sleep(0.05)
    # The counter's rate while the main thread sleeps (the GIL free).
    before, start = count, time.perf_counter()
    time.sleep(0.2)
    rate = (count - before) / (time.perf_counter() - start)
    before, start = count, time.perf_counter()
    call()
    elapsed = time.perf_counter() - start
    counted = count - before
    stop.set()
    thread.join()
    return counted / (rate * elapsed)


def test_planning_releases_the_gil() -> None:
    depth = box_on_table()
    share = python_time_during(lambda: mvgrasp.plan_depth(depth, PRIMESENSE_K))
    # Held, the share is at most a switch interval over the call (~0.02 for a 0.2 s call).
    assert share > 0.3, share


def test_rendering_releases_the_gil() -> None:
    vertices, triangles = mvgrasp.builtin_object("mug", 0)
    cameras = mvgrasp.hemisphere_cameras(count=10, target=(0.0, 0.0, 0.05))
    ks = [c["k"] for c in cameras]
    poses = [c["world_from_camera"] for c in cameras]
    size = {"width": cameras[0]["width"], "height": cameras[0]["height"]}
    mvgrasp.render(vertices, triangles, ks[:1], poses[:1], **size)  # the renderer opened
    share = python_time_during(lambda: mvgrasp.render(vertices, triangles, ks, poses, **size))
    assert share > 0.3, share


def test_two_threads_plan_the_same_as_one() -> None:
    depth = box_on_table()
    alone = mvgrasp.plan_depth(depth, PRIMESENSE_K, seed=5)
    results: list[object] = [None, None]

    def plan(i: int) -> None:
        results[i] = mvgrasp.plan_depth(depth, PRIMESENSE_K, seed=5)

    threads = [threading.Thread(target=plan, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert results[0] == alone and results[1] == alone
    assert np.isfinite(alone["grasps"][0]["quality"])


def test_two_threads_plan_faster_than_one_after_the_other() -> None:
    vertices, triangles = mvgrasp.builtin_object("mug", 0)
    # The top-down GQ-CNN's plan runs on one thread; the multi-view planner's (the default)
    # already spreads its views over the cores, leaving a second thread nothing to gain here.
    planner = mvgrasp.Planner(fuse=False)

    def plan() -> None:
        planner.plan_mesh(vertices, triangles, physics=False)

    plan()  # the renderer and the network loaded
    ratios = []
    for _ in range(3):
        start = time.perf_counter()
        plan()
        plan()
        one_after_the_other = time.perf_counter() - start
        threads = [threading.Thread(target=plan) for _ in range(2)]
        start = time.perf_counter()
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        ratios.append((time.perf_counter() - start) / one_after_the_other)
    # Measured 0.66-0.78 on the 2-core machine; with the GIL held it cannot be below 1.
    assert min(ratios) < 0.92, ratios
