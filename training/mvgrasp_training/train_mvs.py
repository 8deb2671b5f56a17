"""Training the multi-view stereo network (:mod:`mvgrasp_training.mvs`) on an mvgrasp RGB-D
dataset (``render`` output).

    python -m mvgrasp_training.train_mvs CONFIG.toml --out DIR [--export models/NAME]

The dataset is read and split as the LSM's training reads it (``train_lsm.load_dataset``,
object-wise split by the seed). A batch draws its view count from ``data.min_views`` to
``data.max_views``; each sample is one object and that many views of one split (the test
split's top-down view first). What the network is given is disturbed as cameras disturb it:
each view's colour channels get a gain and an offset (``data.colour_jitter``) and Gaussian
noise (``data.noise_std``), and each camera's pose given to the network is moved by up to
``data.pose_noise_m`` and ``data.pose_noise_rad`` (calibration error), while the true depth
stays the truth. Two views a sample are reference views (the first and one other); the loss is
the L1 depth error (centimetres) of the coarse (1/4), fine (1/2) and refined (full) depths,
weights 0.5, 1 and 2, plus the cross-entropy of the coarse logits against the hypothesis
nearest the true depth, over the pixels whose true depth lies inside the pixel's workspace
range, an object pixel weighing ``1 + data.object_weight``.

Checkpoints, resumption, the best epoch by the validation error on the object pixels (at the
network's resolution, ``data.val_views`` views), the history and the export follow
``train_lsm`` (``checkpoint.pt``, ``best.pt``, ``history.json``, atomic writes).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import asdict
from pathlib import Path

import numpy as np
import torch
from torch.nn import functional as F

from mvgrasp_training._files import (
    check_resumable,
    checkpoint_identity,
    save_atomically,
    write_text_atomically,
)
from mvgrasp_training.config import MvsExperimentConfig, load_config
from mvgrasp_training.export import export_mvs
from mvgrasp_training.lsm import grid_centre, scale_intrinsics
from mvgrasp_training.mvs import MVS, MvsArchitecture, MvsOutput, depth_range
from mvgrasp_training.plots import plot_lsm_history
from mvgrasp_training.train import depth_training_report
from mvgrasp_training.train_lsm import batch, load_dataset

# The loss weights of the coarse, fine and refined depths.
STAGE_WEIGHTS = (0.5, 1.0, 2.0)


def rotation_about(axis: torch.Tensor, angle: torch.Tensor) -> torch.Tensor:
    """Rodrigues: rotations (N, 3, 3) by ``angle`` (N,) about unit ``axis`` (N, 3)."""
    x, y, z = axis.unbind(-1)
    zero = torch.zeros_like(x)
    cross = torch.stack([zero, -z, y, z, zero, -x, -y, x, zero], dim=-1).reshape(-1, 3, 3)
    eye = torch.eye(3, dtype=axis.dtype).expand_as(cross)
    s, c = angle.sin()[:, None, None], angle.cos()[:, None, None]
    return eye + s * cross + (1 - c) * (cross @ cross)


def disturb(
    rgb: torch.Tensor,
    pose: torch.Tensor,
    data,  # MvsDataConfig
    generator: torch.Generator,
) -> tuple[torch.Tensor, torch.Tensor]:
    """The images and camera poses as a real rig gives them (see the module docs)."""
    b, v = rgb.shape[:2]
    jitter = data.colour_jitter
    gain = 1 + (torch.rand(b, v, 3, 1, 1, generator=generator) * 2 - 1) * jitter
    offset = (torch.rand(b, v, 3, 1, 1, generator=generator) * 2 - 1) * jitter * 0.5
    noise = torch.randn(rgb.shape, generator=generator) * data.noise_std
    rgb = (rgb * gain + offset + noise).clamp(0, 1)
    n = b * v
    axis = F.normalize(torch.randn(n, 3, generator=generator), dim=-1)
    angle = torch.rand(n, generator=generator) * data.pose_noise_rad
    shift = F.normalize(torch.randn(n, 3, generator=generator), dim=-1) * (
        torch.rand(n, 1, generator=generator) * data.pose_noise_m
    )
    moved = pose.reshape(n, 4, 4).clone()
    moved[:, :3, :3] = rotation_about(axis, angle) @ moved[:, :3, :3]
    moved[:, :3, 3] = moved[:, :3, 3] + shift
    return rgb, moved.reshape(b, v, 4, 4)


def truth_at(depth: torch.Tensor, height: int, width: int) -> torch.Tensor:
    """True depth (B, V, H, W) at a stage's resolution, by nearest pixel (no mixed depths)."""
    b, v = depth.shape[:2]
    return F.interpolate(depth.reshape(b * v, 1, *depth.shape[2:]), size=(height, width))[
        :, 0
    ].reshape(b, v, height, width)


