"""One exception tree: every subclass of `mvgrasp.MvGraspError` is raised, as itself, by a real
call with bad input, with a message that names the file or the fault."""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np
import pytest

import mvgrasp
from test_planning import PRIMESENSE_K


def render_on_a_backend_this_machine_lacks() -> None:
    vertices, triangles = mvgrasp.builtin_object("box", 0)
    (camera,) = mvgrasp.cameras.hemisphere(1)
    mvgrasp.render(vertices, triangles, [camera.k], [camera.world_from_camera],
                   width=camera.width, height=camera.height, backend="dx12")  # fmt: skip


def raisers(tmp: Path) -> dict[type[Exception], tuple[Callable[[], object], str]]:
    bad_gripper = tmp / "bad_hand.toml"
    bad_gripper.write_text("max_opening_m = -1.0\n")
    not_a_shard = tmp / "not_a_shard.safetensors"
    not_a_shard.write_bytes(b"abc")
    return {
        mvgrasp.MeshError: (lambda: mvgrasp.load_mesh(tmp / "none.obj"), "none.obj"),
        mvgrasp.CameraError: (lambda: mvgrasp.intrinsics_preset("kinect"), "kinect"),
        mvgrasp.WeightsError: (lambda: mvgrasp.load_network(tmp / "net.json"), "net.json"),
        mvgrasp.RenderError: (render_on_a_backend_this_machine_lacks, "no graphics adapter"),
        mvgrasp.PlanningError: (
            lambda: mvgrasp.plan_depth(np.full((480, 640), 0.7, np.float32), PRIMESENSE_K),
            "nothing stands on the table",
        ),
        mvgrasp.GraspError: (lambda: mvgrasp.gripper(bad_gripper), "bad_hand.toml"),
        mvgrasp.DatasetError: (lambda: mvgrasp.read_grasp_shard(not_a_shard), "not_a_shard"),
    }


def test_every_subclass_is_raised_as_itself(tmp_path: Path) -> None:
    table = raisers(tmp_path)
    assert set(table) == set(mvgrasp.MvGraspError.__subclasses__())
    for error, (call, named) in table.items():
        with pytest.raises(error, match=named) as caught:
            call()
        assert type(caught.value) is error
        assert isinstance(caught.value, mvgrasp.MvGraspError)
        assert "\n" not in str(caught.value), str(caught.value)  # one line
