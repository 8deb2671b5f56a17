"""Typed experiment configs, one TOML file per experiment.

Every config is a frozen dataclass whose fields carry their unit in the name where it is not
obvious. :func:`load_config` reads a TOML file and checks it completely before a run starts:
unknown keys (typos), missing keys, wrong types and out-of-range values all raise
:class:`ConfigError`, a ``ValueError`` whose message names the file and the dotted key, e.g.::

    configs/example.toml: train.batch_size: expected an integer, got str '64'

Conversions are strict: an integer field rejects ``true`` and ``10.5``; a float field accepts an
integer (``learning_rate = 1``) and rejects NaN and infinity; a path is resolved against the
folder of the config file that names it.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import sys
import typing
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

if TYPE_CHECKING:
    from mvgrasp_training.lsm import LsmArchitecture
    from mvgrasp_training.mvs import MvsArchitecture

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10: the same parser, packaged separately.
    import tomli as tomllib

__all__ = [
    "ConfigError",
    "DataConfig",
    "ExperimentConfig",
    "LsmDataConfig",
    "LsmExperimentConfig",
    "LsmModelConfig",
    "LsmTrainConfig",
    "ModelConfig",
    "MvsDataConfig",
    "MvsExperimentConfig",
    "MvsModelConfig",
    "SweepRefinerDataConfig",
    "SweepRefinerExperimentConfig",
    "SweepRefinerModelConfig",
    "TrainConfig",
    "load_config",
    "parse_config",
]

T = TypeVar("T")


class ConfigError(ValueError):
    """A config is unreadable or has an unknown, missing, mistyped or out-of-range key.

    Attributes:
        source: the file (or ``"<TrainConfig>"``-style name for a config built in code).
        key: the dotted key at fault (``"train.batch_size"``), or ``None`` for the whole file.
        reason: what is wrong, without the file and key.
    """

    def __init__(self, source: str, key: str | None, reason: str) -> None:
        self.source = source
        self.key = key
        self.reason = reason
        where = f"{source}: {key}" if key else source
        super().__init__(f"{where}: {reason}")


# A range check: (predicate, what a valid value is).
_Check = tuple[Callable[[Any], bool], str]


def _checked(check: _Check, **kwargs: Any) -> Any:
    """A dataclass field whose values must pass ``check``."""
    return field(metadata={"check": check}, **kwargs)


LABELS = ("robust", "physics", "both")
"""The training labels a grasp dataset offers (see :class:`DataConfig`)."""

_AT_LEAST_ONE: _Check = (lambda v: v >= 1, ">= 1")
_NON_NEGATIVE: _Check = (lambda v: v >= 0, ">= 0")
_POSITIVE: _Check = (lambda v: v > 0, "> 0")
_FRACTION: _Check = (lambda v: 0 <= v < 1, "in [0, 1)")
_NOT_EMPTY: _Check = (lambda v: len(v) > 0, "not empty")


class _Validated:
    """Checks types and ranges of every field when a config is built in code."""

    def __post_init__(self) -> None:
        source = f"<{type(self).__name__}>"
        hints = typing.get_type_hints(type(self))
        for f in dataclasses.fields(self):  # type: ignore[arg-type]
            value = _convert(hints[f.name], getattr(self, f.name), source, f.name, None)
            _check_range(f, value, source, f.name)
            # Store the converted value (int -> float, str -> Path) in the frozen instance.
            object.__setattr__(self, f.name, value)


@dataclass(frozen=True)
class DataConfig(_Validated):
    """Where the training data is and how it is split."""

    dataset_dir: Path
    """The dataset folder; relative paths are relative to the config file's folder."""
    val_fraction: float = _checked(_FRACTION)
    """The fraction of objects held out for validation (split by object, never by image)."""
    label: str = _checked(
        (lambda v: v in LABELS, f"one of {', '.join(LABELS)}"), default="robust"
    )
    """What the network learns to predict: ``robust``, Dex-Net 2.0's robust Ferrari-Canny label
    (the paper's); ``physics``, the physics label (the majority of the datapoint's perturbed
    rapier trials held; a datapoint that collides is a negative, one without trials is left
    out); ``both``, the two together."""


