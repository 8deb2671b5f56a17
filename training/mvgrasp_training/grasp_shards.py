"""Reading mvgrasp grasp datasets (``grasp_dataset`` output) into NumPy, through the wheel.

The Rust core writes the shards and reads them back (checking every column's dtype and shape
against the format); this module only re-exports :mod:`mvgrasp.grasp_dataset`'s readers, so the
training package holds no second parser. A shard or manifest that cannot be read raises
:class:`mvgrasp.DatasetError` (exported here as ``ShardError``) naming the file.
"""

from __future__ import annotations

from mvgrasp import DatasetError as ShardError
from mvgrasp.grasp_dataset import GraspDataset, read_shard

__all__ = ["GraspDataset", "ShardError", "read_shard"]
