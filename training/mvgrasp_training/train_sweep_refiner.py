"""Training the plane sweep's learned refinement (:mod:`mvgrasp_training.sweep_refiner`) on
``examples/sweep_refiner_data.rs`` samples.

    python -m mvgrasp_training.train_sweep_refiner CONFIG.toml --out DIR [--export models/NAME]

Each sample file ``SSSSS_V.npy`` is one view of one rig: the features, the base depth and the
true depth over the object's box. Samples (rigs, all their views together) are split by the
seed. A batch is ``train.batch_size`` random crops of ``data.crop`` pixels a side (zero
padded where the box is smaller; a padded pixel has no base and no loss), flipped at random,
each crop's colours given a gain and an offset (``data.colour_jitter``). Loss, over the object
pixels that have a base depth and a true depth: the L1 error of the refined depth (base +
correction) in millimetres, plus the binary cross-entropy of the confidence logit against
whether that error is within ``model.tolerance_m``.

Checkpoints, resumption, the best epoch (the lowest validation mean error over whole views),
the history and the export follow ``train_lsm`` (``checkpoint.pt``, ``best.pt``,
``history.json``, atomic writes).
"""

from __future__ import annotations

import argparse
import json
import re
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
from mvgrasp_training.config import SweepRefinerExperimentConfig, load_config
from mvgrasp_training.export import export_sweep_refiner
from mvgrasp_training.plots import plot_lsm_history
from mvgrasp_training.sweep_refiner import (
    BASE,
    FEATURES,
    RGB,
    TRUTH,
    SweepRefiner,
    SweepRefinerArchitecture,
)
from mvgrasp_training.train import depth_training_report

_SAMPLE_FILE = re.compile(r"^(\d{5})_(\d+)\.npy$")


def load_samples(root: Path) -> dict[int, list[np.ndarray]]:
    """Every finished sample's views (memory-mapped), by sample number.

    Raises:
        ValueError: naming the folder when it holds no sample, or a file whose shape is not
            ``(len(FEATURES) + 2, h, w)``.
    """
    samples: dict[int, list[np.ndarray]] = {}
    for path in sorted(root.glob("*.npy")):
        match = _SAMPLE_FILE.match(path.name)
        if match is None or not (root / f"{match.group(1)}.done").is_file():
            continue
        array = np.load(path, mmap_mode="r")
        if array.ndim != 3 or array.shape[0] != len(FEATURES) + 2 or array.dtype != np.float32:
            raise ValueError(
                f"{path}: shape {array.shape} {array.dtype}, expected float32 "
                f"({len(FEATURES) + 2}, h, w)"
            )
        samples.setdefault(int(match.group(1)), []).append(array)
    if not samples:
        raise ValueError(f"{root}: no finished samples (run examples/sweep_refiner_data.rs)")
    return samples


def crops(
    views: list[np.ndarray], count: int, side: int, jitter: float, rng: np.random.Generator
) -> torch.Tensor:
    """``count`` random crops (count, channels, side, side) of random views (see the docs)."""
    out = np.zeros((count, len(FEATURES) + 2, side, side), dtype=np.float32)
    for i in range(count):
        view = views[int(rng.integers(len(views)))]
        _, h, w = view.shape
        v0 = int(rng.integers(max(h - side, 0) + 1))
        u0 = int(rng.integers(max(w - side, 0) + 1))
        patch = np.array(view[:, v0 : v0 + side, u0 : u0 + side])
        if rng.random() < 0.5:
            patch = patch[:, :, ::-1]
        if rng.random() < 0.5:
            patch = patch[:, ::-1, :]
        gain = 1 + rng.uniform(-jitter, jitter, size=(3, 1, 1))
        offset = rng.uniform(-jitter, jitter, size=(3, 1, 1)) * 0.5
        patch[RGB] = np.clip((patch[RGB] + 0.5) * gain + offset, 0, 1) - 0.5
        out[i, :, : patch.shape[1], : patch.shape[2]] = patch
    return torch.from_numpy(out)


def valid_pixels(batch: torch.Tensor) -> torch.Tensor:
    """The pixels with a loss: the object's, with a base depth and a true depth."""
    return (batch[:, 0] > 0) & (batch[:, BASE] > 0) & (batch[:, TRUTH] > 0)


def loss_of(net: SweepRefiner, batch: torch.Tensor, tolerance_m: float) -> torch.Tensor:
    correction, logit = net(batch[:, : len(FEATURES)])
    valid = valid_pixels(batch)
    error = (batch[:, BASE] + correction - batch[:, TRUTH]).abs()
    depth_loss = 1e3 * error[valid].mean()
    good = (error.detach() <= tolerance_m).float()
    confidence_loss = F.binary_cross_entropy_with_logits(logit[valid], good[valid])
    return depth_loss + confidence_loss


