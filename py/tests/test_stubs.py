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


def test_the_package_exports_everything_the_native_module_has() -> None:
    public = set(native_functions()) | {n for n, v in vars(_native).items() if isinstance(v, type)}
    assert public | {"__version__"} == set(mvgrasp.__all__)
    for name in public:
        assert getattr(mvgrasp, name) is getattr(_native, name)


def test_every_function_is_documented() -> None:
    for name, function in native_functions().items():
        assert (function.__doc__ or "").strip(), name
        assert ast.get_docstring(stub_functions()[name]), name
