"""Arrays of any layout into every function of `mvgrasp` that takes arrays: each call gives what
the C-contiguous copy of the same values gives, or raises a `ValueError` (a `TypeError` for a
wrong type) whose message names the argument; never another exception, never a crash.

For each array argument of each function (the native module's, whose stubs the first test
reads to find them, and the Python wrappers': `Planner`, `Camera`, `mvgrasp.grasps`) the
argument is replaced, the others kept, by:

- the same values in another layout: Fortran order, a strided view of a bigger array, negative
  strides, a big-endian dtype, read-only, an unaligned buffer, a Python list. Each must give
  the result (or the error) of the plain C-contiguous copy; the right dtype in any of these
  layouts may not be refused.
- another dtype (float64, float32, int16, uint8, bool, complex, strings, objects): the result of
  the C-contiguous copy cast to the expected dtype, or a named `TypeError`/`ValueError`.
- NaN and infinities in a float argument, alone and in another layout: the layouts agree, and
  the contiguous call itself raises nothing but a named `ValueError`/`TypeError` or an
  `mvgrasp.MvGraspError` (a mesh with NaN vertices is a `MeshError`).
- hostile arrays, which can only be accepted or refused by name: 0-size, one axis more or
  less, 0-d, `None`, and huge shapes declared with zero strides (100000 x 100000 from one
  element: no memory behind them, so nothing may copy them).
- random layouts and shapes from a seeded generator.

The calls run in a worker process (with its address space capped at 8 GiB, so that a copy of a
huge array fails at once): a crash is recorded against the case that was running and the
worker restarted after it. The failures are listed with their inputs.
"""

from __future__ import annotations

import ast
import dataclasses
import functools
import hashlib
import json
import os
import re
import subprocess
import sys
import zlib
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pytest

HERE = Path(__file__).resolve().parent
SEED = 20260611
HUGE = 100_000
RANDOM_CASES = 6  # seeded random layouts per array argument

# ---------------------------------------------------------------------------------------------
# The functions and their base inputs (C-contiguous, the dtype each argument expects).


# Arguments that may be None (absent): None is no hostile value for them.
OPTIONAL = {"mask", "masks[0]", "world_from_camera", "world_from_object", "colors",
            "table_from_object"}  # fmt: skip
# The names the native module gives what the Python wrappers pass it.
ALIASES = {
    "cameras[0].k": ("cameras", "k", "ks"),
    "cameras[0].pose": ("cameras", "world_from_camera", "world_from_cameras"),
    "grasp": ("grasp", "object_from_gripper", "world_from_gripper"),
    "grasps": ("grasps", "object_from_grippers"),
    "camera.k": ("camera", "k"),
}
# Documented errors about an argument's values rather than its layout: a mesh whose triangles
# index past its vertices, or with NaN vertices, is a `MeshError` (as a mesh file is).
DOMAIN_ERRORS = {"vertices": "MeshError", "triangles": "MeshError"}


@dataclasses.dataclass
class Spec:
    """A function with its array arguments: `call(arrays)` calls it with `arrays[key]` for
    each key."""

    call: Callable[[dict[str, Any]], Any]
    arrays: dict[str, np.ndarray]

    def names_of(self, key: str) -> tuple[str, ...]:
        """The names an error about argument `key` may carry."""
        return ALIASES.get(key, (key.split("[")[0].split(".")[-1],))


PRIMESENSE_K = np.array([[525.0, 0.0, 319.5], [0.0, 525.0, 239.5], [0.0, 0.0, 1.0]])
SMALL_K = np.array([[552.5, 0.0, 79.5], [0.0, 552.5, 59.5], [0.0, 0.0, 1.0]])  # 160 x 120


@functools.cache
def box() -> tuple[np.ndarray, np.ndarray]:
    sys.path.insert(0, str(HERE))
    from test_planning import box_on_table, box_seen_from

    depth, pose = box_seen_from((0.0, 0.0, 0.7))
    return box_on_table(), pose


