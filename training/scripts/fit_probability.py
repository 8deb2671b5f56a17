"""Fits the chance that a planned grasp holds (``crates/planner/src/probability.rs``): per
policy of ``evaluate`` (``rgb``: the default run, depth predicted from 5 RGB views; ``depth``:
the same planner on a depth camera's depth), a logistic map of the logit of the returned grasp's
network quality to the trial's outcome (Platt scaling), fitted on the development set's
records (built-in objects where settings are chosen, never an evaluation set):

    cargo run --release --bin evaluate -- --out ../runs/calib_dev --set dev --per-category 5 \\
        --seeds 0,1,2 --all-poses --policy rgb --policy depth --suite grasps
    python training/scripts/fit_probability.py ../runs/calib_dev/records.jsonl \\
        --out models/probability_topdown.json

Grasps whose object toppled before the hand came test the pose, not the grasp, and are left
out, as ``evaluate`` leaves them out; objects without a grasp have no quality to map. The
expected calibration error (ECE, in the report's bins) is given on the fitting records, raw
and mapped, and by 5-fold cross-validation over objects. Numpy only; deterministic (the file
records the data's hash, the date and the commit).
"""

from __future__ import annotations

import argparse
import datetime
import hashlib
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np

FORMAT = "mvgrasp-probability/1"
# Per planner: the evaluate policy whose records fit each depth source's map.
PLANNERS = {
    "topdown": {"rgb": "rgb", "depth": "depth"},
    "fused": {"rgb": "rgb-fused", "depth": "depth-fused"},
}
SCORE_FLOOR = 1e-4
FOLDS = 5
# The report's bins (src/evaluate/report/mod.rs, QUALITY_BINS): upper ends.
BINS = [0.5, 0.7, 0.8, 0.9, 0.95, 1.0]
L2 = 1e-3


def logit(p: float) -> float:
    p = min(max(p, SCORE_FLOOR), 1.0 - SCORE_FLOOR)
    return math.log(p / (1.0 - p))


def read_records(paths: list[Path]) -> list[dict]:
    """The grasp records of ``evaluate``'s journals (the last line of a key wins)."""
    records: dict[str, dict] = {}
    for path in paths:
        for number, line in enumerate(path.read_text().splitlines(), 1):
            if not line.strip():
                continue
            try:
                entry = json.loads(line)
            except json.JSONDecodeError as e:
                sys.exit(f"{path}:{number}: not JSON ({e})")
            if str(entry.get("key", "")).startswith("grasp|"):
                records[entry["key"]] = entry["value"]
    return list(records.values())


def graded(rows: list[dict], policy: str) -> list[dict]:
    """The policy's returned grasps that the trial tested (the object at rest when the hand
    came)."""
    return [
        r
        for r in rows
        if r["policy"] == policy and r.get("quality") is not None and r["outcome"] != "toppled"
    ]


