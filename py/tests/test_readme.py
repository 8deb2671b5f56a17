"""The Python examples of README.md and docs/*.md run as they are written.

Every ```python block runs on its own, in a scratch folder with ``../shared/data`` linked beside
it (a block that names it skips when the shared data is absent) and matplotlib drawing to files.
What a block says it writes must be there: each ``savefig("NAME")`` a picture, each
``.write("DIR")`` a ``DIR/grasps.json``.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import REPO_ROOT, shared_data

FENCE = re.compile(r"^```python[ \t]*\n(.*?)^```[ \t]*$", re.MULTILINE | re.DOTALL)


def examples() -> list[tuple[str, str]]:
    """(name, code) of every Python block, the README's first."""
    found = []
    for page in [REPO_ROOT / "README.md", *sorted((REPO_ROOT / "docs").glob("*.md"))]:
        text = page.read_text()
        for match in FENCE.finditer(text):
            line = text.count("\n", 0, match.start()) + 1
            found.append((f"{page.relative_to(REPO_ROOT)}:{line}", match.group(1)))
    return found


EXAMPLES = examples()


def test_the_readme_has_its_python_example() -> None:
    readme = [code for name, code in EXAMPLES if name.startswith("README.md")]
    assert len(readme) == 1
    assert "plan_mesh(" in readme[0] and len(readme[0].splitlines()) <= 15
    assert any(name.startswith("docs/python.md") for name, _ in EXAMPLES)


@pytest.mark.parametrize("code", [code for _, code in EXAMPLES], ids=[n for n, _ in EXAMPLES])
def test_an_example_runs(code: str, tmp_path: Path) -> None:
    if "../shared/data" in code:
        data = shared_data("")
        # "../shared/data" from the folder the example runs in.
        (tmp_path / "shared").mkdir()
        os.symlink(data.resolve(), tmp_path / "shared" / "data")
    work = tmp_path / "work"
    work.mkdir()
    run = subprocess.run(
        [sys.executable, "-c", code],
        cwd=work, env={**os.environ, "MPLBACKEND": "Agg"}, check=False,
        capture_output=True, text=True,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    for picture in re.findall(r"savefig\(\"([^\"]+)\"", code):
        assert (work / picture).stat().st_size > 10_000, picture
    for folder in re.findall(r"\.write\(\"([^\"]+)\"\)", code):
        assert (work / folder / "grasps.json").is_file(), folder
