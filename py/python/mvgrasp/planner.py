"""Planning grasps: a :class:`Planner` with the options of the ``plan`` command, on depth
images (one or several, with or without camera poses) and on meshes, returning a
:class:`PlanResult` of dataclasses and the same ``grasps.json`` as the command.

The keyword arguments carry the command's option names and defaults: ``model`` (a shipped
network or an export's ``NAME.json``; default the multi-view GQ-CNN for the multi-view
planner, else the top-down GQ-CNN), ``fuse`` (the multi-view planner: ``None``, the default,
is the command's choice: fused over several views and on a mesh, the top-down GQ-CNN alone on
one depth image; ``False`` is ``--no-fuse``, ``True`` ``--fuse``), ``cem``, ``hand_check`` (``--no-hand-check``
is ``hand_check=False``), ``seed``; on meshes also ``camera``, ``views``, ``distance_m``,
``stable_pose``, ``physics`` (``--no-physics``) and ``backend``. The GIL is released while a
plan runs.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional, Union

import numpy as np
import numpy.typing as npt

from mvgrasp import _native
from mvgrasp._arrays import as_dtype, f32, f64, optional_f64
from mvgrasp._arrays import masks as _masks
from mvgrasp.cameras import Camera
from mvgrasp.grasps import Grasp


@dataclass(frozen=True)
class PlannedGrasp:
    """One ranked grasp of a plan, as ``grasps.json`` holds it (poses as 4x4 arrays)."""

    rank: int
    view: int
    quality: float
    width_m: float
    world_from_gripper: np.ndarray
    camera_from_gripper: np.ndarray
    u: float
    v: float
    angle_rad: float
    depth_m: float
    p: np.ndarray
    phi_rad: float
    theta_rad: float
    view_quality: Optional[float] = None
    virtual_quality: Optional[float] = None

    @property
    def grasp(self) -> Grasp:
        """The grasp in the world, for the analysis functions of :mod:`mvgrasp.grasps`."""
        return Grasp(self.world_from_gripper, self.width_m, self.quality)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> PlannedGrasp:
        arrays = {"world_from_gripper", "camera_from_gripper", "p"}
        return cls(
            **{k: np.asarray(v, dtype=np.float64) if k in arrays else v for k, v in d.items()}
        )


@dataclass(frozen=True)
class ViewSummary:
    """One view's share of a plan: its camera, how many of the ranked grasps came from it and
    the best of their qualities; on a rendered mesh also the candidates it scored and the
    camera's elevation."""

    camera: Camera
    ranked: int
    best_quality: Optional[float]
    candidates: Optional[int] = None
    elevation_deg: Optional[float] = None


@dataclass(frozen=True)
class PlanResult:
    """What a plan found. ``grasps`` are best first; ``grasps_json`` is the text of the
    ``grasps.json`` the ``plan`` command writes for the same inputs, byte for byte."""

    grasps: list[PlannedGrasp]
    views: list[ViewSummary]
    frame: str
    rejections: dict[str, int]
    timings: dict[str, float]
    grasps_json: str = field(repr=False)
    table: Optional[dict[str, Any]] = None
    report: Optional[dict[str, Any]] = field(default=None, repr=False)
    #: On a mesh, as ``plan`` prints it: the best grasp's chance to hold, the multi-view
    #: planner's ranked quality (``models/ranker_fused.json``) or the top-down GQ-CNN's
    #: quality, mapped to the trial's outcomes with the default views on rendered depth or the
    #: plane sweep's (``models/probability_fused.json``, ``models/probability_topdown.json``);
    #: else ``None``.
    hold_probability: Optional[float] = None

    @property
    def best(self) -> Optional[PlannedGrasp]:
        """The best grasp, or ``None`` when no candidate survived."""
        return self.grasps[0] if self.grasps else None

    @property
    def physics(self) -> Optional[dict[str, Any]]:
        """On a rendered mesh with ``physics``: the rapier trial of the best grasp."""
        return None if self.report is None else self.report.get("physics")

    @property
    def analytic(self) -> Optional[dict[str, Any]]:
        """On a rendered mesh: the best grasp's robust epsilon, collision and label."""
        return None if self.report is None else self.report.get("analytic")

    def write(self, out: Union[str, os.PathLike[str]]) -> Path:
        """Writes ``out/grasps.json`` (creating ``out``); its path."""
        path = Path(out) / "grasps.json"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(self.grasps_json)
        return path

    @classmethod
    def _of(
        cls,
        text: str,
        timings: dict[str, float],
        report: Optional[dict[str, Any]] = None,
        hold_probability: Optional[float] = None,
    ) -> PlanResult:
        content = json.loads(text)
        grasps = [PlannedGrasp.from_dict(g) for g in content["grasps"]]
        views = []
        for i, v in enumerate(content["views"]):
            fx, fy, cx, cy, width, height = v["intrinsics"]
            camera = Camera(
                np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]]),
                int(width),
                int(height),
                np.asarray(v["world_from_camera"], dtype=np.float64),
            )
            mine = [g.quality for g in grasps if g.view == i]
            summary = report["views"][i] if report is not None else {}
            views.append(
                ViewSummary(
                    camera=camera,
                    ranked=len(mine),
                    best_quality=max(mine) if mine else None,
                    candidates=summary.get("candidates"),
                    elevation_deg=summary.get("elevation_deg"),
                )
            )
        return cls(
            grasps=grasps,
            views=views,
            frame=content["frame"],
            rejections=content["rejections"],
            timings=timings,
            grasps_json=text,
            table=content.get("table"),
            report=report,
            hold_probability=hold_probability,
        )


