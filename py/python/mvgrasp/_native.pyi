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

class GraspError(MvGraspError):
    """A gripper file (or an object) that the grasp analysis cannot use; the message names the
    file."""

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

def intrinsics_preset(name: str = "phoxi_s") -> dict[str, Any]:
    """The intrinsics of a preset (``phoxi_s``, the datasets' camera; ``primesense``;
    ``realsense_d435``), as :func:`load_intrinsics` returns them.

    Raises:
        CameraError: another name.
    """

def hemisphere_cameras(
    count: int = 10,
    radius_m: float = 0.5,
    min_elevation_deg: float = 15.0,
    max_elevation_deg: float = 85.0,
    include_top_down: bool = True,
    target: tuple[float, float, float] = (0.0, 0.0, 0.0),
    intrinsics: str = "phoxi_s",
    seed: int = 0,
) -> list[dict[str, Any]]:
    """Cameras on a spherical cap above the table looking at ``target`` (world, z up from the
    table), placed as the datasets place them: elevations stratified in equal-area bands,
    azimuths spread by the golden angle, both jittered from ``seed``; the first exactly
    top-down when ``include_top_down``. The defaults are the seed paper's 10 test views.

    Each camera is a dict: ``k`` (3x3 float64), ``width``, ``height``, ``world_from_camera``
    (4x4 float64, OpenCV frame: x right, y down, z forward).

    Raises:
        CameraError: a count of 0, a radius that is not positive, elevations outside 0 to 90
            degrees or in the wrong order, an unknown preset.
    """

def depth_to_points(
    depth: npt.NDArray[np.float32],
    k: npt.NDArray[np.float64],
    world_from_camera: npt.NDArray[np.float64] | None = None,
) -> npt.NDArray[np.float32]:
    """The 3-D points of a depth image, one per valid pixel (z > 0 and finite) in row-major
    order, as an ``(N, 3)`` float32 array: camera frame, or world with ``world_from_camera``.

    Raises:
        ValueError: a bad shape or camera matrix, a pose that is not rigid.
        TypeError: a depth image that is not float32.
    """

def object_categories() -> list[str]:
    """The built-in object categories, in the library's order."""

def builtin_object(
    category: str = "mug", index: int = 0, seed: int = 0
) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.uint32]]:
    """The ``index``-th built-in object of ``category`` under the library ``seed``, as
    ``(vertices, triangles)``: a closed mesh in metres resting on z = 0, the same one the CLI's
    ``--object CATEGORY:INDEX`` and the datasets use.

    Raises:
        ValueError: an unknown category.
    """

def mesh_from_arrays(
    vertices: npt.ArrayLike, triangles: npt.ArrayLike
) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.uint32]]:
    """Checks ``(vertices, triangles)`` as a mesh file is checked and returns them as float32
    and uint32 arrays, zero-area triangles dropped. Any real and integer dtypes go in (a
    ``trimesh.Trimesh``'s ``vertices`` and ``faces`` as they are).

    Raises:
        ValueError: a shape that is not ``(N, 3)``, a negative index.
        MeshError: an index out of range, NaN/inf vertices, no usable triangles.
    """

def mass_properties(
    vertices: npt.ArrayLike, triangles: npt.ArrayLike, density_kg_m3: float = 1000.0
) -> dict[str, Any]:
    """Volume, mass, centre of mass and inertia at ``density_kg_m3``: ``volume_m3``,
    ``mass_kg``, ``center_of_mass`` (3,), ``inertia_kg_m2`` (3, 3) about the centre of mass,
    ``watertight``, ``from_convex_hull`` (a mesh that is not watertight has no inside: its
    convex hull's figures are given).

    Raises:
        ValueError: a density that is not finite and positive.
        MeshError: a bad or flat mesh.
    """

def stable_poses(vertices: npt.ArrayLike, triangles: npt.ArrayLike) -> list[dict[str, Any]]:
    """The poses a mesh rests in on a table, most probable first: ``probability``,
    ``table_from_object`` (4x4), ``face_normal`` (3,), ``face_area_m2``, ``tipping_angle_rad``,
    ``marginal`` (it rolls or topples at a touch) and ``offered`` (used by the planner and the
    datasets; the CLI's ``--stable-pose K`` is the K-th offered pose).

    Raises:
        MeshError: a bad or flat mesh.
    """

def random_colors(seed: int, n: int) -> npt.NDArray[np.uint8]:
    """``n`` random RGB colours from ``seed`` as an ``(n, 3)`` uint8 array: the colours the
    datasets give a mesh (per vertex or per triangle, from the seeds in ``object.json``)."""