@functools.cache
def can() -> dict[str, Any]:
    """The built-in can, its resting pose, one grasp sampled on it, and 2 RGB views."""
    import mvgrasp

    v, t = mvgrasp.builtin_object("can", 0)
    rest = np.array(mvgrasp.stable_poses(v, t)[0]["table_from_object"])
    sampled = mvgrasp._native.sample_grasps(v, t, count=1, table_from_object=rest)
    grasp = np.array(sampled["grasps"][0]["grasp"]["world_from_gripper"])
    cams = mvgrasp.hemisphere_cameras(count=2, target=(0.0, 0.0, 0.05))
    poses = [np.asarray(c["world_from_camera"]) for c in cams]
    views = mvgrasp.render(v, t, [SMALL_K] * 2, poses, width=160, height=120,
                           world_from_object=rest)  # fmt: skip
    return {"v": v, "t": t.astype(np.int64), "rest": rest, "grasp": grasp, "poses": poses,
            "rgb": list(views["rgb"]), "masks": list(views["mask"] == 1)}  # fmt: skip


def native_specs() -> dict[str, Callable[[], Spec]]:
    import mvgrasp
    from mvgrasp import _native as n

    def mesh(f: Callable[..., Any], **kw: Any) -> Callable[[], Spec]:
        def build() -> Spec:
            c = can()
            extra = {k: v(c) for k, v in kw.items()}
            return Spec(lambda a: f(a["vertices"], a["triangles"], **{k: a[k] for k in extra}),
                        {"vertices": c["v"], "triangles": c["t"], **extra})  # fmt: skip

        return build

    def depth_spec() -> Spec:
        depth, _ = box()
        return Spec(lambda a: n.plan_depth(a["depth"], a["k"], mask=a["mask"],
                                           world_from_camera=a["world_from_camera"]),
                    {"depth": depth, "k": PRIMESENSE_K, "mask": depth < 0.69,
                     "world_from_camera": box()[1]})  # fmt: skip

    def views_spec() -> Spec:
        depth, pose = box()
        return Spec(lambda a: n.plan_views([a["depths[0]"]], [a["ks[0]"]],
                                           [a["world_from_cameras[0]"]], masks=[a["masks[0]"]]),
                    {"depths[0]": depth, "ks[0]": PRIMESENSE_K, "world_from_cameras[0]": pose,
                     "masks[0]": depth < 0.69})  # fmt: skip

    def rgb_spec(f: Callable[..., Any]) -> Callable[[], Spec]:
        def build() -> Spec:
            c = can()
            return Spec(lambda a: f([a["images[0]"], c["rgb"][1]], [a["ks[0]"], SMALL_K],
                                    [a["world_from_cameras[0]"], c["poses"][1]],
                                    masks=[a["masks[0]"], c["masks"][1]]),
                        {"images[0]": c["rgb"][0], "ks[0]": SMALL_K, "masks[0]": c["masks"][0],
                         "world_from_cameras[0]": c["poses"][0]})  # fmt: skip

        return build

    def render_spec() -> Spec:
        c = can()
        return Spec(lambda a: n.render(a["vertices"], a["triangles"], [a["ks[0]"]],
                                       [a["world_from_cameras[0]"]], width=160, height=120,
                                       world_from_object=a["world_from_object"],
                                       colors=a["colors"]),
                    {"vertices": c["v"], "triangles": c["t"], "ks[0]": SMALL_K,
                     "world_from_cameras[0]": c["poses"][0], "world_from_object": c["rest"],
                     "colors": mvgrasp.random_colors(3, len(c["v"]))})  # fmt: skip

    def crops_spec() -> Spec:
        rng = np.random.default_rng(SEED)
        crops = (0.6 + 0.01 * rng.standard_normal((4, 32, 32))).astype(np.float32)
        return Spec(lambda a: n.score_crops("gqcnn_small_topdown", a["depth"], a["pose"]),
                    {"depth": crops, "pose": np.full((4, 1), 0.6, np.float32)})  # fmt: skip

    pixels = np.array([[10.0, 20.0], [319.5, 239.5], [600.0, 400.0]])
    points = np.array([[0.0, 0.0, 0.7], [0.1, -0.05, 0.6], [0.0, 0.0, -1.0]])
    return {
        "plan_depth": depth_spec,
        "plan_views": views_spec,
        "plan_rgb": rgb_spec(n.plan_rgb),
        "predict_depth": rgb_spec(n.predict_depth),
        "plan_mesh": mesh(lambda v, t: n.plan_mesh(v, t, physics=False)),
        "render": render_spec,
        "mesh_from_arrays": mesh(n.mesh_from_arrays),
        "mass_properties": mesh(n.mass_properties),
        "stable_poses": mesh(n.stable_poses),
        "sample_grasps": mesh(lambda v, t, table_from_object: n.sample_grasps(
            v, t, count=2, table_from_object=table_from_object),
            table_from_object=lambda c: c["rest"]),  # fmt: skip
        "grasp_quality": mesh(n.grasp_quality, object_from_gripper=lambda c: c["grasp"]),
        "robust_quality": mesh(lambda v, t, object_from_grippers: n.robust_quality(
            v, t, object_from_grippers, params={"num_samples": 4}),
            object_from_grippers=lambda c: np.stack([c["grasp"], c["grasp"]])),  # fmt: skip
        "check_collision": mesh(lambda v, t, object_from_gripper, table_from_object:
                                n.check_collision(v, t, object_from_gripper, 0.08,
                                                  table_from_object=table_from_object),
                                object_from_gripper=lambda c: c["grasp"],
                                table_from_object=lambda c: c["rest"]),  # fmt: skip
        "physics_trial": mesh(lambda v, t, table_from_object, world_from_gripper:
                              n.physics_trial(v, t, table_from_object, world_from_gripper, 0.08),
                              table_from_object=lambda c: c["rest"],
                              world_from_gripper=lambda c: c["rest"] @ c["grasp"]),  # fmt: skip
        "depth_to_points": lambda: Spec(
            lambda a: n.depth_to_points(a["depth"], a["k"], a["world_from_camera"]),
            {"depth": box()[0], "k": PRIMESENSE_K, "world_from_camera": box()[1]}),
        "project_points": lambda: Spec(
            lambda a: n.project_points(a["points"], a["k"], 640, 480, a["world_from_camera"]),
            {"points": points, "k": PRIMESENSE_K, "world_from_camera": box()[1]}),
        "unproject_pixels": lambda: Spec(
            lambda a: n.unproject_pixels(a["pixels"], a["depths"], a["k"], 640, 480,
                                         a["world_from_camera"]),
            {"pixels": pixels, "depths": np.array([0.5, 0.7, 1.0]), "k": PRIMESENSE_K,
             "world_from_camera": box()[1]}),  # fmt: skip
        "score_crops": crops_spec,
    }


