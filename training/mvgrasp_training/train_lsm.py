"""Training the depth Learnt Stereo Machine on an mvgrasp RGB-D dataset (``render`` output).

    python -m mvgrasp_training.train_lsm CONFIG.toml --out DIR [--export models/NAME]
    torchrun --standalone --nproc_per_node 2 -m mvgrasp_training.train_lsm CONFIG.toml --out DIR

The dataset is read through the wheel (``mvgrasp.read_rgbd_folder``: the Rust readers of
``plan --rgb``). Every object's training and test views are held in memory at the
architecture's resolution (images area-averaged, depth and masks by nearest pixel, the cameras'
``K`` scaled to match). A sample is one object and ``views_per_sample`` of its views from one
split (colours are consistent within a split, not across): from the test split its top-down
view (the first) and random others, as the seed paper trains; from the training split random
views. Objects are split object-wise (``data.val_fraction`` held out, by the seed). The loss is
L1 on depth over the pixels whose true depth lies inside the grid's depth range, in every input
view. Adam; a checkpoint after every epoch (``DIR/checkpoint.pt``; a rerun resumes from it), the
weights of the epoch with the lowest validation error on the object pixels kept
(``DIR/best.pt``), and the learning curve in ``DIR/history.json``. Checkpoints are written to
a ``.partial`` file first and renamed, so an interrupted run loses at most the epoch it was in.
``--export`` writes the best weights for the Rust runtime (``export_lsm``: ``NAME.json`` and
``NAME.safetensors``) with the training report in the JSON (config, dataset, code commit, torch
version, selected epoch, validation figures, history); a finished run only exports.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import mvgrasp
import numpy as np
import torch
from torch import distributed as dist
from torch import nn
from torch.nn import functional as F

from mvgrasp_training._files import (
    check_resumable,
    checkpoint_identity,
    save_atomically,
    write_text_atomically,
)
from mvgrasp_training.config import LsmExperimentConfig, load_config
from mvgrasp_training.export import export_lsm
from mvgrasp_training.lsm import LSM, LsmArchitecture, grid_centre, ray_depths, scale_intrinsics
from mvgrasp_training.plots import plot_lsm_history
from mvgrasp_training.train import depth_training_report, distributed_world


@dataclass
class Split:
    """One object's views of one split, at the architecture's resolution."""

    rgb: torch.Tensor  # (V, 3, H, W) in [0, 1]
    depth: torch.Tensor  # (V, H, W) metres, 0: nothing
    mask: torch.Tensor  # (V, H, W) bool, the object's pixels
    k: torch.Tensor  # (V, 3, 3)
    camera_from_world: torch.Tensor  # (V, 4, 4)
    top_down_first: bool


def load_split(folder: Path, arch: LsmArchitecture) -> Split:
    """One dataset folder through the wheel, resized for ``arch``."""
    data = mvgrasp.read_rgbd_folder(folder)
    rgb = torch.from_numpy(data["rgb"]).permute(0, 3, 1, 2).float() / 255.0
    h, w = rgb.shape[-2:]
    size = (arch.image_height, arch.image_width)
    rgb = F.interpolate(rgb, size=size, mode="area")
    depth = F.interpolate(torch.from_numpy(data["depth"])[:, None], size=size, mode="nearest")[:, 0]
    mask = data["mask"]
    mask = (
        torch.ones_like(depth, dtype=torch.bool)
        if mask is None
        else F.interpolate(torch.from_numpy(mask)[:, None].float(), size=size, mode="nearest")[
            :, 0
        ].bool()
    )
    k = scale_intrinsics(torch.from_numpy(data["k"]), arch.image_width / w, arch.image_height / h)
    camera_from_world = torch.linalg.inv(torch.from_numpy(data["world_from_camera"]))
    return Split(rgb, depth, mask, k.float(), camera_from_world.float(), folder.name == "test")


def load_dataset(root: Path, arch: LsmArchitecture) -> list[tuple[str, list[Split]]]:
    """Every object of a ``render`` dataset: (name, [its splits])."""
    manifest = json.loads((root / "dataset.json").read_text())
    objects = []
    for name in manifest["objects"]:
        splits = [load_split(root / name / split, arch) for split in ("train", "test")]
        objects.append((name, splits))
    return objects


def draw(splits: list[Split], views: int, rng: np.random.Generator) -> tuple[torch.Tensor, ...]:
    """One input: a split of the object, its top-down view (test split) and random others."""
    split = splits[rng.integers(len(splits))]
    count = split.rgb.shape[0]
    if split.top_down_first:
        chosen = [0, *(1 + rng.choice(count - 1, size=views - 1, replace=False))]
    else:
        chosen = list(rng.choice(count, size=views, replace=False))
    index = torch.tensor(chosen)
    return (
        split.rgb[index],
        split.depth[index],
        split.mask[index],
        split.k[index],
        split.camera_from_world[index],
    )


def batch(
    objects: list[tuple[str, list[Split]]], size: int, views: int, rng: np.random.Generator
) -> tuple[torch.Tensor, ...]:
    drawn = [draw(objects[rng.integers(len(objects))][1], views, rng) for _ in range(size)]
    return tuple(torch.stack(parts) for parts in zip(*drawn, strict=True))


def valid_pixels(
    depth: torch.Tensor, camera_from_world: torch.Tensor, arch: LsmArchitecture
) -> torch.Tensor:
    """Pixels whose true depth lies inside the grid's depth range (B, V, H, W)."""
    b, v = depth.shape[:2]
    flat = camera_from_world.reshape(b * v, 4, 4)
    centre = grid_centre(camera_from_world).repeat_interleave(v, dim=0)
    depths, _ = ray_depths(flat, centre, arch.grid_side_m, 2)
    lo, hi = depths[:, 0].reshape(b, v, 1, 1), depths[:, 1].reshape(b, v, 1, 1)
    return (depth > lo) & (depth < hi)