def evaluate(net: SweepRefiner, views: list[np.ndarray], tolerance_m: float) -> dict[str, float]:
    """Over every object pixel of ``views`` with a base and a true depth: the refined and the
    base depth's median and mean error (mm), the shares within 2 and 5 mm, and how often a
    pixel of confidence >= 0.5 is within the tolerance (and what share of pixels that is)."""
    refined, base, confident, confident_good = [], [], 0, 0
    net.eval()
    with torch.no_grad():
        for view in views:
            x = torch.from_numpy(np.array(view))[None]
            correction, logit = net(x[:, : len(FEATURES)])
            valid = valid_pixels(x)[0]
            truth = x[0, TRUTH][valid]
            e = (x[0, BASE][valid] + correction[0][valid] - truth).abs() * 1e3
            refined.append(e.numpy())
            base.append((x[0, BASE][valid] - truth).abs().numpy() * 1e3)
            sure = logit[0][valid] >= 0
            confident += int(sure.sum())
            confident_good += int((sure & (e <= tolerance_m * 1e3)).sum())
    net.train()
    r, b = np.concatenate(refined), np.concatenate(base)
    return {
        "median_mm": float(np.median(r)),
        "mean_mm": float(r.mean()),
        "within_2mm": float((r <= 2).mean()),
        "within_5mm": float((r <= 5).mean()),
        "base_median_mm": float(np.median(b)),
        "base_mean_mm": float(b.mean()),
        "base_within_5mm": float((b <= 5).mean()),
        "confident_share": confident / max(len(r), 1),
        "confident_precision": confident_good / max(confident, 1),
    }


def split(
    samples: dict[int, list[np.ndarray]], fraction: float, seed: int
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Training and validation views, split by sample (rig)."""
    keys = sorted(samples)
    order = np.random.default_rng(seed).permutation(len(keys))
    held = max(1, round(fraction * len(keys))) if fraction else 0
    val = [v for i in order[:held] for v in samples[keys[i]]]
    train = [v for i in order[held:] for v in samples[keys[i]]]
    return train, val


def train(config: SweepRefinerExperimentConfig, out: Path, log=print) -> dict[str, float]:
    """Trains (resuming from ``out/checkpoint.pt`` when there is one); the best figures."""
    out.mkdir(parents=True, exist_ok=True)
    if config.train.threads:
        torch.set_num_threads(config.train.threads)
    m = config.model
    arch = SweepRefinerArchitecture(channels=m.channels, dilations=m.dilations, step_m=m.step_m)
    train_views, val_views = split(
        load_samples(config.data.dataset_dir), config.data.val_fraction, config.seed
    )
    torch.manual_seed(config.seed)
    net = SweepRefiner(arch)
    optimiser = torch.optim.Adam(net.parameters(), lr=config.train.learning_rate)
    history: list[dict[str, float]] = []
    start_epoch, best = 0, float("inf")
    checkpoint = out / "checkpoint.pt"
    if checkpoint.is_file():
        state = torch.load(checkpoint, weights_only=False)
        check_resumable(state, config, checkpoint)
        net.load_state_dict(state["model"])
        optimiser.load_state_dict(state["optimiser"])
        history, start_epoch, best = state["history"], state["epoch"] + 1, state["best"]
        log(f"resumed after epoch {start_epoch}")
    steps = max(1, config.train.samples_per_epoch // config.train.batch_size)
    for epoch in range(start_epoch, config.train.epochs):
        started = time.time()
        for group in optimiser.param_groups:
            group["lr"] = config.train.learning_rate_at(epoch)
        rng = np.random.default_rng([config.seed, epoch])
        total = 0.0
        for _ in range(steps):
            batch = crops(
                train_views, config.train.batch_size, config.data.crop, config.data.colour_jitter,
                rng,
            )
            loss = loss_of(net, batch, m.tolerance_m)
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            total += loss.item()
        figures = evaluate(net, val_views, m.tolerance_m) if val_views else {}
        record = {"epoch": epoch, "train_loss": total / steps, **figures}
        record["seconds"] = time.time() - started
        history.append(record)
        log(json.dumps(record))
        score = figures.get("mean_mm", record["train_loss"])
        if score < best:
            best = score
            save_atomically(
                {"model": net.state_dict(), "arch": asdict(arch), "epoch": epoch}, out / "best.pt"
            )
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
    write_text_atomically(out / "history.json", json.dumps(history, indent=2) + "\n")
    return {"best_mean_mm": best, "epochs": len(history)}


def export_best(config: SweepRefinerExperimentConfig, out: Path, stem: Path) -> Path:
    """The run's best weights exported for the Rust runtime, with the training report in the
    JSON; the learning curve drawn to ``out/learning_curve.png``."""
    best = torch.load(out / "best.pt", weights_only=False)
    history = json.loads((out / "history.json").read_text())
    arch = dict(best["arch"])
    arch["dilations"] = tuple(arch["dilations"])
    net = SweepRefiner(SweepRefinerArchitecture(**arch))
    net.load_state_dict(best["model"])
    report = depth_training_report(config, history, best["epoch"])
    plot_lsm_history(
        history,
        out / "learning_curve.png",
        title=config.name,
        series=(
            ("mean_mm", "validation MAE, refined"),
            ("base_mean_mm", "validation MAE, the sweep's base depth"),
            ("median_mm", "validation median, refined"),
        ),
    )
    return export_sweep_refiner(net, stem, report)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("config", type=Path)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument(
        "--export", type=Path, help="write the best weights as EXPORT.json/.safetensors"
    )
    args = parser.parse_args(argv)
    config = load_config(args.config, SweepRefinerExperimentConfig)
    result = train(config, args.out, log=lambda line: print(line, flush=True))
    print(json.dumps(result))
    if args.export is not None:
        print(f"exported {export_best(config, args.out, args.export)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
