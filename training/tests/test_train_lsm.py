"""Training the LSM end to end on a tiny RGB-D dataset made through the wheel: the data read
back through it, the object-wise split, checkpoints that resume, and the learning curve."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

torch = pytest.importorskip("torch")

from conftest import generate_rgbd_dataset  # noqa: E402
from mvgrasp_training.config import ConfigError, LsmExperimentConfig, load_config  # noqa: E402
from mvgrasp_training.export import load_lsm  # noqa: E402
from mvgrasp_training.train_lsm import export_best, load_dataset, train  # noqa: E402

CONFIG = """name = "lsm_tiny"
seed = 1

[data]
dataset_dir = "{data}"
val_fraction = 0.34
views_per_sample = 3

[train]
epochs = {epochs}
samples_per_epoch = 4
batch_size = 2
learning_rate = 1e-3
threads = 1

[model]
image_width = 32
image_height = 24
features = 8
grid_size = 8
gru_channels = 8
ray_samples = 8
"""


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return generate_rgbd_dataset(tmp_path_factory.mktemp("rgbd"), ["box", "can", "mug"])


def write_config(path: Path, data: Path, epochs: int) -> Path:
    path.write_text(CONFIG.format(data=data, epochs=epochs))
    return path


def test_the_dataset_is_read_through_the_wheel_at_the_network_size(dataset: Path) -> None:
    config = load_config(write_config(dataset / "c.toml", dataset, 1), LsmExperimentConfig)
    objects = load_dataset(dataset, config.model.architecture())
    assert [name for name, _ in objects] == ["box_000", "can_000", "mug_000"]
    train_split, test_split = objects[0][1]
    assert train_split.rgb.shape == (20, 3, 24, 32) and test_split.rgb.shape == (10, 3, 24, 32)
    assert test_split.top_down_first and not train_split.top_down_first
    # The object's pixels have depth, about 0.5 m away; the top-down camera looks straight down.
    assert (test_split.depth[test_split.mask] > 0.3).all()
    assert torch.allclose(test_split.camera_from_world[0, 2, :3], torch.tensor([0.0, 0.0, -1.0]), atol=1e-5)


def test_training_writes_its_curve_and_resumes_from_its_checkpoint(dataset: Path, tmp_path: Path) -> None:
    out = tmp_path / "run"
    config = load_config(write_config(tmp_path / "a.toml", dataset, 1), LsmExperimentConfig)
    first = train(config, out, log=lambda _: None)
    assert first["epochs"] == 1 and (out / "best.pt").is_file()
    history = json.loads((out / "history.json").read_text())
    assert history[0]["object_mm"] > 0 and history[0]["train_l1_mm"] > 0
    lines: list[str] = []
    config = load_config(write_config(tmp_path / "b.toml", dataset, 2), LsmExperimentConfig)
    second = train(config, out, log=lines.append)
    assert lines[0] == "resumed after epoch 1" and second["epochs"] == 2
    assert json.loads((out / "history.json").read_text())[0] == history[0]
    assert not list(out.glob("*.partial")), "checkpoints are renamed into place"
    # The export for the Rust runtime: the best weights, the report in the JSON.
    json_path = export_best(config, out, tmp_path / "models" / "lsm_tiny")
    assert (out / "learning_curve.png").stat().st_size > 1000
    net, description = load_lsm(json_path)
    best = torch.load(out / "best.pt", weights_only=False)
    assert description["format"] == "mvgrasp-lsm/1"
    assert description["architecture"]["grid_size"] == 8
    report = description["training"]
    assert report["selected_epoch"] == best["epoch"] and len(report["history"]) == 2
    assert report["val"]["object_mm"] == report["history"][best["epoch"]]["object_mm"]
    assert report["config"]["data"]["dataset_dir"] == report["dataset"]["path"]
    assert not report["dataset"]["path"].startswith("/"), "relative to the repository"
    for name, tensor in net.state_dict().items():
        assert torch.equal(tensor, best["model"][name]), name


def test_the_learning_rate_decays_by_epoch_alone(dataset: Path, tmp_path: Path) -> None:
    path = write_config(tmp_path / "d.toml", dataset, 4)
    path.write_text(path.read_text().replace("threads = 1", "threads = 1\nlearning_rate_decay = 0.5\ndecay_from_epoch = 2"))
    train_config = load_config(path, LsmExperimentConfig).train
    assert [train_config.learning_rate_at(e) for e in range(4)] == [1e-3, 1e-3, 5e-4, 2.5e-4]


def test_the_evaluation_prints_both_methods_on_the_same_views(
    dataset: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from mvgrasp_training.evaluate_lsm import main

    config = load_config(write_config(tmp_path / "e.toml", dataset, 1), LsmExperimentConfig)
    train(config, tmp_path / "run", log=lambda _: None)
    assert main([str(tmp_path / "run" / "best.pt"), str(dataset), "--views", "3"]) == 0
    rows = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| LSM")
            or line.startswith("| baseline")]  # fmt: skip
    assert len(rows) == 4
    for row in rows:
        mae = float(row.split("|")[4])
        assert 0 < mae < 300, row


def test_bad_configs_name_the_key(dataset: Path, tmp_path: Path) -> None:
    path = write_config(tmp_path / "bad.toml", dataset, 1)
    path.write_text(path.read_text().replace("grid_size = 8", "grid_size = 7"))
    with pytest.raises(ConfigError, match="model.grid_size"):
        load_config(path, LsmExperimentConfig)


def test_two_processes_with_ddp_train_the_weights_one_process_trains(
    dataset: Path, tmp_path: Path
) -> None:
    """torchrun, gloo, 2 processes on the CPU: the same weights as one process (to rounding)."""
    config = write_config(tmp_path / "ddp.toml", dataset, 1)
    run = [sys.executable, "-m", "mvgrasp_training.train_lsm", str(config), "--out"]
    subprocess.run([*run, str(tmp_path / "one")], check=True, timeout=600)
    torchrun = [sys.executable, "-m", "torch.distributed.run", "--standalone", "--nproc_per_node",
                "2", "-m", "mvgrasp_training.train_lsm", str(config), "--out"]  # fmt: skip
    subprocess.run([*torchrun, str(tmp_path / "two")], check=True, timeout=600)
    one = torch.load(tmp_path / "one" / "checkpoint.pt", weights_only=False)
    two = torch.load(tmp_path / "two" / "checkpoint.pt", weights_only=False)
    assert two["history"][0]["train_l1_mm"] == pytest.approx(
        one["history"][0]["train_l1_mm"], rel=1e-4
    )
    # The same network: its depth of an object's views (the weights themselves differ where
    # the gradient is only rounding, as the biases before an instance norm, which cancels
    # them: Adam moves those by the learning rate whatever the noise's size).
    from mvgrasp_training.lsm import LSM

    config_ = load_config(config, LsmExperimentConfig)
    arch = config_.model.architecture()
    split = load_dataset(dataset, arch)[0][1][1]
    inputs = (split.rgb[None, :3], split.k[None, :3], split.camera_from_world[None, :3])
    depths = []
    for state in (one, two):
        net = LSM(arch)
        net.load_state_dict(state["model"])
        with torch.no_grad():
            depths.append(net.eval()(*inputs))
    torch.manual_seed(1)  # the config's seed: the initial weights of both runs
    with torch.no_grad():
        initial = LSM(arch).eval()(*inputs)
    assert float((depths[0] - depths[1]).abs().max()) < 1e-4  # metres
    assert float((depths[0] - initial).abs().max()) > 1e-3, "both runs trained"
