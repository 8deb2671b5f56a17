"""PyRender's side of the render benchmark (see run.sh beside this file).

Renders one mesh from the cameras that `cargo run --example bench_render -- --cameras-out`
wrote (the same views mvgrasp renders), at their resolution, with RGB + depth and, in a second
pass, the segmentation mask (pyrender draws `RenderFlags.SEG` in a separate render), and prints
views per second for RGB + depth alone and for RGB + depth + mask. With `--depth-ref` it also
compares its depth of view 0 with mvgrasp's (both z along the optical axis, metres, 0 for the
background).

The OpenGL platform is PYOPENGL_PLATFORM (default egl); when EGL cannot make a context the
script runs itself again on OSMesa (`libosmesa6`) unless --no-fallback is given.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

import numpy as np
import pyrender
import trimesh

# OpenCV camera frame (x right, y down, z forward) to OpenGL's (x right, y up, z backward).
CV_FROM_GL = np.diag([1.0, -1.0, -1.0, 1.0])


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mesh", type=Path, required=True, help="mesh file (metres)")
    parser.add_argument("--cameras", type=Path, required=True, help="JSON from --cameras-out")
    parser.add_argument("--repeats", type=int, default=5, help="timed calls of all views")
    parser.add_argument("--seed", type=int, default=0, help="seed of the face colours")
    parser.add_argument("--depth-ref", type=Path, help="mvgrasp's depth of view 0 (.npy)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--no-fallback", action="store_true", help="no OSMesa retry")
    return parser.parse_args()


def load_cameras(path: Path) -> list[dict]:
    cameras = json.loads(path.read_text())["cameras"]
    if not cameras:
        raise ValueError(f"{path}: no cameras")
    return cameras


def gl_pose(camera: dict) -> np.ndarray:
    """pyrender's camera pose (world_from_gl) from the OpenCV world_from_camera."""
    return np.asarray(camera["world_from_camera"], dtype=np.float64) @ CV_FROM_GL


def pyrender_camera(intrinsics: dict) -> pyrender.IntrinsicsCamera:
    # pyrender puts the centre of pixel u at image coordinate u + 0.5; mvgrasp (OpenCV) at u.
    # Shifting the principal point by half a pixel makes both draw the same pixels.
    return pyrender.IntrinsicsCamera(
        fx=intrinsics["fx"],
        fy=intrinsics["fy"],
        cx=intrinsics["cx"] + 0.5,
        cy=intrinsics["cy"] + 0.5,
        znear=intrinsics["z_near_m"],
        zfar=intrinsics["z_far_m"],
    )


def build_scene(mesh_path: Path, first: dict, seed: int):
    """The mesh, flat-shaded with random per-face colours (as mvgrasp draws it), a camera and
    a directional light that follows the camera, plus ambient light."""
    mesh = trimesh.load(mesh_path, force="mesh", process=False)
    rng = np.random.default_rng(seed)
    colors = np.concatenate(
        [rng.integers(0, 256, (len(mesh.faces), 3)), np.full((len(mesh.faces), 1), 255)],
        axis=1,
    ).astype(np.uint8)
    mesh.visual = trimesh.visual.ColorVisuals(mesh, face_colors=colors)
    scene = pyrender.Scene(bg_color=[0.0, 0.0, 0.0, 0.0], ambient_light=[0.3, 0.3, 0.3])
    mesh_node = scene.add(pyrender.Mesh.from_trimesh(mesh, smooth=False))
    pose = gl_pose(first)
    camera_node = scene.add(pyrender_camera(first["intrinsics"]), pose=pose)
    light_node = scene.add(pyrender.DirectionalLight(intensity=3.0), pose=pose)
    return scene, mesh_node, camera_node, light_node, len(mesh.faces)


