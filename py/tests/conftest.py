"""What the wheel's tests share: where the shared real data lives.

`../shared/data` beside the repository, or `$MVGRASP_SHARED_DATA`. A test that needs it skips
when it is absent, unless `MVGRASP_REQUIRE_SHARED_DATA=1` (set by `.ci/run` when the folder is
there): then a missing file fails the test, so a test cannot pass by skipping.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]


def shared_data(relative: str) -> Path:
    """The shared data file or folder `relative`; skips (or fails, when required) if absent."""
    root = Path(os.environ.get("MVGRASP_SHARED_DATA", REPO_ROOT.parent / "shared" / "data"))
    path = root / relative
    if path.exists():
        return path
    message = f"no shared data at {path} (set MVGRASP_SHARED_DATA)"
    if os.environ.get("MVGRASP_REQUIRE_SHARED_DATA") == "1":
        pytest.fail(f"MVGRASP_REQUIRE_SHARED_DATA=1 but {message}")
    pytest.skip(message)
