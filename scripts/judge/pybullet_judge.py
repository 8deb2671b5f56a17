"""The project's physics trial replayed in PyBullet: a second engine to judge the judge.

Reads the dump that `label_eval --replay DIR` writes (DIR/replay.json and DIR/meshes/), builds
each grasp's scene in PyBullet and runs the rapier trial's protocol on it (crates/grasp/src/
physics/trial.rs): settle, approach, close, lift, shake, hold. It writes one record per grasp
(DIR/pybullet.json unless --out says otherwise) and prints the agreement of the two engines,
overall and per group, and of the robust Ferrari-Canny label with each.

    pip install pybullet==3.2.7 numpy     # this script installs nothing itself
    python scripts/judge/pybullet_judge.py /tmp/judge/run

The scene, as rapier's (world = table frame, z up, the table's top z = 0, 1/240 s steps):

- The table: a fixed 1.2 x 1.2 x 0.1 m box, friction `table_friction`.
- The object: one dynamic body of the mesh's own mass, centre of mass and inertia (from the
  dump), colliding through the convex parts rapier's trial collides with (`--shape parts`, the
  default: the hull when it adds at most 2 % to the volume, else VHACD's parts,
  crates/grasp/src/physics/object.rs), or the mesh's convex hull (`--shape hull`). Friction 1,
  so that a pair's friction (Bullet multiplies the two) is the table's or the pads'.
- The hand: a palm box and two fingers on prismatic joints along the closing axis, each with a
  velocity motor at `closing_speed_m_s` capped at the closing force (the gripper's
  `force_limit_n`), as rapier's. Each finger's box is set back 3 mm behind its pad, as rapier's;
  the pad is a flat disc (a 24-sided prism, 3 mm thick) of radius (2/3) `pad_radius_m`, centred
  `pad_radius_m` from the finger tip: on a flat face Bullet keeps contact points on its rim, so
  it resists a twist with (2/3) mu F r, a round pad's torsional friction, as rapier's ring of
  contacts plus its twist brake does; Bullet adds no brake where one point touches. The palm is
  a dynamic body held by a fixed constraint whose target moves (Bullet has no kinematic
  multibody that carries contacts' velocities).
- The approach is checked as rapier's is: the open hand's path from `approach_distance_m` back
  along the approach, every 0.5 mm, against the table and the mesh's own triangles (a static
  triangle-mesh body present only for the check), touching within 0.1 mm fails.
- Held: both fingers within `contact_tolerance_m` of the object, the object farther than that
  from the table, its centre of mass raised at least `min_lift_fraction` of the lift.

Deterministic: no randomness; PyBullet runs single-threaded in DIRECT mode.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

try:
    import pybullet as pb
except ImportError:  # the tests skip; the command line says what to install
    pb = None

SWEEP_TOUCH_M = 1.0e-4
SWEEP_STEP_M = 5.0e-4
SHUT_TOLERANCE_M = 1.0e-3
PAD_PROUD_M = 3.0e-3
PAD_SIDES = 24
TABLE_HALF_SIDE_M = 0.6
TABLE_HALF_THICKNESS_M = 0.05
PALM_MASS_KG = 1.0
PALM_HOLD_FORCE_N = 5000.0
SAT = 1
PAD_TWIST = 1.0
MARGIN_M = 1.0e-4
STAGES = ("settle", "approach", "close", "lift", "shake")


# --- small geometry helpers -------------------------------------------------------------------


def quat_of(rotation: np.ndarray) -> list[float]:
    """PyBullet's (x, y, z, w) quaternion of a 3x3 rotation matrix."""
    m = np.asarray(rotation, dtype=float)
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    if trace > 0:
        s = 2.0 * math.sqrt(trace + 1.0)
        w, x = 0.25 * s, (m[2, 1] - m[1, 2]) / s
        y, z = (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        w, x = (m[2, 1] - m[1, 2]) / s, 0.25 * s
        y, z = (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s
    elif m[1, 1] > m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        w, x = (m[0, 2] - m[2, 0]) / s, (m[0, 1] + m[1, 0]) / s
        y, z = 0.25 * s, (m[1, 2] + m[2, 1]) / s
    else:
        s = 2.0 * math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        w, x = (m[1, 0] - m[0, 1]) / s, (m[0, 2] + m[2, 0]) / s
        y, z = (m[1, 2] + m[2, 1]) / s, 0.25 * s
    return [x, y, z, w]


def rot_of(quat) -> np.ndarray:
    return np.array(pb.getMatrixFromQuaternion(quat)).reshape(3, 3)


def pose_matrix(position, quat) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = rot_of(quat)
    m[:3, 3] = position
    return m


def axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * (k @ k)


def rotation_angle(r: np.ndarray) -> float:
    return math.acos(max(-1.0, min(1.0, (np.trace(r) - 1.0) / 2.0)))


def min_jerk(s: float) -> float:
    s = min(max(s, 0.0), 1.0)
    return s * s * s * (10.0 + s * (-15.0 + 6.0 * s))


def read_obj(path: Path) -> list[tuple[np.ndarray, np.ndarray]]:
    """The `o` groups of an OBJ (one group when it has none), each (vertices, 0-based faces)."""
    groups: list[tuple[list, list]] = []
    vertices: list[list[float]] = []
    for line in Path(path).read_text().splitlines():
        if line.startswith("o ") or (line.startswith(("v ", "f ")) and not groups):
            groups.append(([], []))
        if line.startswith("v "):
            vertices.append([float(x) for x in line.split()[1:4]])
            groups[-1][0].append(len(vertices) - 1)
        elif line.startswith("f "):
            groups[-1][1].append([int(x.split("/")[0]) - 1 for x in line.split()[1:4]])
    out = []
    all_v = np.array(vertices)
    for used, faces in groups:
        if not used:
            continue
        used = np.array(used)
        remap = {int(old): new for new, old in enumerate(used)}
        f = np.array([[remap[i] for i in face] for face in faces], dtype=int)
        out.append((all_v[used], f))
    return out


def write_obj(path: Path, vertices: np.ndarray, faces: np.ndarray | None = None) -> None:
    lines = [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in vertices]
    if faces is not None:
        lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces]
    Path(path).write_text("\n".join(lines) + "\n")


# --- what a trial needs -----------------------------------------------------------------------


@dataclass
class TrialObject:
    """An object for a trial, object frame: the convex parts it collides through, its true
    surface (for the approach) and its mass facts."""

    parts: list[tuple[np.ndarray, np.ndarray]]
    surface_vertices: np.ndarray
    surface_faces: np.ndarray
    mass_kg: float
    center_of_mass: np.ndarray
    inertia_kg_m2: np.ndarray

    @classmethod
    def solid(cls, vertices, faces, density_kg_m3: float, parts=None) -> TrialObject:
        """A closed mesh of uniform density (mass facts by the divergence theorem)."""
        v = np.asarray(vertices, dtype=float)
        f = np.asarray(faces, dtype=int)
        mass, com, inertia = mesh_mass(v, f, density_kg_m3)
        return cls(parts or [(v, f)], v, f, mass, com, inertia)


def mesh_mass(v: np.ndarray, f: np.ndarray, density: float):
    """Mass, centre of mass and inertia about it of a closed, outward-wound triangle mesh."""
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    d = np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0  # signed tetra volumes from the origin
    volume = d.sum()
    com = (d[:, None] * (a + b + c) / 4.0).sum(0) / volume
    # Second moments of each tetrahedron (origin, a, b, c).
    s = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            s[i, j] = (
                d
                * (
                    2 * (a[:, i] * a[:, j] + b[:, i] * b[:, j] + c[:, i] * c[:, j])
                    + a[:, i] * b[:, j]
                    + b[:, i] * a[:, j]
                    + a[:, i] * c[:, j]
                    + c[:, i] * a[:, j]
                    + b[:, i] * c[:, j]
                    + c[:, i] * b[:, j]
                )
                / 20.0
            ).sum()
    mass = density * volume
    s = density * s - mass * np.outer(com, com)
    inertia = np.trace(s) * np.eye(3) - s
    return mass, com, inertia


@dataclass
class Outcome:
    success: bool
    failed_at: str | None
    object_lift_m: float = 0.0
    slip_m: float = 0.0
    slip_rad: float = 0.0
    opening_m: float = 0.0
    # Diagnostics: the pads' total normal force and the largest tangential/normal ratio of a
    # pad contact at the end of the close, and the contact normals' angle to the closing axis.
    notes: dict = field(default_factory=dict)


# --- the trial --------------------------------------------------------------------------------


class Trial:
    """One PyBullet trial of one grasp (a fresh world each time)."""

    def __init__(self, client: int, workdir: Path):
        self.c = client
        self.workdir = Path(workdir)

    # The world.
    def _reset(self, physics: dict) -> None:
        c = self.c
        pb.resetSimulation(physicsClientId=c)
        pb.setGravity(0, 0, -9.81, physicsClientId=c)
        pb.setPhysicsEngineParameter(
            fixedTimeStep=physics["timestep_s"],
            numSubSteps=0,
            deterministicOverlappingPairs=1,
            enableConeFriction=1,
            enableSAT=SAT,
            physicsClientId=c,
        )
        half = [TABLE_HALF_SIDE_M, TABLE_HALF_SIDE_M, TABLE_HALF_THICKNESS_M]
        shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=half, physicsClientId=c)
        self.table = pb.createMultiBody(
            0, shape, basePosition=[0, 0, -TABLE_HALF_THICKNESS_M], physicsClientId=c
        )
        pb.changeDynamics(
            self.table,
            -1,
            lateralFriction=physics["table_friction"],
            restitution=0.0,
            physicsClientId=c,
        )

    def _add_object(self, obj: TrialObject, table_from_object: np.ndarray) -> None:
        c = self.c
        files = []
        for i, part in enumerate(obj.parts):
            path = self.workdir / f"part_{len(obj.parts)}_{i}_{id(obj)}.obj"
            if not path.exists():
                write_obj(path, *part)
            files.append(str(path))
        shape = pb.createCollisionShapeArray(
            shapeTypes=[pb.GEOM_MESH] * len(files),
            fileNames=files,
            meshScales=[[1, 1, 1]] * len(files),
            collisionFramePositions=[[0, 0, 0]] * len(files),
            physicsClientId=c,
        )
        # Principal axes of the inertia: Bullet takes a diagonal in the inertial frame.
        moments, axes = np.linalg.eigh(obj.inertia_kg_m2)
        if np.linalg.det(axes) < 0:
            axes[:, 0] = -axes[:, 0]
        self.object_from_inertial = np.eye(4)
        self.object_from_inertial[:3, :3] = axes
        self.object_from_inertial[:3, 3] = obj.center_of_mass
        t = np.asarray(table_from_object, dtype=float)
        self.obj = pb.createMultiBody(
            obj.mass_kg,
            shape,
            basePosition=t[:3, 3].tolist(),
            baseOrientation=quat_of(t[:3, :3]),
            baseInertialFramePosition=obj.center_of_mass.tolist(),
            baseInertialFrameOrientation=quat_of(axes),
            physicsClientId=c,
        )
        pb.changeDynamics(
            self.obj,
            -1,
            lateralFriction=1.0,
            restitution=0.0,
            localInertiaDiagonal=np.maximum(moments, 1e-9).tolist(),
            collisionMargin=MARGIN_M,
            activationState=pb.ACTIVATION_STATE_DISABLE_SLEEPING,
            physicsClientId=c,
        )

    def world_from_object(self) -> np.ndarray:
        pos, quat = pb.getBasePositionAndOrientation(self.obj, physicsClientId=self.c)
        return pose_matrix(pos, quat) @ np.linalg.inv(self.object_from_inertial)

    def object_com(self) -> np.ndarray:
        return np.array(pb.getBasePositionAndOrientation(self.obj, physicsClientId=self.c)[0])

    def _hand_urdf(self, gripper: dict, opening_m: float, physics: dict) -> Path:
        """The hand in the gripper frame, fingers open `opening_m`: a URDF with prismatic
        joints whose coordinate is how far each finger has closed."""
        t = gripper["finger_thickness_m"]
        w = gripper["finger_width_m"]
        length = gripper["finger_length_m"]
        palm = gripper["palm_size_m"]
        open_x = (opening_m + t) / 2.0
        shut_x = (gripper["min_opening_m"] + t) / 2.0
        finger_z = -length / 2.0
        pad_z = -gripper["pad_radius_m"] - finger_z  # pad centre in the finger's frame
        disc = (2.0 / 3.0) * gripper["pad_radius_m"]
        recess = min(PAD_PROUD_M, t)
        # The +x finger's frame: its box centre; the inner face at x = -t/2. The pad: a disc
        # prism from the inner face back `recess`, the box set back behind it.
        pad_path = self.workdir / f"pad_{disc:.6f}_{recess:.6f}.obj"
        if not pad_path.exists():
            ring = [
                (
                    disc * math.cos(2 * math.pi * k / PAD_SIDES),
                    disc * math.sin(2 * math.pi * k / PAD_SIDES),
                )
                for k in range(PAD_SIDES)
            ]
            pts = [(x, y, z) for x in (0.0, recess) for (y, z) in ring]
            n = PAD_SIDES
            faces = [(0, k + 1, k) for k in range(1, n - 1)]  # the face at x = 0
            faces += [(n, n + k, n + k + 1) for k in range(1, n - 1)]  # the back
            for k in range(n):
                a, b = k, (k + 1) % n
                faces += [(a, b, n + b), (a, n + b, n + a)]
            write_obj(pad_path, np.array(pts), np.array(faces))
        mass = physics["finger_mass_kg"]

        def finger(name: str, side: float) -> str:
            # The -x finger is the +x one turned half a turn about z.
            yaw = 0.0 if side > 0 else math.pi
            box_x = recess / 2.0
            return f"""
  <link name="{name}">
    <inertial><origin xyz="0 0 0"/><mass value="{mass}"/>
      <inertia ixx="1e-5" iyy="1e-5" izz="1e-5" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="{side * box_x} 0 0" rpy="0 0 {yaw}"/>
      <geometry><box size="{t - recess} {w} {length}"/></geometry></collision>
    <collision><origin xyz="{side * (-t / 2.0)} 0 {pad_z}" rpy="0 0 {yaw}"/>
      <geometry><mesh filename="{pad_path}"/></geometry></collision>
  </link>
  <joint name="{name}_joint" type="prismatic">
    <parent link="palm"/><child link="{name}"/>
    <origin xyz="{side * open_x} 0 {finger_z}"/><axis xyz="{-side} 0 0"/>
    <limit lower="0" upper="{open_x - shut_x}" effort="1000" velocity="10"/>
  </joint>"""

        urdf = f"""<?xml version="1.0"?>
<robot name="hand">
  <link name="palm">
    <inertial><origin xyz="0 0 0"/><mass value="{PALM_MASS_KG}"/>
      <inertia ixx="1e-3" iyy="1e-3" izz="1e-3" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0 0 {-length - palm[2] / 2.0}"/>
      <geometry><box size="{palm[0]} {palm[1]} {palm[2]}"/></geometry></collision>
  </link>{finger("finger_pos", 1.0)}{finger("finger_neg", -1.0)}
</robot>
"""
        path = self.workdir / f"hand_{opening_m:.6f}.urdf"
        path.write_text(urdf)
        self.open_x, self.thickness = open_x, t
        return path

    # Checks.
    def _distance(self, a: int, b: int, link_a: int | None = None, reach: float = 0.01) -> float:
        kw = {} if link_a is None else {"linkIndexA": link_a}
        pts = pb.getClosestPoints(a, b, reach, physicsClientId=self.c, **kw)
        return min((p[8] for p in pts), default=math.inf)

    def fingers_touch(self, tol: float) -> bool:
        return all(self._distance(self.hand, self.obj, link, 2 * tol) <= tol for link in (0, 1))

    def opening(self) -> float:
        q = [pb.getJointState(self.hand, j, physicsClientId=self.c)[0] for j in (0, 1)]
        return max(0.0, 2 * self.open_x - q[0] - q[1] - self.thickness)

    def gripper_pose(self) -> np.ndarray:
        pos, quat = pb.getBasePositionAndOrientation(self.hand, physicsClientId=self.c)
        return pose_matrix(pos, quat)

    def _move_palm(self, target: np.ndarray) -> None:
        pb.changeConstraint(
            self.palm_hold,
            jointChildPivot=target[:3, 3].tolist(),
            jointChildFrameOrientation=quat_of(target[:3, :3]),
            maxForce=PALM_HOLD_FORCE_N,
            physicsClientId=self.c,
        )

    def _step(self, seconds: float) -> None:
        for _ in range(round(seconds / self.physics["timestep_s"])):
            pb.stepSimulation(physicsClientId=self.c)

    def _approach_hits(self, obj: TrialObject, pregrasp: np.ndarray, travel: np.ndarray) -> bool:
        c = self.c
        surface = pb.createCollisionShape(
            pb.GEOM_MESH,
            vertices=obj.surface_vertices.tolist(),
            indices=obj.surface_faces.reshape(-1).tolist(),
            flags=pb.GEOM_FORCE_CONCAVE_TRIMESH,
            physicsClientId=c,
        )
        w = self.world_from_object()
        probe = pb.createMultiBody(
            0,
            surface,
            basePosition=w[:3, 3].tolist(),
            baseOrientation=quat_of(w[:3, :3]),
            physicsClientId=c,
        )
        pb.setCollisionFilterGroupMask(probe, -1, 0, 0, physicsClientId=c)
        pb.changeDynamics(probe, -1, collisionMargin=0.0, physicsClientId=c)
        n = max(1, math.ceil(np.linalg.norm(travel) / SWEEP_STEP_M))
        hit = False
        for k in range(n + 1):
            p = pregrasp.copy()
            p[:3, 3] += travel * k / n
            pb.resetBasePositionAndOrientation(
                self.hand, p[:3, 3].tolist(), quat_of(p[:3, :3]), physicsClientId=c
            )
            if any(
                self._distance(self.hand, other, None, 0.01) <= SWEEP_TOUCH_M
                for other in (probe, self.table)
            ):
                hit = True
                break
        pb.removeBody(probe, physicsClientId=c)
        return hit

    def _pad_contacts(self) -> dict:
        """The fingers' contacts with the object: total normal force a finger, and the contact
        normals' largest angle to the closing axis, degrees."""
        gx = self.gripper_pose()[:3, 0]
        out = {}
        for link in (0, 1):
            pts = pb.getContactPoints(self.hand, self.obj, link, -1, physicsClientId=self.c)
            force = sum(p[9] for p in pts)
            angles = [math.degrees(math.acos(min(1.0, abs(float(np.dot(p[7], gx)))))) for p in pts]
            out[f"finger{link}_force_n"] = round(force, 3)
            out[f"finger{link}_max_normal_angle_deg"] = round(max(angles, default=-1.0), 2)
        return out

    def _hold(self, tol: float) -> dict:
        p = self.physics
        g = self.gripper_pose()
        com = self.object_com()
        lift = com[2] - self.rest_com_z
        slip = float(
            np.linalg.norm((np.linalg.inv(g) @ np.append(com, 1.0))[:3] - self.com_in_gripper)
        )
        g_from_o = np.linalg.inv(g) @ self.world_from_object()
        slip_rad = rotation_angle(self.gripper_from_object[:3, :3].T @ g_from_o[:3, :3])
        touch = self.fingers_touch(tol)
        off_table = self._distance(self.table, self.obj, None, 2 * tol) > tol
        held = touch and off_table and lift >= p["min_lift_fraction"] * p["lift_height_m"]
        return {
            "held": held,
            "object_lift_m": float(lift),
            "slip_m": slip,
            "slip_rad": slip_rad,
            "opening_m": self.opening(),
            "fingers_touch": touch,
            "off_table": off_table,
        }

    def run(
        self,
        obj: TrialObject,
        table_from_object: np.ndarray,
        world_from_gripper: np.ndarray,
        width_m: float,
        gripper: dict,
        physics: dict,
        closing_force_n: float,
    ) -> Outcome:
        c = self.c
        self.physics = p = physics
        self._reset(p)
        self._add_object(obj, table_from_object)
        tol = p["contact_tolerance_m"]
        dt = p["timestep_s"]

        # 1. Settle.
        placed = self.world_from_object()
        placed_com = self.object_com()
        self._step(p["settle_time_s"])
        rested = self.world_from_object()
        rest_com = self.object_com()
        turned = rotation_angle(placed[:3, :3].T @ rested[:3, :3])
        if (
            np.linalg.norm(rest_com - placed_com) > p["settle_tolerance_m"]
            or turned > p["settle_tolerance_rad"]
        ):
            return Outcome(False, "settle")
        self.rest_com_z = rest_com[2]

        # 2. Approach: the open hand's path, checked against the true surface and the table.
        opening = min(
            max(width_m + gripper["open_margin_m"], gripper["min_opening_m"]),
            gripper["max_opening_m"],
        )
        urdf = self._hand_urdf(gripper, opening, p)
        g = np.asarray(world_from_gripper, dtype=float)
        approach = g[:3, 2]
        travel = approach * gripper["approach_distance_m"]
        pre = g.copy()
        pre[:3, 3] -= travel
        self.hand = pb.loadURDF(
            str(urdf),
            pre[:3, 3].tolist(),
            quat_of(pre[:3, :3]),
            flags=pb.URDF_USE_INERTIA_FROM_FILE,
            physicsClientId=c,
        )
        for link in (-1, 0, 1):
            pb.changeDynamics(
                self.hand,
                link,
                lateralFriction=gripper["pad_friction"],
                restitution=0.0,
                linearDamping=0.0,
                angularDamping=0.0,
                jointDamping=0.0,
                collisionMargin=MARGIN_M,
                physicsClientId=c,
            )
        for link in (0, 1):
            # The pads' torsional friction, (2/3) mu r per newton pressing (Bullet multiplies
            # it by the object's friction, 1).
            pb.changeDynamics(
                self.hand,
                link,
                spinningFriction=PAD_TWIST
                * (2.0 / 3.0)
                * gripper["pad_friction"]
                * gripper["pad_radius_m"],
                physicsClientId=c,
            )
        for j in (0, 1):
            pb.setJointMotorControl2(
                self.hand, j, pb.VELOCITY_CONTROL, targetVelocity=0.0, force=0.0, physicsClientId=c
            )
        if self._approach_hits(obj, pre, travel):
            return Outcome(False, "approach")

        # 3. Close: the hand at the grasp pose, held there; the fingers close at the closing
        # speed until both stop, then squeeze for close_hold_s.
        pb.resetBasePositionAndOrientation(
            self.hand, g[:3, 3].tolist(), quat_of(g[:3, :3]), physicsClientId=c
        )
        pb.resetBaseVelocity(self.hand, [0, 0, 0], [0, 0, 0], physicsClientId=c)
        self.palm_hold = pb.createConstraint(
            self.hand,
            -1,
            -1,
            -1,
            pb.JOINT_FIXED,
            [0, 0, 0],
            [0, 0, 0],
            g[:3, 3].tolist(),
            childFrameOrientation=quat_of(g[:3, :3]),
            physicsClientId=c,
        )
        self._move_palm(g)
        speed = p["closing_speed_m_s"]
        for j in (0, 1):
            pb.setJointMotorControl2(
                self.hand,
                j,
                pb.VELOCITY_CONTROL,
                targetVelocity=speed,
                force=closing_force_n,
                physicsClientId=c,
            )
        travel_m = self.open_x - (gripper["min_opening_m"] + gripper["finger_thickness_m"]) / 2
        max_steps = round((travel_m / speed + 0.1) / dt)
        still = 0
        for _ in range(max_steps):
            pb.stepSimulation(physicsClientId=c)
            v = [abs(pb.getJointState(self.hand, j, physicsClientId=c)[1]) for j in (0, 1)]
            still = still + 1 if max(v) < 0.1 * speed else 0
            if still >= 3:
                break
        self._step(p["close_hold_s"])
        opening_now = self.opening()
        notes = self._pad_contacts()
        if (
            not self.fingers_touch(tol)
            or opening_now <= gripper["min_opening_m"] + SHUT_TOLERANCE_M
        ):
            return Outcome(False, "close", opening_m=opening_now, notes=notes)
        gp = self.gripper_pose()
        self.gripper_from_object = np.linalg.inv(gp) @ self.world_from_object()
        self.com_in_gripper = (np.linalg.inv(gp) @ np.append(self.object_com(), 1.0))[:3]

        # 4. Lift: straight up on a minimum-jerk profile, then hold.
        steps = max(1, round(p["lift_duration_s"] / dt))
        for k in range(1, steps + 1):
            target = g.copy()
            target[2, 3] += p["lift_height_m"] * min_jerk(k / steps)
            self._move_palm(target)
            pb.stepSimulation(physicsClientId=c)
        lifted = g.copy()
        lifted[2, 3] += p["lift_height_m"]
        self._move_palm(lifted)
        self._step(p["lift_hold_s"])
        hold = self._hold(tol)
        notes["after_lift"] = {k: v for k, v in hold.items() if k != "held"}
        if not hold["held"]:
            return self._outcome("lift", hold, notes)

        # 5. Shake: up and down and about the closing axis, faded in and out; then hold.
        axis = lifted[:3, 0]
        steps = round(p["shake_duration_s"] / dt)
        omega = 2 * math.pi * p["shake_frequency_hz"]
        for k in range(1, steps + 1):
            fade = math.sin(math.pi * k / steps)
            u = math.sin(omega * k * dt) * fade
            target = lifted.copy()
            target[2, 3] += p["shake_amplitude_m"] * u
            target[:3, :3] = axis_angle(axis, p["shake_angle_rad"] * u) @ lifted[:3, :3]
            self._move_palm(target)
            pb.stepSimulation(physicsClientId=c)
        self._move_palm(lifted)
        self._step(p["final_hold_s"])
        hold = self._hold(tol)
        return self._outcome(None if hold["held"] else "shake", hold, notes)

    @staticmethod
    def _outcome(stage: str | None, hold: dict, notes: dict) -> Outcome:
        return Outcome(
            stage is None,
            stage,
            hold["object_lift_m"],
            hold["slip_m"],
            hold["slip_rad"],
            hold["opening_m"],
            notes,
        )


