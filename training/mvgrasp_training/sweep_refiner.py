"""The plane sweep's learned refinement (``mvgrasp::sweep_refiner``; the Rust runtime's
``mvgrasp_infer::SweepRefiner``).

Input: one view's per-pixel summary of the plane sweep over the object's box, the channels of
:data:`FEATURES` (made by ``mvgrasp::sweep_refiner::view_features``, in Rust, for training
and inference alike). A context-aggregation network (Yu and Koltun's dilated convolutions): a
3 x 3 convolution per dilation of ``dilations``, each followed by a ReLU, then a 1 x 1
convolution to two maps: the correction to the pixel's base depth in ``step_m`` units, and a
confidence logit (whether the corrected depth is within ``tolerance_m`` of the truth).
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn

# The channels of ``mvgrasp::sweep_refiner::FEATURES``, in order.
FEATURES = (
    "object",
    "has_winner",
    "confirmed",
    "winner_cost",
    "winner_offset",
    "has_hull",
    "hull_offset",
    "base_offset",
    "red",
    "green",
    "blue",
    "has_base",
)
# A sample file's channels after the features: the base depth and the true depth (metres).
BASE, TRUTH = len(FEATURES), len(FEATURES) + 1
RGB = slice(FEATURES.index("red"), FEATURES.index("blue") + 1)


@dataclass(frozen=True)
class SweepRefinerArchitecture:
    """The sizes the Rust runtime reads from the export's JSON."""

    inputs: int = len(FEATURES)
    channels: int = 16
    dilations: tuple[int, ...] = (1, 2, 4, 8, 16, 1)
    step_m: float = 0.01


class SweepRefiner(nn.Module):
    """See the module docs; ``forward`` takes features (N, inputs, H, W) and gives the
    correction in metres and the confidence logit, each (N, H, W)."""

    def __init__(self, arch: SweepRefinerArchitecture) -> None:
        super().__init__()
        self.arch = arch
        layers: list[nn.Module] = []
        cin = arch.inputs
        for dilation in arch.dilations:
            layers.append(nn.Conv2d(cin, arch.channels, 3, padding=dilation, dilation=dilation))
            cin = arch.channels
        layers.append(nn.Conv2d(cin, 2, 1))
        self.layers = nn.ModuleList(layers)

    def forward(self, features: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        x = features
        for layer in self.layers[:-1]:
            x = torch.relu(layer(x))
        out = self.layers[-1](x)
        return out[:, 0] * self.arch.step_m, out[:, 1]
