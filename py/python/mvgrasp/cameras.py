"""Cameras as a dataclass: the 3x3 camera matrix, the image size and the 4x4 pose.

Frames follow OpenCV (x right, y down, z forward); ``world_from_camera`` maps camera
coordinates to the world's (z up from the table in mvgrasp's layouts). Projection and
back-projection are the Rust core's.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any, Optional, Union

import numpy as np
import numpy.typing as npt

from mvgrasp import _native
from mvgrasp._arrays import f32, f64, optional_f64


def _atleast(a: npt.ArrayLike, ndim: int) -> Any:
    """``a`` with leading axes of 1 up to ``ndim`` (one point as a batch of one); what NumPy
    cannot make an array of as it is, for the conversion to name."""
    try:
        return np.atleast_2d(a) if ndim == 2 else np.atleast_1d(a)
    except (TypeError, ValueError):
        return a


@dataclass(frozen=True)
class Camera:
    """A pinhole camera, with its pose when it is known (``world_from_camera`` ``None``: its
    world is its own frame, and a planner fits the table to find one)."""

    k: np.ndarray
    width: int
    height: int
    world_from_camera: Optional[np.ndarray] = None

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Camera:
        """A camera from the binding's dicts (``hemisphere_cameras``) or a ``grasps.json``
        view (``k`` or ``intrinsics``, ``width``, ``height``, ``world_from_camera``)."""
        k = d.get("k")
        if k is None:
            i = d["intrinsics"]
            k = [[i["fx"], 0.0, i["cx"]], [0.0, i["fy"], i["cy"]], [0.0, 0.0, 1.0]]
            width, height = i["width"], i["height"]
        else:
            width, height = d["width"], d["height"]
        return cls(
            f64(k, "k"),
            int(width),
            int(height),
            optional_f64(d.get("world_from_camera"), "world_from_camera"),
        )

    @classmethod
    def preset(
        cls, name: str = "phoxi_s", world_from_camera: Optional[npt.ArrayLike] = None
    ) -> Camera:
        """A camera with a preset's intrinsics (``phoxi_s``, ``primesense``,
        ``realsense_d435``)."""
        return cls._of(_native.intrinsics_preset(name), world_from_camera)

    @classmethod
    def from_intr_file(
        cls,
        path: Union[str, os.PathLike[str]],
        world_from_camera: Optional[npt.ArrayLike] = None,
    ) -> Camera:
        """A camera with a Berkeley ``.intr`` file's intrinsics."""
        return cls._of(_native.load_intrinsics(os.fspath(path)), world_from_camera)

    @classmethod
    def _of(cls, i: dict[str, Any], world_from_camera: Optional[npt.ArrayLike]) -> Camera:
        return cls.from_dict({"intrinsics": i, "world_from_camera": world_from_camera})

    def _args(self) -> tuple[np.ndarray, int, int, Optional[np.ndarray]]:
        return (
            f64(self.k, "camera.k"),
            self.width,
            self.height,
            optional_f64(self.world_from_camera, "camera.world_from_camera"),
        )

    def project(self, points: npt.ArrayLike) -> np.ndarray:
        """The ``(N, 2)`` pixels (u, v) of world points ``(N, 3)``; NaN behind the camera."""
        k, w, h, pose = self._args()
        return _native.project_points(f64(_atleast(points, 2), "points"), k, w, h, pose)

    def unproject(self, pixels: npt.ArrayLike, depths: npt.ArrayLike) -> np.ndarray:
        """The ``(N, 3)`` world points at pixels ``(N, 2)`` and depths ``(N,)`` (metres along
        the optical axis)."""
        k, w, h, pose = self._args()
        return _native.unproject_pixels(
            f64(_atleast(pixels, 2), "pixels"), f64(_atleast(depths, 1), "depths"), k, w, h, pose
        )

    def depth_to_points(self, depth: npt.ArrayLike) -> np.ndarray:
        """The world points of a depth image of this camera, one per valid pixel."""
        k, _, _, pose = self._args()
        return _native.depth_to_points(f32(depth, "depth"), k, pose)


def hemisphere(
    count: int = 10,
    radius_m: float = 0.5,
    *,
    target: tuple[float, float, float] = (0.0, 0.0, 0.0),
    intrinsics: str = "phoxi_s",
    include_top_down: bool = True,
    seed: int = 0,
) -> list[Camera]:
    """Cameras on the hemisphere looking at ``target``, as ``hemisphere_cameras`` places them
    (the defaults: the seed paper's 10 test views, the first top-down)."""
    return [
        Camera.from_dict(c)
        for c in _native.hemisphere_cameras(
            count=count,
            radius_m=radius_m,
            include_top_down=include_top_down,
            target=target,
            intrinsics=intrinsics,
            seed=seed,
        )
    ]