def render(
    vertices: npt.ArrayLike,
    triangles: npt.ArrayLike,
    ks: Sequence[npt.NDArray[np.float64]],
    world_from_cameras: Sequence[npt.NDArray[np.float64]],
    *,
    width: int,
    height: int,
    world_from_object: npt.NDArray[np.float64] | None = None,
    colors: npt.NDArray[np.uint8] | None = None,
    per_face: bool = False,
    table: bool = True,
    backend: str = "auto",
) -> dict[str, npt.NDArray[Any]]:
    """Renders a mesh for a batch of cameras as the CLI's ``render`` does (the GIL released).

    Returns ``rgb`` ``(V, H, W, 3)`` uint8, ``depth`` ``(V, H, W)`` float32 (z along the
    optical axis, metres; 0 where nothing was drawn) and ``mask`` ``(V, H, W)`` uint8 (0
    background, 1 object, 2 table). ``ks`` and ``world_from_cameras``: per view a 3x3 camera
    matrix and a 4x4 pose (OpenCV frame). ``world_from_object``: where the mesh is (default:
    where it is). ``colors``: ``(N, 3)`` per vertex, or ``(M, 3)`` per triangle with
    ``per_face``; default one grey. ``table``: the datasets' 0.8 m grey square at z = 0.
    ``backend``: ``auto``, ``vulkan`` or ``gl``.

    Raises:
        ValueError: a bad array (named), lists of different lengths, an unknown backend.
        RenderError: no graphics adapter could be opened.
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
    as_json: bool = False,
) -> Any:
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
    ``angle_rad``, ``depth_m``, ``p``, ``phi_rad``, ``theta_rad``), ``rejections``, ``table``;
    with ``as_json``, the file's text, byte for byte what ``plan --out`` writes.

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
    as_json: bool = False,
) -> Any:
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

def score_crops(
    model: str,
    depth: npt.NDArray[np.float32],
    pose: npt.NDArray[np.float32],
    *,
    logits: bool = False,
) -> npt.NDArray[np.float32]:
    """Scores a batch of grasp crops with a GQ-CNN as the planner scores its candidates (the
    GIL released).

    ``model``: a shipped network's name (``gqcnn_small_topdown``, ``gqcnn_small_multiview``) or
    an export's ``NAME.json``. ``depth``: float32 crops ``(N, S, S)`` or ``(N, 1, S, S)`` with
    the network's crop side (metres, cut to its input contract). ``pose``: float32 ``(N, P)``
    with its pose inputs (grasp depth, and theta for a multi-view GQ-CNN), or ``(N,)`` when
    ``P`` is 1. Returns each grasp's probability of being robust, ``(N,)``, or with
    ``logits`` the two logits (not robust, robust), ``(N, 2)``.

    Raises:
        ValueError: a shape the network does not take (named).
        TypeError: arrays that are not float32.
        WeightsError: the network cannot be loaded.
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

def read_grasp_shard(path: str | os.PathLike[str]) -> dict[str, npt.NDArray[Any]]:
    """Every column of a shard as a NumPy array (its dtype and shape, datapoints first), after
    checking it against the format; ``DatasetError`` naming the file and the fault."""

def read_grasp_manifest(dir: str | os.PathLike[str]) -> dict[str, Any]:
    """The content of ``dir/dataset.json``, checked to be a grasp-dataset manifest."""

def plan_mesh(
    vertices: npt.ArrayLike,
    triangles: npt.ArrayLike,
    *,
    model: str | None = None,
    fuse: bool = False,
    cem: bool = False,
    hand_check: bool = True,
    seed: int = 0,
    camera: str = "phoxi_s",
    views: int | None = None,
    distance_m: float | None = None,
    stable_pose: int = 0,
    physics: bool = True,
    backend: str = "auto",
    depth_from: str = "rendered",
) -> dict[str, Any]:
    """Plans a grasp on a mesh as ``plan --mesh --depth-from DEPTH_FROM`` does (rest, render,
    predict depth from the colour views with ``"baseline"``, ``"mvs"`` or ``"lsm"``, plan, check); returns
    ``{"report", "grasps_json", "timings", "hold_probability"}``: ``plan --json``'s plan
    report, the text of ``grasps.json``, each stage's seconds and the best grasp's chance to
    hold (``None`` for planners without one). ``ValueError`` for a bad option value,
    ``CameraError`` for an unknown camera preset, ``RenderError``, ``WeightsError``."""

def project_points(
    points: npt.NDArray[np.float64],
    k: npt.NDArray[np.float64],
    width: int,
    height: int,
    world_from_camera: npt.NDArray[np.float64] | None = None,
) -> npt.NDArray[np.float64]:
    """The ``(N, 2)`` pixels of world points ``(N, 3)``; NaN behind the camera."""

def unproject_pixels(
    pixels: npt.NDArray[np.float64],
    depths: npt.NDArray[np.float64],
    k: npt.NDArray[np.float64],
    width: int,
    height: int,
    world_from_camera: npt.NDArray[np.float64] | None = None,
) -> npt.NDArray[np.float64]:
    """The ``(N, 3)`` world points at pixels ``(N, 2)`` and depths ``(N,)``."""