def arrays(kept: list[dict]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(logit of the quality, the quality, held as 1.0 or 0.0) of graded records."""
    q = np.array([r["quality"] for r in kept])
    x = np.array([logit(v) for v in q])
    y = np.array([1.0 if r["outcome"] == "held" else 0.0 for r in kept])
    return x, q, y


def fit(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """(a, b) of P(held) = sigmoid(a + b x): Newton's method with a backtracking line search on
    the log-likelihood (the slope lightly penalised), from the base rate."""
    design = np.stack([np.ones_like(x), x], axis=1)
    penalty = L2 * np.diag([0.0, 1.0])

    def loss(w: np.ndarray) -> float:
        z = design @ w
        return float(np.sum(np.logaddexp(0.0, z) - y * z) + 0.5 * w @ penalty @ w)

    rate = min(max(y.mean(), 1e-3), 1.0 - 1e-3)
    w = np.array([math.log(rate / (1.0 - rate)), 0.0])
    for _ in range(100):
        p = 1.0 / (1.0 + np.exp(-(design @ w)))
        gradient = design.T @ (p - y) + penalty @ w
        hessian = (design.T * (p * (1.0 - p))) @ design + penalty + 1e-9 * np.eye(2)
        step = np.linalg.solve(hessian, gradient)
        t, before = 1.0, loss(w)
        while loss(w - t * step) > before and t > 1e-6:
            t *= 0.5
        w = w - t * step
        if np.abs(t * step).max() < 1e-10:
            break
    return float(w[0]), float(w[1])


def apply(a: float, b: float, x: np.ndarray) -> np.ndarray:
    return 1.0 / (1.0 + np.exp(-(a + b * x)))


def ece(p: np.ndarray, y: np.ndarray) -> float:
    """The report's expected calibration error: bins' |mean p - share held| by their counts
    (a value's bin: the first whose upper end exceeds it, else the last)."""
    bins = np.array([next((i for i, u in enumerate(BINS) if v < u), len(BINS) - 1) for v in p])
    total = 0.0
    for i in range(len(BINS)):
        inside = bins == i
        if inside.any():
            total += inside.sum() / len(p) * abs(p[inside].mean() - y[inside].mean())
    return float(total)


def bucket(key: str) -> int:
    return int(hashlib.sha256(key.encode()).hexdigest(), 16) % FOLDS


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("records", type=Path, nargs="+", help="evaluate's records.jsonl")
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument(
        "--min-grasps", type=int, default=20, help="graded grasps wanted per policy (default 20)"
    )
    parser.add_argument(
        "--planner", choices=sorted(PLANNERS), default="topdown", help="whose quality to map"
    )
    parser.add_argument(
        "--measure",
        type=Path,
        nargs="*",
        default=[],
        help="evaluate records to measure the fitted maps on (not fitted on)",
    )
    args = parser.parse_args()
    rows = read_records(args.records)
    measured = read_records(args.measure) if args.measure else []
    fitted, report = {}, {}
    for source, policy in PLANNERS[args.planner].items():
        kept = graded(rows, policy)
        if len(kept) < max(args.min_grasps, 2):
            sys.exit(
                f"{policy}: {len(kept)} graded grasps in the records, "
                f"{max(args.min_grasps, 2)} at least wanted"
            )
        x, q, y = arrays(kept)
        a, b = fit(x, y)
        folds = np.array([bucket(r["object"]) for r in kept])
        crossed = np.zeros_like(y)
        for k in range(FOLDS):
            held_out = folds == k
            if held_out.any() and (~held_out).any():
                fa, fb = fit(x[~held_out], y[~held_out])
                crossed[held_out] = apply(fa, fb, x[held_out])
        fitted[source] = {"bias": round(a, 6), "slope": round(b, 6)}
        report[source] = {
            "policy": policy,
            "grasps": len(kept),
            "objects": len({r["object"] for r in kept}),
            "held": int(y.sum()),
            "ece_raw": round(ece(q, y), 4),
            "ece_fitted": round(ece(apply(a, b, x), y), 4),
            "ece_cross_validated": round(ece(crossed, y), 4),
        }
        print(f"{policy}: {report[source]} -> P = sigmoid({a:.3f} + {b:.3f} logit(quality))")
        if measured:
            other = graded(measured, policy)
            if other:
                mx, mq, my = arrays(other)
                print(
                    f"  measured on {len(other)} grasps of {len({r['object'] for r in other})} "
                    f"objects ({', '.join(p.name for p in args.measure)}): ECE raw "
                    f"{ece(mq, my):.4f}, mapped {ece(apply(a, b, mx), my):.4f}"
                )
    digest = [
        {"file": p.name, "sha256": hashlib.sha256(p.read_bytes()).hexdigest()} for p in args.records
    ]
    try:
        commit = subprocess.run(
            ["git", "rev-parse", "HEAD"], capture_output=True, text=True, check=True
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        commit = "unknown"
    out = {
        "format": FORMAT,
        "score_floor": SCORE_FLOOR,
        "policies": fitted,
        "training": {
            "data": digest,
            "date": datetime.date.today().isoformat(),
            "commit": commit,
            "development_set": report,
        },
    }
    args.out.write_text(json.dumps(out, indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
