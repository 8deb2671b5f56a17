"""Export of a trained GQ-CNN for the Rust runtime: ``NAME.safetensors`` (every tensor of the
state dict, float32) and ``NAME.json`` (format, architecture, normalisation, tensor shapes, and
whatever the caller records about training)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import torch
from safetensors.torch import save_file

from mvgrasp_training.gqcnn import GQCNN

FORMAT = "mvgrasp-gqcnn/1"


def export_gqcnn(net: GQCNN, stem: str | Path, training: dict[str, Any] | None = None) -> Path:
    """Writes ``stem.safetensors`` and ``stem.json``; returns the JSON's path."""
    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    tensors = {k: v.detach().to(torch.float32).contiguous() for k, v in net.state_dict().items()}
    weights = stem.with_suffix(".safetensors")
    save_file(tensors, str(weights))
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
    path = stem.with_suffix(".json")
    path.write_text(json.dumps(description, indent=2) + "\n")
    return path