def evaluate(
    net: LSM, objects: list[tuple[str, list[Split]]], views: int, seed: int
) -> dict[str, float]:
    """Mean absolute depth error on the object pixels and on all valid pixels, millimetres,
    over a fixed draw of inputs (the same for every epoch)."""
    rng = np.random.default_rng(seed)
    errors = {"object_mm": [0.0, 0], "all_mm": [0.0, 0]}
    net.eval()
    with torch.no_grad():
        for _ in range(max(len(objects), 1) * 2):
            rgb, depth, mask, k, pose = batch(objects, 1, views, rng)
            predicted = net(rgb, k, pose)
            valid = valid_pixels(depth, pose, net.arch)
            error = (predicted - depth).abs() * 1e3
            for key, where in (("object_mm", valid & mask), ("all_mm", valid)):
                errors[key][0] += float(error[where].sum())
                errors[key][1] += int(where.sum())
    net.train()
    return {key: total / max(count, 1) for key, (total, count) in errors.items()}


def export_best(config: LsmExperimentConfig, out: Path, stem: Path) -> Path:
    """The run's best weights (``out/best.pt``) exported for the Rust runtime, with the training
    report in the JSON; the learning curve drawn to ``out/learning_curve.png``."""
    best = torch.load(out / "best.pt", weights_only=False)
    history = json.loads((out / "history.json").read_text())
    net = LSM(LsmArchitecture(**best["arch"]))
    net.load_state_dict(best["model"])
    report = depth_training_report(config, history, best["epoch"], keep=lambda k: k.endswith("_mm"))
    plot_lsm_history(history, out / "learning_curve.png", title=config.name)
    return export_lsm(net, stem, report)


def train(config: LsmExperimentConfig, out: Path, log=print) -> dict[str, float]:
    """Trains (resuming from ``out/checkpoint.pt`` when there is one); the best validation
    figures. Under torchrun every process calls this (DistributedDataParallel on gloo, the
    CPU's backend): each draws the same global batch and runs its share of the samples, the
    loss normalised by the global batch's pixel count, so two processes train the weights one
    does; process 0 writes the files."""
    rank, world = distributed_world()
    joined = world > 1 and not dist.is_initialized()
    if joined:
        dist.init_process_group("gloo")
    try:
        return _train(config, out, log, rank, world)
    finally:
        if joined:
            dist.destroy_process_group()