def wrapper_specs() -> dict[str, Callable[[], Spec]]:
    import mvgrasp
    from mvgrasp import Camera, Grasp, Planner

    def plan() -> Spec:
        depth, pose = box()
        return Spec(lambda a: Planner().plan(a["depth"], Camera(a["camera.k"], 640, 480),
                                             mask=a["mask"],
                                             world_from_camera=a["world_from_camera"]),
                    {"depth": depth, "camera.k": PRIMESENSE_K, "mask": depth < 0.69,
                     "world_from_camera": pose})  # fmt: skip

    def plan_views() -> Spec:
        depth, pose = box()
        return Spec(lambda a: Planner().plan_views(
            [a["depths[0]"]], [Camera(a["cameras[0].k"], 640, 480, a["cameras[0].pose"])],
            masks=[a["masks[0]"]]),
            {"depths[0]": depth, "cameras[0].k": PRIMESENSE_K, "cameras[0].pose": pose,
             "masks[0]": depth < 0.69})  # fmt: skip

    def plan_rgb() -> Spec:
        c = can()
        return Spec(lambda a: Planner().plan_rgb(
            [a["images[0]"], c["rgb"][1]],
            [Camera(SMALL_K, 160, 120, a["cameras[0].pose"]),
             Camera(SMALL_K, 160, 120, c["poses"][1])], masks=[a["masks[0]"], c["masks"][1]]),
            {"images[0]": c["rgb"][0], "cameras[0].pose": c["poses"][0],
             "masks[0]": c["masks"][0]})  # fmt: skip

    def camera(method: str, **arrays: np.ndarray) -> Callable[[], Spec]:
        def build() -> Spec:
            def call(a: dict[str, Any]) -> Any:
                cam = Camera(a["k"], 640, 480, a["world_from_camera"])
                return getattr(cam, method)(*(a[k] for k in arrays))

            return Spec(call, {"k": PRIMESENSE_K, "world_from_camera": box()[1], **arrays})

        return build

    def grasps(f: Callable[..., Any], arrays: Callable[[dict[str, Any]], dict[str, Any]],
               **kw: Any) -> Callable[[], Spec]:  # fmt: skip
        def build() -> Spec:
            c = can()
            return Spec(lambda a: f(a["vertices"], a["triangles"], a, **kw),
                        {"vertices": c["v"], "triangles": c["t"], **arrays(c)})  # fmt: skip

        return build

    g = mvgrasp.grasps
    return {
        "Planner.plan": plan,
        "Planner.plan_views": plan_views,
        "Planner.plan_rgb": plan_rgb,
        "Planner.plan_mesh": lambda: Spec(
            lambda a: Planner().plan_mesh(a["vertices"], a["triangles"], physics=False),
            {"vertices": can()["v"], "triangles": can()["t"]}),
        "Camera.project": camera("project", points=np.array([[0.0, 0.0, 0.7], [0.1, 0.0, 0.5]])),
        "Camera.unproject": camera("unproject", pixels=np.array([[10.0, 20.0], [320.0, 240.0]]),
                                   depths=np.array([0.5, 0.7])),
        "Camera.depth_to_points": camera("depth_to_points", depth=box()[0]),
        "grasps.sample_grasps": grasps(
            lambda v, t, a: g.sample_grasps(v, t, count=2,
                                            table_from_object=a["table_from_object"]),
            lambda c: {"table_from_object": c["rest"]}),  # fmt: skip
        "grasps.grasp_quality": grasps(lambda v, t, a: g.grasp_quality(v, t, a["grasp"]),
                                       lambda c: {"grasp": c["grasp"]}),
        "grasps.robust_quality": grasps(
            lambda v, t, a: g.robust_quality(v, t, a["grasps"], params={"num_samples": 4}),
            lambda c: {"grasps": np.stack([c["grasp"], c["grasp"]])}),
        "grasps.check_collision": grasps(
            lambda v, t, a: g.check_collision(v, t, Grasp(a["grasp"], 0.08),
                                              table_from_object=a["table_from_object"]),
            lambda c: {"grasp": c["grasp"], "table_from_object": c["rest"]}),  # fmt: skip
        "grasps.physics_trial": grasps(
            lambda v, t, a: g.physics_trial(v, t, a["table_from_object"], Grasp(a["grasp"], 0.08)),
            lambda c: {"grasp": c["rest"] @ c["grasp"], "table_from_object": c["rest"]}),
    }


