"""The type stubs (`_native.pyi`) against the native module's real signatures: names,
parameters, their kinds and defaults, so that the stubs cannot drift from the Rust code."""

from __future__ import annotations

import ast
import inspect
from pathlib import Path

import mvgrasp
from mvgrasp import _native

STUBS = Path(mvgrasp.__file__).with_name("_native.pyi")


def stub_functions() -> dict[str, ast.FunctionDef]:
    tree = ast.parse(STUBS.read_text())
    return {node.name: node for node in tree.body if isinstance(node, ast.FunctionDef)}


def stub_classes() -> set[str]:
    tree = ast.parse(STUBS.read_text())
    return {node.name for node in tree.body if isinstance(node, ast.ClassDef)}


def stub_parameters(function: ast.FunctionDef) -> list[tuple[str, str, object]]:
    """(name, kind, default) per parameter, in order; `inspect.Parameter.empty` for none."""
    args = function.args
    positional = args.posonlyargs + args.args
    defaults: list[object] = [inspect.Parameter.empty] * (len(positional) - len(args.defaults))
    defaults += [ast.literal_eval(d) for d in args.defaults]
    params = [
        (a.arg, "POSITIONAL_ONLY" if a in args.posonlyargs else "POSITIONAL_OR_KEYWORD", d)
        for a, d in zip(positional, defaults)
    ]
    for a, d in zip(args.kwonlyargs, args.kw_defaults):
        default = inspect.Parameter.empty if d is None else ast.literal_eval(d)
        params.append((a.arg, "KEYWORD_ONLY", default))
    return params


def native_parameters(function: object) -> list[tuple[str, str, object]]:
    signature = inspect.signature(function)  # type: ignore[arg-type]
    return [(p.name, p.kind.name, p.default) for p in signature.parameters.values()]


def native_functions() -> dict[str, object]:
    return {
        name: value
        for name, value in vars(_native).items()
        if callable(value) and not isinstance(value, type) and not name.startswith("_")
    }


def test_every_native_function_has_a_stub_and_every_stub_a_function() -> None:
    assert set(native_functions()) == set(stub_functions())
    classes = {n for n, v in vars(_native).items() if isinstance(v, type)}
    assert classes == stub_classes()


def test_stub_signatures_match_the_native_ones() -> None:
    stubs = stub_functions()
    for name, function in sorted(native_functions().items()):
        assert stub_parameters(stubs[name]) == native_parameters(function), name


# Native functions the package exports through dataclass wrappers (mvgrasp.grasps), and the
# package's own classes and modules.
WRAPPED = {
    "sample_grasps", "grasp_quality", "robust_quality", "check_collision", "physics_trial",
    "gripper",
}  # fmt: skip
PYTHON_SIDE = {
    "Camera", "Grasp", "PlanResult", "PlannedGrasp", "Planner", "Sampling", "ViewSummary",
    "grasps",
}  # fmt: skip


def test_the_package_exports_everything_the_native_module_has() -> None:
    public = set(native_functions()) | {n for n, v in vars(_native).items() if isinstance(v, type)}
    assert public | {"__version__"} | PYTHON_SIDE == set(mvgrasp.__all__)
    for name in public - WRAPPED:
        assert getattr(mvgrasp, name) is getattr(_native, name)
    for name in WRAPPED:
        assert getattr(mvgrasp, name) is getattr(mvgrasp.grasps, name)
        # The wrapper takes the native keywords, with the native defaults.
        wrapper = inspect.signature(getattr(mvgrasp.grasps, name)).parameters
        wrapped = inspect.signature(getattr(_native, name)).parameters
        for keyword, p in wrapped.items():
            if p.kind is p.KEYWORD_ONLY:
                assert wrapper[keyword].default == p.default, (name, keyword)


def test_every_function_is_documented() -> None:
    for name, function in native_functions().items():
        assert (function.__doc__ or "").strip(), name
        assert ast.get_docstring(stub_functions()[name]), name
