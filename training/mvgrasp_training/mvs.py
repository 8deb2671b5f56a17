"""A learned multi-view stereo network (``mvs``): a cascade of plane-sweep cost volumes over
learned features, regularised in 3-D and regressed, then refined at the input's resolution, as
the best multi-view stereo systems are built (MVSNet, Yao et al. 2018; its cascade form,
CasMVSNet, Gu et al. 2020; group-wise correlation, Xu and Tao 2020), shrunk for a CPU.

Every view is a reference view in turn; the others are its sources.

1. **Features.** A 2-D encoder (shared by the views) gives features at 1/2 and 1/4 of the input
   resolution, and an image-resolution stem for the refinement.
2. **Coarse stage (1/4).** Each reference pixel's ray is cut by the workspace: a box
   ``workspace_half_side_m`` around the point the cameras look at (least squares of their
   optical axes, as the LSM centres its grid), from 1 cm below the table (z = 0) to
   ``workspace_height_m`` above it. ``coarse_planes`` depths, uniform in inverse depth, span
   that stretch of each ray. Each source's features are sampled (bilinear, zero outside the
   image or behind the camera, never clamped) where the hypothesis' 3-D point falls, and
   compared with the reference's by group-wise correlation (the features are unit vectors; the
   mean product over each of ``groups`` groups of channels), averaged over the sources that see
   the point and, for occlusions, its maximum over them.
3. A small 3-D U-Net regularises the cost volume to one logit per hypothesis; the depth is the
   softmax's expectation (soft argmax), and the **confidence** the probability mass of the 4
   hypotheses around it (MVSNet's photometric confidence).
4. **Fine stage (1/2).** ``fine_planes`` depths ``fine_step_m`` apart centred on the coarse
   depth (upsampled); the same matching and regularisation.
5. **Refinement.** The fine depth, upsampled to the input resolution, with the image stem's
   features, through three 2-D convolutions to a residual of at most ``fine_step_m``.

Conventions are mvgrasp's (``../shared/GUIDE.md``) and the LSM's (:mod:`mvgrasp_training.lsm`):
metres, OpenCV camera frames, pixel centres at integers, the world the table frame (z up);
cameras as ``K`` (3x3 at the input resolution) and ``camera_from_world`` (4x4). No
normalisation layer: every op is a convolution, a ReLU, a sampling or a softmax, and the Rust
runtime (``mvgrasp_infer::Mvs``) runs the same ones.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn
from torch.nn import functional as F

from mvgrasp_training.lsm import grid_centre, scale_intrinsics


@dataclass(frozen=True)
class MvsArchitecture:
    """The network's sizes."""

    image_width: int = 256
    image_height: int = 192
    features: int = 8
    """Channels of the matching features at 1/4 and 1/2 resolution."""
    groups: int = 8
    """Groups of the group-wise correlation (``features`` must divide by it)."""
    coarse_planes: int = 32
    fine_planes: int = 8
    fine_step_m: float = 0.004
    regulariser: int = 8
    """Channels of the 3-D regulariser (twice that at its lower level)."""
    workspace_half_side_m: float = 0.2
    workspace_height_m: float = 0.3


def pixel_rays(k: torch.Tensor, height: int, width: int) -> torch.Tensor:
    """Each pixel's ray in its camera at unit depth: ``K^-1 [u, v, 1]`` (B, H, W, 3)."""
    v, u = torch.meshgrid(
        torch.arange(height, dtype=k.dtype, device=k.device),
        torch.arange(width, dtype=k.dtype, device=k.device),
        indexing="ij",
    )
    x = (u[None] - k[:, 0, 2, None, None]) / k[:, 0, 0, None, None]
    y = (v[None] - k[:, 1, 2, None, None]) / k[:, 1, 1, None, None]
    return torch.stack([x, y, torch.ones_like(x)], dim=-1)


# The nearest depth a hypothesis may have, metres.
MIN_DEPTH_M = 0.05
# A ray that misses the workspace spans this much either side of the look-at point's depth.
MISS_HALF_RANGE_M = 0.3
# The workspace reaches this far below the table (its plane must be inside).
BELOW_TABLE_M = 0.01


