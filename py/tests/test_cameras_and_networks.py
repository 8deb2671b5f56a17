"""Intrinsics files and network exports from Python, and the errors they raise."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

import mvgrasp
from conftest import REPO_ROOT, shared_data


def test_a_berkeley_intrinsics_file_reads_as_a_dict() -> None:
    path = shared_data("real_depth/gqcnn/data/calib/primesense/primesense.intr")
    k = mvgrasp.load_intrinsics(path)
    assert (k["fx"], k["fy"], k["cx"], k["cy"]) == (525.0, 525.0, 319.5, 239.5)
    assert (k["width"], k["height"]) == (640, 480)


def test_a_bad_intrinsics_file_raises_camera_error_naming_it(tmp_path: Path) -> None:
    bad = tmp_path / "bad.intr"
    bad.write_text('{"_fx": 525.0}')
    with pytest.raises(mvgrasp.CameraError, match="bad.intr"):
        mvgrasp.load_intrinsics(bad)
    with pytest.raises(mvgrasp.CameraError, match="missing.intr"):
        mvgrasp.load_intrinsics(tmp_path / "missing.intr")


def test_a_shipped_network_loads_with_its_description() -> None:
    description = mvgrasp.load_network(REPO_ROOT / "models" / "gqcnn_small_multiview.json")
    assert description["format"] == "mvgrasp-gqcnn/1"
    assert description["architecture"]["pose_inputs"] == 2
    assert description["architecture"]["image_size_px"] == 32
    # The input contract the training recorded: the PhoXi S's 96-pixel window scaled to 32.
    contract = description["input"]
    assert contract["crop_window_px"] == 96
    assert contract["crop_size_px"] == 32
    assert contract["focal_px"] == pytest.approx(552.5)
    assert contract["pose_inputs"] == ["grasp_depth_m", "theta_rad"]


def test_a_broken_export_raises_weights_error_naming_the_file(tmp_path: Path) -> None:
    for suffix in (".json", ".safetensors"):
        shutil.copy(REPO_ROOT / "models" / f"gqcnn_small_topdown{suffix}", tmp_path)
    json_path = tmp_path / "gqcnn_small_topdown.json"
    description = json.loads(json_path.read_text())
    description["architecture"]["image_fc"] += 1  # the stored tensors no longer fit
    json_path.write_text(json.dumps(description))
    with pytest.raises(mvgrasp.WeightsError, match="gqcnn_small_topdown"):
        mvgrasp.load_network(json_path)
    (tmp_path / "gqcnn_small_topdown.safetensors").unlink()
    with pytest.raises(mvgrasp.WeightsError, match="gqcnn_small_topdown.safetensors"):
        mvgrasp.load_network(json_path)
