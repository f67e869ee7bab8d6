"""Arrays from trimesh, meshio and libigl go straight in."""

from __future__ import annotations

import numpy as np
import pytest
import shapeup

from conftest import DATA


def deform(V, F):
    s = shapeup.Solver(V, F)
    s.add("iso_one_ring")
    low = V[:, 1] < V[:, 1].min() + 0.02 * np.ptp(V[:, 1])
    high = V[:, 1] > V[:, 1].max() - 0.02 * np.ptp(V[:, 1])
    s.add("position", low, name="base")
    s.add("position", high, name="top", translate=[0.1 * np.ptp(V[:, 0]), 0.0, 0.0])
    q, report = s.solve(iterations=20)
    assert np.isfinite(q).all() and report["energy"][-1] <= report["initial_energy"]
    return q


def test_trimesh():
    trimesh = pytest.importorskip("trimesh")
    m = trimesh.load(DATA / "stanford-bunny.obj", process=False, maintain_order=True)
    ref = shapeup.read_mesh(DATA / "stanford-bunny.obj")
    np.testing.assert_array_equal(m.vertices, ref.V)  # every vertex, in file order
    q = deform(m.vertices, m.faces)
    assert q.shape == m.vertices.shape


def test_meshio():
    meshio = pytest.importorskip("meshio")
    m = meshio.read(DATA / "stanford-bunny.obj")
    q = deform(m.points, m.cells_dict["triangle"])
    ref = shapeup.read_mesh(DATA / "stanford-bunny.obj")
    np.testing.assert_allclose(q, deform(ref.V, ref.F), atol=1e-12)


def test_libigl():
    igl = pytest.importorskip("igl")
    V, F = igl.read_triangle_mesh(str(DATA / "stanford-bunny.obj"))
    q = deform(V, F)
    assert q.shape == V.shape


def test_the_trimesh_polyscope_example_renders_headless(tmp_path):
    pytest.importorskip("trimesh")
    pytest.importorskip("polyscope")
    import subprocess
    import sys

    from conftest import ROOT

    out = tmp_path / "shot.png"
    run = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "python" / "trimesh_polyscope.py"), "--screenshot", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    assert "->" in run.stdout
    assert out.stat().st_size > 10_000 and out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
