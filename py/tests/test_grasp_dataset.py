"""Grasp-dataset shards from Python: one machine, and a local Ray cluster writing the same bytes."""

from __future__ import annotations

import json
import struct
from pathlib import Path

import numpy as np
import pytest

import mvgrasp
from mvgrasp import grasp_dataset

CATEGORIES = ["mug", "box", "can"]
SMALL = (
    "stable_poses_per_object = 1\ngrasps_per_pose = 16\nviews_per_pose = 2\n"
    "objects_per_shard = 1\nphysics_fraction = 0.05\n"
)


def read_safetensors(path: Path) -> dict[str, np.ndarray]:
    """A minimal reader of the format (8-byte header length, JSON header, raw data)."""
    data = path.read_bytes()
    (length,) = struct.unpack("<Q", data[:8])
    header = json.loads(data[8 : 8 + length])
    dtypes = {"F32": "<f4", "U8": "u1", "I8": "i1", "U32": "<u4", "U64": "<u8"}
    tensors = {}
    for name, info in header.items():
        if name == "__metadata__":
            continue
        start, end = info["data_offsets"]
        raw = data[8 + length + start : 8 + length + end]
        tensors[name] = np.frombuffer(raw, dtype=dtypes[info["dtype"]]).reshape(info["shape"])
    return tensors


def files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


@pytest.fixture(scope="module")
def config(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("config") / "small.toml"
    path.write_text(SMALL)
    return path


@pytest.fixture(scope="module")
def single_machine(tmp_path_factory: pytest.TempPathFactory, config: Path) -> Path:
    out = tmp_path_factory.mktemp("single")
    grasp_dataset.generate(out, config, categories=CATEGORIES)
    return out


def test_one_machine_writes_shards_and_a_manifest(single_machine: Path) -> None:
    manifest = json.loads((single_machine / "dataset.json").read_text())
    assert manifest["format"] == "mvgrasp-grasp-dataset/1"
    assert manifest["num_shards"] == 3 and len(manifest["shards"]) == 3
    assert [o["id"] for o in manifest["objects"]] == [0, 1, 2]
    total = 0
    for record in manifest["shards"]:
        shard = read_safetensors(single_machine / record["file"])
        n = record["datapoints"]
        total += n
        assert shard["depth_crops"].shape == (n, 32, 32)
        assert shard["robust_label"].sum() == record["positives"]
        assert set(np.unique(shard["object_id"])) <= set(record["objects"])
        assert ((shard["physics"] >= -1) & (shard["physics"] <= 1)).all()
    assert total == manifest["totals"]["datapoints"] > 0


def test_a_finished_shard_is_not_made_again(single_machine: Path, config: Path) -> None:
    before = files(single_machine)
    record = grasp_dataset.generate_shard(single_machine, 1, config, categories=CATEGORIES)
    assert record["index"] == 1
    assert files(single_machine) == before


def test_a_shard_made_with_another_config_is_refused_not_reused(
    single_machine: Path, tmp_path: Path
) -> None:
    # The regression: from Python the old shards were reused and the manifest then claimed
    # the new config. Every shard records the hash of its config and objects.
    other = tmp_path / "other.toml"
    other.write_text(SMALL.replace("grasps_per_pose = 16", "grasps_per_pose = 17"))
    before = files(single_machine)
    with pytest.raises(mvgrasp.DatasetError, match="another config"):
        grasp_dataset.generate_shard(single_machine, 1, other, categories=CATEGORIES)
    with pytest.raises(mvgrasp.DatasetError, match="another config"):
        grasp_dataset.write_manifest(single_machine, other, categories=CATEGORIES)
    with pytest.raises(mvgrasp.DatasetError, match="another config"):
        grasp_dataset.generate(single_machine, other, categories=CATEGORIES)
    assert files(single_machine) == before


def test_bad_requests_raise_with_the_file_named(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("grasps_per_pose = 0\n")
    with pytest.raises(mvgrasp.DatasetError, match="bad.toml: config key grasps_per_pose = 0"):
        grasp_dataset.num_shards(bad)
    unknown = tmp_path / "unknown.toml"
    unknown.write_text("grasp_per_pose = 3\n")
    with pytest.raises(mvgrasp.DatasetError, match="unknown.toml: not a valid config"):
        grasp_dataset.num_shards(unknown)
    with pytest.raises(ValueError, match="nowhere.obj"):
        grasp_dataset.num_shards(meshes=[tmp_path / "nowhere.obj"])
    with pytest.raises(mvgrasp.DatasetError, match="does not exist"):
        grasp_dataset.generate_shard(tmp_path / "out", 7, categories=CATEGORIES)


def test_a_local_ray_cluster_writes_the_same_bytes(
    tmp_path: Path, config: Path, single_machine: Path
) -> None:
    ray = pytest.importorskip("ray")
    from mvgrasp.ray_launcher import generate_with_ray

    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        generate_with_ray(tmp_path, config, categories=CATEGORIES)
    finally:
        ray.shutdown()
    assert files(tmp_path) == files(single_machine)


def test_a_changed_shard_is_refused_by_its_checksum_and_made_again(
    single_machine: Path, config: Path, tmp_path: Path
) -> None:
    # A copy, so that the module's dataset stays as it was for the other tests.
    out = tmp_path / "copy"
    out.mkdir()
    for name, data in files(single_machine).items():
        (out / name).write_bytes(data)
    manifest = json.loads((out / "dataset.json").read_text())
    record = manifest["shards"][1]
    assert len(record["sha256"]) == 64
    shard = out / record["file"]
    whole = shard.read_bytes()
    shard.write_bytes(whole[:-1] + bytes([whole[-1] ^ 1]))
    dataset = grasp_dataset.GraspDataset.open(out)
    with pytest.raises(mvgrasp.DatasetError, match=rf"{record['file']}: its SHA-256"):
        list(dataset.shards())
    # A rerun makes the changed shard again, byte for byte.
    grasp_dataset.generate(out, config, categories=CATEGORIES)
    assert files(out) == files(single_machine)
    assert sum(1 for _ in grasp_dataset.GraspDataset.open(out).shards()) == 3