def all_specs() -> dict[str, Callable[[], Spec]]:
    return {**native_specs(), **wrapper_specs()}


# ---------------------------------------------------------------------------------------------
# Layouts. Each case is (function, argument key, variant, params); the worker rebuilds the
# array from them, so that a case that crashed can be named and skipped.

SAME_VALUES = ["fortran", "strided", "negative", "transposed_copy", "readonly", "unaligned"]
DTYPES = ["float64", "float32", "int16", "uint8", "bool", "complex64", "str", "object"]
HOSTILE = ["empty", "empty_all", "extra_axis", "fewer_axes", "zero_d", "none",
           "huge", "huge_rows", "huge_float64", "huge_rows_other", "list_of_rows"]  # fmt: skip


def layout(a: np.ndarray, how: str) -> Any:
    """`a`'s values in layout `how` (the same values, another memory layout)."""
    if how == "c":
        return np.ascontiguousarray(a)
    if how == "fortran":
        return np.asfortranarray(a)
    if how == "strided":
        big = np.zeros(tuple(2 * s + 1 for s in a.shape), dtype=a.dtype)
        view = big[tuple(slice(1, None, 2) for _ in a.shape)]
        view[...] = a
        return view
    if how == "negative":
        flipped = tuple(slice(None, None, -1) for _ in a.shape)
        return np.ascontiguousarray(a[flipped])[flipped]
    if how == "transposed_copy":
        return np.ascontiguousarray(a.T).T
    if how == "readonly":
        r = a.copy()
        r.flags.writeable = False
        return r
    if how == "unaligned":
        buf = np.zeros(a.nbytes + 1, dtype=np.uint8)
        u = buf[1:].view(a.dtype).reshape(a.shape)  # 1 byte past an aligned start
        u[...] = a
        return u
    if how == "bigendian":
        return a.astype(a.dtype.newbyteorder(">"))
    if how == "list":
        return a.tolist()
    raise ValueError(how)