def in_range(
    truth: torch.Tensor,
    k: torch.Tensor,
    pose: torch.Tensor,
    centre: torch.Tensor,
    arch: MvsArchitecture,
) -> torch.Tensor:
    """The pixels (B, V, H, W) whose true depth lies in their ray's workspace range; ``k`` and
    ``pose`` (B, V, ...) those views' cameras (``k`` at the network's input size), ``centre``
    (B, 3) the workspace's."""
    b, v, h, w = truth.shape
    ks = scale_intrinsics(k, w / arch.image_width, h / arch.image_height)
    near, far = depth_range(
        ks.reshape(b * v, 3, 3),
        pose.reshape(b * v, 4, 4),
        centre.repeat_interleave(v, dim=0),
        arch,
        h,
        w,
    )
    near, far = near.reshape(b, v, h, w), far.reshape(b, v, h, w)
    return (truth > 0) & (truth >= near) & (truth <= far)


def loss_of(
    out: MvsOutput,
    depth: torch.Tensor,
    mask: torch.Tensor,
    k: torch.Tensor,
    pose: torch.Tensor,
    centre: torch.Tensor,
    arch: MvsArchitecture,
    object_weight: float,
) -> torch.Tensor:
    """The weighted L1 of the three stages in centimetres, plus the cross-entropy of the coarse
    logits against the hypothesis nearest the truth in inverse depth (see the module docs);
    ``depth``, ``mask``, ``k`` and ``pose`` (true) those of the output's views."""
    total = torch.zeros(())
    for weight, predicted in zip(STAGE_WEIGHTS, (out.coarse, out.fine, out.depth), strict=True):
        h, w = predicted.shape[-2:]
        truth = truth_at(depth, h, w)
        on_object = truth_at(mask.float(), h, w)
        valid = in_range(truth, k, pose, centre, arch).float()
        pixel_weight = valid * (1 + object_weight * on_object)
        error = (predicted - truth).abs() * pixel_weight
        total = total + weight * 100.0 * error.sum() / pixel_weight.sum().clamp(min=1)
    h, w = out.coarse.shape[-2:]
    truth = truth_at(depth, h, w)
    pixel_weight = in_range(truth, k, pose, centre, arch).float() * (
        1 + object_weight * truth_at(mask.float(), h, w)
    )
    inverse = 1.0 / out.coarse_planes  # (B, V, D, h, w)
    target = (inverse - 1.0 / truth.clamp(min=1e-3).unsqueeze(2)).abs().argmin(dim=2)
    b, v, d = out.coarse_logits.shape[:3]
    cross_entropy = F.cross_entropy(
        out.coarse_logits.reshape(b * v, d, h, w), target.reshape(b * v, h, w), reduction="none"
    ).reshape(b, v, h, w)
    return total + (cross_entropy * pixel_weight).sum() / pixel_weight.sum().clamp(min=1)


def evaluate(net: MVS, objects: list, views: int, seed: int) -> dict[str, float]:
    """On a fixed draw of inputs (the same each epoch): the refined depth's mean absolute error
    on the object pixels and on every pixel in range (mm), and the object pixels within 5 mm."""
    rng = np.random.default_rng(seed)
    sums = {"object_mm": [0.0, 0], "all_mm": [0.0, 0], "object_within_5mm": [0.0, 0]}
    net.eval()
    with torch.no_grad():
        for _ in range(max(len(objects), 1)):
            rgb, depth, mask, k, pose = batch(objects, 1, views, rng)
            out = net(rgb, k, pose)
            valid = in_range(depth, k, pose, grid_centre(pose), net.arch)
            error = (out.depth - depth).abs() * 1e3
            for key, where in (("object_mm", valid & mask), ("all_mm", valid)):
                sums[key][0] += float(error[where].sum())
                sums[key][1] += int(where.sum())
            where = valid & mask
            sums["object_within_5mm"][0] += float((error[where] <= 5.0).sum())
            sums["object_within_5mm"][1] += int(where.sum())
    net.train()
    return {key: total / max(count, 1) for key, (total, count) in sums.items()}


