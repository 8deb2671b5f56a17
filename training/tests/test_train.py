"""One short training run on a dataset the wheel generates: resumable, exported, measured."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("mvgrasp.grasp_dataset")

from mvgrasp_training.config import parse_config  # noqa: E402
from mvgrasp_training.train import train  # noqa: E402


def test_a_short_run_trains_resumes_and_exports(tmp_path: Path) -> None:
    config_toml = tmp_path / "small.toml"
    config_toml.write_text(
        "stable_poses_per_object = 1\ngrasps_per_pose = 24\nviews_per_pose = 3\n"
        "objects_per_shard = 2\nphysics_fraction = 0.0\n"
    )
    data = tmp_path / "data"
    # In its own process: the renderer's Mesa LLVM and the LLVM in torch's triton, loaded into
    # one process, crash it.
    subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys, mvgrasp.grasp_dataset as g; "
            "g.generate(sys.argv[1], sys.argv[2], categories=['box', 'can', 'mug', 'bottle'])",
            str(data),
            str(config_toml),
        ],
        check=True,
    )
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
    assert 0.0 <= report["val"]["balanced_accuracy"] <= 1.0
    assert report["val_objects"] == 1 and report["train_objects"] == 3
    description = json.loads((out / "gqcnn.json").read_text())
    assert description["training"]["train_count"] == report["train_count"]
    assert (out / "gqcnn.safetensors").exists()
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
