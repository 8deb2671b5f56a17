"""The sweep refiner: its network, export, samples and training."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch

from mvgrasp_training.config import ConfigError, SweepRefinerExperimentConfig, load_config
from mvgrasp_training.export import export_sweep_refiner, load_sweep_refiner
from mvgrasp_training.sweep_refiner import (
    BASE,
    FEATURES,
    TRUTH,
    SweepRefiner,
    SweepRefinerArchitecture,
)
from mvgrasp_training.train_sweep_refiner import export_best, load_samples, train

CONFIG = """
name = "sweep_refiner_test"
seed = 0
[data]
dataset_dir = "{data}"
val_fraction = 0.25
crop = 24
[train]
epochs = {epochs}
samples_per_epoch = 160
batch_size = 8
learning_rate = 2e-2
threads = 1
[model]
channels = 4
dilations = [1, 2]
"""


def write_samples(root: Path, count: int = 8) -> Path:
    """Synthetic samples: a tilted surface whose base depth is the truth where "confirmed" and
    1 cm short elsewhere (the hull), with a ``dataset.json``."""
    rng = np.random.default_rng(0)
    root.mkdir(parents=True, exist_ok=True)
    for s in range(count):
        for v in range(2):
            h, w = 30, 40
            array = np.zeros((len(FEATURES) + 2, h, w), dtype=np.float32)
            truth = 0.5 + 0.001 * np.arange(w)[None, :] + np.zeros((h, 1))
            confirmed = rng.random((h, w)) < 0.5
            base = np.where(confirmed, truth, truth - 0.01)
            array[FEATURES.index("object")] = 1
            array[FEATURES.index("confirmed")] = confirmed
            array[FEATURES.index("has_base")] = 1
            array[BASE], array[TRUTH] = base, truth
            np.save(root / f"{s:05}_{v}.npy", array)
        (root / f"{s:05}.done").write_text("2\n")
    (root / "dataset.json").write_text(json.dumps({"format": "test"}) + "\n")
    return root


def test_the_network_gives_a_correction_and_a_logit_per_pixel_and_exports_exactly(
    tmp_path: Path,
) -> None:
    net = SweepRefiner(SweepRefinerArchitecture(channels=4, dilations=(1, 2, 4))).eval()
    x = torch.randn(2, len(FEATURES), 11, 13)
    correction, logit = net(x)
    assert correction.shape == logit.shape == (2, 11, 13)
    path = export_sweep_refiner(net, tmp_path / "tiny")
    again, description = load_sweep_refiner(path)
    assert description["architecture"]["dilations"] == [1, 2, 4]
    with torch.no_grad():
        assert torch.equal(again(x)[0], net(x)[0])


def test_samples_are_read_only_when_finished_and_a_misshapen_one_is_named(
    tmp_path: Path,
) -> None:
    root = write_samples(tmp_path / "data", count=2)
    np.save(root / "00002_0.npy", np.zeros((len(FEATURES) + 2, 4, 4), dtype=np.float32))
    assert sorted(load_samples(root)) == [0, 1]  # sample 2 has no .done: still being written
    np.save(root / "00001_1.npy", np.zeros((3, 4, 4), dtype=np.float32))
    with pytest.raises(ValueError, match="00001_1.npy"):
        load_samples(root)
    with pytest.raises(ValueError, match="no finished samples"):
        load_samples(tmp_path / "empty")


def test_training_learns_the_hull_offset_resumes_and_exports_its_best_epoch(
    tmp_path: Path,
) -> None:
    data = write_samples(tmp_path / "data")
    out, path = tmp_path / "run", tmp_path / "a.toml"
    path.write_text(CONFIG.format(data=data, epochs=1))
    first = train(load_config(path, SweepRefinerExperimentConfig), out, log=lambda _: None)
    assert first["epochs"] == 1
    history = json.loads((out / "history.json").read_text())
    assert history[0]["base_mean_mm"] == pytest.approx(5.0, abs=1.0)
    path.write_text(CONFIG.format(data=data, epochs=12))
    config = load_config(path, SweepRefinerExperimentConfig)
    lines: list[str] = []
    train(config, out, log=lines.append)
    assert lines[0] == "resumed after epoch 1"
    history = json.loads((out / "history.json").read_text())
    # The confirmed flag tells where the base is 1 cm short: the refined error falls below the
    # base's.
    assert min(h["mean_mm"] for h in history) < 0.6 * history[0]["base_mean_mm"]
    exported = export_best(config, out, tmp_path / "models" / "tiny")
    _net, description = load_sweep_refiner(exported)
    assert description["training"]["val"]["mean_mm"] == min(h["mean_mm"] for h in history)
    assert not list(out.glob("*.partial"))


def test_dilations_must_be_a_list_of_integers(tmp_path: Path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(CONFIG.format(data=tmp_path, epochs=1).replace("[1, 2]", '"1, 2"'))
    with pytest.raises(ConfigError, match="model.dilations"):
        load_config(path, SweepRefinerExperimentConfig)
    path.write_text(CONFIG.format(data=tmp_path, epochs=1).replace("[1, 2]", "[1, 2.5]"))
    with pytest.raises(ConfigError, match=r"model.dilations\[1\]"):
        load_config(path, SweepRefinerExperimentConfig)