def depth_range(
    k: torch.Tensor,
    camera_from_world: torch.Tensor,
    centre: torch.Tensor,
    arch: MvsArchitecture,
    height: int,
    width: int,
) -> tuple[torch.Tensor, torch.Tensor]:
    """Each pixel's stretch of ray inside the workspace (see the module docs): near and far
    depths (B, H, W), metres along the optical axis. ``centre`` (B, 3)."""
    rays = pixel_rays(k, height, width)  # camera frame, depth 1
    rotation = camera_from_world[:, :3, :3]
    translation = camera_from_world[:, :3, 3]
    origin = -(rotation.transpose(1, 2) @ translation.unsqueeze(-1)).squeeze(-1)  # (B, 3)
    direction = rays @ rotation[:, None]  # world frame, (B, H, W, 3): R^T ray
    lo = torch.stack(
        [
            centre[:, 0] - arch.workspace_half_side_m,
            centre[:, 1] - arch.workspace_half_side_m,
            torch.full_like(centre[:, 0], -BELOW_TABLE_M),
        ],
        dim=-1,
    )
    hi = torch.stack(
        [
            centre[:, 0] + arch.workspace_half_side_m,
            centre[:, 1] + arch.workspace_half_side_m,
            torch.full_like(centre[:, 0], arch.workspace_height_m),
        ],
        dim=-1,
    )
    near = torch.full(rays.shape[:3], -float("inf"), dtype=k.dtype, device=k.device)
    far = torch.full(rays.shape[:3], float("inf"), dtype=k.dtype, device=k.device)
    for axis in range(3):
        d = direction[..., axis]
        o = origin[:, axis, None, None]
        parallel = d.abs() < 1e-9
        safe = torch.where(parallel, torch.ones_like(d), d)
        t0 = (lo[:, axis, None, None] - o) / safe
        t1 = (hi[:, axis, None, None] - o) / safe
        enter = torch.minimum(t0, t1)
        leave = torch.maximum(t0, t1)
        outside = (o < lo[:, axis, None, None]) | (o > hi[:, axis, None, None])
        enter = torch.where(parallel, torch.where(outside, float("inf"), -float("inf")), enter)
        leave = torch.where(parallel, torch.where(outside, -float("inf"), float("inf")), leave)
        near = torch.maximum(near, enter)
        far = torch.minimum(far, leave)
    near = near.clamp(min=MIN_DEPTH_M)
    centre_depth = (rotation[:, 2] * centre).sum(-1) + translation[:, 2]  # (B,)
    miss = far <= near + 1e-3
    miss_near = (centre_depth - MISS_HALF_RANGE_M).clamp(min=MIN_DEPTH_M)[:, None, None]
    miss_far = (centre_depth + MISS_HALF_RANGE_M)[:, None, None]
    near = torch.where(miss, miss_near.expand_as(near), near)
    far = torch.where(miss, miss_far.expand_as(far), far)
    return near, far


def inverse_depth_planes(near: torch.Tensor, far: torch.Tensor, planes: int) -> torch.Tensor:
    """``planes`` depths from ``near`` to ``far`` (B, H, W), uniform in inverse depth:
    (B, planes, H, W)."""
    t = torch.linspace(0.0, 1.0, planes, dtype=near.dtype, device=near.device)[None, :, None, None]
    inverse = 1.0 / near[:, None] + (1.0 / far[:, None] - 1.0 / near[:, None]) * t
    return 1.0 / inverse