def hostile(a: np.ndarray, how: str) -> Any:
    """An array of `a`'s kind that cannot be `a`'s values."""
    if how == "empty":
        return np.zeros((0, *a.shape[1:]), dtype=a.dtype)
    if how == "empty_all":
        return np.zeros((0,) * a.ndim, dtype=a.dtype)
    if how == "extra_axis":
        return a[None]
    if how == "fewer_axes":
        return a.reshape(-1) if a.ndim > 1 else a[0]
    if how == "zero_d":
        return np.asarray(a.reshape(-1)[0])
    if how == "none":
        return None
    if how == "list_of_rows":  # ragged
        return [list(range(3)), list(range(2))]
    one = np.zeros(1, dtype=a.dtype if "other" not in how else np.float64)
    if how == "huge_float64":
        one = np.zeros(1, dtype=np.float64 if a.dtype != np.float64 else np.float32)
    if how == "huge_rows" or how == "huge_rows_other":
        shape = (10**9, *a.shape[1:]) if a.ndim else (10**9,)
    else:
        shape = (HUGE, HUGE, *a.shape[2:]) if a.ndim >= 2 else (HUGE * HUGE,)
    if how == "huge_rows_other" and a.dtype == np.float64:
        one = np.zeros(1, dtype=np.float32)
    return np.lib.stride_tricks.as_strided(one, shape, (0,) * len(shape))


