"""Reading mvgrasp grasp datasets (``grasp_dataset`` output) without torch or safetensors.

A shard is a safetensors file: an 8-byte little-endian header length, a JSON header naming each
tensor's dtype, shape and byte range, then the raw little-endian data. torch users can equally
call ``safetensors.torch.load_file``; this reader gives NumPy arrays with no dependency beyond
NumPy, maps the file instead of reading it, and checks what it reads.
"""

from __future__ import annotations

import json
import mmap
import struct
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mvgrasp_training._files import read_format_json

DTYPES = {
    "F32": np.dtype("<f4"),
    "F64": np.dtype("<f8"),
    "U8": np.dtype("u1"),
    "I8": np.dtype("i1"),
    "U32": np.dtype("<u4"),
    "I32": np.dtype("<i4"),
    "U64": np.dtype("<u8"),
    "I64": np.dtype("<i8"),
}
FORMAT = "mvgrasp-grasp-dataset/1"


class ShardError(ValueError):
    """A shard or manifest cannot be read; the message names the file."""


def read_shard(path: str | Path) -> dict[str, np.ndarray]:
    """Every tensor of the shard at ``path``, as read-only NumPy arrays backed by the file."""
    path = Path(path)
    try:
        with path.open("rb") as f:
            data = mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ)
    except (OSError, ValueError) as e:
        raise ShardError(f"{path}: cannot read: {e}") from e
    if len(data) < 8:
        raise ShardError(f"{path}: {len(data)} bytes, too short for a safetensors header")
    (length,) = struct.unpack("<Q", data[:8])
    if 8 + length > len(data):
        raise ShardError(f"{path}: header of {length} bytes runs past the end of the file")
    try:
        header: dict[str, Any] = json.loads(bytes(data[8 : 8 + length]))
    except json.JSONDecodeError as e:
        raise ShardError(f"{path}: header is not JSON: {e}") from e
    body = 8 + length
    tensors = {}
    for name, info in header.items():
        if name == "__metadata__":
            continue
        dtype = DTYPES.get(info.get("dtype"))
        if dtype is None:
            raise ShardError(f"{path}: tensor {name}: unknown dtype {info.get('dtype')!r}")
        start, end = info["data_offsets"]
        shape = tuple(info["shape"])
        if end - start != dtype.itemsize * int(np.prod(shape, dtype=np.int64)) or (
            body + end > len(data)
        ):
            raise ShardError(f"{path}: tensor {name}: byte range does not fit shape {shape}")
        count = (end - start) // dtype.itemsize
        tensors[name] = np.frombuffer(data, dtype=dtype, count=count, offset=body + start)
        tensors[name] = tensors[name].reshape(shape)
    return tensors


@dataclass(frozen=True)
class GraspDataset:
    """A grasp dataset folder: its manifest and finished shards."""

    root: Path
    manifest: dict[str, Any]

    @classmethod
    def open(cls, root: str | Path) -> GraspDataset:
        root = Path(root)
        path = root / "dataset.json"
        return cls(root, read_format_json(path, FORMAT, "manifest", ShardError))

    def shards(self) -> Iterator[dict[str, np.ndarray]]:
        """The finished shards, in index order."""
        for record in self.manifest["shards"]:
            yield read_shard(self.root / record["file"])

    def object_ids(self) -> list[int]:
        return [o["id"] for o in self.manifest["objects"]]