def warp(
    source: torch.Tensor,
    k_source: torch.Tensor,
    source_from_reference: torch.Tensor,
    rays: torch.Tensor,
    depths: torch.Tensor,
) -> tuple[torch.Tensor, torch.Tensor]:
    """A source view's features (B, C, h, w) sampled where each reference pixel's ray (``rays``,
    B, H, W, 3 at depth 1) at each depth (B, D, H, W) falls in it: (B, C, D, H, W), and the
    mask of samples inside the source image in front of its camera (B, D, H, W). Bilinear
    (pixel centres at integers); outside samples are 0."""
    b, c, h, w = source.shape
    points = rays[:, None] * depths[..., None]  # (B, D, H, W, 3) reference camera frame
    rotation = source_from_reference[:, None, None, None, :3, :3]
    p = (rotation @ points.unsqueeze(-1)).squeeze(-1) + source_from_reference[
        :, None, None, None, :3, 3
    ]
    z = p[..., 2]
    safe_z = torch.where(z > 1e-6, z, torch.ones_like(z))
    u = (
        k_source[:, 0, 0, None, None, None] * p[..., 0] / safe_z
        + k_source[:, 0, 2, None, None, None]
    )
    v = (
        k_source[:, 1, 1, None, None, None] * p[..., 1] / safe_z
        + k_source[:, 1, 2, None, None, None]
    )
    inside = (z > 1e-6) & (u >= 0) & (u <= w - 1) & (v >= 0) & (v <= h - 1)
    grid = torch.stack([2 * u / (w - 1) - 1, 2 * v / (h - 1) - 1], dim=-1)
    # An outside sample is sent well beyond the image, where every bilinear tap is padding: 0.
    grid = torch.where(inside.unsqueeze(-1), grid, torch.full_like(grid, -3.0))
    d, hh, ww = depths.shape[1:]
    sampled = F.grid_sample(
        source,
        grid.reshape(b, d, hh * ww, 2),
        mode="bilinear",
        padding_mode="zeros",
        align_corners=True,
    ).reshape(b, c, d, hh, ww)
    return sampled, inside.to(source.dtype)


