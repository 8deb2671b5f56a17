"""The Planner and its dataclasses: the same grasps.json, byte for byte, as the `plan` command
on the same inputs (a depth image, a mesh); views, timings and the physics check; cameras."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

import mvgrasp
from conftest import REPO_ROOT
from test_planning import PRIMESENSE_K, box_on_table


def same(a: object, b: object) -> bool:
    """Equal structures whose numbers agree to float32 precision."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    if isinstance(a, float) or isinstance(b, float):
        return bool(np.isclose(a, b, rtol=1e-6, atol=1e-9))
    return a == b


def plan_cli(*args: str) -> None:
    subprocess.run(
        ["cargo", "run", "--quiet", "--profile", "dist", "--bin", "plan", "--", *args],
        cwd=REPO_ROOT, check=True, stdout=subprocess.DEVNULL,
    )  # fmt: skip


def test_planning_on_depth_writes_the_cli_grasps_json_byte_for_byte(tmp_path: Path) -> None:
    depth = box_on_table()
    np.save(tmp_path / "depth.npy", depth)
    intrinsics = {"K": PRIMESENSE_K.tolist(), "width": 640, "height": 480}
    (tmp_path / "camera.json").write_text(json.dumps(intrinsics))
    plan_cli("--depth", str(tmp_path / "depth.npy"), "--intrinsics", str(tmp_path / "camera.json"),
             "--seed", "4", "--out", str(tmp_path / "cli"))  # fmt: skip
    result = mvgrasp.Planner(seed=4).plan(depth, PRIMESENSE_K)
    written = result.write(tmp_path / "python")
    assert written.read_bytes() == (tmp_path / "cli" / "grasps.json").read_bytes()
    # The dataclasses hold what the file holds.
    content = json.loads(result.grasps_json)
    assert result.frame == "estimated" and len(result.grasps) == len(content["grasps"])
    best = result.best
    assert best is not None and best.rank == 0
    assert np.allclose(best.world_from_gripper, content["grasps"][0]["world_from_gripper"])
    assert best.world_from_gripper.shape == (4, 4) and best.p.shape == (3,)
    assert 0.035 < best.width_m < 0.05
    assert best.grasp.width_m == best.width_m
    assert np.allclose(best.grasp.center, best.p, atol=1e-6)
    (view,) = result.views
    assert view.ranked == len(result.grasps) and view.best_quality == best.quality
    assert np.allclose(view.camera.k, PRIMESENSE_K)
    assert result.timings["total_s"] > 0
    assert result.table is not None


def test_planning_on_a_mesh_matches_the_cli_and_checks_in_physics(tmp_path: Path) -> None:
    plan_cli("--category", "box", "--no-physics", "--depth-from", "rendered", "--no-fuse",
             "--out", str(tmp_path / "cli"))  # fmt: skip
    vertices, triangles = mvgrasp.builtin_object("box", 0)
    result = mvgrasp.Planner(fuse=False).plan_mesh(vertices, triangles)
    assert result.grasps_json.encode() == (tmp_path / "cli" / "grasps.json").read_bytes()
    assert result.frame == "rendered"
    assert result.physics is not None and result.physics["success"]
    assert result.analytic is not None and result.analytic["collision_free"]
    assert set(result.timings) == {"render_s", "depth_s", "fuse_s", "plan_s", "check_s", "total_s"}
    (view,) = result.views  # the top-down GQ-CNN plans in the top-down view
    assert view.elevation_deg == pytest.approx(90.0)
    assert view.candidates is not None and view.candidates > 0
    # The multi-view planner over 3 views.
    fused = mvgrasp.Planner(fuse=True).plan_mesh(vertices, triangles, views=3, physics=False)
    assert len(fused.views) == 3 and fused.physics is None
    assert fused.best is not None and fused.best.view_quality is not None
    assert fused.best.virtual_quality is not None and 0.0 <= fused.best.quality <= 1.0
    with pytest.raises(ValueError, match="views = 11"):
        mvgrasp.Planner().plan_mesh(vertices, triangles, views=11)
    # The CLI's default: depth predicted by the baseline from 5 colour views, the multi-view
    # planner over them; the same bytes.
    plan_cli("--category", "box", "--no-physics", "--out", str(tmp_path / "rgb"))
    assert (tmp_path / "rgb" / "views.png").is_file()
    default = mvgrasp.Planner().plan_mesh(vertices, triangles, physics=False,
                                          depth_from="baseline")  # fmt: skip
    assert default.grasps_json.encode() == (tmp_path / "rgb" / "grasps.json").read_bytes()
    assert len(default.views) == 5 and default.best is not None
    assert default.best.virtual_quality is not None
    # The chance to hold is the CLI's, for the planners that have one.
    shown = json.loads(subprocess.run(
        ["cargo", "run", "--quiet", "--profile", "dist", "--bin", "plan", "--",
         "--category", "box", "--no-physics", "--json"],
        cwd=REPO_ROOT, check=True, capture_output=True, text=True,
    ).stdout)  # fmt: skip
    assert default.hold_probability is not None and 0.0 < default.hold_probability < 1.0
    assert default.hold_probability == pytest.approx(shown["hold_probability"], abs=1e-6)
    # The multi-view planner's chance is its ranked quality; the top-down GQ-CNN's is mapped.
    assert fused.hold_probability == pytest.approx(fused.best.quality, abs=1e-6)
    assert result.hold_probability is not None and result.best is not None
    assert result.hold_probability != pytest.approx(result.best.quality, abs=1e-6)
    learnt = mvgrasp.Planner(fuse=False).plan_mesh(vertices, triangles, physics=False,
                                                   depth_from="lsm")  # fmt: skip
    assert learnt.timings["depth_s"] > 0 and len(learnt.views) == 5
    assert learnt.grasps and all(g.view == 0 for g in learnt.grasps)
    # --fuse: the multi-view planner on the same predicted views.
    plan_cli("--category", "box", "--no-physics", "--fuse", "--depth-from", "lsm", "--out",
             str(tmp_path / "lsm_fused"))  # fmt: skip
    fused_rgb = mvgrasp.Planner(fuse=True).plan_mesh(vertices, triangles, physics=False,
                                                     depth_from="lsm")  # fmt: skip
    assert fused_rgb.grasps_json.encode() == (tmp_path / "lsm_fused" / "grasps.json").read_bytes()
    with pytest.raises(ValueError, match="at least 2 views"):
        mvgrasp.Planner(fuse=True).plan_mesh(vertices, triangles, views=1, depth_from="lsm")
    with pytest.raises(ValueError, match="depth_from"):
        mvgrasp.Planner(fuse=True).plan_mesh(vertices, triangles, depth_from="stereo")
    with pytest.raises(mvgrasp.CameraError, match="kinect"):
        mvgrasp.Planner().plan_mesh(vertices, triangles, camera="kinect")


