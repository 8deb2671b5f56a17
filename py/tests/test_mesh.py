"""mvgrasp.load_mesh and the exception tree, against the built wheel."""

from __future__ import annotations

import ast
import math
import sys
from pathlib import Path

import numpy as np
import pytest

import mvgrasp

if sys.version_info >= (3, 11):
    import tomllib
else:  # the wheel supports Python 3.9+
    tomllib = pytest.importorskip("tomli")

from conftest import shared_data

REPO_ROOT = Path(__file__).resolve().parents[2]

# A tetrahedron with 5 cm legs along the axes.
TETRA_VERTICES = np.array(
    [[0.0, 0.0, 0.0], [0.05, 0.0, 0.0], [0.0, 0.05, 0.0], [0.0, 0.0, 0.05]],
    dtype=np.float32,
)
TETRA_FACES = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]


def write_obj(path: Path, vertices: list[tuple[float, float, float]]) -> Path:
    lines = [f"v {x} {y} {z}" for x, y, z in vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in TETRA_FACES]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture
def tetrahedron(tmp_path: Path) -> Path:
    return write_obj(tmp_path / "tetra.obj", [tuple(map(float, v)) for v in TETRA_VERTICES])


def test_version_is_the_crate_version() -> None:
    cargo = tomllib.loads((REPO_ROOT / "Cargo.toml").read_text())
    assert mvgrasp.__version__ == cargo["workspace"]["package"]["version"]


def test_stub_lists_exactly_the_native_exports() -> None:
    stub = Path(mvgrasp.__file__).with_name("_native.pyi")
    tree = ast.parse(stub.read_text())
    stubbed = {
        node.name if not isinstance(node, ast.AnnAssign) else ast.unparse(node.target)
        for node in tree.body
        if isinstance(node, (ast.ClassDef, ast.FunctionDef, ast.AnnAssign))
    }
    native = {name for name in dir(mvgrasp._native) if not name.startswith("_")}
    assert stubbed == native | {"__version__"}


def test_exception_tree() -> None:
    assert issubclass(mvgrasp.MvGraspError, Exception)
    for error in (
        mvgrasp.MeshError,
        mvgrasp.CameraError,
        mvgrasp.WeightsError,
        mvgrasp.RenderError,
        mvgrasp.PlanningError,
        mvgrasp.DatasetError,
        mvgrasp.GraspError,
    ):
        assert issubclass(error, mvgrasp.MvGraspError)
    assert mvgrasp.MeshError.__module__ == "mvgrasp"


def test_load_tetrahedron(tetrahedron: Path) -> None:
    vertices, triangles = mvgrasp.load_mesh(tetrahedron)
    assert vertices.shape == (4, 3)
    assert vertices.dtype == np.float32
    assert triangles.shape == (4, 3)
    assert triangles.dtype == np.uint32
    # The loader may reorder vertices; compare as sets of points and faces.
    assert sorted(map(tuple, vertices.tolist())) == sorted(map(tuple, TETRA_VERTICES.tolist()))
    faces = {tuple(sorted(tuple(vertices[i].tolist()) for i in tri)) for tri in triangles}
    expected = {tuple(sorted(tuple(TETRA_VERTICES[i].tolist()) for i in f)) for f in TETRA_FACES}
    assert faces == expected


def test_load_accepts_str_path(tetrahedron: Path) -> None:
    vertices, _ = mvgrasp.load_mesh(str(tetrahedron))
    assert vertices.shape == (4, 3)


def test_scale_multiplies_coordinates(tmp_path: Path) -> None:
    # The same tetrahedron written in millimetres.
    path = write_obj(tmp_path / "tetra_mm.obj", [tuple(1000.0 * v) for v in TETRA_VERTICES])
    vertices, _ = mvgrasp.load_mesh(path, scale=0.001)
    np.testing.assert_allclose(vertices.max(axis=0), [0.05, 0.05, 0.05], rtol=1e-6)


def test_millimetre_mesh_without_scale_is_a_mesh_error(tmp_path: Path) -> None:
    path = write_obj(tmp_path / "tetra_mm.obj", [tuple(1000.0 * v) for v in TETRA_VERTICES])
    with pytest.raises(mvgrasp.MeshError, match="tetra_mm.obj"):
        mvgrasp.load_mesh(path)


@pytest.mark.parametrize("scale", [0.0, -1.0, math.nan, math.inf])
def test_bad_scale_is_a_value_error(tetrahedron: Path, scale: float) -> None:
    with pytest.raises(ValueError, match="scale"):
        mvgrasp.load_mesh(tetrahedron, scale=scale)


def test_missing_file_is_a_mesh_error_naming_the_path(tmp_path: Path) -> None:
    missing = tmp_path / "no_such_mesh.obj"
    with pytest.raises(mvgrasp.MeshError) as info:
        mvgrasp.load_mesh(missing)
    assert str(missing) in str(info.value)
    # Catchable as the base class too.
    assert isinstance(info.value, mvgrasp.MvGraspError)


def test_nan_vertex_is_a_mesh_error(tmp_path: Path) -> None:
    vertices = [tuple(map(float, v)) for v in TETRA_VERTICES]
    vertices[2] = (0.0, math.nan, 0.0)
    path = write_obj(tmp_path / "nan.obj", vertices)
    with pytest.raises(mvgrasp.MeshError, match="nan.obj"):
        mvgrasp.load_mesh(path)


def test_ycb_mesh_has_plausible_extents() -> None:
    ycb_meshes = shared_data("meshes/ycb/meshes")
    objs = sorted(ycb_meshes.glob("*.obj"))
    assert objs, f"no .obj files in {ycb_meshes}"
    vertices, triangles = mvgrasp.load_mesh(objs[0])
    assert vertices.dtype == np.float32 and triangles.dtype == np.uint32
    assert len(vertices) > 100 and len(triangles) > 100
    assert np.isfinite(vertices).all()
    assert int(triangles.max()) < len(vertices)
    extents = vertices.max(axis=0) - vertices.min(axis=0)
    assert 0.01 < extents.max() < 0.5, f"{objs[0].name}: extents {extents} m"
