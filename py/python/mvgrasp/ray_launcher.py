"""Spreads a grasp dataset's shards over a Ray cluster.

Each shard is one Ray task that calls :func:`mvgrasp.grasp_dataset.generate_shard` on a worker;
the driver writes the manifest at the end. Shards depend only on the config and the object list,
so the result is byte for byte what one machine makes. Workers must see the output folder (a
shared filesystem) and the mesh files at the same paths, and have mvgrasp installed.

From the command line, on a machine of the cluster::

    python -m mvgrasp.ray_launcher --address auto --out /shared/dataset \\
        --config dataset.toml --per-category 10

``--address`` is what ``ray.init(address=...)`` takes (``auto`` joins the cluster this machine
belongs to; omitted, a local Ray starts with ``--num-cpus`` workers).
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Sequence
from typing import Any, Optional

from mvgrasp import grasp_dataset
from mvgrasp.grasp_dataset import PathLike


def generate_with_ray(
    out: PathLike,
    config: Optional[PathLike] = None,
    meshes: Optional[Sequence[PathLike]] = None,
    per_category: int = 1,
    categories: Optional[Sequence[str]] = None,
    library_seed: int = 0,
    address: Optional[str] = None,
    num_cpus: Optional[int] = None,
    cpus_per_shard: float = 1.0,
) -> dict[str, Any]:
    """Makes every unfinished shard as a Ray task and writes the manifest; returns it.

    Connects with ``ray.init(address=address)`` unless Ray is already initialised (a local
    cluster with ``num_cpus`` CPUs when ``address`` is None). Each task asks for
    ``cpus_per_shard`` CPUs and uses that many threads.
    """
    import ray

    if not ray.is_initialized():
        ray.init(address=address, num_cpus=num_cpus if address is None else None)
    objects = grasp_dataset.objects_arguments(meshes, per_category, categories, library_seed)
    out = os.path.abspath(out)
    config_path = None if config is None else os.path.abspath(config)
    threads = max(1, int(cpus_per_shard))

    @ray.remote(num_cpus=cpus_per_shard)
    def shard_task(index: int) -> dict[str, Any]:
        os.environ["RAYON_NUM_THREADS"] = str(threads)
        return grasp_dataset.generate_shard(out, index, config_path, **objects)

    count = grasp_dataset.num_shards(config_path, **objects)
    ray.get([shard_task.remote(i) for i in range(count)])
    return grasp_dataset.write_manifest(out, config_path, **objects)


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--config")
    parser.add_argument("--mesh", action="append", help="mesh file or folder (repeatable)")
    parser.add_argument("--per-category", type=int, default=1)
    parser.add_argument("--categories", help="comma-separated built-in categories")
    parser.add_argument("--library-seed", type=int, default=0)
    parser.add_argument("--address", help="ray.init address, e.g. auto or ray://host:10001")
    parser.add_argument("--num-cpus", type=int, help="CPUs of a local Ray (no --address)")
    parser.add_argument("--cpus-per-shard", type=float, default=1.0)
    args = parser.parse_args(argv)
    manifest = generate_with_ray(
        args.out,
        config=args.config,
        meshes=args.mesh,
        per_category=args.per_category,
        categories=None if args.categories is None else args.categories.split(","),
        library_seed=args.library_seed,
        address=args.address,
        num_cpus=args.num_cpus,
        cpus_per_shard=args.cpus_per_shard,
    )
    totals = manifest["totals"]
    print(f"{totals['datapoints']} datapoints in {len(manifest['shards'])} shards: {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
