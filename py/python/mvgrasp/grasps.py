"""Grasps as dataclasses, and grasp analysis on meshes given as ``(vertices, triangles)``.

A :class:`Grasp` is mvgrasp's 6-DoF parallel-jaw grasp: ``world_from_gripper`` is the 4x4 pose
of the gripper frame (origin midway between the finger tips, +z the approach, +x the closing
axis) in the frame the grasp lives in (the object's for sampled grasps, the world's for
planned ones), and ``width_m`` the opening at the contacts.

The analysis is the Rust core's (``mvgrasp._native``): antipodal sampling, force closure and
Ferrari-Canny epsilon, Dex-Net's robust quality, collision checks of the open hand, and the
rapier close-lift-shake trial. Its settings default to the grasp datasets' (the labels the
shipped networks learnt, the Panda hand); ``params`` dicts override any field (unknown keys are
a ``ValueError``), and ``gripper`` is a preset name (``panda``, ``yumi``, ``robotiq_2f_85``), a
gripper file (``.toml``, ``.json``, Dex-Net's ``params.json``, ``.urdf``) or a dict of fields.
Every call releases the GIL.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any, Optional, Union

import numpy as np
import numpy.typing as npt

from mvgrasp import _native
from mvgrasp._arrays import f64, optional_f64

ArrayLike = npt.ArrayLike
GripperSpec = Union[str, "os.PathLike[str]", dict[str, Any], None]


@dataclass(frozen=True)
class Contact:
    """Where a jaw touches the object: the point and the surface normal out of the object."""

    point: np.ndarray
    outward_normal: np.ndarray


@dataclass(frozen=True)
class Grasp:
    """A 6-DoF parallel-jaw grasp (see the module docs for the frame)."""

    world_from_gripper: np.ndarray
    width_m: float
    quality: Optional[float] = None
    contacts: Optional[tuple[Contact, Contact]] = None
    extra: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)

    @property
    def center(self) -> np.ndarray:
        """The grasp centre, midway between the finger tips."""
        return self.world_from_gripper[:3, 3]

    @property
    def approach(self) -> np.ndarray:
        """The unit direction the hand comes in along (gripper +z)."""
        return self.world_from_gripper[:3, 2]

    @property
    def closing_axis(self) -> np.ndarray:
        """The unit direction from the first jaw to the second (gripper +x)."""
        return self.world_from_gripper[:3, 0]

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Grasp:
        """A grasp from the native functions' and ``grasps.json``'s dicts (the pose under
        ``world_from_gripper`` or, for sampled grasps, ``grasp.world_from_gripper``); the
        entries it does not model stay in :attr:`extra`."""
        inner = d.get("grasp", d)
        contacts = d.get("contacts")
        pair = None
        if contacts is not None:
            pair = tuple(
                Contact(np.asarray(c["point"], float), np.asarray(c["outward_normal"], float))
                for c in contacts["contacts"]
            )
        known = {"grasp", "contacts", "world_from_gripper", "width_m", "quality"}
        return cls(
            world_from_gripper=np.asarray(inner["world_from_gripper"], dtype=np.float64),
            width_m=float(inner["width_m"]),
            quality=None if d.get("quality") is None else float(d["quality"]),
            contacts=pair,  # type: ignore[arg-type]
            extra={k: v for k, v in d.items() if k not in known},
        )


def _gripper(gripper: GripperSpec) -> Any:
    return os.fspath(gripper) if isinstance(gripper, os.PathLike) else gripper


def gripper(spec: GripperSpec = None) -> dict[str, Any]:
    """The gripper ``spec`` names as a dict of its dimensions (metres), force limit (newtons),
    pad friction and approach distance; ``None`` is the datasets' gripper, the Panda hand."""
    return _native.gripper(_gripper(spec))


@dataclass(frozen=True)
class Sampling:
    """What :func:`sample_grasps` found: the grasps (object frame) and why other tries failed."""

    grasps: list[Grasp]
    tries: int
    antipodal_axes: int
    rejected: dict[str, int]


