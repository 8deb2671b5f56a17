"""The array conversions the package's modules share before calling the native module."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Optional

import numpy as np
import numpy.typing as npt


def f64(a: npt.ArrayLike) -> np.ndarray:
    """A contiguous float64 array (camera matrices, poses, points)."""
    return np.ascontiguousarray(a, dtype=np.float64)


def f32(a: npt.ArrayLike) -> np.ndarray:
    """A float32 array, the array itself when it already is one (depth images)."""
    return np.asarray(a, dtype=np.float32)


def optional_f64(a: Optional[npt.ArrayLike]) -> Optional[np.ndarray]:
    """:func:`f64` of ``a``, or ``None``."""
    return None if a is None else f64(a)


def masks(per_view: Optional[Sequence[Optional[npt.ArrayLike]]]) -> Optional[list]:
    """Per view a bool mask or ``None``; ``None`` for no masks at all."""
    if per_view is None:
        return None
    return [None if m is None else np.asarray(m, dtype=bool) for m in per_view]
