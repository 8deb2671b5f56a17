"""Training a GQ-CNN on an mvgrasp grasp dataset.

    python -m mvgrasp_training.train CONFIG.toml --out DIR [--test-dataset DIR]
    torchrun --standalone --nproc_per_node 2 -m mvgrasp_training.train CONFIG.toml --out DIR

Object-wise split (``data.val_fraction`` of the objects held out, chosen by the seed), Dex-Net's
flips (both together: the 180-degree rotation) and optional depth noise, class-balanced loss,
Adam with a per-epoch step-size decay, a checkpoint after every epoch (``DIR/checkpoint.pt``; a
rerun resumes from it), the weights of the epoch with the best validation balanced accuracy
kept (early stopping on the held-out objects; the test split never chooses), the learning curve in ``DIR/history.json`` and ``DIR/learning_curve.png``,
and the final network exported for the Rust runtime (``DIR/NAME.json`` + ``.safetensors``, NAME
the config's name)
with its validation (and test) figures.

Under ``torchrun`` (``WORLD_SIZE`` > 1) the run is data-parallel with torch's
DistributedDataParallel on the gloo backend (CPU): every process draws the same global batch
and takes every ``WORLD_SIZE``-th sample of it, and the loss is normalised by the global batch,
so the averaged gradient is the single-process gradient; process 0 validates, checkpoints and
exports.
"""

from __future__ import annotations

import argparse
import copy
import hashlib
import json
import os
import subprocess
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch
import torch.distributed as dist
from torch import nn
from torch.nn import functional as F

from mvgrasp_training._files import (
    check_resumable,
    checkpoint_identity,
    save_atomically,
    write_text_atomically,
)
from mvgrasp_training.config import ExperimentConfig, load_config
from mvgrasp_training.export import export_gqcnn
from mvgrasp_training.gqcnn import ARCHITECTURES, GQCNN
from mvgrasp_training.grasp_shards import GraspDataset
from mvgrasp_training.plots import plot_history


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


def shard_labels(shard: dict[str, np.ndarray], label: str, where: str) -> np.ndarray:
    """A shard's training labels (see ``DataConfig.label``) as int64, -1 where a datapoint has
    none (collision-free but without physics trials)."""
    robust = np.asarray(shard["robust_label"], dtype=np.int64)
    if label == "robust":
        return robust
    # Shards made before physics labels hold one unperturbed trial in `physics` and no rate.
    if "physics_rate" not in shard:
        raise ValueError(f"{where}: the dataset has no physics labels (made before them)")
    physics = np.asarray(shard["physics"], dtype=np.int64)
    free = np.asarray(shard["collision_free"], dtype=bool)
    # A colliding approach fails the trial's approach: a physics negative.
    physics = np.where(free, physics, 0)
    if label == "physics":
        return physics
    return np.where(physics < 0, -1, robust & physics)


def load_arrays(root: Path, pose_inputs: int, label: str = "robust") -> Arrays:
    """Every datapoint of the dataset at ``root`` that has the ``label`` asked for."""
    parts: dict[str, list[np.ndarray]] = {"depth": [], "pose": [], "label": [], "object_id": []}
    for shard in GraspDataset.open(root).shards():
        n = len(shard["robust_label"])
        if n == 0:
            continue
        labels = shard_labels(shard, label, str(root))
        keep = labels >= 0
        parts["depth"].append(np.asarray(shard["depth_crops"], dtype=np.float32)[keep, None])
        pose = [shard["grasp_depth_m"]] + ([shard["theta_rad"]] if pose_inputs == 2 else [])
        parts["pose"].append(np.stack(pose, axis=1).astype(np.float32)[keep])
        parts["label"].append(labels[keep])
        parts["object_id"].append(np.asarray(shard["object_id"], dtype=np.int64)[keep])
    if not parts["label"] or sum(len(x) for x in parts["label"]) == 0:
        raise ValueError(f"{root}: the dataset has no datapoints with {label} labels")
    return Arrays(*(np.concatenate(parts[k]) for k in ("depth", "pose", "label", "object_id")))


REPO_ROOT = Path(__file__).resolve().parents[2]


def dataset_record(root: Path) -> dict[str, Any]:
    """How the export names a dataset: its folder relative to the repository (no absolute path
    of the machine it was trained on) and the SHA-256 of its manifest."""
    manifest = Path(root) / "dataset.json"
    return {
        "path": os.path.relpath(Path(root).resolve(), REPO_ROOT),
        "manifest_sha256": hashlib.sha256(manifest.read_bytes()).hexdigest(),
    }