@dataclass(frozen=True)
class TrainConfig(_Validated):
    """The optimisation schedule."""

    epochs: int = _checked(_AT_LEAST_ONE)
    """Full passes over the training split."""
    batch_size: int = _checked(_AT_LEAST_ONE)
    """Samples per optimiser step."""
    learning_rate: float = _checked(_POSITIVE)
    """The optimiser's initial step size."""
    learning_rate_decay: float = _checked((lambda v: 0 < v <= 1, "in (0, 1]"), default=1.0)
    """The step size is multiplied by this after every epoch (Dex-Net 2.0: 0.95)."""
    weight_decay: float = _checked(_NON_NEGATIVE, default=0.0)
    """L2 penalty on the weights."""
    flip_augment: bool = True
    """Dex-Net's augmentations: random horizontal and vertical flips (together: the 180-degree
    rotation); a parallel-jaw grasp's crop means the same grasp flipped."""
    noise_sigma_m: float = _checked(_NON_NEGATIVE, default=0.0)
    """Standard deviation of Gaussian noise added to the depth crops while training, metres."""
    balance_classes: bool = True
    """Weigh the loss so that positives and negatives count equally."""
    threads: int = _checked(_NON_NEGATIVE, default=0)
    """torch intra-op threads of each process (0: torch's default)."""


_ARCHITECTURE_NAMES = ("dexnet2", "small")


@dataclass(frozen=True)
class ModelConfig(_Validated):
    """Which network."""

    architecture: str = _checked(
        (lambda v: v in _ARCHITECTURE_NAMES, f"one of {', '.join(_ARCHITECTURE_NAMES)}"),
        default="small",
    )
    """``dexnet2`` (Dex-Net 2.0's GQ-CNN) or ``small``."""
    pose_inputs: int = _checked((lambda v: v in (1, 2), "1 or 2"), default=1)
    """1: the grasp depth (GQ-CNN); 2: the grasp depth and theta (multi-view GQ-CNN)."""


@dataclass(frozen=True)
class ExperimentConfig(_Validated):
    """One training run: everything needed to reproduce it."""

    name: str = _checked(_NOT_EMPTY)
    """A short identifier, used for the output folder."""
    seed: int = _checked(_NON_NEGATIVE)
    """Seeds every random choice (split, shuffling, initialisation, augmentation)."""
    data: DataConfig
    train: TrainConfig
    model: ModelConfig = field(default_factory=ModelConfig)


@dataclass(frozen=True)
class LsmDataConfig(_Validated):
    """The RGB-D dataset and its split."""

    dataset_dir: Path
    """A ``render`` output folder; relative paths are relative to the config file's folder."""
    val_fraction: float = _checked(_FRACTION, default=0.1)
    """The fraction of objects held out for validation."""
    views_per_sample: int = _checked((lambda v: v >= 2, ">= 2"), default=4)
    """Views in one input (the paper: the top-down view and 3 more)."""


@dataclass(frozen=True)
class LsmTrainConfig(_Validated):
    """The optimisation schedule."""

    epochs: int = _checked(_AT_LEAST_ONE)
    samples_per_epoch: int = _checked(_AT_LEAST_ONE)
    batch_size: int = _checked(_AT_LEAST_ONE)
    learning_rate: float = _checked(_POSITIVE)
    threads: int = _checked(_NON_NEGATIVE, default=0)
    """torch intra-op threads (0: torch's default)."""
    learning_rate_decay: float = _checked((lambda v: 0 < v <= 1, "in (0, 1]"), default=1.0)
    """Factor applied to the learning rate per epoch from ``decay_from_epoch`` on."""
    decay_from_epoch: int = _checked(_NON_NEGATIVE, default=0)
    """The first epoch trained at ``learning_rate * learning_rate_decay``."""

    def learning_rate_at(self, epoch: int) -> float:
        """The learning rate of ``epoch`` (0-based): a function of the epoch alone, so that a
        resumed run trains as one that never stopped."""
        decayed = max(0, epoch + 1 - self.decay_from_epoch) if self.decay_from_epoch else 0
        return self.learning_rate * self.learning_rate_decay**decayed


@dataclass(frozen=True)
class LsmModelConfig(_Validated):
    """The architecture's sizes (see :class:`LsmArchitecture`)."""

    image_width: int = _checked(_AT_LEAST_ONE, default=128)
    image_height: int = _checked(_AT_LEAST_ONE, default=96)
    features: int = _checked(_AT_LEAST_ONE, default=16)
    grid_size: int = _checked((lambda v: v >= 4 and v % 2 == 0, "even and >= 4"), default=24)
    grid_side_m: float = _checked(_POSITIVE, default=0.3)
    gru_channels: int = _checked(_AT_LEAST_ONE, default=24)
    ray_samples: int = _checked((lambda v: v >= 2, ">= 2"), default=24)

    def architecture(self) -> LsmArchitecture:
        """The network's sizes (imports torch)."""
        from mvgrasp_training.lsm import LsmArchitecture

        return LsmArchitecture(**dataclasses.asdict(self))


@dataclass(frozen=True)
class LsmExperimentConfig(_Validated):
    """One LSM training run."""

    name: str = _checked(_NOT_EMPTY)
    seed: int = _checked(_NON_NEGATIVE)
    data: LsmDataConfig
    train: LsmTrainConfig
    model: LsmModelConfig = field(default_factory=LsmModelConfig)


