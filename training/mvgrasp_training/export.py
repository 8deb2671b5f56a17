"""Export of trained networks for the Rust runtime. A GQ-CNN: ``NAME.safetensors`` (every
tensor of the state dict, float32) and ``NAME.json`` (format, architecture, normalisation, tensor shapes, the
input contract, and whatever the caller records about training); an LSM: the same pair, its
architecture in place of the normalisation (``export_lsm``)."""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path
from typing import Any

import torch
from safetensors.torch import load_file, save_file

from mvgrasp_training._files import read_format_json, write_text_atomically
from mvgrasp_training.gqcnn import GQCNN
from mvgrasp_training.lsm import LSM, LsmArchitecture
from mvgrasp_training.mvs import MVS, MvsArchitecture
from mvgrasp_training.sweep_refiner import SweepRefiner, SweepRefinerArchitecture

FORMAT = "mvgrasp-gqcnn/1"


def _save_weights(net: torch.nn.Module, stem: Path) -> tuple[dict[str, torch.Tensor], Path]:
    """Writes ``stem.safetensors``: every tensor of the state dict, float32."""
    stem.parent.mkdir(parents=True, exist_ok=True)
    tensors = {k: v.detach().to(torch.float32).contiguous() for k, v in net.state_dict().items()}
    weights = stem.with_suffix(".safetensors")
    partial = weights.with_suffix(".safetensors.partial")
    save_file(tensors, str(partial))
    partial.replace(weights)
    return tensors, weights


def export_gqcnn(
    net: GQCNN,
    stem: str | Path,
    training: dict[str, Any] | None = None,
    input_contract: dict[str, Any] | None = None,
) -> Path:
    """Writes ``stem.safetensors`` and ``stem.json``; returns the JSON's path.

    ``input_contract`` (see ``train.input_contract``) is what the network expects of its inputs;
    the Rust planner cuts its crops to it.
    """
    stem = Path(stem)
    tensors, weights = _save_weights(net, stem)
    description = {
        "format": FORMAT,
        "weights": weights.name,
        "architecture": net.arch.describe(),
        "normalisation": {
            "image_mean": float(net.image_mean.item()),
            "image_std": float(net.image_std.item()),
            "pose_mean": [float(v) for v in net.pose_mean],
            "pose_std": [float(v) for v in net.pose_std],
        },
        "tensors": {k: list(v.shape) for k, v in sorted(tensors.items())},
        "training": training or {},
    }
    if input_contract is not None:
        description["input"] = input_contract
    path = stem.with_suffix(".json")
    write_text_atomically(path, json.dumps(description, indent=2) + "\n")
    return path


def load_gqcnn(path: str | Path) -> tuple[GQCNN, dict[str, Any]]:
    """Reads an export back into torch: the network (in eval mode) and its description.

    Raises:
        ValueError: the JSON is not an export of this format, or a tensor is missing or has
            another shape; the message names the file.
    """
    from safetensors.torch import load_file

    from mvgrasp_training.gqcnn import Architecture, ConvSpec

    path = Path(path)
    description = read_format_json(path, FORMAT, "network description")
    arch = dict(description["architecture"])
    arch["convs"] = tuple(ConvSpec(**c) for c in arch["convs"])
    net = GQCNN(Architecture(**arch))
    weights = path.parent / description["weights"]
    tensors = load_file(str(weights))
    expected = net.state_dict()
    for name, value in expected.items():
        if name not in tensors:
            raise ValueError(f"{weights}: tensor {name} is missing")
        if tensors[name].shape != value.shape:
            raise ValueError(
                f"{weights}: tensor {name} has shape {list(tensors[name].shape)}, "
                f"expected {list(value.shape)}"
            )
    net.load_state_dict({name: tensors[name] for name in expected})
    return net.eval(), description


LSM_FORMAT = "mvgrasp-lsm/1"
MVS_FORMAT = "mvgrasp-mvs/1"
SWEEP_REFINER_FORMAT = "mvgrasp-sweep-refiner/1"


