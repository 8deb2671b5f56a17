"""Experiment configs: the example loads, and every kind of mistake is a ConfigError."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from mvgrasp_training.config import (
    ConfigError,
    DataConfig,
    ExperimentConfig,
    LsmExperimentConfig,
    MvsExperimentConfig,
    SweepRefinerExperimentConfig,
    TrainConfig,
    load_config,
)

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
EXAMPLE = CONFIGS / "example.toml"

VALID = """\
name = "tiny"
seed = 7

[data]
dataset_dir = "data/tiny"
val_fraction = 0.2

[train]
epochs = 3
batch_size = 16
learning_rate = 0.01
"""


def write(tmp_path: Path, text: str, name: str = "run.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def edit(old: str, new: str) -> str:
    assert old in VALID, old
    return VALID.replace(old, new)


def test_example_loads() -> None:
    config = load_config(EXAMPLE)
    assert isinstance(config, ExperimentConfig)
    assert config.name == "example"
    assert config.seed == 0
    assert config.train == TrainConfig(
        epochs=20, batch_size=64, learning_rate=1e-3, weight_decay=5e-4
    )
    assert config.data.val_fraction == pytest.approx(0.1)
    # Relative paths are relative to the config file, so the result is absolute.
    assert config.data.dataset_dir.is_absolute()
    assert config.data.dataset_dir == (CONFIGS / "../../out/datasets/example").resolve()


@pytest.mark.parametrize("path", sorted(CONFIGS.glob("*.toml")), ids=lambda p: p.name)
def test_every_shipped_config_loads(path: Path) -> None:
    # The depth networks' configs (lsm_*.toml, mvs_*.toml, sweep_refiner_*.toml) are of their
    # own kinds.
    kinds = {
        "lsm_": LsmExperimentConfig,
        "mvs_": MvsExperimentConfig,
        "sweep_refiner_": SweepRefinerExperimentConfig,
    }
    kind = next(
        (k for prefix, k in kinds.items() if path.name.startswith(prefix)), ExperimentConfig
    )
    load_config(path, kind)


def test_valid_config_with_defaults(tmp_path: Path) -> None:
    config = load_config(write(tmp_path, VALID))
    assert config.train.weight_decay == 0.0
    assert config.data.dataset_dir == tmp_path.resolve() / "data" / "tiny"


def test_config_is_frozen(tmp_path: Path) -> None:
    config = load_config(write(tmp_path, VALID))
    with pytest.raises(dataclasses.FrozenInstanceError):
        config.train.epochs = 5  # type: ignore[misc]


def test_config_error_is_a_value_error() -> None:
    assert issubclass(ConfigError, ValueError)


@pytest.mark.parametrize(
    ("text", "key"),
    [
        ('optimizer = "adam"\n' + VALID, "optimizer"),
        (edit("batch_size = 16", "batch_size = 16\nlearnig_rate = 0.1"), "train.learnig_rate"),
        (edit("[data]", "[data]\nimage_size = 32"), "data.image_size"),
    ],
)
def test_unknown_key_names_file_and_key(tmp_path: Path, text: str, key: str) -> None:
    path = write(tmp_path, text)
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert info.value.key == key
    assert str(path) in str(info.value)
    assert key in str(info.value)
    assert "unknown key" in str(info.value)


def test_unknown_key_suggests_the_near_miss(tmp_path: Path) -> None:
    text = edit("batch_size = 16", "batch_size = 16\nlearnig_rate = 0.1")
    with pytest.raises(ConfigError, match="did you mean 'learning_rate'"):
        load_config(write(tmp_path, text))


@pytest.mark.parametrize(
    ("old", "new", "key"),
    [
        ("batch_size = 16", 'batch_size = "16"', "train.batch_size"),
        ("epochs = 3", "epochs = 3.5", "train.epochs"),
        ("epochs = 3", "epochs = true", "train.epochs"),
        ("learning_rate = 0.01", 'learning_rate = "fast"', "train.learning_rate"),
        ("learning_rate = 0.01", "learning_rate = nan", "train.learning_rate"),
        ("seed = 7", "seed = [7]", "seed"),
        ('name = "tiny"', "name = 3", "name"),
        ('dataset_dir = "data/tiny"', "dataset_dir = 1", "data.dataset_dir"),
    ],
)
def test_wrong_type_names_file_and_key(tmp_path: Path, old: str, new: str, key: str) -> None:
    path = write(tmp_path, edit(old, new))
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert info.value.key == key
    assert str(info.value).startswith(f"{path}: {key}: ")


def test_scalar_where_a_table_belongs(tmp_path: Path) -> None:
    text = "train = 1\n" + VALID.split("[train]")[0]
    with pytest.raises(ConfigError, match="expected a table") as info:
        load_config(write(tmp_path, text))
    assert info.value.key == "train"


def test_integer_is_accepted_for_a_float(tmp_path: Path) -> None:
    config = load_config(write(tmp_path, edit("learning_rate = 0.01", "learning_rate = 1")))
    assert config.train.learning_rate == 1.0
    assert isinstance(config.train.learning_rate, float)


@pytest.mark.parametrize(
    ("old", "new", "key"),
    [
        ("val_fraction = 0.2", "val_fraction = 1.0", "data.val_fraction"),
        ("val_fraction = 0.2", "val_fraction = -0.1", "data.val_fraction"),
        ("learning_rate = 0.01", "learning_rate = 0", "train.learning_rate"),
        ("batch_size = 16", "batch_size = 0", "train.batch_size"),
        ("seed = 7", "seed = -1", "seed"),
        ('name = "tiny"', 'name = ""', "name"),
    ],
)
def test_out_of_range_names_key(tmp_path: Path, old: str, new: str, key: str) -> None:
    with pytest.raises(ConfigError, match="must be") as info:
        load_config(write(tmp_path, edit(old, new)))
    assert info.value.key == key


@pytest.mark.parametrize("missing", ["seed = 7\n", "epochs = 3\n"])
def test_missing_key(tmp_path: Path, missing: str) -> None:
    with pytest.raises(ConfigError, match="missing"):
        load_config(write(tmp_path, VALID.replace(missing, "")))


def test_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "nope.toml"
    with pytest.raises(ConfigError, match="no such file") as info:
        load_config(path)
    assert str(path) in str(info.value)


def test_invalid_toml(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_config(write(tmp_path, "name = \n"))


def test_constructing_in_code_validates_and_converts() -> None:
    data = DataConfig(dataset_dir="x", val_fraction=0)  # type: ignore[arg-type]
    assert data.dataset_dir == Path("x") and isinstance(data.val_fraction, float)
    with pytest.raises(ConfigError, match="<TrainConfig>: batch_size"):
        TrainConfig(epochs=1, batch_size=0, learning_rate=0.1)
