"""One short training run on a dataset the wheel generates: resumable, exported, measured."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from conftest import generate_grasp_dataset  # noqa: E402
from mvgrasp_training.config import parse_config  # noqa: E402
from mvgrasp_training.export import load_gqcnn  # noqa: E402
from mvgrasp_training.gqcnn import GQCNN, small  # noqa: E402
from mvgrasp_training.train import (  # noqa: E402
    load_arrays,
    metrics,
    shard_labels,
    predict,
    split_by_object,
    train,
)


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small grasp dataset of four built-in objects, made by the wheel."""
    return generate_grasp_dataset(
        tmp_path_factory.mktemp("grasps"),
        "stable_poses_per_object = 1\ngrasps_per_pose = 24\nviews_per_pose = 3\n"
        "objects_per_shard = 2\nphysics_fraction = 0.0\n",
        ["box", "can", "mug", "bottle"],
    )


def test_a_short_run_trains_resumes_and_exports(dataset: Path, tmp_path: Path) -> None:
    data = dataset
    config = parse_config(
        {
            "name": "test",
            "seed": 0,
            "data": {"dataset_dir": str(data), "val_fraction": 0.25},
            "train": {"epochs": 1, "batch_size": 32, "learning_rate": 1e-3},
        }
    )
    out = tmp_path / "run"
    report = train(config, out)
    assert report["val_objects"] == 1 and report["train_objects"] == 3
    description = json.loads((out / "test.json").read_text())
    assert description["training"]["train_count"] == report["train_count"]
    assert (out / "test.safetensors").exists()
    # The reported validation figures are the exported network's on the held-out object.
    net, _ = load_gqcnn(out / "test.json")
    _, val_set = split_by_object(load_arrays(data, 1), 0.25, 0)
    recomputed = metrics(predict(net, val_set), val_set.label)
    assert recomputed["count"] == report["val"]["count"] > 0
    for key in ("balanced_accuracy", "precision", "recall"):
        assert recomputed[key] == pytest.approx(report["val"][key], nan_ok=True), key
    # The input contract comes from the dataset (the default PhoXi S, Dex-Net's 96 -> 32 crop).
    contract = description["input"]
    assert contract["crop_window_px"] == 96 and contract["crop_size_px"] == 32
    assert contract["focal_px"] == pytest.approx(552.5)
    assert contract["camera_distance_m"] == pytest.approx([0.65, 0.75])
    low, high = contract["grasp_depth_m"]
    assert 0.5 < low < high < 0.8
    assert contract["pose_inputs"] == ["grasp_depth_m"]
    # Provenance without a machine's absolute paths.
    training = description["training"]
    assert len(training["dataset"]["manifest_sha256"]) == 64
    assert training["torch"] == torch.__version__
    assert training["code_commit"]

    def strings(value):
        if isinstance(value, dict):
            return [s for v in value.values() for s in strings(v)]
        if isinstance(value, list):
            return [s for v in value for s in strings(v)]
        return [value] if isinstance(value, str) else []

    assert not [s for s in strings(description) if s.startswith("/")], "absolute path recorded"
    # A second run with more epochs resumes after the first.
    longer = parse_config(
        {
            "name": "test",
            "seed": 0,
            "data": {"dataset_dir": str(data), "val_fraction": 0.25},
            "train": {"epochs": 2, "batch_size": 32, "learning_rate": 1e-3},
        }
    )
    report = train(longer, out)
    assert [h["epoch"] for h in report["history"]] == [1, 2]
    assert (out / "learning_curve.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # A run with another setting into the same folder is refused, naming the checkpoint and
    # the setting, and leaves the run's files as they were.
    other = parse_config(
        {
            "name": "test",
            "seed": 0,
            "data": {"dataset_dir": str(data), "val_fraction": 0.25},
            "train": {"epochs": 3, "batch_size": 32, "learning_rate": 2e-3},
        }
    )
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    with pytest.raises(ValueError, match=r"checkpoint.*another config \(train\.learning_rate"):
        train(other, out)
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before
    # As is a checkpoint that another version of the training code wrote.
    checkpoint = next(out.glob("*.pt"))
    state = torch.load(checkpoint, weights_only=False)
    state["identity"]["format"] = "mvgrasp-checkpoint/0"
    torch.save(state, checkpoint)
    with pytest.raises(ValueError, match="another version of the training code"):
        train(longer, out)


def _tensors(path: Path) -> dict[str, np.ndarray]:
    from safetensors.numpy import load_file

    return load_file(str(path))


def test_two_processes_with_ddp_train_the_network_one_process_trains(
    dataset: Path, tmp_path: Path
) -> None:
    """torchrun, gloo, 2 processes on the CPU: the same weights as one process (to rounding)."""
    config = tmp_path / "ddp.toml"
    config.write_text(
        f'name = "ddp"\nseed = 3\n[data]\ndataset_dir = "{dataset}"\nval_fraction = 0.25\n'
        "[train]\nepochs = 2\nbatch_size = 16\nlearning_rate = 1e-3\nthreads = 1\n"
    )
    run = [sys.executable, "-m", "mvgrasp_training.train", str(config), "--out"]
    subprocess.run([*run, str(tmp_path / "one")], check=True, timeout=600)
    torchrun = [sys.executable, "-m", "torch.distributed.run", "--standalone", "--nproc_per_node",
                "2", "-m", "mvgrasp_training.train", str(config), "--out"]
    subprocess.run([*torchrun, str(tmp_path / "two")], check=True, timeout=600)
    described = json.loads((tmp_path / "two" / "ddp.json").read_text())
    assert described["training"]["processes"] == 2
    assert [h["epoch"] for h in described["training"]["history"]] == [1, 2]
    one = _tensors(tmp_path / "one" / "ddp.safetensors")
    two = _tensors(tmp_path / "two" / "ddp.safetensors")
    torch.manual_seed(3)  # the config's seed: the initial weights of both runs
    initial = GQCNN(small()).state_dict()
    assert one.keys() == two.keys()
    moved = {}
    for name in one:
        moved[name] = np.abs(one[name] - initial[name].numpy()).max()
        apart = np.abs(one[name] - two[name]).max()
        print(f"{name}: moved {moved[name]:.2e}, one vs two processes {apart:.2e}")
        assert apart < 1e-4, name
    # Both runs trained: every parameter moved, by a few Adam steps of 1e-3.
    assert all(moved[n] > 0 for n in one if n.endswith(("weight", "bias")))
    assert moved["convs.0.weight"] > 1e-3


def test_the_physics_and_combined_labels_follow_the_trials() -> None:
    shard = {
        "robust_label": np.array([1, 1, 0, 0, 1], dtype=np.uint8),
        "collision_free": np.array([1, 1, 1, 0, 1], dtype=np.uint8),
        "physics": np.array([1, 0, 1, -1, -1], dtype=np.int8),
        "physics_rate": np.array([0.7, 0.2, 0.5, -1.0, -1.0], dtype=np.float32),
    }
    assert shard_labels(shard, "robust", "d").tolist() == [1, 1, 0, 0, 1]
    # A colliding datapoint is a physics negative; a free one without trials has no label.
    assert shard_labels(shard, "physics", "d").tolist() == [1, 0, 1, 0, -1]
    assert shard_labels(shard, "both", "d").tolist() == [1, 0, 0, 0, -1]
    old = {k: v for k, v in shard.items() if k != "physics_rate"}
    with pytest.raises(ValueError, match="d: the dataset has no physics labels"):
        shard_labels(old, "physics", "d")