def gripper(spec: Any = None) -> dict[str, Any]:
    """The gripper a preset name, a gripper file or a dict of fields names (``None``: the
    datasets' Panda), as a dict of its fields. ``ValueError`` for an unknown name,
    ``GraspError`` for a file it cannot use."""

def sample_grasps(
    vertices: npt.ArrayLike,
    triangles: npt.ArrayLike,
    *,
    gripper: Any = None,
    count: int = 100,
    table_from_object: npt.NDArray[np.float64] | None = None,
    params: dict[str, Any] | None = None,
    seed: int = 0,
) -> dict[str, Any]:
    """Collision-free antipodal grasps on the mesh (object frame); the sampling report."""

def grasp_quality(
    vertices: npt.ArrayLike,
    triangles: npt.ArrayLike,
    object_from_gripper: npt.NDArray[np.float64],
    *,
    gripper: Any = None,
    friction_coef: float = 0.5,
    params: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Contacts, force closure and Ferrari-Canny epsilon of one grasp."""

def robust_quality(
    vertices: npt.ArrayLike,
    triangles: npt.ArrayLike,
    object_from_grippers: npt.NDArray[np.float64],
    *,
    gripper: Any = None,
    params: dict[str, Any] | None = None,
    seed: int = 0,
) -> list[dict[str, Any]]:
    """Robust Ferrari-Canny quality of one grasp or a batch ``(N, 4, 4)``."""

def check_collision(
    vertices: npt.ArrayLike,
    triangles: npt.ArrayLike,
    object_from_gripper: npt.NDArray[np.float64],
    width_m: float,
    *,
    gripper: Any = None,
    table_from_object: npt.NDArray[np.float64] | None = None,
    params: dict[str, Any] | None = None,
) -> dict[str, bool]:
    """Whether the open hand on its approach meets the object or the table."""

def physics_trial(
    vertices: npt.ArrayLike,
    triangles: npt.ArrayLike,
    table_from_object: npt.NDArray[np.float64],
    world_from_gripper: npt.NDArray[np.float64],
    width_m: float,
    *,
    gripper: Any = None,
    params: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """The rapier close-lift-shake trial of one grasp; its outcome."""

def generate_rgbd_dataset(
    out: str | os.PathLike[str],
    *,
    meshes: list[str] | None = None,
    per_category: int = 1,
    categories: list[str] | None = None,
    library_seed: int = 0,
    seed: int = 0,
    camera: str = "phoxi_s",
    table: bool = True,
    backend: str = "auto",
) -> dict[str, int]:
    """Renders the multi-view RGB-D dataset into ``out`` as ``render`` does (the same bytes):
    per object its training and novel test views, finished objects skipped; returns
    ``{"written", "skipped", "views"}``."""

def plan_rgb(
    images: Sequence[npt.NDArray[np.uint8]],
    ks: Sequence[npt.NDArray[np.float64]],
    world_from_cameras: Sequence[npt.NDArray[np.float64]],
    *,
    masks: Sequence[npt.NDArray[np.bool_] | None] | None = None,
    model: str | None = None,
    depth_from: str = "baseline",
    cem: bool = False,
    hand_check: bool = True,
    seed: int = 0,
    as_json: bool = False,
) -> Any:
    """Plans a grasp on RGB views as ``plan --rgb`` does: depth predicted by the plane-sweep
    baseline (``depth_from="baseline"``, the default), the shipped multi-view stereo network
    (``"mvs"``) or the shipped Learnt Stereo Machine (``"lsm"``), then
    the multi-view planner. ``images``: ``(H, W, 3)`` uint8 per view, with their
    3x3 camera matrices and 4x4 poses in the table frame; ``masks``: the object's pixels or
    ``None`` per view. Returns ``grasps.json``'s content (with ``as_json``, its text)."""

def read_rgbd_folder(dir: str | os.PathLike[str]) -> dict[str, Any]:
    """One RGB-D dataset folder (``OBJECT/train`` or ``OBJECT/test``) read back by the Rust
    readers: ``rgb`` (V, H, W, 3) uint8, ``depth`` (V, H, W) float32 metres, ``mask``
    (V, H, W) bool or ``None``, ``k`` (V, 3, 3), ``world_from_camera`` (V, 4, 4)."""

def predict_depth(
    images: Sequence[npt.NDArray[np.uint8]],
    ks: Sequence[npt.NDArray[np.float64]],
    world_from_cameras: Sequence[npt.NDArray[np.float64]],
    *,
    masks: Sequence[npt.NDArray[np.bool_] | None] | None = None,
    depth_from: str = "baseline",
) -> npt.NDArray[np.float32]:
    """Each RGB view's depth predicted from all of them as ``plan --rgb`` predicts it
    (``"baseline"``, ``"mvs"`` or ``"lsm"``): (V, H, W) float32 metres, 0 where unknown. The
    inputs are ``plan_rgb``'s; the LSM also takes one view (the others need two)."""
