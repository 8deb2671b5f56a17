"""Scores an exported GQ-CNN on grasp datasets.

    python -m mvgrasp_training.evaluate MODEL.json DATASET [DATASET ...] [--held-out F --seed S]

Prints, per dataset, the balanced accuracy, accuracy, precision and recall of the robust label
(or with ``--label`` the physics label or both) at 0.5 as JSON, precision and recall at the
stricter thresholds a planner that takes only confident grasps uses (0.8, 0.9), and what a
planner that takes the top of each object's ranking gets: the precision of each object's
top-1 and top-10 scored datapoints, averaged over the objects (``top1_precision``,
``top10_precision``). With ``--held-out F --seed S`` only the objects a training
config with ``val_fraction = F`` and ``seed = S`` holds out are scored (the validation objects of
that run: a network trained with that config never saw them). The network takes what its pose stream takes from each datapoint: the grasp
depth, and theta for a multi-view GQ-CNN; a top-down GQ-CNN applied to a multi-view dataset
sees each crop with its depth alone (the paper's reason for the multi-view GQ-CNN).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

from mvgrasp_training.config import LABELS
from mvgrasp_training.export import load_gqcnn
from mvgrasp_training.train import load_arrays, metrics, predict, split_by_object


def evaluate(
    model: str | Path,
    datasets: list[str | Path],
    held_out: tuple[float, int] | None = None,
    label: str = "robust",
) -> dict[str, dict[str, Any]]:
    """The metrics of the export at ``model`` on each dataset against ``label`` (see
    ``DataConfig.label``), keyed by the dataset's path; ``held_out = (val_fraction, seed)``
    scores only the objects such a split holds out."""
    net, _ = load_gqcnn(model)
    results = {}
    for root in datasets:
        data = load_arrays(Path(root), net.arch.pose_inputs, label)
        if held_out is not None:
            data = split_by_object(data, *held_out)[1]
        prob = predict(net, data)
        result = metrics(prob, data.label)
        for threshold in (0.8, 0.9):
            above = prob > threshold
            positive = data.label == 1
            result[f"precision_at_{threshold}"] = (
                float((above & positive).sum() / above.sum()) if above.any() else float("nan")
            )
            result[f"recall_at_{threshold}"] = float((above & positive).sum() / max(positive.sum(), 1))
        for k in (1, 10):
            result[f"top{k}_precision"] = top_k_precision(prob, data.label, data.object_id, k)
        results[str(root)] = result
    return results


def top_k_precision(prob: np.ndarray, label: np.ndarray, object_id: np.ndarray, k: int) -> float:
    """The share of positives among each object's ``k`` best-scored datapoints (all of them for
    an object with fewer), averaged over the objects; ties keep the datasets' order."""
    shares = []
    for obj in np.unique(object_id):
        mine = np.flatnonzero(object_id == obj)
        best = mine[np.argsort(-prob[mine], kind="stable")[:k]]
        shares.append(float((label[best] == 1).mean()))
    return float(np.mean(shares)) if shares else float("nan")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("model", type=Path, help="an export's JSON (NAME.json)")
    parser.add_argument("datasets", type=Path, nargs="+", help="grasp_dataset output folders")
    parser.add_argument("--held-out", type=float, help="score only this split's held-out objects")
    parser.add_argument("--seed", type=int, default=0, help="the split's seed (with --held-out)")
    parser.add_argument(
        "--label", choices=LABELS, default="robust", help="the label scored against"
    )
    args = parser.parse_args(argv)
    held_out = None if args.held_out is None else (args.held_out, args.seed)
    print(json.dumps(evaluate(args.model, args.datasets, held_out, args.label), indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