def train(config: MvsExperimentConfig, out: Path, log=print) -> dict[str, float]:
    """Trains (resuming from ``out/checkpoint.pt`` when there is one); the best validation
    figures."""
    data = config.data
    if data.min_views > data.max_views:
        raise ValueError(f"data.min_views ({data.min_views}) > data.max_views ({data.max_views})")
    out.mkdir(parents=True, exist_ok=True)
    if config.train.threads:
        torch.set_num_threads(config.train.threads)
    arch = config.model.architecture()
    objects = load_dataset(data.dataset_dir, arch)
    rng = np.random.default_rng(config.seed)
    order = rng.permutation(len(objects))
    held = max(1, round(data.val_fraction * len(objects))) if data.val_fraction else 0
    val = [objects[i] for i in order[:held]]
    train_objects = [objects[i] for i in order[held:]]
    torch.manual_seed(config.seed)
    net = MVS(arch)
    for regulariser in (net.coarse_regulariser, net.fine_regulariser):
        regulariser.to(memory_format=torch.channels_last_3d)
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
    steps = max(1, config.train.samples_per_epoch // config.train.batch_size)
    for epoch in range(start_epoch, config.train.epochs):
        started = time.time()
        for group in optimiser.param_groups:
            group["lr"] = config.train.learning_rate_at(epoch)
        epoch_rng = np.random.default_rng([config.seed, epoch])
        generator = torch.Generator().manual_seed(int(epoch_rng.integers(2**62)))
        total = 0.0
        for _ in range(steps):
            views = int(epoch_rng.integers(data.min_views, data.max_views + 1))
            rgb, depth, mask, k, pose = batch(
                train_objects, config.train.batch_size, views, epoch_rng
            )
            given_rgb, given_pose = disturb(rgb, pose, data, generator)
            # Two reference views a sample (the first, top-down in a test split, and one
            # other): the cost of every view as a reference, for a little less signal.
            refs = [0, int(epoch_rng.integers(1, views))]
            predicted = net(given_rgb, k, given_pose, refs)
            loss = loss_of(
                predicted,
                depth[:, refs],
                mask[:, refs],
                k[:, refs],
                pose[:, refs],
                grid_centre(pose),
                arch,
                data.object_weight,
            )
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            total += loss.item()
        figures = evaluate(net, val, data.val_views, config.seed) if val else {}
        record = {"epoch": epoch, "train_loss": total / steps, **figures}
        record["seconds"] = time.time() - started
        history.append(record)
        log(json.dumps(record))
        score = figures.get("object_mm", record["train_loss"])
        if score < best:
            best = score
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
    # Again after the loop: a run killed between the checkpoint and this file resumes with no
    # epoch left, and must still leave the whole history.
    write_text_atomically(out / "history.json", json.dumps(history, indent=2) + "\n")
    return {"best_object_mm": best, "epochs": len(history)}


def export_best(config: MvsExperimentConfig, out: Path, stem: Path) -> Path:
    """The run's best weights exported for the Rust runtime, with the training report in the
    JSON; the learning curve drawn to ``out/learning_curve.png``."""
    best = torch.load(out / "best.pt", weights_only=False)
    history = json.loads((out / "history.json").read_text())
    net = MVS(MvsArchitecture(**best["arch"]))
    net.load_state_dict(best["model"])
    report = depth_training_report(config, history, best["epoch"])
    plot_lsm_history(history, out / "learning_curve.png", title=config.name)
    return export_mvs(net, stem, report)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("config", type=Path)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument(
        "--export", type=Path, help="write the best weights as EXPORT.json/.safetensors"
    )
    args = parser.parse_args(argv)
    config = load_config(args.config, MvsExperimentConfig)
    result = train(config, args.out, log=lambda line: print(line, flush=True))
    print(json.dumps(result))
    if args.export is not None:
        print(f"exported {export_best(config, args.out, args.export)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
