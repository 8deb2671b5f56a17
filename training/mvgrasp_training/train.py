"""Training a GQ-CNN on an mvgrasp grasp dataset.

    python -m mvgrasp_training.train CONFIG.toml --out DIR [--test-dataset DIR]

Object-wise split (``data.val_fraction`` of the objects held out, chosen by the seed), Dex-Net's
flips and optional depth noise, class-balanced loss, Adam, a checkpoint after every epoch
(``DIR/checkpoint.pt``; a rerun resumes from it), the learning curve in ``DIR/history.json``,
and the final network exported for the Rust runtime (``DIR/gqcnn.json`` + ``.safetensors``)
with its validation (and test) figures.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn

from mvgrasp_training.config import ExperimentConfig, load_config
from mvgrasp_training.export import export_gqcnn
from mvgrasp_training.gqcnn import ARCHITECTURES, GQCNN
from mvgrasp_training.grasp_shards import GraspDataset


@dataclass
class Arrays:
    """A dataset held in memory: crops [N, 1, S, S], poses [N, P], labels [N], object ids [N]."""

    depth: np.ndarray
    pose: np.ndarray
    label: np.ndarray
    object_id: np.ndarray

    def subset(self, mask: np.ndarray) -> Arrays:
        return Arrays(self.depth[mask], self.pose[mask], self.label[mask], self.object_id[mask])

    def __len__(self) -> int:
        return len(self.label)


def load_arrays(root: Path, pose_inputs: int) -> Arrays:
    """Every datapoint of the dataset at ``root``."""
    parts: dict[str, list[np.ndarray]] = {"depth": [], "pose": [], "label": [], "object_id": []}
    for shard in GraspDataset.open(root).shards():
        n = len(shard["robust_label"])
        if n == 0:
            continue
        parts["depth"].append(np.asarray(shard["depth_crops"], dtype=np.float32)[:, None])
        pose = [shard["grasp_depth_m"]] + ([shard["theta_rad"]] if pose_inputs == 2 else [])
        parts["pose"].append(np.stack(pose, axis=1).astype(np.float32))
        parts["label"].append(np.asarray(shard["robust_label"], dtype=np.int64))
        parts["object_id"].append(np.asarray(shard["object_id"], dtype=np.int64))
    if not parts["label"]:
        raise ValueError(f"{root}: the dataset has no datapoints")
    return Arrays(*(np.concatenate(parts[k]) for k in ("depth", "pose", "label", "object_id")))


def split_by_object(data: Arrays, val_fraction: float, seed: int) -> tuple[Arrays, Arrays]:
    """Training and validation sets with no object in both."""
    objects = np.unique(data.object_id)
    rng = np.random.default_rng(seed)
    held = rng.choice(objects, size=max(1, round(val_fraction * len(objects))), replace=False)
    val = np.isin(data.object_id, held)
    return data.subset(~val), data.subset(val)


def metrics(prob: np.ndarray, label: np.ndarray) -> dict[str, float]:
    """Balanced accuracy, accuracy, precision and recall at 0.5 (NaN where undefined)."""
    pred = prob > 0.5
    pos, neg = label == 1, label == 0
    tp, fp = int((pred & pos).sum()), int((pred & neg).sum())
    tn, fn = int((~pred & neg).sum()), int((~pred & pos).sum())
    tpr = tp / max(tp + fn, 1)
    tnr = tn / max(tn + fp, 1)
    return {
        "balanced_accuracy": (tpr + tnr) / 2,
        "accuracy": (tp + tn) / max(len(label), 1),
        "precision": tp / (tp + fp) if tp + fp else float("nan"),
        "recall": tpr,
        "positives": int(pos.sum()),
        "count": int(len(label)),
    }


@torch.no_grad()
def predict(net: GQCNN, data: Arrays, batch: int = 1024) -> np.ndarray:
    net.eval()
    out = []
    for i in range(0, len(data), batch):
        depth = torch.from_numpy(data.depth[i : i + batch])
        pose = torch.from_numpy(data.pose[i : i + batch])
        out.append(torch.softmax(net(depth, pose), dim=1)[:, 1].numpy())
    return np.concatenate(out) if out else np.zeros(0, dtype=np.float32)


def augment(depth: torch.Tensor, gen: torch.Generator, config: ExperimentConfig) -> torch.Tensor:
    if config.train.flip_augment:
        flip_h = torch.rand(len(depth), generator=gen) < 0.5
        flip_v = torch.rand(len(depth), generator=gen) < 0.5
        depth = torch.where(flip_h[:, None, None, None], depth.flip(3), depth)
        depth = torch.where(flip_v[:, None, None, None], depth.flip(2), depth)
    sigma = config.train.noise_sigma_m
    if sigma > 0:
        seen = depth > 0
        depth = torch.where(seen, depth + sigma * torch.randn(depth.shape, generator=gen), depth)
    return depth


def train(config: ExperimentConfig, out: Path, test_dir: Path | None = None) -> dict[str, Any]:
    """Runs (or resumes) the experiment; returns the report written beside the weights."""
    out.mkdir(parents=True, exist_ok=True)
    if config.train.threads:
        torch.set_num_threads(config.train.threads)
    torch.manual_seed(config.seed)
    pose_inputs = config.model.pose_inputs
    data = load_arrays(config.data.dataset_dir, pose_inputs)
    train_set, val_set = split_by_object(data, config.data.val_fraction, config.seed)
    net = GQCNN(ARCHITECTURES[config.model.architecture](pose_inputs=pose_inputs))
    seen = train_set.depth[train_set.depth > 0]
    net.set_normalisation(
        float(seen.mean()),
        float(seen.std()),
        torch.from_numpy(train_set.pose.mean(axis=0)),
        torch.from_numpy(train_set.pose.std(axis=0)),
    )
    optimiser = torch.optim.Adam(
        net.parameters(), lr=config.train.learning_rate, weight_decay=config.train.weight_decay
    )
    positive_rate = float(train_set.label.mean())
    weight = (
        torch.tensor([0.5 / max(1 - positive_rate, 1e-6), 0.5 / max(positive_rate, 1e-6)])
        if config.train.balance_classes
        else None
    )
    loss_fn = nn.CrossEntropyLoss(weight=weight)
    checkpoint = out / "checkpoint.pt"
    history: list[dict[str, Any]] = []
    start_epoch = 0
    if checkpoint.exists():
        state = torch.load(checkpoint, weights_only=False)
        net.load_state_dict(state["net"])
        optimiser.load_state_dict(state["optimiser"])
        history, start_epoch = state["history"], state["epoch"]
        print(f"resuming after epoch {start_epoch}", file=sys.stderr)
    gen = torch.Generator().manual_seed(config.seed)
    depth_all = torch.from_numpy(train_set.depth)
    pose_all = torch.from_numpy(train_set.pose)
    label_all = torch.from_numpy(train_set.label)
    n, batch = len(train_set), config.train.batch_size
    for epoch in range(start_epoch, config.train.epochs):
        gen.manual_seed(config.seed * 1000 + epoch)
        net.train()
        order = torch.randperm(n, generator=gen)
        started, total = time.time(), 0.0
        steps = max(1, (n + batch - 1) // batch)
        for step in range(steps):
            idx = order[step * batch : (step + 1) * batch]
            depth = augment(depth_all[idx], gen, config)
            loss = loss_fn(net(depth, pose_all[idx]), label_all[idx])
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            total += loss.item()
            if step % 50 == 0 or step == steps - 1:
                rate = (step + 1) * batch / max(time.time() - started, 1e-9)
                left = (steps - step - 1) * batch / max(rate, 1e-9)
                print(
                    f"\repoch {epoch + 1}/{config.train.epochs} step {step + 1}/{steps} "
                    f"loss {total / (step + 1):.4f} {rate:.0f} crops/s {left:.0f} s left",
                    end="",
                    file=sys.stderr,
                )
        val = metrics(predict(net, val_set), val_set.label)
        history.append({"epoch": epoch + 1, "loss": total / steps, "val": val})
        print(f"\nepoch {epoch + 1}: val {json.dumps(val)}", file=sys.stderr)
        torch.save(
            {"net": net.state_dict(), "optimiser": optimiser.state_dict(),
             "history": history, "epoch": epoch + 1},
            checkpoint,
        )
    report: dict[str, Any] = {
        "config": json.loads(json.dumps(asdict(config), default=str)),
        "dataset": str(config.data.dataset_dir),
        "train_count": len(train_set),
        "train_objects": int(len(np.unique(train_set.object_id))),
        "val": metrics(predict(net, val_set), val_set.label),
        "val_objects": int(len(np.unique(val_set.object_id))),
        "history": history,
        "date": time.strftime("%Y-%m-%d"),
    }
    if test_dir is not None:
        test = load_arrays(test_dir, pose_inputs)
        report["test"] = metrics(predict(net, test), test.label)
        report["test_dataset"] = str(test_dir)
    (out / "history.json").write_text(json.dumps(history, indent=2) + "\n")
    export_gqcnn(net, out / "gqcnn", report)
    return report


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("config")
    parser.add_argument("--out", required=True, type=Path)
    parser.add_argument("--test-dataset", type=Path)
    args = parser.parse_args(argv)
    report = train(load_config(args.config), args.out, args.test_dataset)
    print(json.dumps({k: report[k] for k in ("val", "test") if k in report}, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