def _export_depth_network(
    net: LSM | MVS | SweepRefiner, stem: str | Path, format_tag: str, training: dict[str, Any] | None
) -> Path:
    """Writes a depth network's ``stem.safetensors`` (its state dict, float32) and
    ``stem.json`` (format, architecture, tensor shapes, what the caller records about
    training); returns the JSON's path."""
    stem = Path(stem)
    tensors, weights = _save_weights(net, stem)
    description = {
        "format": format_tag,
        "weights": weights.name,
        "architecture": asdict(net.arch),
        "tensors": {k: list(v.shape) for k, v in sorted(tensors.items())},
        "training": training or {},
    }
    path = stem.with_suffix(".json")
    write_text_atomically(path, json.dumps(description, indent=2) + "\n")
    return path


def _load_depth_network(path: str | Path, format_tag: str, build) -> tuple[Any, dict[str, Any]]:
    """Reads a depth network's export back into torch with ``build(architecture dict)``: the
    network (eval mode) and its description.

    Raises:
        ValueError: the JSON is not an export of ``format_tag``, or its weights do not fit the
            architecture.
    """
    path = Path(path)
    description = json.loads(path.read_text())
    if description.get("format") != format_tag:
        raise ValueError(f"{path}: format {description.get('format')!r}, expected {format_tag!r}")
    net = build(description["architecture"])
    try:
        net.load_state_dict(load_file(str(path.parent / description["weights"])))
    except RuntimeError as e:
        raise ValueError(f"{path}: weights do not fit the architecture: {e}") from e
    return net.eval(), description


def export_lsm(net: LSM, stem: str | Path, training: dict[str, Any] | None = None) -> Path:
    """Writes an LSM's ``stem.safetensors`` and ``stem.json`` for the Rust runtime
    (``mvgrasp_infer::Lsm``); returns the JSON's path."""
    return _export_depth_network(net, stem, LSM_FORMAT, training)


def load_lsm(path: str | Path) -> tuple[LSM, dict[str, Any]]:
    """Reads an LSM export back into torch: the network (eval mode) and its description.

    Raises:
        ValueError: the JSON is not an LSM export, or its weights do not fit the architecture.
    """
    return _load_depth_network(path, LSM_FORMAT, lambda arch: LSM(LsmArchitecture(**arch)))


def export_mvs(net: MVS, stem: str | Path, training: dict[str, Any] | None = None) -> Path:
    """Writes the multi-view stereo network's ``stem.safetensors`` and ``stem.json`` for the
    Rust runtime (``mvgrasp_infer::Mvs``); returns the JSON's path."""
    return _export_depth_network(net, stem, MVS_FORMAT, training)


def load_mvs(path: str | Path) -> tuple[MVS, dict[str, Any]]:
    """Reads a multi-view stereo export back into torch: the network (eval mode) and its
    description.

    Raises:
        ValueError: the JSON is not such an export, or its weights do not fit the architecture.
    """
    return _load_depth_network(path, MVS_FORMAT, lambda arch: MVS(MvsArchitecture(**arch)))


def export_sweep_refiner(
    net: SweepRefiner, stem: str | Path, training: dict[str, Any] | None = None
) -> Path:
    """Writes the sweep refiner's ``stem.safetensors`` and ``stem.json`` for the Rust runtime
    (``mvgrasp_infer::SweepRefiner``); returns the JSON's path."""
    return _export_depth_network(net, stem, SWEEP_REFINER_FORMAT, training)


def load_sweep_refiner(path: str | Path) -> tuple[SweepRefiner, dict[str, Any]]:
    """Reads a sweep refiner export back into torch: the network (eval mode) and its
    description.

    Raises:
        ValueError: the JSON is not such an export, or its weights do not fit the architecture.
    """

    def build(arch: dict[str, Any]) -> SweepRefiner:
        return SweepRefiner(
            SweepRefinerArchitecture(**{**arch, "dilations": tuple(arch["dilations"])})
        )

    return _load_depth_network(path, SWEEP_REFINER_FORMAT, build)
