"""The learned multi-view stereo network: its geometry against hand-computed cases, what it
refuses, its export round trip, and its training end to end on a tiny RGB-D dataset (resuming
from its checkpoint)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

torch = pytest.importorskip("torch")

from conftest import generate_rgbd_dataset

from mvgrasp_training.config import ConfigError, MvsExperimentConfig, load_config
from mvgrasp_training.export import export_mvs, load_mvs
from mvgrasp_training.mvs import (
    MVS,
    MvsArchitecture,
    correlation_volume,
    depth_range,
    inverse_depth_planes,
    soft_argmax,
)
from mvgrasp_training.train_mvs import disturb, export_best, train

TINY = MvsArchitecture(
    image_width=32,
    image_height=24,
    features=4,
    groups=2,
    coarse_planes=8,
    fine_planes=4,
    regulariser=4,
)


def look_at(eye: list[float], target: list[float]) -> torch.Tensor:
    """camera_from_world of an OpenCV camera at ``eye`` looking at ``target``."""
    eye_t, target_t = torch.tensor(eye), torch.tensor(target)
    z = (target_t - eye_t) / (target_t - eye_t).norm()
    up = torch.tensor([0.0, 0.0, 1.0]) if abs(float(z[2])) < 0.99 else torch.tensor([0.0, 1.0, 0.0])
    x = torch.linalg.cross(z, up)
    x = x / x.norm()
    y = torch.linalg.cross(z, x)
    out = torch.eye(4)
    out[:3, :3] = torch.stack([x, y, z])
    out[:3, 3] = -out[:3, :3] @ eye_t
    return out


def cameras(views: int) -> tuple[torch.Tensor, torch.Tensor]:
    """``views`` cameras 0.5 m from a point 3 cm above the origin, the first from above."""
    poses = []
    for v in range(views):
        elevation = math.radians(89.0 if v == 0 else 50.0)
        azimuth = 2.1 * v
        eye = [
            0.5 * math.cos(elevation) * math.cos(azimuth),
            0.5 * math.cos(elevation) * math.sin(azimuth),
            0.03 + 0.5 * math.sin(elevation),
        ]
        poses.append(look_at(eye, [0.0, 0.0, 0.03]))
    k = torch.tensor([[30.0, 0.0, 15.5], [0.0, 30.0, 11.5], [0.0, 0.0, 1.0]])
    return k.expand(views, 3, 3).clone(), torch.stack(poses)


def test_a_ray_down_the_middle_spans_the_workspace_from_its_top_to_below_the_table() -> None:
    k, pose = cameras(1)
    centre = torch.tensor([[0.0, 0.0, 0.03]])
    near, far = depth_range(k, pose, centre, TINY, 24, 32)
    middle_near, middle_far = float(near[0, 12, 16]), float(far[0, 12, 16])
    height = 0.03 + 0.5 * math.sin(math.radians(89.0))
    # The ray is 1 degree off vertical: the depths are the heights over its cosine, nearly.
    assert middle_near == pytest.approx(height - TINY.workspace_height_m, abs=2e-3)
    assert middle_far == pytest.approx(height + 0.01, abs=2e-3)
    assert bool((near < far).all()) and bool((near >= 0.05).all())


def test_planes_run_uniformly_in_inverse_depth_from_near_to_far() -> None:
    near, far = torch.tensor([[[0.2]]]), torch.tensor([[[0.6]]])
    planes = inverse_depth_planes(near, far, 5)[0, :, 0, 0]
    assert float(planes[0]) == pytest.approx(0.2) and float(planes[-1]) == pytest.approx(0.6)
    steps = (1 / planes).diff()
    assert torch.allclose(steps, steps[0].expand_as(steps), atol=1e-5)


def test_a_source_that_sees_nothing_adds_nothing_to_the_cost() -> None:
    k, pose = cameras(3)
    features = torch.randn(1, 3, 4, 24, 32)
    depths = torch.full((1, 2, 24, 32), -1.0)  # behind every camera
    volume = correlation_volume(features, k[None], pose[None], 0, depths, 2)
    assert bool((volume == 0).all())


def test_soft_argmax_of_a_sharp_peak_is_its_depth_with_full_confidence() -> None:
    logits = torch.full((1, 8, 1, 1), -30.0)
    logits[0, 3] = 30.0
    depths = torch.arange(8.0).reshape(1, 8, 1, 1) * 0.01
    depth, confidence = soft_argmax(logits, depths)
    assert float(depth) == pytest.approx(0.03) and float(confidence) == pytest.approx(1.0)


def test_the_network_predicts_a_depth_and_a_confidence_per_view_and_refuses_one_view() -> None:
    torch.manual_seed(0)
    net = MVS(TINY)
    k, pose = cameras(3)
    images = torch.rand(2, 3, 3, 24, 32)
    out = net(images, k.expand(2, 3, 3, 3), pose.expand(2, 3, 4, 4))
    assert out.depth.shape == (2, 3, 24, 32) and out.confidence.shape == (2, 3, 24, 32)
    assert out.coarse.shape == (2, 3, 6, 8) and out.fine.shape == (2, 3, 12, 16)
    assert bool((out.confidence >= 0).all()) and bool((out.confidence <= 1 + 1e-6).all())
    # The reference views asked for are those computed, in that order.
    some = net(images, k.expand(2, 3, 3, 3), pose.expand(2, 3, 4, 4), [2, 0])
    assert torch.allclose(some.depth, out.depth[:, [2, 0]], atol=1e-6)
    with pytest.raises(ValueError, match="at least 2 views"):
        net(images[:, :1], k[None, :1], pose[None, :1])
    with pytest.raises(ValueError, match="divide by"):
        MVS(MvsArchitecture(image_width=30))


def test_an_export_reads_back_to_the_same_network(tmp_path: Path) -> None:
    torch.manual_seed(1)
    net = MVS(TINY).eval()
    path = export_mvs(net, tmp_path / "mvs", {"purpose": "test"})
    back, description = load_mvs(path)
    assert description["format"] == "mvgrasp-mvs/1" and description["training"]["purpose"] == "test"
    k, pose = cameras(2)
    images = torch.rand(1, 2, 3, 24, 32)
    with torch.no_grad():
        assert torch.equal(
            net(images, k[None], pose[None]).depth, back(images, k[None], pose[None]).depth
        )
    broken = json.loads(path.read_text())
    broken["architecture"]["features"] = 8
    path.write_text(json.dumps(broken))
    with pytest.raises(ValueError, match="do not fit"):
        load_mvs(path)


def test_disturbing_the_inputs_moves_the_cameras_within_the_configured_error() -> None:
    _k, pose = cameras(3)
    rgb = torch.rand(2, 3, 3, 24, 32)

    class Data:
        colour_jitter = 0.1
        noise_std = 0.01
        pose_noise_m = 0.002
        pose_noise_rad = 0.01

    gen = torch.Generator().manual_seed(0)
    moved_rgb, moved = disturb(rgb, pose.expand(2, 3, 4, 4), Data, gen)
    assert moved_rgb.shape == rgb.shape and bool((moved_rgb >= 0).all() & (moved_rgb <= 1).all())
    shift = (moved[..., :3, 3] - pose[None, :, :3, 3]).norm(dim=-1)
    assert bool((shift <= 0.002 + 1e-6).all()) and bool((shift > 0).any())
    # The rotations stay rotations, each within the angle.
    rotation = moved[..., :3, :3] @ pose[None, :, :3, :3].transpose(-1, -2)
    angle = torch.arccos(((rotation.diagonal(dim1=-2, dim2=-1).sum(-1) - 1) / 2).clamp(-1, 1))
    assert bool((angle <= 0.01 + 1e-4).all())


CONFIG = """name = "mvs_tiny"
seed = 1

