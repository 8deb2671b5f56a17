"""scripts/kill_resume.py in CI: two kills -9 in each of the fast jobs (grasp-dataset generation
from the Rust CLI and from Python, RGB-D rendering from the CLI), each resumed to bytes identical
with an uninterrupted run. The full pass (10 kills, Ray, training, evaluate) is
scripts/reliability.sh's."""

from __future__ import annotations

import subprocess
import sys

import pytest

from conftest import REPO_ROOT

BIN_DIR = REPO_ROOT / "target" / "dist"


def test_killed_jobs_resume_to_the_same_bytes(tmp_path) -> None:
    for binary in ("grasp_dataset", "render"):
        if not (BIN_DIR / binary).is_file():
            pytest.skip(f"no {BIN_DIR / binary} (build: cargo build --profile dist --bins)")
    run = subprocess.run(
        [sys.executable, str(REPO_ROOT / "scripts" / "kill_resume.py"), "--kills", "2",
         "--jobs", "grasp-cli", "grasp-python", "rgbd-cli", "--bin-dir", str(BIN_DIR),
         "--work", str(tmp_path)],
        capture_output=True, text=True, timeout=900,
    )  # fmt: skip
    assert run.returncode == 0, run.stdout + run.stderr
    rows = [line for line in run.stdout.splitlines() if line.startswith("| grasp-") or
            line.startswith("| rgbd-")]  # fmt: skip
    assert len(rows) == 3, run.stdout
    for row in rows:
        cells = [c.strip() for c in row.strip("|").split("|")]
        assert cells[5] == "yes", row
        assert int(cells[4]) > 10, row  # files compared
