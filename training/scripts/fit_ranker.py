"""Fits the multi-view planner's ranker (``crates/planner/src/ranker.rs``): a logistic model of
the chance that a re-scored candidate holds in physics, from the physics trials of the planner's
own candidates (``cargo run --release --bin ranker_data``, ``mvgrasp::ranker_data``).

    cargo run --release --bin ranker_data -- --out ../datasets/ranker/fit --set builtin:60 \\
        --per-category 10
    python training/scripts/fit_ranker.py ../datasets/ranker/fit/rescored.jsonl \\
        --validate ../datasets/ranker/dev/rescored.jsonl --out models/ranker_fused.json

Each line of a dump is one candidate: its re-score (``quality``, or ``virtual_quality`` where the
dump was made with a ranker), the proposing network's score (``view_quality``), the approach's
tilt, who proposed it, its width, its height and the trial's outcome. Trials whose object
toppled while settling test the pose, not the grasp, and are left out, as the evaluation leaves
them out. The features are the Rust ranker's, computed the same way (``features`` below and
``Ranker::features``); their names are written beside the weights and checked on loading.

Numpy only (no torch): Newton's method on the L2-penalised log-likelihood (the bias is not
penalised). Deterministic: the same dumps give the same weights (the file also records the
date and the commit).
"""

from __future__ import annotations

import argparse
import datetime
import hashlib
import json
import math
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

FORMAT = "mvgrasp-ranker/2"
FEATURES = [
    "bias",
    "logit_quality",
    "logit_view_quality",
    "tilt",
    "tilt_squared",
    "by_scorer",
    "width",
    "height",
    "from_cloud",
]
SCORE_FLOOR = 1e-4
FOLDS = 5


def logit(p: float) -> float:
    p = min(max(p, SCORE_FLOOR), 1.0 - SCORE_FLOOR)
    return math.log(p / (1.0 - p))


def features(row: dict, table_z_m: float = 0.0) -> list[float]:
    """The Rust ranker's inputs for one dumped candidate (the dumps' table is at z = 0)."""
    rescore = row.get("virtual_quality")
    if rescore is None:
        rescore = row["quality"]
    view = row.get("view_quality")
    tilt = row["tilt_deg"] / 45.0
    return [
        1.0,
        logit(rescore),
        logit(view if view is not None else rescore),
        tilt,
        tilt * tilt,
        1.0 if row["by_scorer"] else 0.0,
        row["width_m"] / 0.05,
        (row["z_m"] - table_z_m) / 0.05,
        1.0 if row.get("from_cloud") else 0.0,
    ]


def read_dump(path: Path) -> list[dict]:
    """The candidates of a dump that have a trial whose object stayed in its pose."""
    rows = []
    with open(path) as f:
        for number, line in enumerate(f, 1):
            try:
                row = json.loads(line)
            except json.JSONDecodeError as e:
                raise SystemExit(f"{path}:{number}: not a JSON line ({e})") from e
            if row.get("held") is None or row.get("failed_at") == "Settle":
                continue
            rows.append(row)
    if not rows:
        raise SystemExit(f"{path}: no candidate with a physics trial")
    return rows


def fit(x: np.ndarray, y: np.ndarray, l2: float, steps: int = 50) -> np.ndarray:
    """Logistic regression by Newton's method, L2 on every weight but the bias."""
    w = np.zeros(x.shape[1])
    penalty = l2 * np.eye(x.shape[1])
    penalty[0, 0] = 0.0
    for _ in range(steps):
        p = 1.0 / (1.0 + np.exp(-(x @ w)))
        gradient = x.T @ (p - y) + penalty @ w
        hessian = (x.T * (p * (1.0 - p))) @ x + penalty
        step = np.linalg.solve(hessian, gradient)
        w -= step
        if np.abs(step).max() < 1e-10:
            break
    return w


def selections(rows: list[dict], score: np.ndarray) -> dict[str, list[bool]]:
    """Per object, whether its best candidate by ``score`` held, and whether the dump's own
    choice (its lowest rank: the re-score's best where the dump was made without a ranker)
    held."""
    by_object: dict[str, list[int]] = defaultdict(list)
    for i, row in enumerate(rows):
        by_object[row["object"]].append(i)
    ranked, rescored = [], []
    for indices in by_object.values():
        best = max(indices, key=lambda i: (score[i], -rows[i]["rank"]))
        first = min(indices, key=lambda i: rows[i]["rank"])
        ranked.append(bool(rows[best]["held"]))
        rescored.append(bool(rows[first]["held"]))
    return {"ranked": ranked, "rescored": rescored}


def summary(picks: dict[str, list[bool]]) -> dict[str, object]:
    n = len(picks["ranked"])
    return {
        "objects": n,
        "held_ranked": sum(picks["ranked"]),
        "held_dump_choice": sum(picks["rescored"]),
    }


def cross_validate(rows: list[dict], x: np.ndarray, y: np.ndarray, l2: float) -> dict[str, object]:
    """Object-wise folds (objects sorted by name, dealt round robin): each fold's objects
    ranked by a model fitted without them."""
    names = sorted({row["object"] for row in rows})
    fold_of = {name: i % FOLDS for i, name in enumerate(names)}
    folds = np.array([fold_of[row["object"]] for row in rows])
    score = np.zeros(len(rows))
    for k in range(FOLDS):
        test = folds == k
        w = fit(x[~test], y[~test], l2)
        score[test] = x[test] @ w
    return summary(selections(rows, score))


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def code_commit() -> str:
    try:
        root = Path(__file__).resolve().parents[2]
        out = subprocess.run(
            ["git", "-C", str(root), "rev-parse", "HEAD"],
            capture_output=True,
            text=True,
            check=True,
        )
        return out.stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("data", type=Path, nargs="+", help="ranker_data's rescored.jsonl files")
    parser.add_argument("--validate", type=Path, help="a dump of other objects to report on")
    parser.add_argument("--l2", type=float, default=1.0, help="L2 penalty (default 1)")
    parser.add_argument("--out", type=Path, required=True, help="the ranker file to write")
    args = parser.parse_args(argv)

    rows = [row for path in args.data for row in read_dump(path)]
    x = np.array([features(row) for row in rows])
    y = np.array([1.0 if row["held"] else 0.0 for row in rows])
    w = fit(x, y, args.l2)
    training: dict[str, object] = {
        "data": [{"file": p.name, "sha256": sha256(p)} for p in args.data],
        "objects": len({row["object"] for row in rows}),
        "candidates": len(rows),
        "held": int(y.sum()),
        "l2": args.l2,
        "in_sample": summary(selections(rows, x @ w)),
        "cross_validated": cross_validate(rows, x, y, args.l2),
        "code_commit": code_commit(),
        "date": datetime.date.today().isoformat(),
    }
    if args.validate:
        held_out = read_dump(args.validate)
        xv = np.array([features(row) for row in held_out])
        training["validation"] = {
            "file": args.validate.name,
            "sha256": sha256(args.validate),
            **summary(selections(held_out, xv @ w)),
        }
    out = {
        "format": FORMAT,
        "features": FEATURES,
        "weights": [round(float(v), 6) for v in w],
        "training": training,
    }
    args.out.write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps(training, indent=2), file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
