"""torch's side of the GQ-CNN benchmark (see run.sh beside this file).

Loads a training export with ``mvgrasp_training.export.load_gqcnn`` and times what the Rust
example ``bench_gqcnn`` times: ``softmax(net(depth, pose))[:, 1]`` under
``torch.inference_mode()`` with ``torch.set_num_threads(T)``, on the same seeded inputs
(SplitMix64, the same numbers as the Rust example draws), a warm-up, then calls until
``--seconds`` have passed and at least 5 calls were made. Prints one JSON line per batch size:
the median call, crops per second at that median, and the mean probability (a check that both
runtimes scored the same inputs alike).

``--flush-denormal`` runs with ``torch.set_flush_denormal(True)`` (runtime "torch-ftz"): trained
weights hold many subnormal values, each product with one costs x86 a microcode assist, and the
Rust runtime flushes them to zero when it loads a network; this is torch's switch for the same.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

import numpy as np
import torch

from mvgrasp_training.export import load_gqcnn


def splitmix64(seed: int, count: int) -> np.ndarray:
    """``count`` SplitMix64 outputs from ``seed``, as the Rust example's generator gives them."""
    with np.errstate(over="ignore"):
        state = np.uint64(seed) + np.arange(1, count + 1, dtype=np.uint64) * np.uint64(
            0x9E3779B97F4A7C15
        )
        z = state
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        return z ^ (z >> np.uint64(31))


def uniform(bits: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Uniform in ``[lo, hi)`` from 53 bits, in f64, rounded once to f32 (as in Rust)."""
    unit = (bits >> np.uint64(11)).astype(np.float64) / float(1 << 53)
    return (lo + (hi - lo) * unit).astype(np.float32)


def inputs(batch: int, size: int, pose_inputs: int, seed: int) -> tuple[torch.Tensor, ...]:
    """Crops ``[batch, 1, size, size]`` (0.6..0.75 m), then poses ``[batch, P]`` (grasp depth
    0.6..0.75 m, theta 0..1.57 rad), drawn in that order from one generator."""
    pixels = batch * size * size
    bits = splitmix64(seed, pixels + batch * pose_inputs)
    depth = uniform(bits[:pixels], 0.6, 0.75).reshape(batch, 1, size, size)
    pose_bits = bits[pixels:].reshape(batch, pose_inputs)
    pose = np.empty((batch, pose_inputs), dtype=np.float32)
    pose[:, 0] = uniform(pose_bits[:, 0], 0.6, 0.75)
    if pose_inputs > 1:
        pose[:, 1:] = uniform(pose_bits[:, 1:], 0.0, 1.57)
    return torch.from_numpy(depth), torch.from_numpy(pose)


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("model", type=Path, help="the network's NAME.json (weights beside it)")
    parser.add_argument("--threads", type=int, default=1, help="torch.set_num_threads")
    parser.add_argument("--batches", default="1,64,256", help="batch sizes, comma-separated")
    parser.add_argument("--seconds", type=float, default=2.0, help="timed seconds per batch")
    parser.add_argument("--warmup-seconds", type=float, default=0.3, help="untimed seconds")
    parser.add_argument("--seed", type=int, default=0, help="seed of the inputs")
    parser.add_argument(
        "--flush-denormal", action="store_true", help="torch.set_flush_denormal(True)"
    )
    return parser.parse_args()


def main() -> int:
    args = parse_args()
    torch.set_num_threads(args.threads)
    if args.flush_denormal and not torch.set_flush_denormal(True):
        raise SystemExit("error: torch cannot flush denormals on this CPU")
    net, description = load_gqcnn(args.model)
    arch = description["architecture"]
    size, pose_inputs = arch["image_size_px"], arch["pose_inputs"]

    def call(depth: torch.Tensor, pose: torch.Tensor) -> torch.Tensor:
        return torch.softmax(net(depth, pose), dim=-1)[:, 1]

    for batch in (int(b) for b in args.batches.split(",")):
        depth, pose = inputs(batch, size, pose_inputs, args.seed)
        with torch.inference_mode():
            warm = time.perf_counter()
            calls = 0
            while calls < 2 or time.perf_counter() - warm < args.warmup_seconds:
                p = call(depth, pose)
                calls += 1
            times = []
            started = time.perf_counter()
            while len(times) < 5 or time.perf_counter() - started < args.seconds:
                t = time.perf_counter()
                p = call(depth, pose)
                times.append(time.perf_counter() - t)
        median_s = statistics.median(times)
        line = {
            "runtime": "torch-ftz" if args.flush_denormal else "torch",
            "torch": torch.__version__,
            "model": str(args.model),
            "architecture": arch["name"],
            "pose_inputs": pose_inputs,
            "threads": args.threads,
            "batch": batch,
            "calls": len(times),
            "median_s": median_s,
            "crops_per_s": batch / median_s,
            "mean_p": float(p.double().mean()),
        }
        print(json.dumps(line, sort_keys=True), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
