"""The depth Learnt Stereo Machine (D-LSM, Kar, Haene and Malik 2017), shrunk for a CPU.

A few RGB views with their cameras in, a metric depth map per view out, in one feed-forward
pass, as the original code builds it (akar43/lsm, ``models.py`` and ``ops.py``):

1. a 2-D U-Net encoder per view (shared weights): features at half resolution, instance norm;
2. **unprojection** of each view's features into a 3-D grid around the object with the
   camera's intrinsics and extrinsics, each voxel's depth in that camera appended: bilinear
   samples, with samples outside the image or behind the camera masked to zero (never clamped
   to the border, the original's silent GPU behaviour) and the mask appended as a channel;
3. a 3-D convolutional GRU that fuses the views in sequence;
4. a 3-D U-Net refiner;
5. **projection** of the grid back along each camera's rays (``ray_samples`` trilinear samples
   over the grid's depth range, stacked as channels) and a 2-D decoder with skips from the
   image encoder to a metric depth map per view.

Conventions are mvgrasp's (``../shared/GUIDE.md``): metres; OpenCV camera frames (x right, y
down, z forward); pixel centres at integer coordinates (``u = fx x / z + cx``); the world is the
table frame (z up). Cameras enter as ``K`` (3x3, at the input image's resolution) and
``camera_from_world`` (4x4), as plain matrices, so the Rust runtime needs no geometry.

The grid is a cube of side ``grid_side_m`` centred where the cameras look: the point nearest
all their optical axes (least squares), so it follows the object wherever the cameras were
aimed, not a hard-coded unit cube.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch
from torch import nn
from torch.nn import functional as F


@dataclass(frozen=True)
class LsmArchitecture:
    """The network's sizes. The original: 224 x 224 images, 32^3 grid, 32-channel GRU, 64 ray
    samples (about 51 GMAC for 4 views); these defaults train on a 2-core CPU."""

    image_width: int = 128
    image_height: int = 96
    features: int = 16
    """Channels of the image encoder at half resolution (the full-resolution skip: half)."""
    grid_size: int = 24
    """Voxels along each side of the grid."""
    grid_side_m: float = 0.3
    """The grid's side, metres."""
    gru_channels: int = 24
    ray_samples: int = 24
    """Samples along each ray when the grid is projected back to a view."""


def scale_intrinsics(k: torch.Tensor, sx: float, sy: float) -> torch.Tensor:
    """``k`` (..., 3, 3) for an image resized by ``sx`` x ``sy``, pixel centres at integers:
    ``u' = (u + 0.5) sx - 0.5``."""
    out = k.clone()
    out[..., 0, 0] = k[..., 0, 0] * sx
    out[..., 1, 1] = k[..., 1, 1] * sy
    out[..., 0, 2] = (k[..., 0, 2] + 0.5) * sx - 0.5
    out[..., 1, 2] = (k[..., 1, 2] + 0.5) * sy - 0.5
    return out


def grid_centre(camera_from_world: torch.Tensor) -> torch.Tensor:
    """The point nearest all the cameras' optical axes, least squares: (B, V, 4, 4) -> (B, 3)."""
    rotation = camera_from_world[..., :3, :3]
    translation = camera_from_world[..., :3, 3]
    centre = -(rotation.transpose(-1, -2) @ translation.unsqueeze(-1)).squeeze(-1)  # (B, V, 3)
    axis = rotation[..., 2, :]  # the optical axis in the world: row 2 of camera_from_world
    eye = torch.eye(3, dtype=axis.dtype, device=axis.device)
    projector = eye - axis.unsqueeze(-1) * axis.unsqueeze(-2)  # (B, V, 3, 3)
    a = projector.sum(1)
    b = (projector @ centre.unsqueeze(-1)).sum(1)
    return torch.linalg.solve(a, b).squeeze(-1)


def voxel_centres(centre: torch.Tensor, size: int, side_m: float) -> torch.Tensor:
    """The world positions of a (size^3) grid's voxel centres around ``centre`` (B, 3):
    (B, size, size, size, 3), indexed [z, y, x] (torch's depth, height, width)."""
    step = side_m / size
    offsets = (torch.arange(size, dtype=centre.dtype, device=centre.device) + 0.5) * step
    offsets = offsets - side_m / 2
    z, y, x = torch.meshgrid(offsets, offsets, offsets, indexing="ij")
    grid = torch.stack([x, y, z], dim=-1)  # (S, S, S, 3) as (x, y, z)
    return grid.unsqueeze(0) + centre[:, None, None, None, :]


def to_camera(points: torch.Tensor, camera_from_world: torch.Tensor) -> torch.Tensor:
    """World points (B, ..., 3) in the camera of (B, 4, 4)."""
    shape = points.shape
    flat = points.reshape(shape[0], -1, 3)
    out = flat @ camera_from_world[:, :3, :3].transpose(1, 2) + camera_from_world[:, None, :3, 3]
    return out.reshape(shape)