[data]
dataset_dir = "{data}"
val_fraction = 0.34
min_views = 2
max_views = 3
val_views = 3

[train]
epochs = {epochs}
samples_per_epoch = 4
batch_size = 2
learning_rate = 1e-3
threads = 1

[model]
image_width = 32
image_height = 24
features = 4
groups = 2
coarse_planes = 8
fine_planes = 4
regulariser = 4
"""


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return generate_rgbd_dataset(tmp_path_factory.mktemp("rgbd"), ["box", "can", "mug"])


def test_training_resumes_from_its_checkpoint_and_exports_its_best_epoch(
    dataset: Path, tmp_path: Path
) -> None:
    out = tmp_path / "run"
    path = tmp_path / "a.toml"
    path.write_text(CONFIG.format(data=dataset, epochs=1))
    first = train(load_config(path, MvsExperimentConfig), out, log=lambda _: None)
    assert first["epochs"] == 1 and (out / "best.pt").is_file()
    history = json.loads((out / "history.json").read_text())
    assert history[0]["object_mm"] > 0 and 0 <= history[0]["object_within_5mm"] <= 1
    lines: list[str] = []
    path.write_text(CONFIG.format(data=dataset, epochs=2))
    config = load_config(path, MvsExperimentConfig)
    second = train(config, out, log=lines.append)
    assert lines[0] == "resumed after epoch 1" and second["epochs"] == 2
    assert json.loads((out / "history.json").read_text())[0] == history[0]
    assert not list(out.glob("*.partial"))
    exported = export_best(config, out, tmp_path / "models" / "mvs_tiny")
    _net, description = load_mvs(exported)
    assert description["training"]["selected_epoch"] in (0, 1)
    assert (out / "learning_curve.png").is_file()


def test_a_config_with_more_min_views_than_max_views_is_refused(
    dataset: Path, tmp_path: Path
) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(CONFIG.format(data=dataset, epochs=1).replace("min_views = 2", "min_views = 4"))
    with pytest.raises(ValueError, match="min_views"):
        train(load_config(path, MvsExperimentConfig), tmp_path / "run", log=lambda _: None)
    path.write_text(CONFIG.format(data=dataset, epochs=1).replace("groups = 2", 'groups = "two"'))
    with pytest.raises(ConfigError, match="groups"):
        load_config(path, MvsExperimentConfig)