@dataclass(frozen=True)
class MvsDataConfig(_Validated):
    """The RGB-D dataset, its split and how inputs are drawn and disturbed."""

    dataset_dir: Path
    """A ``render`` output folder; relative paths are relative to the config file's folder."""
    val_fraction: float = _checked(_FRACTION, default=0.1)
    min_views: int = _checked((lambda v: v >= 2, ">= 2"), default=3)
    max_views: int = _checked((lambda v: v >= 2, ">= 2"), default=5)
    """Each batch draws its view count uniformly from ``min_views`` to ``max_views``."""
    val_views: int = _checked((lambda v: v >= 2, ">= 2"), default=5)
    object_weight: float = _checked(_NON_NEGATIVE, default=3.0)
    """A pixel of the object weighs ``1 + object_weight`` in the loss, the others 1."""
    colour_jitter: float = _checked(_FRACTION, default=0.1)
    """Per view: gains and offsets of each colour channel drawn within this fraction."""
    noise_std: float = _checked(_NON_NEGATIVE, default=0.01)
    """Gaussian pixel noise (colours in [0, 1])."""
    pose_noise_m: float = _checked(_NON_NEGATIVE, default=0.0015)
    pose_noise_rad: float = _checked(_NON_NEGATIVE, default=0.0087)
    """Calibration error: each camera given to the network is moved by up to these."""


@dataclass(frozen=True)
class MvsModelConfig(_Validated):
    """The architecture's sizes (see :class:`MvsArchitecture`)."""

    image_width: int = _checked((lambda v: v >= 8 and v % 8 == 0, "a multiple of 8"), default=256)
    image_height: int = _checked((lambda v: v >= 8 and v % 8 == 0, "a multiple of 8"), default=192)
    features: int = _checked(_AT_LEAST_ONE, default=8)
    groups: int = _checked(_AT_LEAST_ONE, default=8)
    coarse_planes: int = _checked((lambda v: v >= 2 and v % 2 == 0, "even and >= 2"), default=32)
    fine_planes: int = _checked((lambda v: v >= 2 and v % 2 == 0, "even and >= 2"), default=8)
    fine_step_m: float = _checked(_POSITIVE, default=0.004)
    regulariser: int = _checked(_AT_LEAST_ONE, default=8)
    workspace_half_side_m: float = _checked(_POSITIVE, default=0.2)
    workspace_height_m: float = _checked(_POSITIVE, default=0.3)

    def architecture(self) -> MvsArchitecture:
        """The network's sizes (imports torch)."""
        from mvgrasp_training.mvs import MvsArchitecture

        return MvsArchitecture(**dataclasses.asdict(self))


@dataclass(frozen=True)
class MvsExperimentConfig(_Validated):
    """One training run of the multi-view stereo network (the LSM's schedule keys)."""

    name: str = _checked(_NOT_EMPTY)
    seed: int = _checked(_NON_NEGATIVE)
    data: MvsDataConfig
    train: LsmTrainConfig
    model: MvsModelConfig = field(default_factory=MvsModelConfig)


@dataclass(frozen=True)
class SweepRefinerDataConfig(_Validated):
    """The sweep refiner's samples (``examples/sweep_refiner_data.rs`` output) and crops."""

    dataset_dir: Path
    """A ``sweep_refiner_data`` output folder; relative to the config file's folder."""
    val_fraction: float = _checked(_FRACTION, default=0.1)
    """The fraction of samples (rigs, with all their views) held out for validation."""
    crop: int = _checked((lambda v: v >= 16, ">= 16"), default=96)
    """Training crops' side, pixels."""
    colour_jitter: float = _checked(_FRACTION, default=0.1)
    """Per crop: gains and offsets of each colour channel drawn within this fraction."""


@dataclass(frozen=True)
class SweepRefinerModelConfig(_Validated):
    """The architecture's sizes (see :class:`SweepRefinerArchitecture`)."""

    channels: int = _checked(_AT_LEAST_ONE, default=16)
    dilations: tuple[int, ...] = (1, 2, 4, 8, 16, 1)
    step_m: float = _checked(_POSITIVE, default=0.01)
    tolerance_m: float = _checked(_POSITIVE, default=0.003)
    """The confidence learns whether the refined depth is within this of the truth."""


@dataclass(frozen=True)
class SweepRefinerExperimentConfig(_Validated):
    """One training run of the sweep refiner (the LSM's schedule keys)."""

    name: str = _checked(_NOT_EMPTY)
    seed: int = _checked(_NON_NEGATIVE)
    data: SweepRefinerDataConfig
    train: LsmTrainConfig
    model: SweepRefinerModelConfig = field(default_factory=SweepRefinerModelConfig)


