"""mvgrasp: 6-DoF parallel-jaw grasp planning from a few RGB cameras.

Units are metres, radians, seconds and kilograms everywhere. Every error mvgrasp raises is a
subclass of :class:`MvGraspError`, whose message is one line naming the file and the fault.

The work happens in Rust (the private module ``mvgrasp._native``); this package only re-exports
it with types (see ``_native.pyi``).
"""

from mvgrasp._native import (
    CameraError,
    MeshError,
    MvGraspError,
    WeightsError,
    __version__,
    load_mesh,
)

__all__ = [
    "CameraError",
    "MeshError",
    "MvGraspError",
    "WeightsError",
    "__version__",
    "load_mesh",
]
