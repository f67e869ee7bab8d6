"""The Solver: every registered type is reachable, the energy never increases, and a solve
equals the command line's on the same scene."""

from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest
import shapeup

from conftest import DATA, grid, tet_cube

TYPES = [t.name for t in shapeup.constraint_types()]

# These tests run a few iterations on purpose (monotone energy, rigid motions): that they stop
# short of the minimum is expected, and said (test_scene.py checks the warning itself).
pytestmark = pytest.mark.filterwarnings("ignore::shapeup.UnconvergedWarning")


def test_registry_is_complete():
    # The same list `shapeup types` prints; and help() on add lists every type.
    table = shapeup.catalogue_markdown()
    for name in TYPES:
        assert f"`{name}`" in table
        assert name in shapeup.Solver.add.__doc__
    assert {"plane", "circle", "rigid", "position", "surface_closeness", "gravity"} <= set(TYPES)


@pytest.mark.parametrize("kind", TYPES)
def test_every_type_solves_and_never_raises_the_energy(kind):
    info = {t.name: t for t in shapeup.constraint_types()}[kind]
    if info.acts_on == "tetrahedra":
        V, T = tet_cube()
        s = shapeup.Solver(V, T=T)
        anchor = [0]
    else:
        V, F = grid(4, 3, bump=0.3)
        anchor = [0, 4]
    selection = None
    if info.acts_on == "vertices of pieces that follow others":
        # A flake of its own above the grid: the piece that follows it.
        n = len(V)
        centre = V.mean(axis=0)
        flake = centre + np.array([[0.0, 0.0, 0.05], [0.1, 0.0, 0.05], [0.1, 0.1, 0.05], [0.0, 0.1, 0.05]])
        V, F = np.vstack([V, flake]), np.vstack([F, [[n, n + 1, n + 2, n + 3]]])
        selection = [n, n + 1, n + 2, n + 3]
    if info.acts_on != "tetrahedra":
        s = shapeup.Solver(V, F)
    kwargs = {"translate": [0.0, 0.1, 0.0]} if info.has_targets else {}
    g = s.add(kind, selection, **kwargs) if selection is not None else s.add(kind, **kwargs)
    assert g.type == kind and g.constraints > 0
    if kind != "position":
        s.add("position", anchor, weight=10.0, name="anchor")
    # Something to work against, so that the energy is not already 0.
    s.add("edge_spring" if kind != "edge_spring" else "laplacian", weight=0.1, name="extra")
    q0 = V + 0.05 * np.random.default_rng(1).standard_normal(V.shape)
    q, report = s.solve(q0, iterations=8, acceleration="none")
    assert q.shape == V.shape and np.isfinite(q).all()
    e = [report["initial_energy"]] + report["energy"]
    assert all(b <= a + 1e-9 * abs(a) + 1e-12 for a, b in zip(e, e[1:])), e
    energy = s.energy(q)
    assert energy["total"] == pytest.approx(report["energy"][-1], rel=1e-9, abs=1e-12)
    assert set(energy["groups"]) == {g.name for g in s.groups}


def test_handles_move_and_groups_change():
    V, F = grid(6, 6)
    s = shapeup.Solver(V, F)
    s.add("edge_spring")
    base = s.add("position", V[:, 0] < 1e-9, name="base")
    tip = s.add("position", V[:, 0] > 1 - 1e-9, name="tip")
    held = s.held(tip)
    np.testing.assert_array_equal(held, np.flatnonzero(V[:, 0] > 1 - 1e-9))
    s.set_targets("tip", V[held] + [0.0, 0.3, 0.0])
    q, _ = s.solve(iterations=50)
    np.testing.assert_allclose(q[held, 1], 0.3, atol=0.05)
    s.set_weight(base, 0.0)
    s.remove(tip)
    assert [g.name for g in s.groups] == ["edge_spring", "base"]
    # A second group of the same type gets its own name.
    assert s.add("edge_spring").name == "edge_spring_2"


