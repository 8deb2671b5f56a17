"""Spreads an ``evaluate`` run over a Ray cluster, as ``mvgrasp.ray_launcher`` spreads a grasp
dataset's shards.

Each of ``--shards N`` Ray tasks runs ``evaluate ARGS --shard K/N`` on a worker: the objects and
clutter rounds whose place in the run's order leaves K over N, their records appended to
``OUT/shards/K-of-N.jsonl``. Then the driver runs ``evaluate ARGS`` itself, which reads every
shard's records, does what is missing (the speed suite times the driver's machine) and writes
the report: the same bytes as one machine's run. Workers must see the report folder, the mesh
files and the ``evaluate`` binary at the same paths (a shared filesystem) and run from the same
folder (the repository's root, where the shipped weights and ``../shared/data`` are found).

    cargo build --release --bin evaluate
    python scripts/evaluate_ray.py --address auto --shards 16 -- --full --out /shared/report-full

``--address`` is what ``ray.init(address=...)`` takes (``auto`` joins the cluster this machine
belongs to; omitted, a local Ray starts with ``--num-cpus`` CPUs). Ray is the only dependency
(``pip install ray``).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Optional

ROOT = Path(__file__).resolve().parents[1]


def evaluate_with_ray(
    evaluate: Path,
    arguments: Sequence[str],
    shards: int,
    address: Optional[str] = None,
    num_cpus: Optional[int] = None,
    cpus_per_shard: float = 1.0,
    cwd: Optional[Path] = None,
) -> str:
    """Runs the ``shards`` shards of ``evaluate arguments`` as Ray tasks, then the run that
    writes the report; returns that run's standard output. A shard that fails raises
    ``RuntimeError`` with its command and the end of its output. Every run starts in ``cwd``
    (default: this process's folder)."""
    import ray

    if shards < 1:
        raise ValueError(f"--shards {shards}: expected at least 1")
    if "--shard" in arguments:
        raise ValueError("the evaluate arguments must not hold --shard: the launcher gives it")
    if not ray.is_initialized():
        ray.init(address=address, num_cpus=num_cpus if address is None else None)
    evaluate = Path(evaluate).resolve()
    cwd = str(cwd or os.getcwd())
    threads = max(1, int(cpus_per_shard))

    @ray.remote(num_cpus=cpus_per_shard)
    def shard_task(index: int) -> tuple[list[str], int, str]:
        command = [str(evaluate), *arguments, "--shard", f"{index}/{shards}", "--plain"]
        done = subprocess.run(
            command,
            cwd=cwd,
            env=dict(os.environ, RAYON_NUM_THREADS=str(threads)),
            capture_output=True,
            text=True,
            check=False,
        )
        return command, done.returncode, done.stdout + done.stderr

    for command, code, output in ray.get([shard_task.remote(k) for k in range(shards)]):
        if code != 0:
            tail = "\n".join(output.splitlines()[-5:])
            raise RuntimeError(f"{' '.join(command)} exited with {code}:\n{tail}")
    merged = subprocess.run(
        [str(evaluate), *arguments, "--plain"],
        cwd=cwd,
        capture_output=True,
        text=True,
        check=False,
    )
    if merged.returncode != 0:
        raise RuntimeError(f"evaluate {' '.join(arguments)} exited with {merged.returncode}:\n"
                           f"{merged.stderr[-2000:]}")
    return merged.stdout


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0],
        usage="%(prog)s [options] -- EVALUATE_ARGUMENTS",
    )
    parser.add_argument("--shards", type=int, required=True, help="Ray tasks, one shard each")
    parser.add_argument(
        "--evaluate",
        type=Path,
        default=ROOT / "target" / "release" / "evaluate",
        help="the evaluate binary (default: target/release/evaluate)",
    )
    parser.add_argument("--address", help="ray.init address, e.g. auto or ray://host:10001")
    parser.add_argument("--num-cpus", type=int, help="CPUs of a local Ray (no --address)")
    parser.add_argument("--cpus-per-shard", type=float, default=1.0)
    parser.add_argument("arguments", nargs=argparse.REMAINDER, help="after --: evaluate's own")
    args = parser.parse_args(argv)
    arguments = args.arguments[1:] if args.arguments[:1] == ["--"] else args.arguments
    if not args.evaluate.is_file():
        print(f"error: {args.evaluate}: no evaluate binary (cargo build --release --bin evaluate)",
              file=sys.stderr)
        return 2
    try:
        print(
            evaluate_with_ray(
                args.evaluate,
                arguments,
                args.shards,
                address=args.address,
                num_cpus=args.num_cpus,
                cpus_per_shard=args.cpus_per_shard,
            ),
            end="",
        )
    except (RuntimeError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
