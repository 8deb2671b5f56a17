"""mvgrasp: 6-DoF parallel-jaw grasp planning from a few RGB cameras.

Units are metres, radians, seconds and kilograms everywhere. Every error mvgrasp raises is a
subclass of :class:`MvGraspError`, whose message is one line naming the file and the fault.

The work happens in Rust (the private module ``mvgrasp._native``); this package only re-exports
it with types (see ``_native.pyi``). Grasp datasets have a friendlier face in
:mod:`mvgrasp.grasp_dataset` (and :mod:`mvgrasp.ray_launcher` for clusters).
"""

from mvgrasp._native import (
    CameraError,
    DatasetError,
    MeshError,
    MvGraspError,
    PlanningError,
    RenderError,
    WeightsError,
    __version__,
    builtin_object,
    depth_to_points,
    generate_grasp_dataset,
    generate_grasp_shard,
    grasp_dataset_num_shards,
    hemisphere_cameras,
    intrinsics_preset,
    load_intrinsics,
    load_mesh,
    load_network,
    mass_properties,
    mesh_from_arrays,
    object_categories,
    plan_depth,
    plan_views,
    random_colors,
    read_grasp_manifest,
    read_grasp_shard,
    render,
    score_crops,
    stable_poses,
    write_grasp_manifest,
)

__all__ = [
    "CameraError",
    "DatasetError",
    "MeshError",
    "MvGraspError",
    "PlanningError",
    "RenderError",
    "WeightsError",
    "__version__",
    "builtin_object",
    "depth_to_points",
    "generate_grasp_dataset",
    "generate_grasp_shard",
    "grasp_dataset_num_shards",
    "hemisphere_cameras",
    "intrinsics_preset",
    "load_intrinsics",
    "load_mesh",
    "load_network",
    "mass_properties",
    "mesh_from_arrays",
    "object_categories",
    "plan_depth",
    "plan_views",
    "random_colors",
    "read_grasp_manifest",
    "read_grasp_shard",
    "render",
    "score_crops",
    "stable_poses",
    "write_grasp_manifest",
]