def with_content(a: np.ndarray, content: str, rng: np.random.Generator) -> np.ndarray:
    """`a` with a few values made NaN or infinite (a float array)."""
    b = a.copy()
    flat = b.reshape(-1)
    picks = rng.choice(flat.size, size=max(1, flat.size // 50), replace=False)
    flat[picks] = {"nan": np.nan, "inf": np.inf, "-inf": -np.inf}[content]
    return b


def as_dtype(a: np.ndarray, dtype: str) -> np.ndarray:
    if dtype == "str":
        return a.astype(str)
    if dtype == "object":
        return a.astype(object)
    with np.errstate(all="ignore"):
        return a.astype(dtype)


def random_layout(a: np.ndarray, seed: int) -> np.ndarray:
    """`a`'s values in a random layout: embedded with random steps and offsets, some axes
    flipped, in C or Fortran order, in either byte order."""
    rng = np.random.default_rng(seed)
    steps = rng.integers(1, 4, size=a.ndim)
    offsets = rng.integers(0, 3, size=a.ndim)
    order = "F" if rng.random() < 0.5 else "C"
    dtype = a.dtype.newbyteorder(">") if rng.random() < 0.3 and a.dtype.itemsize > 1 else a.dtype
    shape = tuple(int(o + s * n) for o, s, n in zip(offsets, steps, a.shape))
    big = np.zeros(shape, dtype=dtype, order=order)
    view = big[tuple(slice(int(o), None, int(s)) for o, s in zip(offsets, steps))]
    flips = rng.random(a.ndim) < 0.5
    index = tuple(slice(None, None, -1) if f else slice(None) for f in flips)
    view[index] = a
    return view[index]


def random_hostile(a: np.ndarray, seed: int) -> np.ndarray:
    """A random shape (0 to 4 axes, sizes 0 to 5, or a huge axis by zero strides) and dtype."""
    rng = np.random.default_rng(seed)
    ndim = int(rng.integers(0, 5))
    shape = tuple(int(s) for s in rng.integers(0, 6, size=ndim))
    dtype = rng.choice([a.dtype.str, "<f8", "<f4", "<i2", "|u1", "|b1", ">f4", "<c8"])
    if ndim and rng.random() < 0.3:
        shape = (*shape[:-1], 10**10)
        return np.lib.stride_tricks.as_strided(np.zeros(1, dtype), shape, (0,) * ndim)
    with np.errstate(all="ignore"):
        return rng.normal(0.3, 1.0, size=shape).astype(dtype)


def cases_of(function: str, spec: Spec) -> list[dict[str, Any]]:
    """Every case of one function, each with its `kind`: `same` (the reference's values),
    `cast` (the reference: the values cast to the argument's dtype), `content` (NaN or
    infinities: the reference is the contiguous array with them) or `hostile`."""
    cases: list[dict[str, Any]] = []
    for key, base in spec.arrays.items():
        seed = zlib.crc32(f"{function}/{key}".encode()) ^ SEED

        def add(kind: str, variant: str, **params: Any) -> None:
            cases.append({"function": function, "key": key, "kind": kind, "variant": variant,
                          **params})  # fmt: skip

        for how in [*SAME_VALUES, "bigendian", "list"]:
            if how == "bigendian" and base.dtype.itemsize == 1:
                continue
            add("same", how)
        for dtype in DTYPES:
            if np.dtype(dtype if dtype not in ("str", "object") else "O") != base.dtype:
                add("cast", dtype)
        if base.dtype.kind == "f":
            for content in ["nan", "inf", "-inf"]:
                for how in ["c", "fortran", "negative"]:
                    add("content", f"{content}/{how}", content=content, how=how, seed=seed)
        for how in HOSTILE:
            if not (how == "none" and key in OPTIONAL):
                add("hostile", how)
        for i in range(RANDOM_CASES):
            add("same", f"random_layout#{i}", seed=seed + i)
            add("hostile", f"random_hostile#{i}", seed=seed + 1000 + i)
    return cases


def variant_of(spec: Spec, case: dict[str, Any]) -> tuple[Any, np.ndarray | None]:
    """The case's argument, and its reference (the contiguous array of the argument's dtype
    with the same values; `None` for a hostile case)."""
    base = spec.arrays[case["key"]]
    kind, variant = case["kind"], case["variant"]
    if kind == "same":
        if variant.startswith("random_layout"):
            return random_layout(base, case["seed"]), base
        return layout(base, variant), base
    if kind == "cast":
        value = as_dtype(base, variant)
        try:
            with np.errstate(all="ignore"):
                reference = np.ascontiguousarray(value.astype(base.dtype))
        except (TypeError, ValueError):
            reference = None
        return value, reference
    if kind == "content":
        rng = np.random.default_rng(case["seed"])
        value = with_content(base, case["content"], rng)
        return layout(value, case["how"]), value
    if variant.startswith("random_hostile"):
        return random_hostile(base, case["seed"]), None
    return hostile(base, variant), None


# ---------------------------------------------------------------------------------------------
# Outcomes.


def digest(value: Any) -> str:
    """A canonical hash of a result (timings left out: they differ run to run)."""

    def canon(v: Any) -> Any:
        if hasattr(v, "grasps_json"):
            return canon(v.grasps_json)
        if dataclasses.is_dataclass(v) and not isinstance(v, type):
            return canon({f.name: getattr(v, f.name) for f in dataclasses.fields(v)})
        if isinstance(v, np.ndarray):
            return ["nd", v.dtype.str, list(v.shape), hashlib.sha256(v.tobytes()).hexdigest()]
        if isinstance(v, dict):
            return {str(k): canon(x) for k, x in sorted(v.items()) if k != "timings"}
        if isinstance(v, (list, tuple)):
            return [canon(x) for x in v]
        if isinstance(v, float):
            return repr(v)
        if isinstance(v, str) and v.lstrip().startswith("{"):
            return canon(json.loads(v))
        return repr(v)

    text = json.dumps(canon(value), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def outcome(call: Callable[[], Any]) -> list[Any]:
    """`["ok", digest]` or `["raise", class, ValueError?, TypeError?, MvGraspError?, text]`."""
    import mvgrasp

    try:
        return ["ok", digest(call())]
    except BaseException as e:  # a PanicException is a BaseException
        if isinstance(e, KeyboardInterrupt):
            raise
        return ["raise", type(e).__name__, isinstance(e, ValueError),
                isinstance(e, TypeError), isinstance(e, mvgrasp.MvGraspError), str(e)]  # fmt: skip


def worker(function: str, cases_file: str, start: int) -> None:
    """Runs cases `start`... of `cases_file`, a line before and after each."""
    import resource
    import warnings

    resource.setrlimit(resource.RLIMIT_AS, (8 << 30, 8 << 30))
    warnings.simplefilter("ignore")
    cases = json.loads(Path(cases_file).read_text())
    spec = all_specs()[function]()
    references: dict[str, list[Any]] = {}
    for i in range(start, len(cases)):
        case = cases[i]
        print(json.dumps({"start": i}), flush=True)
        value, reference = variant_of(spec, case)
        arrays = {**spec.arrays, case["key"]: value}
        got = outcome(lambda: spec.call(arrays))
        expected = None
        if reference is not None:
            key = case["key"] + hashlib.sha256(
                reference.tobytes() + reference.dtype.str.encode()).hexdigest()  # fmt: skip
            if key not in references:
                references[key] = outcome(lambda: spec.call({**spec.arrays,
                                                             case["key"]: reference}))  # fmt: skip
            expected = references[key]
        print(json.dumps({"done": i, "got": got, "expected": expected}), flush=True)


def run_cases(function: str, cases: list[dict[str, Any]], tmp: Path) -> list[dict[str, Any]]:
    """Every case's `got` and `expected`, in worker processes; `got` is `["crash", signal]`
    for a case during which the worker died."""
    cases_file = tmp / "cases.json"
    cases_file.write_text(json.dumps(cases))
    results: list[dict[str, Any]] = [{} for _ in cases]
    start = 0
    path = os.pathsep.join(filter(None, [str(HERE), os.environ.get("PYTHONPATH")]))
    env = dict(os.environ, RUST_BACKTRACE="0", PYTHONPATH=path)
    while start < len(cases):
        code = (f"import test_array_layouts as t; t.worker({function!r}, "
                f"{str(cases_file)!r}, {start})")  # fmt: skip
        proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                              env=env, timeout=900)  # fmt: skip
        running = None
        for line in proc.stdout.splitlines():
            if not line.startswith("{"):
                continue
            record = json.loads(line)
            if "start" in record:
                running = record["start"]
            else:
                results[record["done"]] = record
                running = None
        if proc.returncode == 0 and running is None:
            break
        if running is None:  # died outside a case (building the inputs)
            raise AssertionError(f"{function}: worker failed: {proc.stderr[-2000:]}")
        tail = proc.stderr.strip().splitlines()[-3:]
        results[running] = {"got": ["crash", proc.returncode, " | ".join(tail)],
                            "expected": None}  # fmt: skip
        start = running + 1
    return results


def names_argument(message: str, names: tuple[str, ...]) -> bool:
    """Whether `message` names one of `names` as a word (`depths[1]: shape ...` names
    `depths`; `ks[0]` does not name `k`)."""
    return any(re.search(rf"(?<![\w]){re.escape(n)}(?![\w])", message) for n in names)


def judge(spec: Spec, case: dict[str, Any], result: dict[str, Any]) -> str | None:
    """Why the case's outcome breaks the property, or `None`."""
    got, expected = result.get("got"), result.get("expected")
    if got is None:
        return "never ran"
    if got[0] == "crash":
        return f"crashed (exit status {got[1]}: {got[2]})"
    names = spec.names_of(case["key"])
    named_refusal = got[0] == "raise" and (got[2] or got[3]) and names_argument(got[5], names)
    domain_error = got[0] == "raise" and got[1] == DOMAIN_ERRORS.get(case["key"])
    if case["kind"] == "same":
        if got != expected and not (case["variant"] == "list" and named_refusal):
            return f"gave {got}, the C-contiguous copy {expected}"
        return None
    if case["kind"] == "content":
        if got != expected:
            return f"gave {got}, the C-contiguous copy {expected}"
        if got[0] == "raise" and not (named_refusal or got[4]):
            return f"raised {got[1]}: {got[5]!r}"
        return None
    if case["kind"] == "cast" and expected is not None and got == expected:
        return None
    if got[0] == "ok" or named_refusal or domain_error:
        if got[0] == "raise" and got[1] not in ("ValueError", "TypeError") and not got[4]:
            return f"raised {got[1]} (not a ValueError or TypeError): {got[5]!r}"
        return None
    return f"raised {got[1]}: {got[5]!r} (expected a ValueError/TypeError naming {names})"


# ---------------------------------------------------------------------------------------------
# Tests.


def stub_array_arguments() -> set[tuple[str, str]]:
    """(function, argument) for every argument of the native stubs typed as an array."""
    import mvgrasp

    stubs = Path(mvgrasp.__file__).with_name("_native.pyi")
    found = set()
    for node in ast.parse(stubs.read_text()).body:
        if isinstance(node, ast.FunctionDef):
            args = node.args.args + node.args.kwonlyargs
            for a in args:
                if a.annotation is not None and "npt." in ast.unparse(a.annotation):
                    found.add((node.name, a.arg))
    return found


def test_every_array_argument_of_the_native_module_is_covered() -> None:
    covered = set()
    for function, build in native_specs().items():
        for key in build().arrays:
            covered.add((function, key.split("[")[0]))
    # Array arguments only given with their defaults here (or nested in other arguments).
    assert stub_array_arguments() - covered == set()


@pytest.mark.parametrize("function", list(all_specs()))
def test_base_inputs_plan(function: str) -> None:
    spec = all_specs()[function]()
    got = outcome(lambda: spec.call(spec.arrays))
    assert got[0] == "ok", got


@pytest.mark.parametrize("function", list(all_specs()))
def test_any_layout_is_read_as_its_contiguous_copy_or_refused_by_name(
    function: str, tmp_path: Path
) -> None:
    spec = all_specs()[function]()
    cases = cases_of(function, spec)
    results = run_cases(function, cases, tmp_path)
    failures = []
    for case, result in zip(cases, results):
        why = judge(spec, case, result)
        if why is not None:
            failures.append(f"{function}({case['key']}={case['kind']}:{case['variant']}): {why}")
    assert not failures, f"{len(failures)} of {len(cases)} cases:\n" + "\n".join(failures[:40])