def load_config(path: str | Path, cls: type[T] = ExperimentConfig) -> T:  # type: ignore[assignment]
    """Reads a TOML file as a ``cls`` (an :class:`ExperimentConfig` unless told otherwise).

    Raises:
        ConfigError: the file is missing or not TOML, or a key is unknown, missing, of the
            wrong type or out of range; the message names the file and the key.
    """
    path = Path(path)
    source = str(path)
    try:
        with path.open("rb") as file:
            data = tomllib.load(file)
    except FileNotFoundError:
        raise ConfigError(source, None, "no such file") from None
    except OSError as error:
        raise ConfigError(source, None, f"cannot read: {error.strerror}") from error
    except tomllib.TOMLDecodeError as error:
        raise ConfigError(source, None, f"not valid TOML: {error}") from error
    return parse_config(data, cls, source=source, base_dir=path.parent.resolve())


def parse_config(
    data: Mapping[str, Any],
    cls: type[T] = ExperimentConfig,  # type: ignore[assignment]
    *,
    source: str = "<dict>",
    base_dir: Path | None = None,
) -> T:
    """Builds a ``cls`` from a mapping (a parsed TOML document), checking every key.

    ``source`` names the origin in error messages; relative paths are resolved against
    ``base_dir`` (left relative when it is ``None``).
    """
    return _parse_dataclass(cls, data, source, "", base_dir)


def _parse_dataclass(cls: type[T], data: Any, source: str, prefix: str, base_dir: Path | None) -> T:
    if not isinstance(data, Mapping):
        key = prefix.rstrip(".") or None
        raise ConfigError(source, key, f"expected a table, got {_describe(data)}")
    fields = {f.name: f for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    hints = typing.get_type_hints(cls)

    unknown = sorted(set(data) - set(fields))
    if unknown:
        key = unknown[0]
        close = difflib.get_close_matches(key, fields, n=1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise ConfigError(
            source,
            prefix + key,
            f"unknown key ({hint}{cls.__name__} takes: {', '.join(sorted(fields))})",
        )

    values: dict[str, Any] = {}
    for name, f in fields.items():
        key = prefix + name
        if name not in data:
            if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
                raise ConfigError(source, key, "missing (required)")
            continue
        raw = data[name]
        hint = hints[name]
        if dataclasses.is_dataclass(hint):
            values[name] = _parse_dataclass(hint, raw, source, key + ".", base_dir)
        else:
            value = _convert(hint, raw, source, key, base_dir)
            _check_range(f, value, source, key)
            values[name] = value
    return cls(**values)


def _convert(hint: Any, raw: Any, source: str, key: str, base_dir: Path | None) -> Any:
    """Checks ``raw`` against the field type ``hint``; converts int to float and str to Path."""
    if dataclasses.is_dataclass(hint):
        if not isinstance(raw, hint):
            raise ConfigError(source, key, f"expected a {hint.__name__}, got {_describe(raw)}")
        return raw
    if hint is bool:
        if not isinstance(raw, bool):
            raise ConfigError(source, key, f"expected true or false, got {_describe(raw)}")
        return raw
    if hint is int:
        if isinstance(raw, bool) or not isinstance(raw, int):
            raise ConfigError(source, key, f"expected an integer, got {_describe(raw)}")
        return raw
    if hint is float:
        if isinstance(raw, bool) or not isinstance(raw, (int, float)):
            raise ConfigError(source, key, f"expected a number, got {_describe(raw)}")
        if not math.isfinite(raw):
            raise ConfigError(source, key, f"expected a finite number, got {raw}")
        return float(raw)
    if hint is str:
        if not isinstance(raw, str):
            raise ConfigError(source, key, f"expected a string, got {_describe(raw)}")
        return raw
    if typing.get_origin(hint) is tuple:
        (item, rest) = typing.get_args(hint)
        if rest is not Ellipsis or item is not int:
            raise TypeError(f"config field {key} has unsupported type {hint!r}")
        if not isinstance(raw, (list, tuple)) or not raw:
            raise ConfigError(source, key, f"expected a non-empty list, got {_describe(raw)}")
        return tuple(_convert(int, v, source, f"{key}[{i}]", base_dir) for i, v in enumerate(raw))
    if hint is Path:
        if not isinstance(raw, (str, Path)):
            raise ConfigError(source, key, f"expected a path string, got {_describe(raw)}")
        path = Path(raw)
        if base_dir is not None and not path.is_absolute():
            path = (base_dir / path).resolve()
        return path
    raise TypeError(f"config field {key} has unsupported type {hint!r}")


def _check_range(f: dataclasses.Field[Any], value: Any, source: str, key: str) -> None:
    check: _Check | None = f.metadata.get("check")
    if check is not None and not check[0](value):
        raise ConfigError(source, key, f"must be {check[1]}, got {value!r}")


def _describe(value: Any) -> str:
    text = repr(value)
    if len(text) > 40:
        text = text[:37] + "..."
    return f"{type(value).__name__} {text}"
