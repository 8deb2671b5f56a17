"""The fused planner's ranker fit (training/scripts/fit_ranker.py)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import load_script



@pytest.fixture(scope="module")
def fit_ranker():
    return load_script("fit_ranker")


def test_features_are_the_rust_rankers(fit_ranker):
    # The same candidate as crates/planner/src/ranker.rs's test: top-down, 4 cm wide, 3 cm up.
    row = {
        "quality": 0.99,
        "view_quality": 0.9,
        "tilt_deg": 0.0,
        "by_scorer": False,
        "width_m": 0.04,
        "z_m": 0.03,
    }
    got = fit_ranker.features(row)
    want = [1.0, math.log(99.0), math.log(9.0), 0.0, 0.0, 0.0, 0.8, 0.6, 0.0]
    assert got == pytest.approx(want)
    # A dump made with a ranker: the re-score is `virtual_quality`, `quality` the ranking.
    ranked = dict(row, quality=0.5, virtual_quality=0.99)
    assert fit_ranker.features(ranked) == pytest.approx(want)
    assert len(got) == len(fit_ranker.FEATURES)


def synthetic_dump(path: Path, features, weights: np.ndarray, objects: int, seed: int) -> None:
    """Candidates whose outcome follows a known logistic model of the ranker's `features`."""
    rng = np.random.default_rng(seed)
    with open(path, "w") as f:
        for o in range(objects):
            for rank in range(12):
                row = {
                    "object": f"thing_{o:03d}",
                    "policy": "fused, 5 views",
                    "rank": rank,
                    "quality": float(rng.uniform(0.3, 0.999)),
                    "view_quality": float(rng.uniform(0.3, 0.999)),
                    "tilt_deg": float(rng.uniform(0.0, 70.0)),
                    "by_scorer": bool(rng.random() < 0.3),
                    "width_m": float(rng.uniform(0.01, 0.08)),
                    "z_m": float(rng.uniform(0.005, 0.1)),
                    "from_cloud": bool(rng.random() < 0.3),
                }
                p = 1.0 / (1.0 + math.exp(-float(np.dot(weights, features(row)))))
                row["held"] = bool(rng.random() < p)
                row["failed_at"] = None if row["held"] else "Lift"
                f.write(json.dumps(row) + "\n")
        # A toppled trial and one without physics: both left out.
        f.write(json.dumps({"object": "x", "held": False, "failed_at": "Settle"}) + "\n")
        f.write(json.dumps({"object": "y", "held": None, "failed_at": None}) + "\n")


def test_the_fit_recovers_a_known_model_and_writes_the_rankers_file(fit_ranker, tmp_path):
    truth = np.array([0.5, 1.0, 0.0, -1.5, 0.0, 1.0, -0.5, -0.5, 0.8])
    dump = tmp_path / "fit.jsonl"
    synthetic_dump(dump, fit_ranker.features, truth, objects=150, seed=1)
    out = tmp_path / "ranker.json"
    assert fit_ranker.main([str(dump), "--validate", str(dump), "--out", str(out)]) == 0
    written = json.loads(out.read_text())
    assert written["format"] == "mvgrasp-ranker/2"
    assert written["features"] == fit_ranker.FEATURES
    w = np.array(written["weights"])
    # The strong effects come back with their signs, near their sizes (the tilt's through its
    # two terms together, at 45 degrees: they trade off against each other).
    for i in (1, 5, 8):
        assert abs(w[i] - truth[i]) < 0.5, (i, w)
    assert abs((w[3] + w[4]) - (truth[3] + truth[4])) < 0.5, w
    training = written["training"]
    assert training["candidates"] == 150 * 12
    assert training["objects"] == 150
    # The same dumps give the same weights.
    again = tmp_path / "again.json"
    fit_ranker.main([str(dump), "--out", str(again)])
    assert json.loads(again.read_text())["weights"] == written["weights"]


def test_a_broken_dump_names_the_file_and_line(fit_ranker, tmp_path):
    dump = tmp_path / "broken.jsonl"
    dump.write_text('{"object": "a", "held": true}\n{not json\n')
    with pytest.raises(SystemExit, match=r"broken.jsonl:2: not a JSON line"):
        fit_ranker.main([str(dump), "--out", str(tmp_path / "r.json")])
    empty = tmp_path / "empty.jsonl"
    empty.write_text(json.dumps({"object": "a", "held": None}) + "\n")
    with pytest.raises(SystemExit, match=r"empty.jsonl: no candidate with a physics trial"):
        fit_ranker.main([str(empty), "--out", str(tmp_path / "r.json")])
