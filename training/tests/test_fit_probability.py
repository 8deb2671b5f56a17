"""The chance-to-hold fit (training/scripts/fit_probability.py)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import SCRIPTS, load_script

SCRIPT = SCRIPTS / "fit_probability.py"


@pytest.fixture(scope="module")
def fit_probability():
    return load_script("fit_probability")


def synthetic_records(
    path: Path, objects: int, seed: int, policies: tuple[str, ...] = ("rgb", "depth")
) -> None:
    """Evaluate's journal lines for `policies`: overconfident qualities (most near 1) whose
    true chance to hold is sigmoid(-0.5 + 0.4 logit q), plus toppled and grasp-less records
    that the fit must leave out."""
    rng = np.random.default_rng(seed)
    with open(path, "w") as f:
        for policy in policies:
            for o in range(objects):
                for s in range(3):
                    q = float(1.0 - rng.beta(0.6, 6.0))
                    x = np.log(q / (1.0 - q))
                    held = rng.random() < 1.0 / (1.0 + np.exp(-(-0.5 + 0.4 * x)))
                    outcome = "held" if held else "slipped"
                    quality: float | None = q
                    if s == 2 and o % 7 == 0:
                        outcome = "toppled"
                    if s == 2 and o % 11 == 0:
                        outcome, quality = "no grasp", None
                    value = {
                        "object": f"thing_{o:03d}",
                        "policy": policy,
                        "seed": s,
                        "quality": quality,
                        "outcome": outcome,
                    }
                    key = f"grasp|{policy}|thing_{o:03d}|{s}"
                    f.write(json.dumps({"key": key, "value": value}) + "\n")
        f.write(json.dumps({"key": "depth|x", "value": {}}) + "\n")


def run(records: Path, out: Path, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, str(SCRIPT), str(records), "--out", str(out), *extra],
        capture_output=True,
        check=False,
        text=True,
    )


def test_fit_recovers_a_known_map(fit_probability):
    rng = np.random.default_rng(3)
    x = rng.normal(2.0, 2.0, 4000)
    y = (rng.random(4000) < 1.0 / (1.0 + np.exp(-(-0.5 + 0.7 * x)))).astype(float)
    a, b = fit_probability.fit(x, y)
    assert a == pytest.approx(-0.5, abs=0.15)
    assert b == pytest.approx(0.7, abs=0.08)


def test_ece_is_the_reports(fit_probability):
    # Two bins: 0.6 predicted and 1 of 2 held (0.1 off); 0.97 predicted and 2 of 2 held (0.03).
    p = np.array([0.6, 0.6, 0.97, 0.97])
    y = np.array([1.0, 0.0, 1.0, 1.0])
    assert fit_probability.ece(p, y) == pytest.approx(0.5 * 0.1 + 0.5 * 0.03)


def test_fit_improves_calibration_and_is_deterministic(tmp_path):
    records = tmp_path / "records.jsonl"
    synthetic_records(records, objects=80, seed=1)
    first, second = tmp_path / "a.json", tmp_path / "b.json"
    for out in (first, second):
        done = run(records, out)
        assert done.returncode == 0, done.stderr
    assert first.read_bytes() == second.read_bytes()
    model = json.loads(first.read_text())
    assert model["format"] == "mvgrasp-probability/1"
    for policy in ["rgb", "depth"]:
        report = model["training"]["development_set"][policy]
        # Toppled and grasp-less records are not graded.
        assert report["grasps"] == 80 * 3 - len([o for o in range(80) if o % 7 == 0 or o % 11 == 0])
        assert report["ece_fitted"] < report["ece_raw"] / 2
        assert report["ece_cross_validated"] < report["ece_raw"]
        assert 0.2 < model["policies"][policy]["slope"] < 1.0


def test_too_few_grasps_are_refused(tmp_path):
    records = tmp_path / "records.jsonl"
    synthetic_records(records, objects=3, seed=2)
    done = run(records, tmp_path / "out.json")
    assert done.returncode != 0
    assert "graded grasps in the records" in done.stderr
    assert not (tmp_path / "out.json").exists()


def test_the_fused_planner_is_fitted_on_its_own_policies_and_measured_elsewhere(tmp_path):
    dev, other = tmp_path / "dev.jsonl", tmp_path / "held_out.jsonl"
    fused = ("rgb-fused", "depth-fused")
    synthetic_records(dev, objects=80, seed=1, policies=fused)
    synthetic_records(other, objects=40, seed=5, policies=fused)
    out = tmp_path / "fused.json"
    # The top-down planner's policies are not in these records.
    assert run(dev, out).returncode != 0
    done = run(dev, out, "--planner", "fused", "--measure", str(other))
    assert done.returncode == 0, done.stderr
    model = json.loads(out.read_text())
    assert set(model["policies"]) == {"rgb", "depth"}
    report = model["training"]["development_set"]
    assert report["rgb"]["policy"] == "rgb-fused"
    assert report["depth"]["policy"] == "depth-fused"
    # The measured set is reported, mapped better than raw, and not fitted on.
    lines = [line for line in done.stdout.splitlines() if "measured on" in line]
    assert len(lines) == 2, done.stdout
    raw, mapped = (float(v) for v in lines[0].split("ECE raw ")[1].split(", mapped "))
    assert mapped < raw
    alone = tmp_path / "alone.json"
    assert run(dev, alone, "--planner", "fused").returncode == 0
    assert json.loads(alone.read_text())["policies"] == model["policies"]
