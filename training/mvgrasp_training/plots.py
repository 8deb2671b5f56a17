"""Learning-curve plots (PNG) of a training history."""

from __future__ import annotations

from pathlib import Path
from typing import Any


def plot_history(history: list[dict[str, Any]], path: str | Path, title: str = "") -> Path:
    """Writes the training loss and the validation balanced accuracy, precision and recall per
    epoch to ``path`` (a PNG); returns the path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    epochs = [h["epoch"] for h in history]
    fig, (ax_loss, ax_val) = plt.subplots(1, 2, figsize=(10, 4), dpi=100)
    ax_loss.plot(epochs, [h["loss"] for h in history], marker="o", label="training loss")
    ax_loss.set_xlabel("epoch")
    ax_loss.set_ylabel("class-balanced cross-entropy")
    ax_loss.grid(alpha=0.3)
    ax_loss.legend()
    for key, label in (
        ("balanced_accuracy", "balanced accuracy"),
        ("precision", "precision at 0.5"),
        ("recall", "recall at 0.5"),
    ):
        ax_val.plot(epochs, [h["val"][key] for h in history], marker="o", label=label)
    ax_val.set_xlabel("epoch")
    ax_val.set_ylabel("validation (held-out objects)")
    ax_val.set_ylim(0.5, 1.0)
    ax_val.grid(alpha=0.3)
    ax_val.legend(loc="lower right")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    path = Path(path)
    partial = Path(path).with_suffix(".partial.png")
    fig.savefig(partial)
    partial.replace(path)
    plt.close(fig)
    return path


_DEPTH_SERIES = (
    ("train_l1_mm", "training L1 (all pixels in range)"),
    ("object_mm", "validation MAE, object pixels"),
    ("all_mm", "validation MAE, all pixels in range"),
)


def plot_lsm_history(
    history: list[dict[str, Any]],
    path: str | Path,
    title: str = "",
    series: tuple[tuple[str, str], ...] = _DEPTH_SERIES,
) -> Path:
    """Writes a depth network's curve to ``path`` (a PNG): by default the training L1 (where
    the history has it) and the validation mean absolute depth error over the held-out objects'
    pixels and over all pixels in range, millimetres per epoch (``series``: other keys of the
    history, with their labels); returns the path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    epochs = [h["epoch"] for h in history]
    fig, ax = plt.subplots(figsize=(7, 4), dpi=100)
    for key, label in series:
        # A run that records no such figure (the MVS network's training loss is not a depth
        # error) draws no line for it.
        if any(key in h for h in history):
            ax.plot(epochs, [h.get(key) for h in history], marker="o", markersize=3, label=label)
    ax.set_xlabel("epoch")
    ax.set_ylabel("depth error (mm)")
    ax.grid(alpha=0.3)
    ax.legend()
    if title:
        ax.set_title(title)
    fig.tight_layout()
    path = Path(path)
    partial = Path(path).with_suffix(".partial.png")
    fig.savefig(partial)
    partial.replace(path)
    plt.close(fig)
    return path
