"""The Learnt Stereo Machine's geometry against mvgrasp's cameras (the wheel), and the network's
shapes, range and gradients."""

from __future__ import annotations

import math

import numpy as np
import pytest

torch = pytest.importorskip("torch")

import mvgrasp  # noqa: E402
from mvgrasp_training.lsm import (  # noqa: E402
    LSM,
    LsmArchitecture,
    grid_centre,
    project,
    scale_intrinsics,
    to_camera,
    unproject,
    voxel_centres,
)

TARGET = (0.02, -0.01, 0.05)


def cameras(count: int = 4) -> tuple[torch.Tensor, torch.Tensor, int, int]:
    """Hemisphere cameras from the Rust core looking at TARGET: K (1, V, 3, 3),
    camera_from_world (1, V, 4, 4), width, height."""
    cams = mvgrasp.hemisphere_cameras(count=count, radius_m=0.5, target=TARGET, seed=3)
    k = torch.tensor(np.stack([c["k"] for c in cams]))[None]
    pose = torch.tensor(np.stack([np.linalg.inv(c["world_from_camera"]) for c in cams]))[None]
    return k, pose, cams[0]["width"], cams[0]["height"]


def test_projection_matches_the_rust_cameras_and_resizing_keeps_pixel_centres() -> None:
    k, camera_from_world, w, h = cameras()
    points = torch.tensor([[0.03, 0.02, 0.04], [-0.05, 0.0, 0.1]], dtype=torch.float64)
    for view in range(k.shape[1]):
        world_from_camera = np.linalg.inv(camera_from_world[0, view].numpy())
        rust = mvgrasp.project_points(points.numpy(), k[0, view].numpy(), w, h, world_from_camera)
        p = to_camera(points[None], camera_from_world[:, view])[0]
        u = k[0, view, 0, 0] * p[:, 0] / p[:, 2] + k[0, view, 0, 2]
        v = k[0, view, 1, 1] * p[:, 1] / p[:, 2] + k[0, view, 1, 2]
        assert np.allclose(torch.stack([u, v], 1).numpy(), rust, atol=1e-3)
        # Half the size: pixel centres stay at integers.
        half = scale_intrinsics(k[0, view], 0.5, 0.5)
        u2 = half[0, 0] * p[:, 0] / p[:, 2] + half[0, 2]
        assert torch.allclose(u2, (u + 0.5) * 0.5 - 0.5, atol=1e-9)


def test_the_grid_is_centred_where_the_cameras_look() -> None:
    _, camera_from_world, _, _ = cameras(5)
    centre = grid_centre(camera_from_world)
    assert torch.allclose(centre[0], torch.tensor(TARGET, dtype=centre.dtype), atol=1e-4)
    voxels = voxel_centres(centre, 4, 0.2)
    assert voxels.shape == (1, 4, 4, 4, 3)
    assert torch.allclose(voxels.mean(dim=(1, 2, 3)), centre)
    # [z, y, x] indexing: the last index moves along world x by a voxel (5 cm).
    assert torch.allclose(voxels[0, 0, 0, 1] - voxels[0, 0, 0, 0], torch.tensor([0.05, 0, 0]).double())


def test_unprojection_samples_the_pixel_each_voxel_projects_to_and_masks_the_rest() -> None:
    k, camera_from_world, w, h = cameras(1)
    k, camera_from_world = k[:, 0], camera_from_world[:, 0]
    v, u = torch.meshgrid(torch.arange(h).double(), torch.arange(w).double(), indexing="ij")
    features = torch.stack([u, v])[None]  # each pixel holds its own coordinates
    centre = torch.tensor([TARGET], dtype=torch.float64)
    # A grid wider than the view: some voxels project outside the image.
    voxels = voxel_centres(centre, 8, 2.0)
    out = unproject(features, k, camera_from_world, voxels, 1.0)
    assert out.shape == (1, 4, 8, 8, 8)
    mask = out[0, 3] > 0
    assert mask.any() and not mask.all()
    p = to_camera(voxels, camera_from_world)[0]
    u_expected = k[0, 0, 0] * p[..., 0] / p[..., 2] + k[0, 0, 2]
    assert torch.allclose(out[0, 0][mask], u_expected[mask], atol=1e-6)
    # Outside the image: zeros, not the border pixel's value.
    assert (out[0, :3][:, ~mask] == 0).all()
    # Behind the camera: masked too.
    behind = voxel_centres(torch.tensor([[0.0, 0.0, 2.0]], dtype=torch.float64), 2, 0.1)
    assert (unproject(features, k, camera_from_world, behind, 1.0)[0, 3] == 0).all()


def test_projection_sees_an_occupied_cube_between_its_entry_and_exit() -> None:
    k, camera_from_world, w, h = cameras(1)
    k, camera_from_world = k[:, 0], camera_from_world[:, 0]
    centre = torch.tensor([TARGET], dtype=torch.float64)
    side, samples = 0.2, 41
    grid = torch.zeros(1, 1, 8, 8, 8, dtype=torch.float64)
    grid[..., 2:6, 2:6, 2:6] = 1.0  # the central 10 cm cube
    rays = project(grid, k, camera_from_world, centre, side, samples, h, w)
    assert rays.shape == (1, samples, h, w)
    # The ray through the grid's centre meets the cube; the image's corner ray misses it.
    p = to_camera(centre[None], camera_from_world)[0, 0]
    u = int(round(float(k[0, 0, 0] * p[0] / p[2] + k[0, 0, 2])))
    v = int(round(float(k[0, 1, 1] * p[1] / p[2] + k[0, 1, 2])))
    along = rays[0, :, v, u]
    assert along.max() > 0.99 and along[0] == 0 and along[-1] == 0
    assert (rays[0, :, 0, 0] == 0).all()
    # The occupied samples span about the cube's 10 cm (the samples are 1.7 cm apart).
    step = side * math.sqrt(3) / (samples - 1)
    assert abs((along > 0.5).sum().item() * step - 0.1) < 3 * step


def test_the_network_gives_a_depth_per_view_in_range_and_learns() -> None:
    torch.manual_seed(0)
    arch = LsmArchitecture(
        image_width=32, image_height=24, features=8, grid_size=8, gru_channels=8, ray_samples=8
    )
    net = LSM(arch)
    k, camera_from_world, w, h = cameras(3)
    k = scale_intrinsics(k, 32 / w, 24 / h).float()
    camera_from_world = camera_from_world.float()
    images = torch.rand(1, 3, 3, 24, 32)
    depth = net(images, k, camera_from_world)
    assert depth.shape == (1, 3, 24, 32)
    # A grid centre given is used as given: the cameras' own gives the same depth, another not.
    with torch.no_grad():
        centre = grid_centre(camera_from_world)
        assert torch.equal(net(images, k, camera_from_world, centre=centre), depth.detach())
        moved = net(images, k, camera_from_world, centre=centre + 0.05)
        assert not torch.allclose(moved, depth.detach())
    radius = arch.grid_side_m * math.sqrt(3) / 2
    assert (depth > 0.5 - radius - 1e-3).all() and (depth < 0.5 + radius + 1e-3).all()
    target = torch.full_like(depth, 0.45)
    optimiser = torch.optim.Adam(net.parameters(), lr=1e-2)
    first = None
    for _ in range(20):
        loss = (net(images, k, camera_from_world) - target).abs().mean()
        first = first if first is not None else loss.item()
        optimiser.zero_grad()
        loss.backward()
        optimiser.step()
    assert loss.item() < 0.5 * first