def _check_size(name: str, image: npt.ArrayLike, camera: Camera, camera_name: str) -> None:
    """``ValueError`` naming both when ``image``'s (H, W) is not ``camera``'s size (a depth
    image at half resolution must come with its halved intrinsics, as ``plan --depth`` asks)."""
    try:
        shape = np.shape(image)
    except (TypeError, ValueError):
        return  # not an array: the conversion names it
    if len(shape) >= 2 and (shape[0], shape[1]) != (camera.height, camera.width):
        raise ValueError(
            f"{name}: {shape[1]} x {shape[0]} pixels, but {camera_name} is "
            f"{camera.width} x {camera.height} (width x height): give the camera the image "
            "was taken with"
        )


def _posed(cameras: Sequence[Camera]) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """The cameras' matrices and poses; ``ValueError`` for a camera without a pose."""
    for i, c in enumerate(cameras):
        if c.world_from_camera is None:
            raise ValueError(f"cameras[{i}]: no world_from_camera (views need their poses)")
    ks = [f64(c.k, f"cameras[{i}].k") for i, c in enumerate(cameras)]
    poses = [f64(c.world_from_camera, f"cameras[{i}].world_from_camera")
             for i, c in enumerate(cameras)]  # fmt: skip
    return ks, poses


class Planner:
    """A grasp planner with ``plan``'s options (see the module docs)."""

    def __init__(
        self,
        *,
        model: Optional[str] = None,
        fuse: Optional[bool] = None,
        cem: bool = False,
        hand_check: bool = True,
        seed: int = 0,
    ) -> None:
        self.model = model
        self.fuse = fuse
        self.cem = cem
        self.hand_check = hand_check
        self.seed = seed

    def _options(self, several_views: bool) -> dict[str, Any]:
        """The native planner's keywords; ``several_views``: the input has several views (or
        is a mesh), where the multi-view planner is the default."""
        return {
            "model": self.model,
            "fuse": several_views if self.fuse is None else self.fuse,
            "cem": self.cem,
            "hand_check": self.hand_check,
            "seed": self.seed,
        }

    def plan(
        self,
        depth: npt.ArrayLike,
        camera: Union[Camera, npt.ArrayLike],
        *,
        mask: Optional[npt.ArrayLike] = None,
        world_from_camera: Optional[npt.ArrayLike] = None,
    ) -> PlanResult:
        """Plans on one depth image (float32 metres, ``(H, W)``; 0, NaN and infinities are
        missing), as ``plan --depth`` does. ``camera``: a :class:`Camera` (its pose is used
        unless ``world_from_camera`` is given; a camera without one has none) or a 3x3 camera
        matrix. Without a pose the world is put on the table fitted in the image (frame
        ``estimated``)."""
        if isinstance(camera, Camera):
            _check_size("depth", depth, camera, "camera")
            k = camera.k
            if world_from_camera is None:
                world_from_camera = camera.world_from_camera
        else:
            k = camera
        started = time.perf_counter()
        text = _native.plan_depth(
            f32(depth, "depth"),
            f64(k, "camera.k" if isinstance(camera, Camera) else "camera"),
            mask=None if mask is None else as_dtype(mask, bool, "mask"),
            world_from_camera=optional_f64(world_from_camera, "world_from_camera"),
            as_json=True,
            **self._options(several_views=False),
        )
        return PlanResult._of(text, {"total_s": time.perf_counter() - started})

    def plan_views(
        self,
        depths: Sequence[npt.ArrayLike],
        cameras: Sequence[Camera],
        *,
        masks: Optional[Sequence[Optional[npt.ArrayLike]]] = None,
    ) -> PlanResult:
        """Plans over several depth images of one scene with their posed cameras (one world
        frame; with ``fuse`` its z up from the table), as ``plan --views-dir`` does."""
        for i, (d, c) in enumerate(zip(depths, cameras)):
            _check_size(f"depths[{i}]", d, c, f"cameras[{i}]")
        started = time.perf_counter()
        text = _native.plan_views(
            [f32(d, f"depths[{i}]") for i, d in enumerate(depths)],
            *_posed(cameras),
            masks=_masks(masks),
            as_json=True,
            **self._options(several_views=True),
        )
        return PlanResult._of(text, {"total_s": time.perf_counter() - started})

    def plan_rgb(
        self,
        images: Sequence[npt.ArrayLike],
        cameras: Sequence[Camera],
        *,
        masks: Optional[Sequence[Optional[npt.ArrayLike]]] = None,
        depth_from: str = "baseline",
    ) -> PlanResult:
        """Plans on RGB views (``(H, W, 3)`` uint8, at least two) with their posed cameras (the
        table frame: z up, the table at z = 0), as ``plan --rgb`` does: the views' depth
        predicted by the classical baseline (``depth_from="baseline"``, the default: silhouette
        carving and a plane sweep), the shipped multi-view stereo network (``"mvs"``) or the
        shipped Learnt Stereo Machine (``"lsm"``), then the multi-view planner
        (``fuse`` is implied). ``masks``: per view the object's pixels, or ``None``."""
        for i, (image, c) in enumerate(zip(images, cameras)):
            _check_size(f"images[{i}]", image, c, f"cameras[{i}]")
        started = time.perf_counter()
        options = self._options(several_views=True)
        options.pop("fuse")
        text = _native.plan_rgb(
            [as_dtype(image, np.uint8, f"images[{i}]") for i, image in enumerate(images)],
            *_posed(cameras),
            masks=_masks(masks),
            depth_from=depth_from,
            as_json=True,
            **options,
        )
        return PlanResult._of(text, {"total_s": time.perf_counter() - started})

    def plan_mesh(
        self,
        vertices: npt.ArrayLike,
        triangles: npt.ArrayLike,
        *,
        camera: str = "phoxi_s",
        views: Optional[int] = None,
        distance_m: Optional[float] = None,
        stable_pose: int = 0,
        physics: bool = True,
        backend: str = "auto",
        depth_from: str = "rendered",
    ) -> PlanResult:
        """Plans on a mesh as ``plan --mesh --depth-from DEPTH_FROM`` does: rests it on the
        table in a stable pose, renders the views' depth (``"rendered"``, the default here) or
        renders them in colour and predicts their depth (``"baseline"``, the CLI's default,
        ``"refined"``, ``"mvs"`` or ``"lsm"``: 5 views unless ``views`` says otherwise), plans
        (the multi-view planner over the views; with ``fuse=False`` the top-down GQ-CNN in
        the first, top-down one), and
        checks the best grasp analytically and (with ``physics``) in the rapier trial
        (:attr:`PlanResult.physics`). Timings per stage."""
        started = time.perf_counter()
        result = _native.plan_mesh(
            vertices,
            triangles,
            camera=camera,
            views=views,
            distance_m=distance_m,
            stable_pose=stable_pose,
            physics=physics,
            backend=backend,
            depth_from=depth_from,
            **self._options(several_views=True),
        )
        timings = dict(result["timings"], total_s=time.perf_counter() - started)
        return PlanResult._of(
            result["grasps_json"], timings, result["report"], result["hold_probability"]
        )