def render_all(renderer, scene, nodes, poses, with_seg: bool) -> list:
    """One call: every view rendered and read back, as a user of pyrender would."""
    mesh_node, camera_node, light_node = nodes
    seg_map = {mesh_node: (255, 255, 255)}
    frames = []
    for pose in poses:
        scene.set_pose(camera_node, pose)
        scene.set_pose(light_node, pose)
        rgb, depth = renderer.render(scene)
        if with_seg:
            seg, _ = renderer.render(scene, flags=pyrender.RenderFlags.SEG, seg_node_map=seg_map)
            frames.append((rgb, depth, seg[..., 0] // 255))
        else:
            frames.append((rgb, depth))
    return frames


def time_calls(repeats: int, call) -> list[float]:
    call()  # warm-up: uploads the mesh, compiles the shaders
    times_ms = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times_ms.append((time.perf_counter() - start) * 1e3)
    return times_ms


def depth_agreement(ours: np.ndarray, reference: np.ndarray) -> dict:
    if ours.shape != reference.shape:
        raise ValueError(f"depth shapes differ: pyrender {ours.shape}, mvgrasp {reference.shape}")
    both = (ours > 0) & (reference > 0)
    either = (ours > 0) | (reference > 0)
    diff = np.abs(ours[both] - reference[both])
    return {
        "pixels_both": int(both.sum()),
        "pixels_either": int(either.sum()),
        "silhouette_iou": float(both.sum() / max(int(either.sum()), 1)),
        "within_1mm_of_both": float((diff < 1e-3).mean()) if diff.size else 0.0,
        "within_1mm_of_either": float((diff < 1e-3).sum() / max(int(either.sum()), 1)),
        "median_abs_diff_m": float(np.median(diff)) if diff.size else float("nan"),
    }


def main() -> int:
    args = parse_args()
    if args.repeats < 1:
        print("error: --repeats must be at least 1", file=sys.stderr)
        return 2
    try:
        cameras = load_cameras(args.cameras)
        if not args.mesh.is_file():
            raise ValueError(f"{args.mesh}: no such mesh file")
    except (OSError, ValueError, KeyError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    width, height = cameras[0]["intrinsics"]["width"], cameras[0]["intrinsics"]["height"]
    platform = os.environ["PYOPENGL_PLATFORM"]
    try:
        renderer = pyrender.OffscreenRenderer(width, height)
    except Exception as error:  # noqa: BLE001 - any failure to get a context means: try OSMesa
        if platform != "egl" or args.no_fallback:
            print(f"error: no {platform} context: {error}", file=sys.stderr)
            return 2
        print(f"pyrender: EGL failed ({error}); retrying on OSMesa", file=sys.stderr)
        env = dict(os.environ, PYOPENGL_PLATFORM="osmesa")
        os.execve(sys.executable, [sys.executable, *sys.argv], env)
    from OpenGL import GL

    gl_renderer = GL.glGetString(GL.GL_RENDERER).decode()
    gl_version = GL.glGetString(GL.GL_VERSION).decode()

    scene, mesh_node, camera_node, light_node, faces = build_scene(args.mesh, cameras[0], args.seed)
    nodes = (mesh_node, camera_node, light_node)
    poses = [gl_pose(c) for c in cameras]
    report = {
        "renderer": "pyrender",
        "pyrender_version": pyrender.__version__,
        "platform": platform,
        "gl_renderer": gl_renderer,
        "gl_version": gl_version,
        "triangles": faces,
        "width": width,
        "height": height,
        "views": len(poses),
        "repeats": args.repeats,
    }
    for name, with_seg in [("rgb+depth", False), ("rgb+depth+seg", True)]:
        times_ms = time_calls(
            args.repeats, lambda s=with_seg: render_all(renderer, scene, nodes, poses, s)
        )
        median_ms = float(np.median(times_ms))
        report[name] = {
            "call_ms": times_ms,
            "median_call_ms": median_ms,
            "ms_per_view": median_ms / len(poses),
            "views_per_s": len(poses) / (median_ms / 1e3),
        }
    if args.depth_ref is not None:
        frames = render_all(renderer, scene, nodes, poses[:1], with_seg=True)
        seen = frames[0][2]
        report["mask_pixels_view0"] = int(seen.sum())
        report["depth_agreement_view0"] = depth_agreement(frames[0][1], np.load(args.depth_ref))
    renderer.delete()

    if args.json:
        print(json.dumps(report))
    else:
        print(f"pyrender {pyrender.__version__} on {platform} [{gl_renderer}, {gl_version}]")
        for name in ["rgb+depth", "rgb+depth+seg"]:
            r = report[name]
            print(f"  {name:<14} {r['views_per_s']:7.1f} views/s  {r['ms_per_view']:6.2f} ms/view")
        if "depth_agreement_view0" in report:
            print(f"  depth agreement, view 0: {report['depth_agreement_view0']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
