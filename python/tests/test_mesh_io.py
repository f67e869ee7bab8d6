"""numpy <-> library round trips: what a file carries comes back out, moved."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
import shapeup

from conftest import DATA, grid


def test_read_gives_arrays_in_file_order():
    m = shapeup.read_mesh(DATA / "stanford-bunny.obj")
    lines = (DATA / "stanford-bunny.obj").read_text().splitlines()
    rows = [list(map(float, l.split()[1:4])) for l in lines if l.startswith("v ")]
    assert m.V.dtype == np.float64 and m.V.shape == (len(rows), 3)
    np.testing.assert_array_equal(m.V, np.array(rows))
    assert m.F.dtype == np.int64 and m.F.shape[1] == 3
    assert m.F.min() >= 0 and m.F.max() < len(m)


def test_quads_stay_quads_and_move(tmp_path):
    m = shapeup.read_mesh(DATA / "suzanne.obj")
    sizes = {len(p) for p in m.polygons}
    assert 4 in sizes
    V2 = m.V + np.array([0.5, -1.0, 2.0])
    out = tmp_path / "moved.obj"
    shapeup.write_mesh(out, V2, like=m)
    back = shapeup.read_mesh(out)
    np.testing.assert_allclose(back.V, V2, rtol=0, atol=1e-12)
    assert [p.tolist() for p in back.polygons] == [p.tolist() for p in m.polygons]


def test_texture_coordinates_round_trip(tmp_path):
    m = shapeup.read_mesh(DATA / "spot.obj")
    uv = m.texcoords
    assert uv is not None and uv[0].shape[1] == 2
    out = tmp_path / "spot.obj"
    shapeup.write_mesh(out, m.V * 2.0, like=m)
    back = shapeup.read_mesh(out)
    np.testing.assert_allclose(back.V, m.V * 2.0, atol=1e-12)
    np.testing.assert_array_equal(back.texcoords[0], uv[0])
    np.testing.assert_array_equal(back.texcoords[1], uv[1])


@pytest.mark.parametrize("ext", ["obj", "ply", "off"])
def test_arrays_round_trip(tmp_path, ext):
    V, F = grid(3, 2)
    out = tmp_path / f"grid.{ext}"
    shapeup.write_mesh(out, V, F)
    back = shapeup.read_mesh(out)
    np.testing.assert_allclose(back.V, V, atol=1e-12)
    assert [p.tolist() for p in back.polygons] == F.tolist()


def test_polygon_lists_and_tetrahedra(tmp_path):
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 1.5, 0]], dtype=float)
    F = [[0, 1, 2, 3], [3, 2, 4]]
    m = shapeup.Mesh.from_arrays(V, F)
    assert [p.tolist() for p in m.polygons] == F
    assert m.F.shape == (3, 3)
    from conftest import tet_cube

    Vt, T = tet_cube()
    out = tmp_path / "cube.msh"
    shapeup.write_mesh(out, Vt, T=T)
    back = shapeup.read_mesh(out)
    np.testing.assert_allclose(back.V, Vt, atol=1e-12)
    assert sorted(map(sorted, back.T.tolist())) == sorted(map(sorted, T.tolist()))


def test_c_contiguous_float64_is_not_copied():
    from shapeup._api import _vertices

    V = np.zeros((4, 3))
    assert _vertices(V) is V
    # Other layouts are converted (a copy), not refused.
    Vf = np.asfortranarray(np.ones((4, 3)))
    assert _vertices(Vf).flags.c_contiguous
    assert _vertices(np.ones((4, 3), dtype=np.float32)).dtype == np.float64


def test_duplicate_faces_are_kept_and_said_once():
    # Faces on the same vertices as an earlier one (reversed, rotated) stay, in their order,
    # and are said once with a count, as a MeshWarning and in Mesh.warnings; a quad is no
    # warning; the solver runs on what was given.
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float)
    F = np.array([[0, 1, 2], [1, 3, 2], [2, 1, 0], [1, 2, 0]])
    with pytest.warns(shapeup.MeshWarning, match=r"2 face\(s\) on the same vertices.*first: face 2, as face 0"):
        mesh = shapeup.Mesh.from_arrays(V, F)
    np.testing.assert_array_equal(mesh.F, F)
    assert [w for w in mesh.warnings if "same vertices" in w]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        shapeup.Mesh.from_arrays(V, [[0, 1, 3, 2]])
    with pytest.warns(shapeup.MeshWarning, match=r"1 face\(s\) on the same vertices"):
        solver = shapeup.Solver(V, F[:3])
    solver.add("edge_spring")
    solver.add("position", vertices=[0, 1, 2])
    X, _ = solver.solve()
    assert np.isfinite(X).all()


def test_read_mesh_says_duplicate_faces_as_arrays_do(tmp_path):
    # A file's duplicate faces are said as a MeshWarning too (the command line's line), and a
    # file's quads are not.
    path = tmp_path / "twice.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\nf 3 2 1\n")
    with pytest.warns(shapeup.MeshWarning, match=r"1 face\(s\) on the same vertices"):
        mesh = shapeup.read_mesh(path)
    assert len(mesh.F) == 3
    quad = tmp_path / "quad.obj"
    quad.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        shapeup.read_mesh(quad)


def test_gmsh_physical_groups_select_and_come_back(tmp_path):
    # A .msh file's physical groups select vertices, as `physical = "fixed"` in scenes, and
    # write_mesh(like=mesh) gives the file back with only its coordinates changed.
    src = Path(__file__).resolve().parents[2] / "crates/shapeup-core/tests/data/cube-groups.msh"
    mesh = shapeup.read_mesh(src)
    solver = shapeup.Solver(mesh=mesh)
    solver.add("tet_strain", {"physical": "solid"})
    fixed = solver.add("position", {"physical": "fixed"}, hard=True)
    solver.add("position", np.flatnonzero(mesh.V[:, 0] > 0.9), translate=[0.2, 0, 0])
    X, _ = solver.solve()
    np.testing.assert_array_equal(X[[0, 3, 4, 7]], mesh.V[[0, 3, 4, 7]])
    assert fixed.constraints > 0
    out = tmp_path / "out.msh"
    shapeup.write_mesh(out, X, like=mesh)
    before, after = src.read_text().splitlines(), out.read_text().splitlines()
    assert len(before) == len(after)
    assert sum(a != b for a, b in zip(before, after)) <= 8, "only node lines change"
    assert "$PhysicalNames" in out.read_text()
    with pytest.raises(ValueError, match='no physical group "top".*"fixed", "solid"'):
        solver.add("position", {"physical": "top"})
    plain = shapeup.Solver(mesh.V, mesh.F)
    with pytest.raises(ValueError, match="has none"):
        plain.add("position", {"physical": "fixed"})
