"""The GQ-CNN of Dex-Net 2.0 and a small variant, in torch, described so that Rust can rebuild it.

An architecture is a frozen dataclass: an image stream of convolutions (each with its kernel,
filters, optional local response normalisation and max pooling, "same" padding), a
fully-connected layer, a pose stream (one fully-connected layer over the grasp depth, or depth
and theta for the multi-view GQ-CNN), and a merge stream (a fully-connected layer over both,
then two logits; softmax gives the probability that the grasp is robust). Inputs are normalised
inside the network with the training set's statistics, which travel with the weights.

``dexnet2`` is Dex-Net 2.0's GQ-CNN (Mahler et al., 2017; gqcnn's GQCNN-2.0 config): conv 7x7x64,
conv 5x5x64 + LRN + 2x2 max pool, conv 3x3x64, conv 3x3x64 + LRN + 2x2 max pool, FC 1024; pose FC
16; merged FC 1024; FC 2. Its LRN is TensorFlow's ``local_response_normalization(depth_radius=2,
alpha=2e-5, beta=0.75, bias=1)``, which is torch's ``LocalResponseNorm(size=5, alpha=5 * 2e-5,
beta=0.75, k=1)`` (torch divides alpha by the window size; TensorFlow does not).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import torch
from torch import nn


@dataclass(frozen=True)
class ConvSpec:
    """One convolution of the image stream ("same" padding, stride 1, then ReLU)."""

    filters: int
    kernel: int
    lrn: bool = False
    pool: int = 1  # max-pool window and stride after the activation; 1 = none


@dataclass(frozen=True)
class Architecture:
    """A GQ-CNN's layers; see the module docs."""

    name: str
    image_size_px: int
    convs: tuple[ConvSpec, ...]
    image_fc: int
    pose_inputs: int  # 1: grasp depth; 2: grasp depth and theta (multi-view)
    pose_fc: int
    merge_fc: int
    lrn_size: int = 5
    lrn_alpha: float = 5 * 2e-5
    lrn_beta: float = 0.75
    lrn_k: float = 1.0

    def describe(self) -> dict[str, Any]:
        """The JSON-ready description Rust rebuilds the network from."""
        d = asdict(self)
        d["convs"] = [asdict(c) for c in self.convs]
        return d


def dexnet2(pose_inputs: int = 1, image_size_px: int = 32) -> Architecture:
    """Dex-Net 2.0's GQ-CNN (``pose_inputs=2`` for the multi-view GQ-CNN's depth and theta)."""
    return Architecture(
        name="dexnet2",
        image_size_px=image_size_px,
        convs=(
            ConvSpec(64, 7),
            ConvSpec(64, 5, lrn=True, pool=2),
            ConvSpec(64, 3),
            ConvSpec(64, 3, lrn=True, pool=2),
        ),
        image_fc=1024,
        pose_inputs=pose_inputs,
        pose_fc=16,
        merge_fc=1024,
    )


def small(pose_inputs: int = 1, image_size_px: int = 32) -> Architecture:
    """A GQ-CNN that trains on two CPU cores in under an hour: the same streams, narrower."""
    return Architecture(
        name="small",
        image_size_px=image_size_px,
        convs=(
            ConvSpec(16, 5, pool=2),
            ConvSpec(32, 3, lrn=True, pool=2),
            ConvSpec(32, 3),
        ),
        image_fc=128,
        pose_inputs=pose_inputs,
        pose_fc=16,
        merge_fc=128,
    )


ARCHITECTURES = {"dexnet2": dexnet2, "small": small}


class GQCNN(nn.Module):
    """A GQ-CNN: ``forward(depth [N, 1, S, S], pose [N, pose_inputs]) -> logits [N, 2]``.

    Tensor names (what the Rust runtime loads): ``convs.{i}.weight`` / ``.bias``,
    ``image_fc``, ``pose_fc``, ``merge_fc`` and ``out`` (``.weight`` [out, in], ``.bias``), and
    the normalisation buffers below. Each convolution is followed by ReLU, then LRN and a max
    pool where its spec says so.

    The buffers ``image_mean``, ``image_std``, ``pose_mean`` and ``pose_std`` normalise the
    inputs; set them from the training set before training (:meth:`set_normalisation`).
    """

    def __init__(self, arch: Architecture) -> None:
        super().__init__()
        self.arch = arch
        self.convs = nn.ModuleList()
        channels, size = 1, arch.image_size_px
        for c in arch.convs:
            self.convs.append(nn.Conv2d(channels, c.filters, c.kernel, padding=c.kernel // 2))
            size //= c.pool
            channels = c.filters
        self.lrn = nn.LocalResponseNorm(arch.lrn_size, arch.lrn_alpha, arch.lrn_beta, arch.lrn_k)
        self.image_fc = nn.Linear(channels * size * size, arch.image_fc)
        self.pose_fc = nn.Linear(arch.pose_inputs, arch.pose_fc)
        self.merge_fc = nn.Linear(arch.image_fc + arch.pose_fc, arch.merge_fc)
        self.out = nn.Linear(arch.merge_fc, 2)
        self.register_buffer("image_mean", torch.zeros(1))
        self.register_buffer("image_std", torch.ones(1))
        self.register_buffer("pose_mean", torch.zeros(arch.pose_inputs))
        self.register_buffer("pose_std", torch.ones(arch.pose_inputs))

    def set_normalisation(
        self, image_mean: float, image_std: float, pose_mean: torch.Tensor, pose_std: torch.Tensor
    ) -> None:
        """Sets the input statistics (stds are floored at 1e-6)."""
        self.image_mean.fill_(image_mean)
        self.image_std.fill_(max(image_std, 1e-6))
        self.pose_mean.copy_(pose_mean)
        self.pose_std.copy_(pose_std.clamp_min(1e-6))

    def forward(self, depth: torch.Tensor, pose: torch.Tensor) -> torch.Tensor:
        x = (depth - self.image_mean) / self.image_std
        for spec, conv in zip(self.arch.convs, self.convs):
            x = torch.relu(conv(x))
            if spec.lrn:
                x = self.lrn(x)
            if spec.pool > 1:
                x = nn.functional.max_pool2d(x, spec.pool, spec.pool)
        x = x.flatten(1)
        x = torch.relu(self.image_fc(x))
        p = torch.relu(self.pose_fc((pose - self.pose_mean) / self.pose_std))
        m = torch.relu(self.merge_fc(torch.cat([x, p], dim=1)))
        return self.out(m)
