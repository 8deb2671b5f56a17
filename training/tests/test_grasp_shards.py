"""The shard reader against shards the Rust generator writes (needs the mvgrasp wheel)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from conftest import generate_grasp_dataset
from mvgrasp_training.grasp_shards import GraspDataset, ShardError, read_shard


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return generate_grasp_dataset(
        tmp_path_factory.mktemp("grasps"),
        "stable_poses_per_object = 1\ngrasps_per_pose = 16\nviews_per_pose = 2\n"
        "objects_per_shard = 1\nphysics_fraction = 0.1\n",
        ["box", "can"],
    )


def test_shards_read_with_the_counts_of_the_manifest(dataset: Path) -> None:
    data = GraspDataset.open(dataset)
    assert data.object_ids() == [0, 1]
    for record, shard in zip(data.manifest["shards"], data.shards()):
        n = record["datapoints"]
        assert shard["depth_crops"].shape == (n, 32, 32)
        assert shard["depth_crops"].dtype == np.float32
        assert int(shard["robust_label"].sum()) == record["positives"]
        assert shard["object_from_gripper"].shape == (n, 4, 4)
        # Rigid transforms: the bottom row is (0, 0, 0, 1).
        assert np.allclose(shard["object_from_gripper"][:, 3], [0, 0, 0, 1])
        assert (shard["object_id"] == record["objects"][0]).all()


def test_the_wheel_reads_what_the_safetensors_library_reads(dataset: Path) -> None:
    from safetensors.numpy import load_file

    for record in GraspDataset.open(dataset).manifest["shards"]:
        ours = read_shard(dataset / record["file"])
        theirs = load_file(str(dataset / record["file"]))
        assert set(ours) == set(theirs)
        for name, array in theirs.items():
            assert ours[name].dtype == array.dtype, name
            assert np.array_equal(ours[name], array, equal_nan=True), name


def test_bad_files_name_the_file(dataset: Path, tmp_path: Path) -> None:
    good = (dataset / "shard_00000.safetensors").read_bytes()
    cut = tmp_path / "cut.safetensors"
    cut.write_bytes(good[: len(good) // 2])
    with pytest.raises(ShardError, match="cut.safetensors"):
        read_shard(cut)
    tiny = tmp_path / "tiny.safetensors"
    tiny.write_bytes(b"abc")
    with pytest.raises(ShardError, match="tiny.safetensors"):
        read_shard(tiny)
    with pytest.raises(ShardError, match="dataset.json"):
        GraspDataset.open(tmp_path)