def connect() -> int:
    if pb is None:
        sys.exit("pybullet is not installed: pip install pybullet==3.2.7")
    return pb.connect(pb.DIRECT)


# --- the dump ---------------------------------------------------------------------------------


def load_object(folder: Path, record: dict, shape: str) -> TrialObject:
    surface = read_obj(folder / record["mesh"])
    sv, sf = surface[0] if len(surface) == 1 else _merge(surface)
    if shape == "parts":
        parts = read_obj(folder / record["parts"])
    else:
        parts = [(sv, sf)]
    return TrialObject(
        parts,
        sv,
        sf,
        record["mass_kg"],
        np.array(record["center_of_mass"]),
        np.array(record["inertia_kg_m2"]),
    )


def _merge(groups):
    vs, fs, n = [], [], 0
    for v, f in groups:
        vs.append(v)
        fs.append(f + n)
        n += len(v)
    return np.vstack(vs), np.vstack(fs)


def agreement_table(rows: list[dict]) -> str:
    """Markdown: rapier's unperturbed outcome against PyBullet's, per group and overall, and
    the robust label against each engine."""
    groups = sorted({r["group"] for r in rows}) + ["all"]
    out = [
        (
            "| objects | grasps | both held | both failed | rapier held, PyBullet failed | "
            "rapier failed, PyBullet held | engines agree | robust label = rapier | "
            "robust label = PyBullet |"
        ),
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for group in groups:
        rs = [r for r in rows if group == "all" or r["group"] == group]
        if not rs:
            continue
        hh = sum(r["rapier"] and r["pybullet"] for r in rs)
        ff = sum(not r["rapier"] and not r["pybullet"] for r in rs)
        hf = sum(r["rapier"] and not r["pybullet"] for r in rs)
        fh = sum(not r["rapier"] and r["pybullet"] for r in rs)
        n = len(rs)
        lr = sum(r["robust"] == r["rapier"] for r in rs)
        lp = sum(r["robust"] == r["pybullet"] for r in rs)
        out.append(
            f"| {group} | {n} | {hh} | {ff} | {hf} | {fh} | {100 * (hh + ff) / n:.0f}% | "
            f"{100 * lr / n:.0f}% | {100 * lp / n:.0f}% |"
        )
    return "\n".join(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("folder", type=Path, help="what label_eval --replay wrote")
    parser.add_argument("--shape", choices=["parts", "hull"], default="parts")
    parser.add_argument("--out", type=Path, help="records (default FOLDER/pybullet[-hull].json)")
    parser.add_argument("--limit", type=int, help="only the first N grasps")
    args = parser.parse_args()
    dump = json.loads((args.folder / "replay.json").read_text())
    gripper, physics = dump["gripper"], dump["physics"]
    client = connect()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        trial = Trial(client, Path(tmp))
        cache: dict[int, TrialObject] = {}
        grasps = dump["grasps"][: args.limit] if args.limit else dump["grasps"]
        for n, g in enumerate(grasps):
            o = dump["objects"][g["object"]]
            if g["object"] not in cache:
                cache = {g["object"]: load_object(args.folder, o, args.shape)}
            outcome = trial.run(
                cache[g["object"]],
                np.array(o["table_from_object"]),
                np.array(g["world_from_gripper"]),
                g["width_m"],
                gripper,
                physics,
                dump["closing_force_n"],
            )
            r = g["outcome"]
            rows.append(
                {
                    "object": o["name"],
                    "group": o["group"],
                    "index": g["index"],
                    "robust": g["robust"],
                    "robust_epsilon": g["robust_epsilon"],
                    "physics_rate": g["physics_rate"],
                    "outcome_rate": g["outcome_rate"],
                    "rapier": r["success"],
                    "rapier_failed_at": r["failed_at"],
                    "rapier_slip_m": r["slip_m"],
                    "rapier_slip_rad": r["slip_rad"],
                    "rapier_opening_m": r["opening_m"],
                    "rapier_lift_m": r["object_lift_m"],
                    "pybullet": outcome.success,
                    "pybullet_failed_at": outcome.failed_at,
                    "pybullet_slip_m": outcome.slip_m,
                    "pybullet_slip_rad": outcome.slip_rad,
                    "pybullet_opening_m": outcome.opening_m,
                    "pybullet_lift_m": outcome.object_lift_m,
                    "pybullet_notes": outcome.notes,
                    "width_m": g["width_m"],
                }
            )
            if (n + 1) % 25 == 0:
                print(f"{n + 1} of {len(grasps)} grasps", file=sys.stderr)
    pb.disconnect(client)
    out = args.out or args.folder / (
        "pybullet.json" if args.shape == "parts" else "pybullet-hull.json"
    )
    out.write_text(json.dumps(rows, indent=1))
    # Trials whose object left its pose in either engine test the pose, not the grasp.
    judged = [r for r in rows if "settle" not in (r["rapier_failed_at"], r["pybullet_failed_at"])]
    print(
        f"{len(rows)} grasps, {len(rows) - len(judged)} left out (settle failed in an engine); "
        f"shape: {args.shape}\n"
    )
    print(agreement_table(judged))
    stages = {}
    for r in judged:
        key = (r["rapier_failed_at"] or "held", r["pybullet_failed_at"] or "held")
        stages[key] = stages.get(key, 0) + 1
    print("\nrapier stage -> PyBullet stage: count")
    for (a, b), n in sorted(stages.items(), key=lambda kv: -kv[1]):
        print(f"  {a} -> {b}: {n}")


if __name__ == "__main__":
    main()