def sample_grasps(
    vertices: ArrayLike,
    triangles: ArrayLike,
    *,
    gripper: GripperSpec = None,
    count: int = 100,
    table_from_object: Optional[ArrayLike] = None,
    params: Optional[dict[str, Any]] = None,
    seed: int = 0,
) -> Sampling:
    """Up to ``count`` collision-free antipodal grasps on the mesh, in the object frame, each
    with its two contacts (``params``: the sampler's settings, e.g. ``max_tries``,
    ``friction_coef``). With ``table_from_object`` (the object at rest on the table, z = 0)
    grasps whose hand reaches below the table are turned down too."""
    report = _native.sample_grasps(
        vertices,
        triangles,
        gripper=_gripper(gripper),
        count=count,
        table_from_object=optional_f64(table_from_object, "table_from_object"),
        params=params,
        seed=seed,
    )
    return Sampling(
        grasps=[Grasp.from_dict(g) for g in report["grasps"]],
        tries=report["tries"],
        antipodal_axes=report["antipodal_axes"],
        rejected=report["rejected"],
    )


def grasp_quality(
    vertices: ArrayLike,
    triangles: ArrayLike,
    grasp: Union[Grasp, ArrayLike],
    *,
    gripper: GripperSpec = None,
    friction_coef: float = 0.5,
    params: Optional[dict[str, Any]] = None,
) -> dict[str, Any]:
    """Closes the jaws at ``grasp`` (object frame; a :class:`Grasp` or a 4x4 pose): the
    contacts (``None`` when the jaws miss or the object is wider than the hand), whether they
    are in force closure at ``friction_coef``, and Ferrari-Canny's epsilon (``params``: the
    wrench settings)."""
    pose = grasp.world_from_gripper if isinstance(grasp, Grasp) else grasp
    return _native.grasp_quality(
        vertices,
        triangles,
        f64(pose, "grasp"),
        gripper=_gripper(gripper),
        friction_coef=friction_coef,
        params=params,
    )


def robust_quality(
    vertices: ArrayLike,
    triangles: ArrayLike,
    grasps: Union[Grasp, list[Grasp], ArrayLike],
    *,
    gripper: GripperSpec = None,
    params: Optional[dict[str, Any]] = None,
    seed: int = 0,
) -> list[dict[str, Any]]:
    """Dex-Net's robust Ferrari-Canny quality of each grasp (object frame; grasps, or poses
    ``(4, 4)`` / ``(N, 4, 4)``): ``robust_epsilon`` (the mean epsilon over perturbed friction
    and poses), the nominal epsilon and force closure, and the shares of samples in contact and
    in closure. ``params``: the perturbation settings (``num_samples``,
    ``friction_coef_mean``, ...). The same seed gives the same numbers on any thread count."""
    if isinstance(grasps, Grasp):
        grasps = [grasps]
    if isinstance(grasps, list) and grasps and isinstance(grasps[0], Grasp):
        poses = np.stack([g.world_from_gripper for g in grasps])
    else:
        poses = grasps
    return _native.robust_quality(
        vertices,
        triangles,
        f64(poses, "grasps"),
        gripper=_gripper(gripper),
        params=params,
        seed=seed,
    )


def check_collision(
    vertices: ArrayLike,
    triangles: ArrayLike,
    grasp: Grasp,
    *,
    gripper: GripperSpec = None,
    table_from_object: Optional[ArrayLike] = None,
    params: Optional[dict[str, Any]] = None,
) -> dict[str, bool]:
    """Whether the hand, opened for the grasp and swept in along its approach, meets the object
    (``object``) or, with ``table_from_object``, the table (``table``)."""
    return _native.check_collision(
        vertices,
        triangles,
        f64(grasp.world_from_gripper, "grasp.world_from_gripper"),
        grasp.width_m,
        gripper=_gripper(gripper),
        table_from_object=optional_f64(table_from_object, "table_from_object"),
        params=params,
    )


def physics_trial(
    vertices: ArrayLike,
    triangles: ArrayLike,
    table_from_object: ArrayLike,
    grasp: Grasp,
    *,
    gripper: GripperSpec = None,
    params: Optional[dict[str, Any]] = None,
) -> dict[str, Any]:
    """The rapier trial of ``grasp`` (world = table frame) on the object resting at
    ``table_from_object``: it settles, the open hand comes in, closes, lifts and shakes.
    Returns ``success``, ``failed_at`` (``settle``, ``approach``, ``close``, ``lift``,
    ``shake`` or ``None``), the lift, slip and final object pose. ``params``: the trial's
    settings (friction, density, lift and shake); the defaults are the datasets' physics
    labels'."""
    return _native.physics_trial(
        vertices,
        triangles,
        f64(table_from_object, "table_from_object"),
        f64(grasp.world_from_gripper, "grasp.world_from_gripper"),
        grasp.width_m,
        gripper=_gripper(gripper),
        params=params,
    )
