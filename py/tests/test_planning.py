"""Planning from NumPy: gqcnn's real Primesense depth image to grasps, and bad arrays."""

from __future__ import annotations

import numpy as np
import pytest

import mvgrasp
from conftest import shared_data

PRIMESENSE_K = np.array([[525.0, 0.0, 319.5], [0.0, 525.0, 239.5], [0.0, 0.0, 1.0]])


def box_on_table() -> np.ndarray:
    """A 4 x 6 cm box 5 cm tall on a table 0.7 m below a Primesense looking straight down."""
    v, u = np.mgrid[0:480, 0:640].astype(np.float32)
    x, y = (u - 319.5) * 0.65 / 525.0, (v - 239.5) * 0.65 / 525.0
    depth = np.full((480, 640), 0.7, dtype=np.float32)
    depth[(np.abs(x) < 0.02) & (np.abs(y) < 0.03)] = 0.65
    return depth


def test_a_box_on_a_table_is_grasped_across() -> None:
    result = mvgrasp.plan_depth(box_on_table(), PRIMESENSE_K)
    assert result["format"] == "mvgrasp-grasps/1"
    assert result["frame"] == "estimated"
    best = result["grasps"][0]
    # Across the 4 cm side, centred under the camera.
    assert 0.035 < best["width_m"] < 0.05
    assert abs(best["u"] - 319.5) < 6 and abs(best["v"] - 239.5) < 10
    pose = np.array(best["world_from_gripper"])
    assert pose.shape == (4, 4)
    assert np.allclose(pose[:3, :3] @ pose[:3, :3].T, np.eye(3), atol=1e-5)
    # The same seed, the same grasps; (H, W, 1) reads as (H, W).
    again = mvgrasp.plan_depth(box_on_table()[..., None], PRIMESENSE_K)
    assert again == result


def test_the_real_primesense_image_is_grasped_on_the_object() -> None:
    root = shared_data("real_depth/gqcnn/data/examples/single_object/primesense")
    depth = np.load(root / "depth_0.npy")
    from matplotlib.image import imread

    mask = imread(root / "segmask_0.png") > 0
    result = mvgrasp.plan_depth(depth, PRIMESENSE_K, mask=mask)
    best = result["grasps"][0]
    rows, cols = np.nonzero(mask)
    nearest = np.min(np.hypot(cols - best["u"], rows - best["v"]))
    assert nearest < 3.0
    assert result["table"]["inlier_share"] > 0.5


def test_bad_arrays_raise_value_and_type_errors() -> None:
    depth = box_on_table()
    with pytest.raises(ValueError, match="depth: shape"):
        mvgrasp.plan_depth(depth[None], PRIMESENSE_K)
    with pytest.raises(TypeError):
        mvgrasp.plan_depth(depth.astype(np.float64), PRIMESENSE_K)
    skewed = PRIMESENSE_K.copy()
    skewed[0, 1] = 1.0
    with pytest.raises(ValueError, match="no skew"):
        mvgrasp.plan_depth(depth, skewed)
    with pytest.raises(ValueError, match="mask: shape"):
        mvgrasp.plan_depth(depth, PRIMESENSE_K, mask=np.ones((4, 4), dtype=bool))
    with pytest.raises(ValueError, match="not a rigid transform"):
        mvgrasp.plan_depth(depth, PRIMESENSE_K, world_from_camera=2.0 * np.eye(4))
    with pytest.raises(mvgrasp.PlanningError, match="nothing stands on the table"):
        mvgrasp.plan_depth(np.full((480, 640), 0.7, dtype=np.float32), PRIMESENSE_K)
    with pytest.raises(mvgrasp.WeightsError, match="no_such_model"):
        mvgrasp.plan_depth(depth, PRIMESENSE_K, model="no_such_model.json")