def test_planning_over_posed_views_with_cameras() -> None:
    vertices, triangles = mvgrasp.builtin_object("mug", 2)
    pose = mvgrasp.stable_poses(vertices, triangles)[0]["table_from_object"]
    cameras = mvgrasp.cameras.hemisphere(3, 0.65, target=(0.0, 0.0, 0.05))
    images = mvgrasp.render(vertices, triangles, [c.k for c in cameras],
                            [c.world_from_camera for c in cameras], width=cameras[0].width,
                            height=cameras[0].height, world_from_object=pose)  # fmt: skip
    result = mvgrasp.Planner(fuse=True).plan_views(list(images["depth"]), cameras)
    assert result.frame == "given" and len(result.views) == 3
    assert result.best is not None
    unposed = mvgrasp.Camera(cameras[1].k, cameras[1].width, cameras[1].height)
    with pytest.raises(ValueError, match=r"cameras\[1\]: no world_from_camera"):
        mvgrasp.Planner().plan_views(list(images["depth"][:2]), [cameras[0], unposed])
    native = mvgrasp.plan_views(list(images["depth"]), [c.k for c in cameras],
                                [c.world_from_camera for c in cameras], fuse=True)  # fmt: skip
    # The text holds float32 values in their shortest form, the dict as float64.
    assert same(json.loads(result.grasps_json), native)
    # The grasp is on the mug: its centre projects inside the mask of the view it came from.
    best = result.best
    u, v = cameras[best.view].project(best.p[None])[0]
    mask = images["mask"][best.view]
    assert mask[int(round(v)) - 3 : int(round(v)) + 4, int(round(u)) - 3 : int(round(u)) + 4].any()


def test_cameras_project_and_unproject() -> None:
    camera = mvgrasp.Camera.preset("primesense", world_from_camera=np.eye(4))
    assert np.allclose(camera.k, PRIMESENSE_K)
    assert (camera.width, camera.height) == (640, 480)
    points = np.array([[0.1, -0.05, 0.8], [0.0, 0.0, 0.5], [0.0, 0.0, -1.0]])
    pixels = camera.project(points)
    assert np.allclose(pixels[0], [319.5 + 525 * 0.1 / 0.8, 239.5 - 525 * 0.05 / 0.8])
    assert np.isnan(pixels[2]).all()  # behind the camera
    back = camera.unproject(pixels[:2], points[:2, 2])
    assert np.allclose(back, points[:2], atol=1e-6)
    # A posed camera: 0.7 m above the table looking down sees the origin at its centre.
    (top,) = mvgrasp.cameras.hemisphere(1, 0.7, intrinsics="primesense")
    assert np.allclose(top.project([[0.0, 0.0, 0.0]]), [[319.5, 239.5]], atol=1e-3)
    depth = np.full((480, 640), 0.7, dtype=np.float32)
    assert np.allclose(top.depth_to_points(depth)[:, 2], 0.0, atol=1e-5)
    with pytest.raises(ValueError, match="points: shape"):
        camera.project(np.zeros((2, 2)))


