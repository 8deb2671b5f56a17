"""``scripts/evaluate_ray.py``: an ``evaluate`` run spread over a local Ray cluster writes the
same report as one machine's run."""

from __future__ import annotations

import importlib.util
import subprocess
from pathlib import Path

import numpy as np
import pytest

import mvgrasp
from conftest import REPO_ROOT

EVALUATE = REPO_ROOT / "target" / "dist" / "evaluate"


def launcher():
    spec = importlib.util.spec_from_file_location(
        "evaluate_ray", REPO_ROOT / "scripts" / "evaluate_ray.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def write_obj(path: Path, vertices: np.ndarray, triangles: np.ndarray) -> None:
    lines = [f"v {x} {y} {z}" for x, y, z in vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in triangles]
    path.write_text("\n".join(lines) + "\n")


def test_a_run_spread_over_a_local_ray_cluster_writes_one_machines_report(tmp_path: Path) -> None:
    ray = pytest.importorskip("ray")
    if not EVALUATE.is_file():
        pytest.skip(f"no {EVALUATE} (cargo build --profile dist --bins)")
    meshes = tmp_path / "meshes"
    meshes.mkdir()
    for name, index in [("can", 30), ("box", 31), ("bottle", 32)]:
        vertices, triangles = mvgrasp.builtin_object(name, index)
        write_obj(meshes / f"{name}_{index}.obj", vertices, triangles)
    arguments = [
        "--set", f"folder:{meshes}", "--suite", "labels", "--label-grasps", "2",
        "--label-trials", "2", "--label-outcome-trials", "2", "--data", "/nonexistent",
    ]  # fmt: skip
    single = tmp_path / "single"
    subprocess.run(
        [str(EVALUATE), *arguments, "--out", str(single), "--plain"],
        cwd=REPO_ROOT, check=True, capture_output=True,
    )  # fmt: skip
    spread = tmp_path / "spread"
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        launcher().evaluate_with_ray(
            EVALUATE, [*arguments, "--out", str(spread)], shards=2, cwd=REPO_ROOT
        )
    finally:
        ray.shutdown()
    assert sorted(p.name for p in (spread / "shards").iterdir()) == ["0-of-2.jsonl", "1-of-2.jsonl"]
    for name in ["report.md", "results.json"]:
        assert (spread / name).read_bytes() == (single / name).read_bytes(), name
    with pytest.raises(ValueError, match="--shard"):
        launcher().evaluate_with_ray(EVALUATE, ["--shard", "0/2"], shards=2)