def _train(config: LsmExperimentConfig, out: Path, log, rank: int, world: int) -> dict[str, float]:
    lead = rank == 0
    if not lead:
        log = lambda _line: None
    out.mkdir(parents=True, exist_ok=True)
    if config.train.threads:
        torch.set_num_threads(config.train.threads)
    arch = config.model.architecture()
    objects = load_dataset(config.data.dataset_dir, arch)
    rng = np.random.default_rng(config.seed)
    order = rng.permutation(len(objects))
    held = max(1, round(config.data.val_fraction * len(objects))) if config.data.val_fraction else 0
    val = [objects[i] for i in order[:held]]
    train_objects = [objects[i] for i in order[held:]]
    torch.manual_seed(config.seed)
    net = LSM(arch)
    optimiser = torch.optim.Adam(net.parameters(), lr=config.train.learning_rate)
    history: list[dict[str, float]] = []
    start_epoch = 0
    best = float("inf")
    checkpoint = out / "checkpoint.pt"
    if checkpoint.is_file():
        state = torch.load(checkpoint, weights_only=False)
        check_resumable(state, config, checkpoint)
        net.load_state_dict(state["model"])
        optimiser.load_state_dict(state["optimiser"])
        history = state["history"]
        start_epoch = state["epoch"] + 1
        best = state["best"]
        log(f"resumed after epoch {start_epoch}")
    model = nn.parallel.DistributedDataParallel(net) if world > 1 else net
    mine = slice(rank, None, world)
    views = config.data.views_per_sample
    steps = max(1, config.train.samples_per_epoch // config.train.batch_size)
    for epoch in range(start_epoch, config.train.epochs):
        started = time.time()
        for group in optimiser.param_groups:
            group["lr"] = config.train.learning_rate_at(epoch)
        epoch_rng = np.random.default_rng([config.seed, epoch])
        total = 0.0
        for _ in range(steps):
            rgb, depth, _mask, k, pose = batch(
                train_objects, config.train.batch_size, views, epoch_rng
            )
            valid = valid_pixels(depth, pose, arch)
            error = (model(rgb[mine], k[mine], pose[mine]) - depth[mine]).abs()[valid[mine]]
            if world == 1:
                loss = error.mean()
            else:
                # DDP averages gradients over processes: scaled by `world`, the average is the
                # gradient of the global batch's mean.
                loss = error.sum() / valid.sum().clamp(min=1) * world
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            total += loss.item() / world
        if world > 1:
            summed = torch.tensor([total], dtype=torch.float64)
            dist.all_reduce(summed)
            total = float(summed[0])
        figures = evaluate(net, val, views, config.seed) if val else {}
        record = {"epoch": epoch, "train_l1_mm": 1e3 * total / steps, **figures}
        record["seconds"] = time.time() - started
        history.append(record)
        log(json.dumps(record))
        score = figures.get("object_mm", record["train_l1_mm"])
        improved = score < best
        best = min(best, score)
        if not lead:
            continue
        if improved:
            state = {"model": net.state_dict(), "arch": asdict(arch), "epoch": epoch}
            save_atomically(state, out / "best.pt")
        save_atomically(
            {
                "model": net.state_dict(),
                "optimiser": optimiser.state_dict(),
                "history": history,
                "epoch": epoch,
                "best": best,
                "identity": checkpoint_identity(config),
            },
            checkpoint,
        )
        write_text_atomically(out / "history.json", json.dumps(history, indent=2) + "\n")
    if lead:
        # Again after the loop: a run killed between the checkpoint and this file resumes
        # with no epoch left, and must still leave the whole history.
        write_text_atomically(out / "history.json", json.dumps(history, indent=2) + "\n")
    if world > 1:
        dist.barrier()
    return {"best_object_mm": best, "epochs": len(history)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("config", type=Path)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument(
        "--export", type=Path, help="write the best weights as EXPORT.json/.safetensors"
    )
    args = parser.parse_args(argv)
    config = load_config(args.config, LsmExperimentConfig)
    result = train(config, args.out, log=lambda line: print(line, flush=True))
    if distributed_world()[0] != 0:
        return 0
    print(json.dumps(result))
    if args.export is not None:
        print(f"exported {export_best(config, args.out, args.export)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
