"""Grasp datasets: labelled grasp crops as safetensors shards with a JSON manifest.

The Rust generator does the work; these functions make the whole dataset (the generator's own
loop), or one shard, count the shards, and write the manifest, so that shards can be spread
over processes or machines
(:mod:`mvgrasp.ray_launcher`). Every shard depends only on the config and the object list, so
any split of the shards writes the same bytes as one machine making them all.

Reading a dataset back (:class:`GraspDataset`, :func:`read_shard`) goes through the same Rust
code, which checks every column against the format.

Objects are mesh files or folders (``meshes``), or, when ``meshes`` is None, the built-in
library (``per_category`` objects of each of ``categories``, default all).
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Optional, Union

import numpy as np

from mvgrasp import _native
from mvgrasp._native import DatasetError

PathLike = Union[str, "os.PathLike[str]"]


def objects_arguments(
    meshes: Optional[Sequence[PathLike]],
    per_category: int,
    categories: Optional[Sequence[str]],
    library_seed: int,
) -> dict[str, Any]:
    """The object-selection keyword arguments of the native functions (mesh paths as text;
    the native side makes them absolute)."""
    return {
        "meshes": None if meshes is None else [os.fspath(m) for m in meshes],
        "per_category": per_category,
        "categories": None if categories is None else list(categories),
        "library_seed": library_seed,
    }


def num_shards(
    config: Optional[PathLike] = None,
    meshes: Optional[Sequence[PathLike]] = None,
    per_category: int = 1,
    categories: Optional[Sequence[str]] = None,
    library_seed: int = 0,
) -> int:
    """How many shards the dataset has (``objects_per_shard`` objects each)."""
    return _native.grasp_dataset_num_shards(
        None if config is None else os.fspath(config),
        **objects_arguments(meshes, per_category, categories, library_seed),
    )


def generate_shard(
    out: PathLike,
    shard: int,
    config: Optional[PathLike] = None,
    meshes: Optional[Sequence[PathLike]] = None,
    per_category: int = 1,
    categories: Optional[Sequence[str]] = None,
    library_seed: int = 0,
    backend: str = "auto",
) -> dict[str, Any]:
    """Makes shard ``shard`` in ``out`` (skipped when already finished); returns its record
    (object ids, datapoints, positives, physics counts). The GIL is released while it runs."""
    return _native.generate_grasp_shard(
        os.fspath(out),
        shard,
        None if config is None else os.fspath(config),
        backend=backend,
        **objects_arguments(meshes, per_category, categories, library_seed),
    )


def write_manifest(
    out: PathLike,
    config: Optional[PathLike] = None,
    meshes: Optional[Sequence[PathLike]] = None,
    per_category: int = 1,
    categories: Optional[Sequence[str]] = None,
    library_seed: int = 0,
) -> dict[str, Any]:
    """Writes ``out/dataset.json`` from the shards finished in ``out``; returns it."""
    return _native.write_grasp_manifest(
        os.fspath(out),
        None if config is None else os.fspath(config),
        **objects_arguments(meshes, per_category, categories, library_seed),
    )


def generate(
    out: PathLike,
    config: Optional[PathLike] = None,
    meshes: Optional[Sequence[PathLike]] = None,
    per_category: int = 1,
    categories: Optional[Sequence[str]] = None,
    library_seed: int = 0,
    backend: str = "auto",
) -> dict[str, Any]:
    """Makes every unfinished shard on this machine and the manifest, with the Rust
    generator's loop (the checks and bytes of the ``grasp_dataset`` command: a folder holding a
    dataset of another config is refused); returns the manifest. The GIL is released while it
    runs."""
    return _native.generate_grasp_dataset(
        os.fspath(out),
        None if config is None else os.fspath(config),
        backend=backend,
        **objects_arguments(meshes, per_category, categories, library_seed),
    )


def read_shard(path: PathLike) -> dict[str, np.ndarray]:
    """Every column of the shard at ``path`` as a NumPy array (see the Rust docs of
    ``mvgrasp::grasp_dataset::shard`` for the table); :class:`mvgrasp.DatasetError` naming the
    file when it is not a readable shard of this format."""
    return _native.read_grasp_shard(os.fspath(path))


@dataclass(frozen=True)
class GraspDataset:
    """A grasp dataset folder: its manifest (``dataset.json``) and finished shards."""

    root: Path
    manifest: dict[str, Any]

    @classmethod
    def open(cls, root: PathLike) -> GraspDataset:
        """Reads ``root/dataset.json``; :class:`mvgrasp.DatasetError` when it is missing or not
        a grasp-dataset manifest."""
        return cls(Path(root), _native.read_grasp_manifest(os.fspath(root)))

    def shards(self) -> Iterator[dict[str, np.ndarray]]:
        """The finished shards' columns, in index order; :class:`mvgrasp.DatasetError` naming
        a shard whose bytes are not the ones the manifest records (its ``sha256``: changed or
        damaged since it was written)."""
        for record in self.manifest["shards"]:
            path = self.root / record["file"]
            expected = record.get("sha256", "")
            if expected:
                try:
                    found = hashlib.sha256(path.read_bytes()).hexdigest()
                except OSError as error:
                    raise DatasetError(f"{path}: cannot read the shard: {error}") from error
                if found != expected:
                    raise DatasetError(
                        f"{path}: its SHA-256 is {found}, the manifest records {expected} "
                        "(changed or damaged since it was written; make it again)"
                    )
            yield read_shard(path)

    def object_ids(self) -> list[int]:
        """The ids of the dataset's objects, in manifest order."""
        return [o["id"] for o in self.manifest["objects"]]
