"""Type stubs of the native module ``mvgrasp._native`` (built from py/src by maturin)."""

import os
from typing import Any, Sequence

import numpy as np
import numpy.typing as npt

__version__: str

class MvGraspError(Exception):
    """The base class of every error that mvgrasp raises."""

class MeshError(MvGraspError):
    """A mesh file cannot be loaded or is not a usable mesh; the message names the file."""

class CameraError(MvGraspError):
    """Camera intrinsics or extrinsics are missing or invalid."""

class WeightsError(MvGraspError):
    """A network's weights are missing, unreadable or do not match its architecture."""

class RenderError(MvGraspError):
    """No graphics adapter could be opened, or rendering failed."""

class PlanningError(MvGraspError):
    """Depth images, views or a network that the planner cannot use."""

class DatasetError(MvGraspError):
    """A dataset's config, folder, shards or manifest cannot be used; the message names the
    file."""

def load_mesh(
    path: str | os.PathLike[str], scale: float = 1.0
) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.uint32]]:
    """Loads an OBJ, STL or URDF file as ``(vertices, triangles)``.

    ``vertices`` is an ``(N, 3)`` float32 array in metres (file coordinates times ``scale``),
    ``triangles`` an ``(M, 3)`` uint32 array of vertex indices. The GIL is released while
    loading.

    Raises:
        MeshError: the file is missing, unparsable, has NaN/inf vertices, no usable triangles
            or an implausible size (largest extent outside 5 mm .. 2 m after scaling).
        ValueError: ``scale`` is not a finite number > 0.
    """

def load_intrinsics(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Reads a Berkeley ``.intr`` file (JSON with ``_fx _fy _cx _cy _width _height``).

    Returns the intrinsics as a dict: ``fx``, ``fy``, ``cx``, ``cy`` (pixels), ``width``,
    ``height``, ``z_near_m``, ``z_far_m``.

    Raises:
        CameraError: the file is missing, unparsable or holds invalid intrinsics; the message
            names the file.
    """

def plan_depth(
    depth: npt.NDArray[np.float32],
    k: npt.NDArray[np.float64],
    *,
    mask: npt.NDArray[np.bool_] | None = None,
    world_from_camera: npt.NDArray[np.float64] | None = None,
    model: str | None = None,
    fuse: bool = False,
    cem: bool = False,
    hand_check: bool = True,
    seed: int = 0,
) -> dict[str, Any]:
    """Plans a grasp on one depth image, as ``plan --depth`` does (the GIL released).

    ``depth``: float32 metres, shape ``(H, W)`` or ``(H, W, 1)``; NaN, infinities and 0 are
    missing. ``k``: the 3x3 camera matrix (no skew). ``mask``: bool ``(H, W)``, the object's
    pixels (without it, the object is what stands on the table fitted in the image).
    ``world_from_camera``: the camera's 4x4 pose (without it the world is put on the fitted
    table). ``model``: a shipped network's name or an export's ``NAME.json`` (default: the
    top-down GQ-CNN; with ``fuse``, the multi-view GQ-CNN). ``fuse``: the multi-view planner's
    checks against the fused views and its re-scoring on virtual views (``plan --fuse``).

    Returns the content of ``grasps.json`` (format ``mvgrasp-grasps/1``): ``frame``,
    ``views``, ``grasps`` (best first, each with ``camera_from_gripper`` and
    ``world_from_gripper`` as 4x4 nested lists, ``width_m``, ``quality``, ``u``, ``v``,
    ``angle_rad``, ``depth_m``, ``p``, ``phi_rad``, ``theta_rad``), ``rejections``, ``table``.

    Raises:
        ValueError: an array of the wrong shape, a camera matrix with skew, a pose that is not
            rigid.
        TypeError: an array of another dtype.
        PlanningError: no table in the image, or nothing on it.
        WeightsError: the network cannot be loaded.
    """

def plan_views(
    depths: Sequence[npt.NDArray[np.float32]],
    ks: Sequence[npt.NDArray[np.float64]],
    world_from_cameras: Sequence[npt.NDArray[np.float64]],
    *,
    masks: Sequence[npt.NDArray[np.bool_] | None] | None = None,
    model: str | None = None,
    fuse: bool = False,
    cem: bool = False,
    hand_check: bool = True,
    seed: int = 0,
) -> dict[str, Any]:
    """Plans a grasp over several depth images of one scene, as ``plan --views-dir`` does.

    One float32 ``(H, W)`` depth image (metres), 3x3 camera matrix and 4x4 ``world_from_camera``
    per view, in one world frame (with ``fuse``, its z up from the table); ``masks``: per view
    the object's pixels or ``None``. The options are ``plan_depth``'s. Returns the content of
    ``grasps.json`` (frame ``given``).

    Raises:
        ValueError: lists of different lengths, or a bad array (named, e.g. ``depths[2]``).
        TypeError: an array of another dtype.
        PlanningError: no table in a view, or nothing on it; with ``fuse``, a world whose z
            is not up from the table.
        WeightsError: the network cannot be loaded.
    """

def load_network(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Loads a GQ-CNN export (``NAME.json`` and the ``NAME.safetensors`` it names) as the
    planner does, checking every tensor's name and shape and the input contract.

    Returns its description: ``format``, ``architecture``, ``normalisation``, ``input`` (the
    input contract, or None for exports made before it was recorded) and ``training``.

    Raises:
        WeightsError: a file is missing or a tensor or the contract does not match the
            architecture; the message names the file.
    """

def grasp_dataset_num_shards(
    config: str | None = None,
    meshes: list[str] | None = None,
    per_category: int = 1,
    categories: list[str] | None = None,
    library_seed: int = 0,
) -> int:
    """How many shards the grasp dataset has."""

def generate_grasp_shard(
    out: str,
    shard: int,
    config: str | None = None,
    meshes: list[str] | None = None,
    per_category: int = 1,
    categories: list[str] | None = None,
    library_seed: int = 0,
    backend: str = "auto",
) -> dict[str, Any]:
    """Makes one shard (skipped when finished); its record."""

def write_grasp_manifest(
    out: str,
    config: str | None = None,
    meshes: list[str] | None = None,
    per_category: int = 1,
    categories: list[str] | None = None,
    library_seed: int = 0,
) -> dict[str, Any]:
    """Writes ``out/dataset.json`` from the finished shards; the manifest."""

def generate_grasp_dataset(
    out: str,
    config: str | None = None,
    meshes: list[str] | None = None,
    per_category: int = 1,
    categories: list[str] | None = None,
    library_seed: int = 0,
    backend: str = "auto",
) -> dict[str, Any]:
    """Makes every unfinished shard and the manifest with the Rust generator's loop; the
    manifest."""