def test_planning_on_rgb_views_writes_the_cli_grasps_json_byte_for_byte(tmp_path: Path) -> None:
    from matplotlib.image import imread

    mvgrasp.generate_rgbd_dataset(tmp_path / "data", categories=["box"])
    folder = tmp_path / "data" / "box_000" / "test"
    plan_cli("--rgb", str(folder), "--out", str(tmp_path / "cli"))
    cameras = [mvgrasp.Camera.from_dict(c)
               for c in json.loads((folder / "cameras.json").read_text())]  # fmt: skip
    images = [np.rint(imread(folder / f"{i:03}_rgb.png") * 255).astype(np.uint8)
              for i in range(len(cameras))]  # fmt: skip
    masks = [np.rint(imread(folder / f"{i:03}_mask.png") * 255) == 1
             for i in range(len(cameras))]  # fmt: skip
    result = mvgrasp.Planner().plan_rgb(images, cameras, masks=masks)
    # The baseline's depth: the top-down view's box to a millimetre (median).
    depth = mvgrasp.predict_depth(images[:5], [c.k for c in cameras[:5]],
                                  [c.world_from_camera for c in cameras[:5]], masks=masks[:5],
                                  depth_from="baseline")  # fmt: skip
    truth = mvgrasp.read_rgbd_folder(folder)["depth"][0]
    assert depth.shape == (5, 386, 516) and depth.dtype == np.float32
    on_box = masks[0] & (depth[0] > 0)
    assert on_box.sum() > 0.8 * masks[0].sum()
    assert np.median(np.abs(depth[0][on_box] - truth[on_box])) < 1e-3
    assert result.grasps_json.encode() == (tmp_path / "cli" / "grasps.json").read_bytes()
    assert result.frame == "given" and len(result.views) == 10
    assert result.best is not None and result.best.view_quality is not None
    # The default is the baseline's.
    default = mvgrasp.predict_depth(images[:5], [c.k for c in cameras[:5]],
                                    [c.world_from_camera for c in cameras[:5]], masks=masks[:5])  # fmt: skip
    assert np.array_equal(default, depth)
    # The LSM's: every pixel predicted, the box's within the network's error.
    learnt = mvgrasp.predict_depth(images[:5], [c.k for c in cameras[:5]],
                                   [c.world_from_camera for c in cameras[:5]], masks=masks[:5],
                                   depth_from="lsm")  # fmt: skip
    assert learnt.shape == depth.shape and (learnt[0][masks[0]] > 0).all()
    assert np.median(np.abs(learnt[0][masks[0]] - truth[masks[0]])) < 0.02
    # The multi-view stereo network's: every box pixel predicted.
    stereo = mvgrasp.predict_depth(images[:5], [c.k for c in cameras[:5]],
                                   [c.world_from_camera for c in cameras[:5]], masks=masks[:5],
                                   depth_from="mvs")  # fmt: skip
    assert stereo.shape == depth.shape and (stereo[0][masks[0]] > 0).all()
    # One view: the LSM alone (its grid centred on the camera's axis); the others need two.
    one = mvgrasp.predict_depth(images[:1], [cameras[0].k], [cameras[0].world_from_camera],
                                masks=masks[:1], depth_from="lsm")  # fmt: skip
    assert one.shape == (1, *depth.shape[1:]) and (one[0][masks[0]] > 0).all()
    with pytest.raises(mvgrasp.PlanningError, match="stereo needs at least 2"):
        mvgrasp.predict_depth(images[:1], [cameras[0].k], [cameras[0].world_from_camera],
                              depth_from="baseline")  # fmt: skip
    with pytest.raises(ValueError, match="depth_from"):
        mvgrasp.Planner().plan_rgb(images, cameras, depth_from="stereo")
    with pytest.raises(ValueError, match="at least 2 views"):
        mvgrasp.Planner().plan_rgb(images[:1], cameras[:1])
    with pytest.raises(ValueError, match=r"images\[0\]: shape"):
        mvgrasp.Planner().plan_rgb([images[0][..., :2], images[1]], cameras[:2])
    with pytest.raises(ValueError, match=r"images\[0\]: shape"):  # grey: not (H, W, 3)
        mvgrasp.Planner().plan_rgb([images[0][..., 0], images[1]], cameras[:2])
