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


@pytest.mark.parametrize("name", ["gqcnn_small_topdown", "gqcnn_small_multiview"])
def test_scoring_crops_gives_torchs_logits(name: str) -> None:
    """The parity fixture of each shipped network (torch's logits on 16 seeded crops, written
    by training/scripts/make_parity_fixtures.py) scored from NumPy."""
    import numpy as np
    from safetensors.numpy import load_file

    io = load_file(REPO_ROOT / "tests" / "fixtures" / "shipped" / f"{name}.io.safetensors")
    depth, pose, expected = io["depth"], io["pose"], io["logits"]
    logits = mvgrasp.score_crops(name, depth, pose, logits=True)
    assert logits.shape == expected.shape == (len(depth), 2)
    assert np.abs(logits - expected).max() < 1e-4
    prob = mvgrasp.score_crops(name, depth[:, 0], pose)
    softmax = np.exp(expected[:, 1]) / np.exp(expected).sum(axis=1)
    assert prob.shape == (len(depth),) and np.abs(prob - softmax).max() < 1e-4
    # The export's JSON scores as the shipped name does.
    again = mvgrasp.score_crops(str(REPO_ROOT / "models" / f"{name}.json"), depth, pose)
    assert np.array_equal(again, prob)


def test_scoring_names_a_bad_batch() -> None:
    import numpy as np

    crops = np.zeros((4, 32, 32), dtype=np.float32)
    with pytest.raises(ValueError, match=r"depth: shape \[4, 16, 16\]"):
        mvgrasp.score_crops("gqcnn_small_topdown", crops[:, :16, :16], np.zeros(4, np.float32))
    with pytest.raises(ValueError, match=r"pose: shape \[4\], expected \(4, 2\)"):
        mvgrasp.score_crops("gqcnn_small_multiview", crops, np.zeros(4, np.float32))
    with pytest.raises(TypeError):
        mvgrasp.score_crops("gqcnn_small_topdown", crops.astype(np.float64), np.zeros(4, np.float32))
    with pytest.raises(mvgrasp.WeightsError, match="no_such.json"):
        mvgrasp.score_crops("no_such.json", crops, np.zeros(4, np.float32))