def correlation_volume(
    features: torch.Tensor,
    k: torch.Tensor,
    camera_from_world: torch.Tensor,
    reference: int,
    depths: torch.Tensor,
    groups: int,
) -> torch.Tensor:
    """The cost volume of view ``reference`` (B, 2 G, D, H, W): features (B, V, C, H, W) at the
    resolution of ``k`` (B, V, 3, 3), group-wise correlation (the mean product over each group
    of channels) of the reference's features with each source's at ``depths`` (B, D, H, W); the
    first G channels its mean over the sources that see the point, the last G its maximum over
    them (a point hidden from some sources still matches in the others). Where no source sees
    the point, both are 0."""
    b, views, c, h, w = features.shape
    rays = pixel_rays(k[:, reference], h, w)
    ref = features[:, reference].reshape(b, groups, c // groups, 1, h, w)
    shape = (b, groups, *depths.shape[1:])
    total = torch.zeros(shape, dtype=features.dtype, device=features.device)
    best = torch.full(shape, -float("inf"), dtype=features.dtype, device=features.device)
    seen = torch.zeros(b, 1, *depths.shape[1:], dtype=features.dtype, device=features.device)
    reference_from_world = camera_from_world[:, reference]
    for source in range(views):
        if source == reference:
            continue
        source_from_reference = camera_from_world[:, source] @ torch.linalg.inv(
            reference_from_world
        )
        warped, mask = warp(features[:, source], k[:, source], source_from_reference, rays, depths)
        warped = warped.reshape(b, groups, c // groups, *depths.shape[1:])
        correlation = (warped * ref).mean(dim=2)
        total = total + correlation
        best = torch.maximum(best, torch.where(mask.unsqueeze(1) > 0, correlation, -float("inf")))
        seen = seen + mask.unsqueeze(1)
    best = torch.where(seen > 0, best, torch.zeros_like(best))
    return torch.cat([total / seen.clamp(min=1.0), best], dim=1)


def conv2d(cin: int, cout: int, stride: int = 1) -> nn.Sequential:
    return nn.Sequential(nn.Conv2d(cin, cout, 3, stride=stride, padding=1), nn.ReLU(inplace=True))


def conv3d(cin: int, cout: int, stride: int = 1) -> nn.Sequential:
    return nn.Sequential(nn.Conv3d(cin, cout, 3, stride=stride, padding=1), nn.ReLU(inplace=True))


class Regulariser(nn.Module):
    """A two-level 3-D U-Net from a cost volume (B, 2 G, D, H, W) to logits (B, D, H, W); D, H
    and W even."""

    def __init__(self, groups: int, channels: int) -> None:
        super().__init__()
        self.inp = conv3d(2 * groups, channels)
        self.down = conv3d(channels, 2 * channels, stride=2)
        self.mid = conv3d(2 * channels, 2 * channels)
        self.up = nn.ConvTranspose3d(2 * channels, channels, 4, stride=2, padding=1)
        self.out = conv3d(channels, channels)
        self.logit = nn.Conv3d(channels, 1, 3, padding=1)

    def forward(self, cost: torch.Tensor) -> torch.Tensor:
        # Channels-last 3-D volumes convolve (and back-propagate) about 3x faster on a CPU; the
        # values are the same.
        x = self.inp(cost.contiguous(memory_format=torch.channels_last_3d))
        x = self.out(x + self.up(self.mid(self.down(x))))
        return self.logit(x)[:, 0]


def soft_argmax(logits: torch.Tensor, depths: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """The expected depth under the softmax over hypotheses (B, H, W), and the probability mass
    of the 4 hypotheses around the expected index (floor - 1 to floor + 2), MVSNet's
    confidence."""
    probability = torch.softmax(logits, dim=1)
    depth = (probability * depths).sum(dim=1)
    planes = logits.shape[1]
    index = (
        probability * torch.arange(planes, dtype=logits.dtype, device=logits.device)[:, None, None]
    ).sum(dim=1)
    first = index.detach().floor().long() - 1
    mass = torch.zeros_like(depth)
    for offset in range(4):
        at = first + offset
        valid = (at >= 0) & (at < planes)
        picked = probability.gather(1, at.clamp(0, planes - 1).unsqueeze(1))[:, 0]
        mass = mass + torch.where(valid, picked, torch.zeros_like(picked))
    return depth, mass


def upsample2(x: torch.Tensor) -> torch.Tensor:
    """Bilinear, twice the size (align_corners=False), over the last two dimensions of
    (B, C, H, W)."""
    return F.interpolate(x, scale_factor=2.0, mode="bilinear", align_corners=False)


@dataclass
class MvsOutput:
    """Per view (B, V, ...): the refined depth at the input resolution, its confidence (the
    product of the stages', upsampled), and for the training's losses the stages' depths and
    the coarse stage's hypotheses and logits (B, V, D, h, w)."""

    depth: torch.Tensor
    confidence: torch.Tensor
    coarse: torch.Tensor
    fine: torch.Tensor
    coarse_planes: torch.Tensor
    coarse_logits: torch.Tensor


class MVS(nn.Module):
    """The learned multi-view stereo network (see the module docs)."""

    def __init__(self, arch: MvsArchitecture = MvsArchitecture()) -> None:
        super().__init__()
        if arch.features % arch.groups:
            raise ValueError(f"features ({arch.features}) must divide by groups ({arch.groups})")
        if arch.image_width % 8 or arch.image_height % 8:
            raise ValueError(
                f"the image ({arch.image_width} x {arch.image_height}) must divide by 8"
            )
        if arch.coarse_planes % 2 or arch.fine_planes % 2:
            raise ValueError("the plane counts must be even (the regulariser halves them)")
        self.arch = arch
        f = arch.features
        self.stem = conv2d(3, 8)
        self.encode_half = nn.Sequential(conv2d(8, 16, stride=2), conv2d(16, 16))
        self.encode_quarter = nn.Sequential(conv2d(16, 32, stride=2), conv2d(32, 32))
        self.coarse_features = nn.Conv2d(32, f, 3, padding=1)
        self.fine_features = nn.Conv2d(16 + 32, f, 3, padding=1)
        self.coarse_regulariser = Regulariser(arch.groups, arch.regulariser)
        self.fine_regulariser = Regulariser(arch.groups, arch.regulariser)
        self.refine = nn.Sequential(conv2d(8 + 1, 8), conv2d(8, 8), nn.Conv2d(8, 1, 3, padding=1))

    def forward(
        self,
        images: torch.Tensor,
        k: torch.Tensor,
        camera_from_world: torch.Tensor,
        references: list[int] | None = None,
    ) -> MvsOutput:
        """``images`` (B, V, 3, H, W) in [0, 1] at the architecture's size (V >= 2), ``k``
        (B, V, 3, 3) at that size, ``camera_from_world`` (B, V, 4, 4) in the table frame. The
        outputs are those of the ``references`` views (default: every view, in order); each
        reference view is matched against all the others."""
        arch = self.arch
        b, views, _, h, w = images.shape
        if views < 2:
            raise ValueError(f"multi-view stereo needs at least 2 views, got {views}")
        flat = images.reshape(b * views, 3, h, w) - 0.5
        stem = self.stem(flat)
        half = self.encode_half(stem)
        quarter = self.encode_quarter(half)
        coarse_f = self.coarse_features(quarter)
        fine_f = self.fine_features(torch.cat([half, upsample2(quarter)], dim=1))
        (h2, w2), (h4, w4) = half.shape[-2:], quarter.shape[-2:]
        k2 = scale_intrinsics(k, w2 / w, h2 / h)
        k4 = scale_intrinsics(k, w4 / w, h4 / h)
        # Unit feature vectors: correlations are cosines (scaled by the groups), whatever the
        # image's contrast.
        coarse_f = F.normalize(coarse_f, dim=1).reshape(b, views, *coarse_f.shape[1:])
        fine_f = F.normalize(fine_f, dim=1).reshape(b, views, *fine_f.shape[1:])
        stem = stem.reshape(b, views, *stem.shape[1:])
        centre = grid_centre(camera_from_world)
        offsets = (
            torch.arange(arch.fine_planes, dtype=images.dtype, device=images.device)
            - (arch.fine_planes - 1) / 2
        ) * arch.fine_step_m
        outputs: dict[str, list[torch.Tensor]] = {
            "depth": [],
            "confidence": [],
            "coarse": [],
            "fine": [],
            "coarse_planes": [],
            "coarse_logits": [],
        }
        for ref in range(views) if references is None else references:
            near, far = depth_range(k4[:, ref], camera_from_world[:, ref], centre, arch, h4, w4)
            planes = inverse_depth_planes(near, far, arch.coarse_planes)
            cost = correlation_volume(coarse_f, k4, camera_from_world, ref, planes, arch.groups)
            coarse_logits = self.coarse_regulariser(cost)
            outputs["coarse_planes"].append(planes)
            outputs["coarse_logits"].append(coarse_logits)
            coarse, coarse_conf = soft_argmax(coarse_logits, planes)
            centre_fine = upsample2(coarse.unsqueeze(1))[:, 0]
            planes = centre_fine.unsqueeze(1) + offsets[None, :, None, None]
            cost = correlation_volume(fine_f, k2, camera_from_world, ref, planes, arch.groups)
            fine, fine_conf = soft_argmax(self.fine_regulariser(cost), planes)
            fine_up = upsample2(fine.unsqueeze(1))
            centre_depth = (camera_from_world[:, ref, 2, :3] * centre).sum(-1) + camera_from_world[
                :, ref, 2, 3
            ]
            normalised = (fine_up - centre_depth[:, None, None, None]) / 0.1
            residual = self.refine(torch.cat([stem[:, ref], normalised], dim=1))[:, 0]
            depth = fine_up[:, 0] + arch.fine_step_m * torch.tanh(residual)
            confidence = upsample2(upsample2(coarse_conf.unsqueeze(1)) * fine_conf.unsqueeze(1))[
                :, 0
            ]
            outputs["depth"].append(depth)
            outputs["confidence"].append(confidence)
            outputs["coarse"].append(coarse)
            outputs["fine"].append(fine)
        return MvsOutput(**{key: torch.stack(value, dim=1) for key, value in outputs.items()})
