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
