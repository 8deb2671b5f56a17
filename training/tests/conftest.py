"""What the training tests share."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest


def generate_grasp_dataset(root: Path, config_toml: str, categories: list[str]) -> Path:
    """A grasp dataset of built-in objects made by the mvgrasp wheel into ``root/data``
    (skips the test when the wheel is not installed).

    In its own process: Mesa's LLVM (the renderer) and the LLVM inside torch's triton, loaded
    into one process, crash it, and pytest runs every test module in one process.
    """
    if importlib.util.find_spec("mvgrasp") is None:
        pytest.skip("the mvgrasp wheel is not installed")
    config = root / "config.toml"
    config.write_text(config_toml)
    data = root / "data"
    subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys, mvgrasp.grasp_dataset as g; "
            "g.generate(sys.argv[1], sys.argv[2], categories=sys.argv[3].split(','))",
            str(data),
            str(config),
            ",".join(categories),
        ],
        check=True,
    )
    return data


def generate_rgbd_dataset(root: Path, categories: list[str]) -> Path:
    """An RGB-D dataset (``render``'s) of built-in objects made by the wheel into ``root``, in
    its own process for the reason :func:`generate_grasp_dataset` gives."""
    if importlib.util.find_spec("mvgrasp") is None:
        pytest.skip("the mvgrasp wheel is not installed")
    subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys, mvgrasp; "
            "mvgrasp.generate_rgbd_dataset(sys.argv[1], categories=sys.argv[2].split(','))",
            str(root),
            ",".join(categories),
        ],
        check=True,
    )
    return root


SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"


def load_script(name: str):
    """``training/scripts/NAME.py`` imported as a module (the scripts are not a package)."""
    spec = importlib.util.spec_from_file_location(name, SCRIPTS / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