def unproject(
    features: torch.Tensor,
    k: torch.Tensor,
    camera_from_world: torch.Tensor,
    voxels: torch.Tensor,
    depth_scale_m: float,
) -> torch.Tensor:
    """Each voxel's bilinear sample of one view's ``features`` (B, C, h, w; ``k`` at that
    resolution), with its depth in the camera (centred on the grid's, over ``depth_scale_m``)
    and a mask (1 where the voxel projects inside the image in front of the camera) appended:
    (B, C + 2, S, S, S). Masked samples are 0, never a border pixel."""
    b, c, h, w = features.shape
    p = to_camera(voxels, camera_from_world)  # (B, S, S, S, 3)
    z = p[..., 2]
    safe_z = torch.where(z > 1e-6, z, torch.ones_like(z))
    u = k[:, 0, 0, None, None, None] * p[..., 0] / safe_z + k[:, 0, 2, None, None, None]
    v = k[:, 1, 1, None, None, None] * p[..., 1] / safe_z + k[:, 1, 2, None, None, None]
    inside = (z > 1e-6) & (u >= 0) & (u <= w - 1) & (v >= 0) & (v <= h - 1)
    # align_corners=True: -1 and +1 are the centres of the first and last pixels.
    grid = torch.stack([2 * u / (w - 1) - 1, 2 * v / (h - 1) - 1], dim=-1)
    grid = torch.where(inside.unsqueeze(-1), grid, torch.zeros_like(grid))
    s = voxels.shape[1]
    sampled = F.grid_sample(
        features, grid.reshape(b, s, s * s, 2), mode="bilinear", align_corners=True
    ).reshape(b, c, s, s, s)
    mask = inside.to(features.dtype).unsqueeze(1)
    centre_depth = to_camera(voxels.mean(dim=(1, 2, 3)).unsqueeze(1), camera_from_world)[:, 0, 2]
    depth = ((z - centre_depth[:, None, None, None]) / depth_scale_m).unsqueeze(1)
    return torch.cat([sampled * mask, depth * mask, mask], dim=1)


def ray_depths(
    camera_from_world: torch.Tensor, centre: torch.Tensor, side_m: float, samples: int
) -> tuple[torch.Tensor, torch.Tensor]:
    """The depths (B, samples) at which each camera's rays are sampled: evenly over the grid's
    bounding sphere around its centre's depth; and the centre's depth (B,)."""
    centre_depth = to_camera(centre.unsqueeze(1), camera_from_world)[:, 0, 2]
    radius = side_m * math.sqrt(3) / 2
    t = torch.linspace(-1.0, 1.0, samples, dtype=centre.dtype, device=centre.device)
    return centre_depth[:, None] + radius * t[None, :], centre_depth


def project(
    grid: torch.Tensor,
    k: torch.Tensor,
    camera_from_world: torch.Tensor,
    centre: torch.Tensor,
    side_m: float,
    samples: int,
    height: int,
    width: int,
) -> torch.Tensor:
    """The grid's features (B, C, S, S, S) sampled along each pixel's ray of a camera (``k`` at
    ``height`` x ``width``) at the depths of :func:`ray_depths` (trilinear; 0 outside the
    grid): (B, C * samples, height, width), the samples stacked as channels."""
    b, c = grid.shape[:2]
    depths, _ = ray_depths(camera_from_world, centre, side_m, samples)  # (B, D)
    v, u = torch.meshgrid(
        torch.arange(height, dtype=grid.dtype, device=grid.device),
        torch.arange(width, dtype=grid.dtype, device=grid.device),
        indexing="ij",
    )
    x = (u[None] - k[:, 0, 2, None, None]) / k[:, 0, 0, None, None]  # (B, H, W) at z = 1
    y = (v[None] - k[:, 1, 2, None, None]) / k[:, 1, 1, None, None]
    ray = torch.stack([x, y, torch.ones_like(x)], dim=-1)  # camera frame, (B, H, W, 3)
    points = ray[:, None] * depths[:, :, None, None, None]  # (B, D, H, W, 3)
    rotation = camera_from_world[:, :3, :3]
    world = (points - camera_from_world[:, None, None, None, :3, 3]) @ rotation[:, None, None]
    # Normalised grid coordinates: -1 and +1 are the grid's faces (align_corners=False).
    normalised = (world - centre[:, None, None, None, :]) / (side_m / 2)
    sampled = F.grid_sample(
        grid, normalised, mode="bilinear", padding_mode="zeros", align_corners=False
    )  # (B, C, D, H, W)
    return sampled.reshape(b, c * samples, height, width)


def conv2d(cin: int, cout: int, stride: int = 1) -> nn.Sequential:
    return nn.Sequential(
        nn.Conv2d(cin, cout, 3, stride=stride, padding=1),
        nn.InstanceNorm2d(cout, affine=True),
        nn.ReLU(inplace=True),
    )


