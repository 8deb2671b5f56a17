"""The array conversions the package's modules share before calling the native module.

Each takes the argument's name for its errors: what NumPy cannot convert is a ``ValueError`` or
``TypeError`` naming it, and an array of another dtype too big to convert (a huge shape declared
with zero strides) is refused before NumPy tries to allocate it. An array that already has the
dtype goes through as it is, whatever its strides: the native module reads it in place.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Optional

import numpy as np
import numpy.typing as npt

# The native module's limit on one array argument (2^28 values: a 16384 x 16384 image).
MAX_VALUES = 1 << 28


def as_dtype(a: Any, dtype: type, name: str) -> np.ndarray:
    """``a`` as an array of ``dtype``: the array itself when it already is one."""
    if isinstance(a, np.ndarray) and a.dtype != dtype and a.size > MAX_VALUES:
        raise ValueError(
            f"{name}: shape {a.shape}, more than the {MAX_VALUES} values an array argument may "
            "hold"
        )
    if a is None:
        raise TypeError(f"{name}: expected an array, got None")
    try:
        return np.asarray(a, dtype=dtype)
    except TypeError as e:
        raise TypeError(f"{name}: {e}") from e
    except (ValueError, OverflowError) as e:
        raise ValueError(f"{name}: {e}") from e


def f64(a: npt.ArrayLike, name: str) -> np.ndarray:
    """A float64 array (camera matrices, poses, points)."""
    return as_dtype(a, np.float64, name)


def f32(a: npt.ArrayLike, name: str) -> np.ndarray:
    """A float32 array (depth images)."""
    return as_dtype(a, np.float32, name)


def optional_f64(a: Optional[npt.ArrayLike], name: str) -> Optional[np.ndarray]:
    """:func:`f64` of ``a``, or ``None``."""
    return None if a is None else f64(a, name)


def masks(
    per_view: Optional[Sequence[Optional[npt.ArrayLike]]], name: str = "masks"
) -> Optional[list]:
    """Per view a bool mask or ``None``; ``None`` for no masks at all."""
    if per_view is None:
        return None
    return [
        None if m is None else as_dtype(m, bool, f"{name}[{i}]") for i, m in enumerate(per_view)
    ]