def test_rigid_motion_commutes():
    V, F = grid(5, 5, bump=0.2)
    rot = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    shift = np.array([1.0, 2.0, -3.0])
    d = np.array([0.0, 0.0, 0.2])
    results = []
    for W, dd in ((V, d), (V @ rot.T + shift, d @ rot.T)):
        s = shapeup.Solver(W, F)
        s.add("plane")
        s.add("position", [0, 1, 2], name="a")
        s.set_targets("a", W[[0, 1, 2]] + dd)
        results.append(s.solve(iterations=20)[0])
    np.testing.assert_allclose(results[0] @ rot.T + shift, results[1], atol=1e-9)


def test_equals_the_command_line(tmp_path, cli):
    # A scene without normalization works in the file's coordinates, as the Solver does.
    mesh = DATA / "stanford-bunny.obj"
    scene = tmp_path / "s.toml"
    scene.write_text(
        f'[mesh]\npath = "{mesh}"\nnormalize = false\n[solver]\niterations = 30\n'
        '[[constraints]]\ntype = "edge_spring"\nweight = 10.0\n'
        '[[constraints]]\ntype = "position"\nname = "base"\nbox = { min = [-1, -1, -1], max = [1, 0.05, 1] }\n'
        '[[constraints]]\ntype = "position"\nname = "ears"\nbox = { min = [-1, 0.16, -1], max = [1, 1, 1] }\n'
        "translate = [0.02, 0.01, 0.0]\n"
    )
    out = tmp_path / "cli.obj"
    subprocess.run([str(cli), "deform", str(scene), "-o", str(out)], check=True, capture_output=True)
    expected = shapeup.read_mesh(out).V

    m = shapeup.read_mesh(mesh)
    V = m.V
    s = shapeup.Solver(m.V, m.F)
    s.add("edge_spring", weight=10.0)
    s.add("position", (V[:, 1] <= 0.05), name="base")
    ears = V[:, 1] >= 0.16
    s.add("position", ears, name="ears", translate=[0.02, 0.01, 0.0])
    q, report = s.solve(iterations=30)
    assert report["iterations"] == 30
    np.testing.assert_allclose(q, expected, rtol=0, atol=1e-12)


def test_groups_lost_to_round_off_are_said(recwarn):
    # Springs at 1e8 dwarf handles at 1e-8: the factorization cannot see the handles. With
    # another anchor the solve runs and says so (RoundOffWarning, report "warnings"); with none
    # the error names the groups instead of asking for a position group.
    V, F = grid(5, 5)
    solver = shapeup.Solver(V, F)
    solver.add("edge_spring", weight=1e8)
    solver.add("position", [0, 5], weight=1e-8, name="pin")
    with pytest.raises(shapeup.SolveFailed, match=r'lost to round-off.*"pin" \(weight 1e-8\) against "edge_spring"'):
        solver.solve(iterations=3)
    solver.add("position", [0], name="anchor")
    with pytest.warns(shapeup.RoundOffWarning, match=r'1 group\(s\) whose terms are below round-off.*"pin"'):
        _, report = solver.solve(iterations=3)
    assert [w["kind"] for w in report["warnings"] if w["kind"] == "groups_lost_to_round_off"] == [
        "groups_lost_to_round_off"
    ]

    # Time steps: the same, warned once per call of Simulation.step, with the step reports'
    # lost_groups.
    sim = shapeup.Simulation(V, F)
    sim.add("edge_spring", weight=1e8)
    sim.add("position", [0, 5], weight=1e-8, name="pin")
    with pytest.warns(shapeup.RoundOffWarning, match=r'1 group\(s\) whose terms are below round-off.*"pin"') as caught:
        reports = sim.step(3)
    assert len([w for w in caught if issubclass(w.category, shapeup.RoundOffWarning)]) == 1
    assert all(r["lost_groups"] == ['"pin" (weight 1e-8) against "edge_spring" (weight 1e8)'] for r in reports)
