"""Reading the JSON files mvgrasp writes (manifests, network descriptions)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any


def read_format_json(
    path: Path, expected_format: str, what: str, error: type[Exception] = ValueError
) -> dict[str, Any]:
    """The JSON object at ``path``, whose ``format`` must be ``expected_format``.

    Raises:
        error: the file is unreadable, not JSON, or of another format; the message names it.
    """
    try:
        document = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as e:
        raise error(f"{path}: cannot read the {what}: {e}") from e
    if not isinstance(document, dict) or document.get("format") != expected_format:
        found = document.get("format") if isinstance(document, dict) else None
        raise error(f"{path}: format {found!r}, expected {expected_format!r}")
    return document


# The version of the training checkpoints' contents: a checkpoint of another is refused.
CHECKPOINT_FORMAT = "mvgrasp-checkpoint/1"


def checkpoint_identity(config: Any) -> dict[str, Any]:
    """What a checkpoint must match to be resumed: the format and the experiment's config,
    apart from the number of epochs (a longer run continues a shorter one)."""
    import dataclasses

    settings = json.loads(json.dumps(dataclasses.asdict(config), default=str))
    settings.get("train", {}).pop("epochs", None)
    return {"format": CHECKPOINT_FORMAT, "config": settings}


def check_resumable(state: dict[str, Any], config: Any, checkpoint: Path) -> None:
    """Refuses to resume from a checkpoint another config or another version of the training
    code wrote (it would mix two runs).

    Raises:
        ValueError: naming the checkpoint and the first setting that differs.
    """
    expected = checkpoint_identity(config)
    found = state.get("identity")
    if not isinstance(found, dict) or found.get("format") != expected["format"]:
        version = found.get("format") if isinstance(found, dict) else None
        raise ValueError(
            f"{checkpoint}: written by another version of the training code (format "
            f"{version!r}, expected {expected['format']!r}); use another --out or delete it"
        )

    def first_difference(a: Any, b: Any, where: str) -> str | None:
        if isinstance(a, dict) and isinstance(b, dict):
            for key in sorted(set(a) | set(b)):
                found_here = first_difference(a.get(key), b.get(key), f"{where}.{key}")
                if found_here:
                    return found_here
            return None
        return None if a == b else f"{where.lstrip('.')} is {a!r} there, {b!r} here"

    difference = first_difference(found["config"], expected["config"], "")
    if difference:
        raise ValueError(
            f"{checkpoint}: made with another config ({difference}); use another --out or "
            "delete it"
        )


def write_text_atomically(path: Path, text: str) -> None:
    """Writes ``text`` to ``path.partial`` and renames it: a kill mid-write leaves the old file."""
    partial = path.with_suffix(path.suffix + ".partial")
    partial.write_text(text)
    partial.replace(path)


def canonical(value: Any) -> Any:
    """``value`` with every string interned, dicts, lists and tuples rebuilt: pickle writes a
    string once and refers back to it when the same object comes again, so a checkpoint's
    bytes would depend on which strings happen to be one object (a resumed run's history keys
    come from the unpickler, a fresh run's from the code). Tensors are kept as they are."""
    import sys

    if isinstance(value, str):
        return sys.intern(value)
    if isinstance(value, dict):
        return {canonical(k): canonical(v) for k, v in value.items()}
    if isinstance(value, list):
        return [canonical(v) for v in value]
    if isinstance(value, tuple):
        return tuple(canonical(v) for v in value)
    return value


def save_atomically(state: dict[str, Any], path: Path) -> None:
    """``torch.save`` of ``canonical(state)`` to ``path.partial``, then renamed: a kill
    mid-write leaves the old file, and the same state gives the same bytes whether the run was
    resumed or not."""
    import torch

    partial = path.with_suffix(path.suffix + ".partial")
    torch.save(canonical(state), partial)
    partial.replace(path)
