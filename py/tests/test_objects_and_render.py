"""Objects, cameras and rendering from NumPy: known shapes, the datasets' cameras, and the
images the CLI's `render` writes, reproduced from Python."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

import mvgrasp
from conftest import REPO_ROOT


def box(x: float, y: float, z: float) -> tuple[np.ndarray, np.ndarray]:
    """A closed box centred at the origin (float64 vertices, int64 faces: trimesh's dtypes)."""
    corners = np.array(
        [[sx * x / 2, sy * y / 2, sz * z / 2] for sz in (-1, 1) for sy in (-1, 1) for sx in (-1, 1)]
    )
    faces = np.array(
        [
            [0, 2, 1], [1, 2, 3],  # bottom (z-)
            [4, 5, 6], [5, 7, 6],  # top (z+)
            [0, 1, 4], [1, 5, 4],  # y-
            [2, 6, 3], [3, 6, 7],  # y+
            [0, 4, 2], [2, 4, 6],  # x-
            [1, 3, 5], [3, 7, 5],  # x+
        ],
        dtype=np.int64,
    )  # fmt: skip
    return corners, faces


def test_a_box_has_the_mass_properties_of_a_box() -> None:
    vertices, faces = box(0.04, 0.06, 0.10)
    facts = mvgrasp.mass_properties(vertices + [0.1, 0.2, 0.3], faces, density_kg_m3=500.0)
    assert facts["watertight"] and not facts["from_convex_hull"]
    assert facts["volume_m3"] == pytest.approx(0.04 * 0.06 * 0.10, rel=1e-4)
    assert facts["mass_kg"] == pytest.approx(500.0 * 0.04 * 0.06 * 0.10, rel=1e-4)
    assert np.allclose(facts["center_of_mass"], [0.1, 0.2, 0.3], atol=1e-6)
    m = facts["mass_kg"]
    expected = np.diag([m * (0.06**2 + 0.1**2), m * (0.04**2 + 0.1**2), m * (0.04**2 + 0.06**2)])
    assert np.allclose(facts["inertia_kg_m2"], expected / 12.0, rtol=1e-3, atol=1e-9)


def test_a_box_rests_on_its_largest_face_most_often() -> None:
    vertices, faces = box(0.04, 0.06, 0.10)
    poses = mvgrasp.stable_poses(vertices, faces)
    assert len(poses) == 6
    assert sum(p["probability"] for p in poses) == pytest.approx(1.0, abs=1e-3)
    best = poses[0]
    # On one of the two 6 x 10 cm faces (normal along x): the box is 4 cm tall on the table.
    assert abs(best["face_normal"][0]) == pytest.approx(1.0, abs=1e-5)
    assert best["face_area_m2"] == pytest.approx(0.06 * 0.10, rel=1e-3)
    assert best["offered"] and not best["marginal"]
    moved = (best["table_from_object"] @ np.c_[vertices, np.ones(8)].T).T[:, :3]
    assert moved[:, 2].min() == pytest.approx(0.0, abs=1e-6)
    assert moved[:, 2].max() == pytest.approx(0.04, abs=1e-5)


def test_meshes_from_arrays_are_checked() -> None:
    vertices, faces = box(0.04, 0.06, 0.10)
    v, f = mvgrasp.mesh_from_arrays(vertices, faces)
    assert v.dtype == np.float32 and f.dtype == np.uint32
    assert np.allclose(v, vertices) and np.array_equal(f, faces)
    with pytest.raises(ValueError, match="vertices: shape"):
        mvgrasp.mesh_from_arrays(vertices[:, :2], faces)
    with pytest.raises(ValueError, match=r"triangles\[0\]: index -1"):
        mvgrasp.mesh_from_arrays(vertices, np.r_[[[-1, 0, 1]], faces])
    with pytest.raises(mvgrasp.MeshError):
        mvgrasp.mesh_from_arrays(vertices, faces + 8)
    bad = vertices.copy()
    bad[3, 1] = np.nan
    with pytest.raises(mvgrasp.MeshError):
        mvgrasp.mass_properties(bad, faces)


def test_the_builtin_library() -> None:
    categories = mvgrasp.object_categories()
    assert len(categories) == 10 and "mug" in categories and "toy_car" in categories
    vertices, triangles = mvgrasp.builtin_object("mug", 3)
    assert vertices.shape[1] == 3 and triangles.shape[1] == 3 and len(triangles) > 100
    assert vertices[:, 2].min() == pytest.approx(0.0, abs=1e-4)
    again = mvgrasp.builtin_object("mug", 3)
    assert np.array_equal(again[0], vertices) and np.array_equal(again[1], triangles)
    assert not np.array_equal(mvgrasp.builtin_object("mug", 4)[0][:10], vertices[:10])
    assert mvgrasp.mass_properties(vertices, triangles)["watertight"]
    with pytest.raises(ValueError, match="category"):
        mvgrasp.builtin_object("teapot")


def test_hemisphere_cameras_look_at_the_target() -> None:
    target = np.array([0.1, -0.05, 0.03])
    cameras = mvgrasp.hemisphere_cameras(target=tuple(target), seed=3)
    assert len(cameras) == 10
    preset = mvgrasp.intrinsics_preset("phoxi_s")
    for i, camera in enumerate(cameras):
        k, pose = camera["k"], camera["world_from_camera"]
        assert np.allclose(k, [[preset["fx"], 0, preset["cx"]], [0, preset["fy"], preset["cy"]], [0, 0, 1]])
        assert (camera["width"], camera["height"]) == (preset["width"], preset["height"])
        assert np.linalg.norm(pose[:3, 3] - target) == pytest.approx(0.5, abs=1e-5)
        forward = pose[:3, 2]
        toward = (target - pose[:3, 3]) / 0.5
        assert np.allclose(forward, toward, atol=1e-5), i
        elevation = np.degrees(np.arcsin(-forward[2]))
        assert 15.0 - 1e-3 <= elevation <= 90.0 + 1e-3
    assert np.allclose(cameras[0]["world_from_camera"][:3, 2], [0, 0, -1], atol=1e-6)
    with pytest.raises(mvgrasp.CameraError):
        mvgrasp.hemisphere_cameras(count=0)
    with pytest.raises(mvgrasp.CameraError, match="preset"):
        mvgrasp.intrinsics_preset("kinect")


def test_depth_to_points_unprojects_a_plane() -> None:
    k = np.array([[500.0, 0.0, 31.5], [0.0, 500.0, 23.5], [0.0, 0.0, 1.0]])
    depth = np.full((48, 64), 0.5, dtype=np.float32)
    depth[0, 0] = 0.0
    depth[1, 1] = np.nan
    points = mvgrasp.depth_to_points(depth, k)
    assert points.shape == (48 * 64 - 2, 3) and points.dtype == np.float32
    assert np.allclose(points[:, 2], 0.5)
    # Pixel (u=2, v=0), the second valid one: x = (2 - 31.5) * 0.5 / 500.
    assert points[1, 0] == pytest.approx((2 - 31.5) * 0.5 / 500.0)
    top_down = mvgrasp.hemisphere_cameras(count=1)[0]["world_from_camera"]
    world = mvgrasp.depth_to_points(depth, k, top_down)
    assert np.allclose(world[:, 2], 0.0, atol=1e-6)
    with pytest.raises(TypeError):
        mvgrasp.depth_to_points(depth.astype(np.float64), k)


def test_rendering_sees_the_object_where_it_is() -> None:
    vertices, triangles = mvgrasp.builtin_object("bowl", 0)
    height = float(vertices[:, 2].max())
    cameras = mvgrasp.hemisphere_cameras(count=3, target=(0.0, 0.0, height / 2), seed=1)
    images = mvgrasp.render(
        vertices,
        triangles,
        [c["k"] for c in cameras],
        [c["world_from_camera"] for c in cameras],
        width=cameras[0]["width"],
        height=cameras[0]["height"],
    )
    h, w = cameras[0]["height"], cameras[0]["width"]
    assert images["rgb"].shape == (3, h, w, 3) and images["rgb"].dtype == np.uint8
    assert images["depth"].shape == (3, h, w) and images["depth"].dtype == np.float32
    lo, hi = vertices.min(axis=0) - 2e-3, vertices.max(axis=0) + 2e-3
    for view, camera in enumerate(cameras):
        mask = images["mask"][view]
        assert (mask == 1).sum() > 1000 and (mask == 2).sum() > 1000
        depth = np.where(mask == 1, images["depth"][view], 0.0).astype(np.float32)
        points = mvgrasp.depth_to_points(depth, camera["k"], camera["world_from_camera"])
        assert np.all((points >= lo) & (points <= hi)), view
        table = np.where(mask == 2, images["depth"][view], 0.0).astype(np.float32)
        on_table = mvgrasp.depth_to_points(table, camera["k"], camera["world_from_camera"])
        assert np.allclose(on_table[:, 2], 0.0, atol=1e-3)
    bare = mvgrasp.render(
        vertices, triangles, [cameras[0]["k"]], [cameras[0]["world_from_camera"]],
        width=w, height=h, table=False,
    )  # fmt: skip
    assert not (bare["mask"] == 2).any()
    with pytest.raises(ValueError, match="colors: shape"):
        mvgrasp.render(
            vertices, triangles, [cameras[0]["k"]], [cameras[0]["world_from_camera"]],
            width=w, height=h, colors=np.zeros((3, 3), dtype=np.uint8),
        )  # fmt: skip
    with pytest.raises(ValueError, match="backend"):
        mvgrasp.render(vertices, triangles, [], [], width=w, height=h, backend="directx9")


def read_png(path: Path) -> np.ndarray:
    """A PNG's integer pixel values (matplotlib reads 8- and 16-bit PNGs as floats in 0..1)."""
    from matplotlib.image import imread

    pixels = imread(path)
    scale = 65535.0 if "depth" in path.name else 255.0
    return np.rint(pixels * scale).astype(np.int64)


def test_the_rgbd_dataset_from_python_is_the_cli_dataset_byte_for_byte(tmp_path: Path) -> None:
    subprocess.run(
        ["cargo", "run", "--quiet", "--profile", "dist", "--bin", "render", "--",
         "--out", str(tmp_path / "cli"), "--categories", "can", "--seed", "3", "--quiet"],
        cwd=REPO_ROOT, check=True,
    )  # fmt: skip
    summary = mvgrasp.generate_rgbd_dataset(tmp_path / "python", categories=["can"], seed=3)
    assert summary == {"written": 1, "skipped": 0, "views": 30}
    cli = sorted(p.relative_to(tmp_path / "cli") for p in (tmp_path / "cli").rglob("*"))
    ours = sorted(p.relative_to(tmp_path / "python") for p in (tmp_path / "python").rglob("*"))
    assert cli == ours and len(cli) > 90
    for path in cli:
        if (tmp_path / "cli" / path).is_file():
            assert (tmp_path / "cli" / path).read_bytes() == (
                tmp_path / "python" / path
            ).read_bytes(), path
    # Read back through the Rust readers: the files' pixels, depth in metres, the cameras.
    folder = mvgrasp.read_rgbd_folder(tmp_path / "python" / "can_000" / "test")
    assert folder["rgb"].shape == (10, 386, 516, 3) and folder["rgb"].dtype == np.uint8
    assert np.array_equal(folder["rgb"][3], read_png(tmp_path / "python" / "can_000" / "test" / "003_rgb.png"))
    depth_png = read_png(tmp_path / "python" / "can_000" / "test" / "003_depth.png")
    assert np.allclose(folder["depth"][3], depth_png / 10000.0, atol=1e-6)
    mask_png = read_png(tmp_path / "python" / "can_000" / "test" / "003_mask.png")
    assert np.array_equal(folder["mask"][3], mask_png == 1)
    cameras = json.loads((tmp_path / "python" / "can_000" / "test" / "cameras.json").read_text())
    assert folder["k"][0, 0, 0] == pytest.approx(cameras[0]["intrinsics"]["fx"])
    assert np.allclose(folder["world_from_camera"][5], cameras[5]["world_from_camera"], atol=1e-6)
    with pytest.raises(mvgrasp.DatasetError, match="cameras.json"):
        mvgrasp.read_rgbd_folder(tmp_path / "python" / "can_000")
    again = mvgrasp.generate_rgbd_dataset(tmp_path / "python", categories=["can"], seed=3)
    assert again == {"written": 0, "skipped": 1, "views": 0}
    with pytest.raises(mvgrasp.CameraError, match="kinect"):
        mvgrasp.generate_rgbd_dataset(tmp_path / "other", camera="kinect")


def test_rendering_from_python_equals_the_cli_render(tmp_path: Path) -> None:
    out = tmp_path / "dataset"
    subprocess.run(
        ["cargo", "run", "--quiet", "--profile", "dist", "--bin", "render", "--",
         "--out", str(out), "--categories", "toy_car", "--quiet"],
        cwd=REPO_ROOT, check=True,
    )  # fmt: skip
    folder = out / "toy_car_000"
    record = json.loads((folder / "object.json").read_text())
    vertices, triangles = mvgrasp.builtin_object("toy_car", 0)
    per_face = record["color_mode"] == "per_face"
    colors = mvgrasp.random_colors(
        record["test_color_seed"], len(triangles) if per_face else len(vertices)
    )
    cameras = json.loads((folder / "test" / "cameras.json").read_text())
    ks = [
        np.array([[c["intrinsics"]["fx"], 0, c["intrinsics"]["cx"]],
                  [0, c["intrinsics"]["fy"], c["intrinsics"]["cy"]], [0, 0, 1]])
        for c in cameras
    ]  # fmt: skip
    images = mvgrasp.render(
        vertices,
        triangles,
        ks,
        [np.array(c["world_from_camera"]) for c in cameras],
        width=cameras[0]["intrinsics"]["width"],
        height=cameras[0]["intrinsics"]["height"],
        world_from_object=np.array(record["table_from_object"], dtype=np.float64),
        colors=colors,
        per_face=per_face,
    )
    # The same renderer and scene; the camera poses differ in their last bits (the CLI's come
    # from look_at, these from the 4x4 matrices in cameras.json, rebuilt as rotations), which
    # moves a few edge pixels and the shading by one level at most.
    pixels = images["mask"][0].size
    for view in range(len(cameras)):
        rgb = read_png(folder / "test" / f"{view:03}_rgb.png")[..., :3]
        mask = read_png(folder / "test" / f"{view:03}_mask.png")
        depth = read_png(folder / "test" / f"{view:03}_depth.png")
        assert (images["mask"][view] != mask).sum() <= 1e-4 * pixels, view
        assert (mask == 1).sum() > 1000, view
        same = images["mask"][view] == mask
        shade = np.abs(images["rgb"][view].astype(np.int64) - rgb).max(axis=2)
        assert (shade[same] > 1).sum() <= 1e-4 * pixels, view
        assert (shade > 0).sum() <= 1e-3 * pixels, view
        # The PNG holds depth in 0.1 mm units, rounded.
        assert np.abs(images["depth"][view] * 1e4 - depth)[same].max() <= 1.0, view