def box_seen_from(eye: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """The 4 x 6 cm box, 5 cm tall, on a table (z = 0) at the origin, seen by a Primesense at
    ``eye`` looking at it: exact depth by ray casting, and the camera's ``world_from_camera``."""
    eye_v = np.array(eye, dtype=np.float64)
    z = np.array([0.0, 0.0, 0.02]) - eye_v
    z /= np.linalg.norm(z)
    x = np.cross(z, [0.0, 1.0, 0.0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    pose = np.eye(4)
    pose[:3, :3] = np.stack([x, y, z], axis=1)
    pose[:3, 3] = eye_v
    v, u = np.mgrid[0:480, 0:640].astype(np.float64)
    rays = np.stack([(u - 319.5) / 525.0, (v - 239.5) / 525.0, np.ones_like(u)], axis=-1)
    rays = rays @ pose[:3, :3].T  # the parameter along these is the depth
    lo, hi = np.array([-0.02, -0.03, 0.0]), np.array([0.02, 0.03, 0.05])
    with np.errstate(divide="ignore", invalid="ignore"):
        ta, tb = (lo - eye_v) / rays, (hi - eye_v) / rays
        near = np.max(np.minimum(ta, tb), axis=-1)
        far = np.min(np.maximum(ta, tb), axis=-1)
        table = np.where(rays[..., 2] < 0, -eye_v[2] / rays[..., 2], 0.0)
    depth = np.where((near <= far) & (near > 0), near, table)
    return depth.astype(np.float32), pose


def test_several_views_plan_together_and_fused() -> None:
    seen = [box_seen_from((0.0, 0.0, 0.7)), box_seen_from((-0.35, 0.0, 0.6))]
    depths = [d for d, _ in seen]
    poses = [p for _, p in seen]
    ks = [PRIMESENSE_K, PRIMESENSE_K]
    for fuse in (False, True):
        result = mvgrasp.plan_views(depths, ks, poses, fuse=fuse)
        assert result["frame"] == "given"
        assert len(result["views"]) == 2
        best = result["grasps"][0]
        x, y, z = best["p"]
        assert abs(x) < 0.03 and abs(y) < 0.04 and 0.0 < z < 0.06, best["p"]
        # The multi-view planner's choices carry the score they were planned with and the
        # re-score the ranker's probability is built on.
        assert ("view_quality" in best) == fuse
        assert ("virtual_quality" in best) == fuse
        assert mvgrasp.plan_views(depths, ks, poses, fuse=fuse) == result


def test_several_views_name_the_bad_one() -> None:
    depth, pose = box_seen_from((0.0, 0.0, 0.7))
    with pytest.raises(ValueError, match="one per view"):
        mvgrasp.plan_views([depth, depth], [PRIMESENSE_K], [pose, pose])
    with pytest.raises(ValueError, match=r"depths\[1\]: shape"):
        mvgrasp.plan_views([depth, depth[None]], [PRIMESENSE_K] * 2, [pose, pose])
    with pytest.raises(ValueError, match=r"world_from_cameras\[0\]"):
        mvgrasp.plan_views([depth], [PRIMESENSE_K], [2.0 * np.eye(4)])
    # Fusing needs the world's z up from the table: this world is turned on its side.
    turned = np.eye(4)
    turned[:3, :3] = [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]
    with pytest.raises(mvgrasp.PlanningError, match="z axis is 90 degrees"):
        mvgrasp.plan_views([depth], [PRIMESENSE_K], [turned @ pose], fuse=True)


def test_an_image_of_another_size_than_its_camera_is_refused_with_both_sizes() -> None:
    camera = mvgrasp.Camera.preset("primesense")
    planner = mvgrasp.Planner()
    half = box_on_table()[::2, ::2]
    with pytest.raises(ValueError, match=r"depth: 320 x 240 pixels, but camera is 640 x 480"):
        planner.plan(half, camera)
    posed = mvgrasp.Camera(camera.k, camera.width, camera.height, np.eye(4))
    with pytest.raises(ValueError, match=r"depths\[1\]: 320 x 240 pixels, but cameras\[1\]"):
        planner.plan_views([box_on_table(), half], [posed, posed])
    rgb = np.zeros((240, 320, 3), dtype=np.uint8)
    with pytest.raises(ValueError, match=r"images\[0\]: 320 x 240 pixels"):
        planner.plan_rgb([rgb, rgb], [posed, posed])