def conv3d(cin: int, cout: int, stride: int = 1) -> nn.Sequential:
    return nn.Sequential(
        nn.Conv3d(cin, cout, 3, stride=stride, padding=1),
        nn.InstanceNorm3d(cout, affine=True),
        nn.ReLU(inplace=True),
    )


class ConvGru3d(nn.Module):
    """A 3-D convolutional GRU cell: gates and candidate from 3x3x3 convolutions of the input
    and the hidden state."""

    def __init__(self, cin: int, hidden: int) -> None:
        super().__init__()
        self.hidden = hidden
        self.gates = nn.Conv3d(cin + hidden, 2 * hidden, 3, padding=1)
        self.candidate = nn.Conv3d(cin + hidden, hidden, 3, padding=1)

    def forward(self, x: torch.Tensor, h: torch.Tensor) -> torch.Tensor:
        update, reset = torch.sigmoid(self.gates(torch.cat([x, h], dim=1))).chunk(2, dim=1)
        candidate = torch.tanh(self.candidate(torch.cat([x, reset * h], dim=1)))
        return (1 - update) * h + update * candidate


class LSM(nn.Module):
    """The depth Learnt Stereo Machine (see the module docs)."""

    def __init__(self, arch: LsmArchitecture = LsmArchitecture()) -> None:
        super().__init__()
        self.arch = arch
        f = arch.features
        half = max(f // 2, 4)
        self.encode_full = nn.Sequential(conv2d(3, half), conv2d(half, half))
        self.encode_half = nn.Sequential(conv2d(half, f, stride=2), conv2d(f, f))
        g = arch.gru_channels
        self.gru = ConvGru3d(f + 2, g)
        self.refine_in = conv3d(g, g)
        self.refine_down = conv3d(g, 2 * g, stride=2)
        self.refine_up = nn.ConvTranspose3d(2 * g, g, 4, stride=2, padding=1)
        self.refine_out = conv3d(g, g)
        self.from_rays = conv2d(g * arch.ray_samples, f)
        self.decode_half = conv2d(2 * f, f)
        self.decode_full = nn.Sequential(conv2d(f + half, half), nn.Conv2d(half, 1, 3, padding=1))

    def forward(
        self,
        images: torch.Tensor,
        k: torch.Tensor,
        camera_from_world: torch.Tensor,
        centre: torch.Tensor | None = None,
    ) -> torch.Tensor:
        """``images`` (B, V, 3, H, W) in [0, 1] at the architecture's size, ``k`` (B, V, 3, 3) at
        that size, ``camera_from_world`` (B, V, 4, 4) in the table frame: depth (B, V, H, W),
        metres along each camera's optical axis. ``centre`` (B, 3): the grid's centre instead of
        where the cameras' axes meet (one view's axis does not place it; the Rust runtime's
        ``Lsm::predict_in``)."""
        arch = self.arch
        b, views, _, h, w = images.shape
        flat = images.reshape(b * views, 3, h, w)
        full = self.encode_full(flat)
        half = self.encode_half(full)
        hh, hw = half.shape[-2:]
        k_half = scale_intrinsics(k, hw / w, hh / h)
        if centre is None:
            centre = grid_centre(camera_from_world)
        voxels = voxel_centres(centre, arch.grid_size, arch.grid_side_m)
        half_views = half.reshape(b, views, *half.shape[1:])
        state = torch.zeros(
            b, arch.gru_channels, *(arch.grid_size,) * 3, dtype=images.dtype, device=images.device
        )
        for view in range(views):
            grid = unproject(
                half_views[:, view],
                k_half[:, view],
                camera_from_world[:, view],
                voxels,
                arch.grid_side_m / 2,
            )
            state = self.gru(grid, state)
        x = self.refine_in(state)
        x = self.refine_out(x + self.refine_up(self.refine_down(x)))
        depths = []
        for view in range(views):
            rays = project(
                x,
                k_half[:, view],
                camera_from_world[:, view],
                centre,
                arch.grid_side_m,
                arch.ray_samples,
                hh,
                hw,
            )
            y = self.from_rays(rays)
            y = self.decode_half(torch.cat([y, half_views[:, view]], dim=1))
            y = F.interpolate(y, size=(h, w), mode="bilinear", align_corners=False)
            full_view = full.reshape(b, views, *full.shape[1:])[:, view]
            out = self.decode_full(torch.cat([y, full_view], dim=1))[:, 0]
            _, centre_depth = ray_depths(
                camera_from_world[:, view], centre, arch.grid_side_m, arch.ray_samples
            )
            radius = arch.grid_side_m * math.sqrt(3) / 2
            depths.append(centre_depth[:, None, None] + radius * torch.tanh(out))
        return torch.stack(depths, dim=1)
