"""Grasp analysis from Python on a box whose answers are known: where antipodal contacts lie,
which grasps close, collide or hold in physics; settings, grippers and their errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import mvgrasp
from mvgrasp import grasps

BOX = mvgrasp.builtin_object("box", 0)
HALF = np.array([0.08515, 0.02075])  # the box's half length (x) and half width (y)
HEIGHT = 0.0367


def across(x: float = 0.0, z: float = HEIGHT / 2, closing=(0.0, 1.0, 0.0)) -> np.ndarray:
    """A grasp from straight above (approach -z) closing along `closing`, centred at (x, 0, z)."""
    pose = np.eye(4)
    close = np.asarray(closing, dtype=float)
    approach = np.array([0.0, 0.0, -1.0])
    pose[:3, 0], pose[:3, 1], pose[:3, 2] = close, np.cross(approach, close), approach
    pose[:3, 3] = (x, 0.0, z)
    return pose


def test_the_box_is_as_this_test_assumes() -> None:
    vertices, _ = BOX
    assert np.allclose(vertices.max(0), [*HALF, HEIGHT], atol=1e-6)
    assert np.allclose(vertices.min(0), [*-HALF, 0.0], atol=1e-6)


def test_sampled_grasps_are_antipodal_on_the_surface_and_fit_the_hand() -> None:
    sampling = grasps.sample_grasps(*BOX, count=20, seed=3)
    assert len(sampling.grasps) == 20 and sampling.tries >= 1
    friction_cone = np.cos(np.arctan(0.5))  # the sampler's friction coefficient
    for g in sampling.grasps:
        assert 0 < g.width_m <= 0.08
        rotation = g.world_from_gripper[:3, :3]
        assert np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-5)
        first, second = g.contacts
        for c in (first, second):
            # On a face of the box: one coordinate at its bound.
            on_face = np.isclose(np.abs(c.point[:2]), HALF, atol=1e-4).any() or np.isclose(
                c.point[2], [0.0, HEIGHT], atol=1e-4
            ).any()
            assert on_face, c.point
        axis = (second.point - first.point) / np.linalg.norm(second.point - first.point)
        assert np.allclose(axis, g.closing_axis, atol=1e-4)
        assert np.isclose(np.linalg.norm(second.point - first.point), g.width_m, atol=1e-5)
        # Each jaw pushes within its contact's friction cone.
        assert -first.outward_normal @ axis >= friction_cone - 1e-4
        assert second.outward_normal @ axis >= friction_cone - 1e-4
    # The same seed, the same grasps.
    again = grasps.sample_grasps(*BOX, count=20, seed=3)
    assert all(np.array_equal(a.world_from_gripper, b.world_from_gripper)
               for a, b in zip(sampling.grasps, again.grasps))  # fmt: skip


def test_quality_across_the_width_and_nothing_along_the_length() -> None:
    good = grasps.grasp_quality(*BOX, across())
    assert good["force_closure"] and good["epsilon"] > 0
    assert np.isclose(good["contacts"]["width_m"], 2 * HALF[1], atol=1e-5)
    # 17 cm long: wider than the Panda's 8 cm, the jaws find no contacts.
    long = grasps.grasp_quality(*BOX, across(closing=(1.0, 0.0, 0.0)))
    assert long["contacts"] is None and not long["force_closure"] and long["epsilon"] == 0
    # Turned 40 degrees from the width, the jaws push outside the friction cone (26.6 deg at
    # 0.5) of faces they still touch.
    turned = across(closing=(np.sin(np.radians(40)), np.cos(np.radians(40)), 0.0))
    oblique = grasps.grasp_quality(*BOX, turned)
    assert np.isclose(oblique["contacts"]["width_m"], 2 * HALF[1] / np.cos(np.radians(40)),
                      atol=1e-4)  # fmt: skip
    assert not oblique["force_closure"] and oblique["epsilon"] == 0
    # ... and inside the cone of a rubbery 0.9.
    assert grasps.grasp_quality(*BOX, turned, friction_coef=0.9)["force_closure"]
    with pytest.raises(ValueError, match="friction_coef = 0"):
        grasps.grasp_quality(*BOX, across(), friction_coef=0.0)


def test_robust_quality_is_seeded_and_batched() -> None:
    centre, edge = across(), across(x=0.075)
    batch = grasps.robust_quality(*BOX, np.stack([centre, edge]), seed=7)
    assert batch[0] == grasps.robust_quality(*BOX, centre, seed=7)[0]
    assert 0 < batch[0]["robust_epsilon"] <= batch[0]["nominal_epsilon"] * 1.5
    # Near the end of the box, perturbations slide the jaws off it: less robust.
    assert batch[1]["robust_epsilon"] < batch[0]["robust_epsilon"]
    few = grasps.robust_quality(*BOX, centre, params={"num_samples": 5}, seed=7)
    assert few[0]["num_samples"] == 5
    with pytest.raises(ValueError, match="unknown key \"samples\""):
        grasps.robust_quality(*BOX, centre, params={"samples": 5})


def test_collisions_with_the_object_and_the_table() -> None:
    table = np.eye(4)  # the box's base is z = 0: it rests on the table as it is
    free = grasps.check_collision(*BOX, mvgrasp.Grasp(across(), 2 * HALF[1]),
                                  table_from_object=table)  # fmt: skip
    assert free == {"object": False, "table": False}
    # Closing along the length, the open fingers come down onto the box's top.
    onto = mvgrasp.Grasp(across(closing=(1.0, 0.0, 0.0)), 0.06)
    assert grasps.check_collision(*BOX, onto)["object"]
    low = mvgrasp.Grasp(across(z=-0.005), 2 * HALF[1])
    assert grasps.check_collision(*BOX, low, table_from_object=table)["table"]
    assert not grasps.check_collision(*BOX, low)["table"]  # no table given


def test_the_physics_trial_holds_across_and_closes_on_nothing_beside() -> None:
    table = np.eye(4)
    held = grasps.physics_trial(*BOX, table, mvgrasp.Grasp(across(), 2 * HALF[1]))
    assert held["success"] and held["failed_at"] is None
    assert held["object_lift_m"] > 0.05
    beside = mvgrasp.Grasp(across(x=0.3), 2 * HALF[1])
    missed = grasps.physics_trial(*BOX, table, beside)
    assert not missed["success"] and missed["failed_at"] == "close"
    # Frictionless pads cannot lift it.
    slick = grasps.physics_trial(*BOX, table, mvgrasp.Grasp(across(), 2 * HALF[1]),
                                 gripper={"pad_friction": 0.002})  # fmt: skip
    assert not slick["success"] and slick["failed_at"] == "lift"


def test_grippers_from_presets_dicts_and_files(tmp_path: Path) -> None:
    assert grasps.gripper()["name"] == "panda"
    assert grasps.gripper()["max_opening_m"] == pytest.approx(0.08)
    assert grasps.gripper("yumi")["max_opening_m"] == pytest.approx(0.05)
    narrow = grasps.gripper({"max_opening_m": 0.03})
    assert narrow["max_opening_m"] == pytest.approx(0.03)
    assert narrow["finger_length_m"] == grasps.gripper()["finger_length_m"]
    # The box's 4.15 cm width does not fit a 3 cm hand.
    assert grasps.grasp_quality(*BOX, across(), gripper=narrow)["contacts"] is None
    path = tmp_path / "hand.toml"
    path.write_text("max_opening_m = 0.06\n")
    assert grasps.gripper(path)["max_opening_m"] == pytest.approx(0.06)
    assert grasps.gripper(path)["name"] == "hand"
    with pytest.raises(ValueError, match=r"baxter.*a preset \(panda"):
        grasps.gripper("baxter")
    with pytest.raises(ValueError, match="unknown key \"stroke\""):
        grasps.gripper({"stroke": 0.1})
    bad = tmp_path / "bad.toml"
    bad.write_text("max_opening_m = -1.0\n")
    with pytest.raises(mvgrasp.GraspError, match="bad.toml"):
        grasps.gripper(bad)


def test_bad_poses_are_named() -> None:
    with pytest.raises(ValueError, match="object_from_gripper: shape"):
        grasps.grasp_quality(*BOX, np.eye(3))
    with pytest.raises(ValueError, match=r"object_from_grippers\[1\]"):
        grasps.robust_quality(*BOX, np.stack([np.eye(4), 2 * np.eye(4)]))
