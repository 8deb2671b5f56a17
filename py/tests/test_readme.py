"""The README's Python examples run as they are written (in a scratch folder beside a link to
the shared data, with matplotlib drawing to files)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import REPO_ROOT, shared_data


def readme_examples() -> list[str]:
    text = (REPO_ROOT / "README.md").read_text()
    section = text.split("\n## Python\n", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```python\n(.*?)```", section, flags=re.S)


def test_the_readme_has_the_two_examples() -> None:
    examples = readme_examples()
    assert len(examples) == 2
    assert "plan(depth" in examples[0] and "plan_mesh(" in examples[1]


@pytest.mark.parametrize("index", [0, 1])
def test_a_readme_example_runs(index: int, tmp_path: Path) -> None:
    data = shared_data("real_depth/gqcnn/data")
    # "../shared/data" from the folder the example runs in.
    (tmp_path / "shared").mkdir()
    os.symlink(data.parents[2], tmp_path / "shared" / "data")
    work = tmp_path / "work"
    work.mkdir()
    run = subprocess.run(
        [sys.executable, "-c", readme_examples()[index]],
        cwd=work, capture_output=True, text=True, env={**os.environ, "MPLBACKEND": "Agg"},
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    picture = work / ("grasp_on_depth.png" if index == 0 else "grasp_on_mesh.png")
    assert picture.stat().st_size > 10_000
    assert "quality" in run.stdout
    if index == 0:
        assert (work / "out" / "grasps.json").is_file()
    else:
        assert "held: " in run.stdout, run.stdout