def depth_training_report(
    config: Any, history: list[dict[str, Any]], epoch: int, keep=lambda key: True
) -> dict[str, Any]:
    """What a depth network's export records about its training: the config (its dataset as
    :func:`dataset_record` names it), the dataset, the code's commit, torch's version, the
    selected ``epoch`` and its validation figures (the history's keys that ``keep`` accepts,
    never the epoch or its seconds), the whole history and the date."""
    dataset = dataset_record(config.data.dataset_dir)
    recorded_config = json.loads(json.dumps(asdict(config), default=str))
    recorded_config["data"]["dataset_dir"] = dataset["path"]
    selected = next(record for record in history if record["epoch"] == epoch)
    return {
        "config": recorded_config,
        "dataset": dataset,
        "code_commit": code_commit(),
        "torch": torch.__version__,
        "selected_epoch": epoch,
        "val": {
            k: v for k, v in selected.items() if k not in ("epoch", "seconds") and keep(k)
        },
        "history": history,
        "date": time.strftime("%Y-%m-%d"),
    }


def code_commit() -> str:
    """The repository's commit (with ``-dirty`` when the tree has changes), or ``unknown``."""

    def git(*args: str) -> str:
        return subprocess.run(
            ["git", "-C", str(REPO_ROOT), *args], capture_output=True, text=True, check=True
        ).stdout.strip()

    try:
        commit = git("rev-parse", "HEAD")
        return commit + ("-dirty" if git("status", "--porcelain", "--untracked-files=no") else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def input_contract(root: Path, train_set: Arrays, pose_inputs: int) -> dict[str, Any]:
    """What the network will expect of its inputs, from the dataset's manifest and crops: the
    crop window and side, the training camera's focal length, the camera distances, the ranges
    of the pose inputs, and their order (the Rust planner scales crops to other cameras by it).
    """
    manifest = GraspDataset.open(root).manifest
    config = manifest["config"]
    contract: dict[str, Any] = {
        "crop_window_px": int(config["crop"]["window_px"]),
        "crop_size_px": int(config["crop"]["size_px"]),
        "focal_px": float(manifest["intrinsics"]["fx"]),
        "camera_distance_m": [float(v) for v in config["cameras"]["radius_m"]],
        "grasp_depth_m": [float(train_set.pose[:, 0].min()), float(train_set.pose[:, 0].max())],
        "pose_inputs": ["grasp_depth_m", "theta_rad"][:pose_inputs],
    }
    if pose_inputs == 2:
        theta = train_set.pose[:, 1]
        contract["theta_rad"] = [float(theta.min()), float(theta.max())]
    return contract


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


def _best_accuracy(history: list[dict[str, Any]], best: dict[str, Any]) -> float:
    return float(history[best["epoch"] - 1]["val"]["balanced_accuracy"])


def distributed_world() -> tuple[int, int]:
    """This process's rank and the number of processes (torchrun's environment; 0, 1 alone)."""
    return int(os.environ.get("RANK", "0")), int(os.environ.get("WORLD_SIZE", "1"))


def train(config: ExperimentConfig, out: Path, test_dir: Path | None = None) -> dict[str, Any]:
    """Runs (or resumes) the experiment; returns the report written beside the weights.

    Under torchrun every process calls this; process 0 writes the files.
    """
    rank, world = distributed_world()
    joined = world > 1 and not dist.is_initialized()
    if joined:
        dist.init_process_group("gloo")
    try:
        return _train(config, out, test_dir, rank, world)
    finally:
        if joined:
            dist.destroy_process_group()


def _train(
    config: ExperimentConfig, out: Path, test_dir: Path | None, rank: int, world: int
) -> dict[str, Any]:
    lead = rank == 0
    out.mkdir(parents=True, exist_ok=True)
    if config.train.threads:
        torch.set_num_threads(config.train.threads)
    torch.manual_seed(config.seed)
    pose_inputs = config.model.pose_inputs
    data = load_arrays(config.data.dataset_dir, pose_inputs, config.data.label)
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
    class_weight = (
        torch.tensor([0.5 / max(1 - positive_rate, 1e-6), 0.5 / max(positive_rate, 1e-6)])
        if config.train.balance_classes
        else torch.ones(2)
    )
    checkpoint = out / "checkpoint.pt"
    history: list[dict[str, Any]] = []
    start_epoch = 0
    # The weights of the epoch with the best validation balanced accuracy: what is exported.
    best: dict[str, Any] = {"epoch": 0, "net": None}
    if checkpoint.exists():
        state = torch.load(checkpoint, weights_only=False)
        check_resumable(state, config, checkpoint)
        net.load_state_dict(state["net"])
        optimiser.load_state_dict(state["optimiser"])
        history, start_epoch, best = state["history"], state["epoch"], state["best"]
        if lead:
            print(f"resuming after epoch {start_epoch}", file=sys.stderr)
    model: nn.Module = net
    if world > 1:
        model = nn.parallel.DistributedDataParallel(net)
    gen = torch.Generator().manual_seed(config.seed)
    depth_all = torch.from_numpy(train_set.depth)
    pose_all = torch.from_numpy(train_set.pose)
    label_all = torch.from_numpy(train_set.label)
    n, batch = len(train_set), config.train.batch_size
    # A last partial batch too small to give every process a sample is dropped.
    steps = max(1, n // batch + (1 if n % batch >= world else 0))
    mine = slice(rank, None, world)
    for epoch in range(start_epoch, config.train.epochs):
        gen.manual_seed(config.seed * 1000 + epoch)
        for group in optimiser.param_groups:
            group["lr"] = config.train.learning_rate * config.train.learning_rate_decay**epoch
        model.train()
        order = torch.randperm(n, generator=gen)
        started, total = time.time(), 0.0
        for step in range(steps):
            idx = order[step * batch : (step + 1) * batch]
            # Every process draws the whole batch's augmentation, so the random stream (and
            # the result) does not depend on the number of processes.
            depth = augment(depth_all[idx], gen, config)
            label = label_all[idx]
            weight = class_weight[label]
            per_sample = F.cross_entropy(model(depth[mine], pose_all[idx][mine]), label[mine],
                                         reduction="none")
            # DDP averages gradients over processes: scaled by `world`, the average is the
            # gradient of the weighted mean over the global batch.
            loss = (weight[mine] * per_sample).sum() / weight.sum() * world
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            total += loss.item() / world
            if lead and (step % 50 == 0 or step == steps - 1):
                rate = (step + 1) * batch / max(time.time() - started, 1e-9)
                left = (steps - step - 1) * batch / max(rate, 1e-9)
                print(
                    f"\repoch {epoch + 1}/{config.train.epochs} step {step + 1}/{steps} "
                    f"loss {total * world / (step + 1):.4f} {rate:.0f} crops/s {left:.0f} s left",
                    end="",
                    file=sys.stderr,
                )
        if world > 1:
            summed = torch.tensor([total], dtype=torch.float64)
            dist.all_reduce(summed)
            total = float(summed.item())
        if lead:
            val = metrics(predict(net, val_set), val_set.label)
            history.append({"epoch": epoch + 1, "loss": total / steps, "val": val})
            print(f"\nepoch {epoch + 1}: val {json.dumps(val)}", file=sys.stderr)
            if best["net"] is None or val["balanced_accuracy"] > _best_accuracy(history, best):
                best = {"epoch": epoch + 1, "net": copy.deepcopy(net.state_dict())}
            state = {"net": net.state_dict(), "optimiser": optimiser.state_dict(),
                     "history": history, "epoch": epoch + 1, "best": best,
                     "identity": checkpoint_identity(config)}
            save_atomically(state, checkpoint)
        if world > 1:
            dist.barrier()
    dataset = dataset_record(config.data.dataset_dir)
    recorded_config = json.loads(json.dumps(asdict(config), default=str))
    recorded_config["data"]["dataset_dir"] = dataset["path"]
    report: dict[str, Any] = {
        "config": recorded_config,
        "dataset": dataset,
        "code_commit": code_commit(),
        "torch": torch.__version__,
        "train_count": len(train_set),
        "train_objects": int(len(np.unique(train_set.object_id))),
        "val_objects": int(len(np.unique(val_set.object_id))),
        "processes": world,
        "date": time.strftime("%Y-%m-%d"),
    }
    if not lead:
        return report
    if best["net"] is not None:
        net.load_state_dict(best["net"])
    report["selected_epoch"] = best["epoch"]
    report["val"] = metrics(predict(net, val_set), val_set.label)
    report["history"] = history
    if test_dir is not None:
        test = load_arrays(test_dir, pose_inputs, config.data.label)
        report["test"] = metrics(predict(net, test), test.label)
        report["test_dataset"] = dataset_record(test_dir)
    write_text_atomically(out / "history.json", json.dumps(history, indent=2) + "\n")
    plot_history(history, out / "learning_curve.png", title=config.name)
    export_gqcnn(
        net,
        out / config.name,
        report,
        input_contract(config.data.dataset_dir, train_set, pose_inputs),
    )
    return report


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("config")
    parser.add_argument("--out", required=True, type=Path)
    parser.add_argument("--test-dataset", type=Path)
    args = parser.parse_args(argv)
    report = train(load_config(args.config), args.out, args.test_dataset)
    if "val" in report:
        print(json.dumps({k: report[k] for k in ("val", "test") if k in report}, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
