"""Scene.load(...).deform() / simulate() give what the command line gives."""

from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest
import shapeup

from conftest import EXAMPLES


@pytest.mark.parametrize("name", ["bunny-springs", "roof-planarize", "spot-rigid-head"])
@pytest.mark.filterwarnings("ignore::shapeup.UnconvergedWarning")
def test_deform_equals_cli(tmp_path, cli, name):
    scene = EXAMPLES / f"{name}.toml"
    out, rep = tmp_path / "cli.obj", tmp_path / "cli.json"
    subprocess.run([str(cli), "deform", str(scene), "-o", str(out), "--report", str(rep)], check=True, capture_output=True)
    expected = shapeup.read_mesh(out).V
    cli_report = json.loads(rep.read_text())

    V, report = shapeup.Scene.load(scene).deform(output=tmp_path / "py.obj", report=tmp_path / "py.json")
    np.testing.assert_allclose(V, expected, rtol=0, atol=1e-12)
    np.testing.assert_allclose(shapeup.read_mesh(tmp_path / "py.obj").V, expected, rtol=0, atol=1e-12)
    assert report["iterations"] == cli_report["iterations"]
    np.testing.assert_allclose(report["energy"], cli_report["energy"], rtol=1e-12)
    # The roof and Spot stop at their caps short of their minima: both doors say so alike.
    assert report["unconverged"] == cli_report["unconverged"] == (name != "bunny-springs")
    np.testing.assert_allclose(report["residual"], cli_report["residual"], rtol=1e-9)
    assert [g["name"] for g in report["groups"]] == [g["name"] for g in cli_report["groups"]]
    assert json.loads((tmp_path / "py.json").read_text())["energy"] == report["energy"]


def test_simulate_equals_cli(tmp_path, cli):
    scene = EXAMPLES / "cloth-drape.toml"
    subprocess.run(
        [str(cli), "simulate", str(scene), "--frames", "12", "--every", "4", "-o", str(tmp_path / "cli")],
        check=True,
        capture_output=True,
    )
    X, report = shapeup.Scene.load(scene).simulate(12, every=4, output=tmp_path / "py")
    assert report["frame_numbers"] == [0, 4, 8, 12]
    for i, k in enumerate(report["frame_numbers"]):
        expected = shapeup.read_mesh(tmp_path / "cli" / f"frame_{k:04d}.obj").V
        np.testing.assert_allclose(X[i], expected, rtol=0, atol=1e-12)
        np.testing.assert_allclose(shapeup.read_mesh(tmp_path / "py" / f"frame_{k:04d}.obj").V, expected, atol=1e-12)


def test_overrides(tmp_path):
    scene = EXAMPLES / "bunny-springs.toml"
    s = shapeup.Scene.load(scene, {"solver.iterations": 3, "constraints.0.weight": 2.5, "output.path": str(tmp_path / "o.obj")})
    assert "iterations = 3" in s.to_toml() and "weight = 2.5" in s.to_toml()
    assert s.output_path == tmp_path / "o.obj"
    _, report = s.deform()
    assert report["iterations"] == 3
    with pytest.raises(KeyError, match="constraints.9"):
        shapeup.Scene.load(scene, {"constraints.9.weight": 1.0})
    with pytest.raises(ValueError, match="iteratons"):
        shapeup.Scene.load(scene, {"solver.iteratons": 1})


def test_a_utf16_scene_loads_with_overrides(tmp_path):
    # The core reads the file and applies the overrides: a UTF-16 file (with its byte-order
    # mark, as Windows editors save "Unicode") loads with overrides as it does without.
    text = (EXAMPLES / "bunny-springs.toml").read_text(encoding="utf-8")
    text = text.replace('"../data/stanford-bunny.obj"', f'"{(EXAMPLES.parent / "data" / "stanford-bunny.obj").as_posix()}"')
    scene = tmp_path / "utf16.toml"
    scene.write_bytes(text.encode("utf-16"))
    assert scene.read_bytes()[:2] in (b"\xff\xfe", b"\xfe\xff")
    plain = shapeup.Scene.load(scene)
    s = shapeup.Scene.load(scene, {"solver.iterations": 3, "constraints.0.weight": 2.5})
    assert "iterations = 3" in s.to_toml() and "weight = 2.5" in s.to_toml()
    assert "iterations = 50" in plain.to_toml()
    _, report = s.deform()
    assert report["iterations"] == 3
    assert report["groups"][0]["weight"] == 2.5


def test_nothing_is_written_when_a_result_cannot_be(tmp_path):
    scene = shapeup.Scene.load(EXAMPLES / "bunny-springs.toml")
    out = tmp_path / "left.obj"
    with pytest.raises(OSError, match="proc"):
        scene.deform(output=out, report="/proc/x.json")
    with pytest.raises(ValueError, match="obj, ply, off, stl, vtu, msh"):
        scene.deform(output=tmp_path / "roof.xyz")
    with pytest.raises(ValueError, match="json"):
        scene.deform(output=out, report=tmp_path / "r.txt")
    assert list(tmp_path.iterdir()) == []


def test_simulate_report_has_the_cli_keys(tmp_path, cli):
    scene = EXAMPLES / "cloth-drape.toml"
    rep = tmp_path / "cli.json"
    subprocess.run(
        [str(cli), "simulate", str(scene), "--frames", "3", "-o", str(tmp_path / "f"), "--report", str(rep)],
        check=True,
        capture_output=True,
    )
    cli_report = json.loads(rep.read_text())
    _, report = shapeup.Scene.load(scene).simulate(3)
    assert set(cli_report) <= set(report), set(cli_report) - set(report)
    assert set(cli_report["timings"]) == set(report["timings"])
    np.testing.assert_allclose(report["energy"], cli_report["energy"], rtol=1e-12)


def test_a_loaded_scene_survives_chdir(tmp_path, monkeypatch):
    monkeypatch.chdir(EXAMPLES.parent)
    scene = shapeup.Scene.load("examples/bunny-springs.toml")
    monkeypatch.chdir(tmp_path)
    V, _ = scene.deform(iterations=1)
    assert V.shape[1] == 3


def test_simulate_never_replaces_its_inputs_and_replaces_an_earlier_runs_frames(tmp_path):
    # A mesh that is frame 0 of an earlier run, simulated into that folder again: the first
    # frame would replace it, so nothing runs (as `shapeup simulate`).
    earlier = tmp_path / "earlier"
    earlier.mkdir()
    mesh = earlier / "frame_0000.obj"
    mesh.write_text("v 0 0 0\nv 1 0 0\nv 0 0 1\nv 1 0 1\nf 1 3 2\nf 2 3 4\n")
    kept = mesh.read_bytes()
    scene = tmp_path / "again.toml"
    scene.write_text(
        '[mesh]\npath = "earlier/frame_0000.obj"\n[solver]\nmode = "dynamic"\n'
        '[[constraints]]\ntype = "edge_spring"\n[[constraints]]\ntype = "position"\nvertices = [0]\n'
    )
    with pytest.raises(ValueError, match="is the scene's mesh.*never replaces its inputs"):
        shapeup.Scene.load(scene).simulate(2, output=earlier)
    assert mesh.read_bytes() == kept
    assert sorted(p.name for p in earlier.iterdir()) == ["frame_0000.obj"]
    # A shorter run into a longer one's folder: it replaces that series, removing the old
    # frames it did not write and saying so once; other files stay.
    cloth = tmp_path / "cloth.toml"
    cloth.write_text(
        '[mesh]\ngenerate = { kind = "cloth", vertices = [4, 4], size = [1.0, 1.0] }\n'
        '[solver]\nmode = "dynamic"\n[[constraints]]\ntype = "edge_spring"\n'
    )
    frames = tmp_path / "frames"
    _, first = shapeup.Scene.load(cloth).simulate(5, output=frames)
    assert not [w for w in first["warnings"] if w["kind"] == "earlier_frames_removed"]
    (frames / "notes.txt").write_text("mine")
    _, report = shapeup.Scene.load(cloth).simulate(2, output=frames)
    [removed] = [w for w in report["warnings"] if w["kind"] == "earlier_frames_removed"]
    assert removed["count"] == 3 and removed["first"] == "frame_0003.obj"
    assert sorted(p.name for p in frames.iterdir()) == [
        "frame_0000.obj", "frame_0001.obj", "frame_0002.obj", "notes.txt"
    ]
    # A run that fails part-way writes nothing: the folder keeps its frames, no staging
    # folder is left beside it, and a missing folder above the output is refused.
    far = tmp_path / "far.toml"
    far.write_text(cloth.read_text() + '[[constraints]]\ntype = "position"\nvertices = [0]\ntranslate = [1e200, 0.0, 0.0]\n')
    kept = {p.name: p.read_bytes() for p in frames.iterdir()}
    with pytest.raises(ValueError, match="not a finite number"):
        shapeup.Scene.load(far).simulate(3, output=frames)
    assert {p.name: p.read_bytes() for p in frames.iterdir()} == kept
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]
    with pytest.raises(ValueError, match="step 1 of 3 failed"):
        shapeup.Scene.load(far).simulate(3, output=tmp_path / "new")
    assert not (tmp_path / "new").exists()
    with pytest.raises(FileNotFoundError, match="does not exist"):
        shapeup.Scene.load(cloth).simulate(2, output=tmp_path / "missing" / "frames")
    assert not (tmp_path / "missing").exists()


STIFF_SPRINGS = """
[mesh]
generate = {{ kind = "cloth", vertices = [11, 11], size = [1.0, 1.0] }}
normalize = false
[solver]
iterations = 200
[[constraints]]
type = "edge_spring"
weight = {weight}
[[constraints]]
type = "position"
vertices = [0]
[[constraints]]
type = "position"
vertices = [120]
translate = [0.5, 0.3, 0.0]
"""


def test_a_solve_stopped_short_of_its_minimum_warns_once(tmp_path):
    # Springs 1e8 times stiffer than the handles: 200 iterations end far from the minimum.
    scene = tmp_path / "stiff.toml"
    scene.write_text(STIFF_SPRINGS.format(weight="1e8"))
    with pytest.warns(shapeup.UnconvergedWarning, match="stiff.toml: 1 static solve .* short of its minimum") as caught:
        _, report = shapeup.Scene.load(scene).deform()
    assert len(caught) == 1
    assert report["unconverged"] and report["residual"] > shapeup._shapeup.STATIC_RESIDUAL_LIMIT
    assert [w["kind"] for w in report["warnings"]] == ["unconverged"]

    # Nothing said where the solve converges within the same cap.
    soft = tmp_path / "soft.toml"
    soft.write_text(STIFF_SPRINGS.format(weight="1.0"))
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", shapeup.UnconvergedWarning)
        _, report = shapeup.Scene.load(soft).deform()
    assert not report["unconverged"] and report["residual"] < shapeup._shapeup.STATIC_RESIDUAL_LIMIT


def test_solver_solve_reports_and_warns_when_short(tmp_path):
    V = np.array([[x / 10, 0.0, z / 10] for z in range(11) for x in range(11)])
    F = [[r * 11 + c, r * 11 + c + 1, (r + 1) * 11 + c] for r in range(10) for c in range(10)]
    F += [[r * 11 + c + 1, (r + 1) * 11 + c + 1, (r + 1) * 11 + c] for r in range(10) for c in range(10)]
    s = shapeup.Solver(V, np.array(F))
    s.add("edge_spring", weight=1e8)
    s.add("position", [0])
    s.add("position", [120], translate=[0.5, 0.3, 0.0])
    with pytest.warns(shapeup.UnconvergedWarning, match="200-iteration cap"):
        _, report = s.solve(iterations=200)
    assert report["unconverged"] and report["residual"] > 0.01
    _, report = s.solve(iterations=5000, tolerance=1e-6)
    assert report["residual"] is None and not report["unconverged"]


def test_override_errors_name_their_key_in_the_scenes_words(tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text(STIFF_SPRINGS.format(weight="1.0"))
    with pytest.raises(ValueError, match=r"s\.toml: solver\.iterations: .*a whole number ≥ 0") as e:
        shapeup.Scene.load(scene, {"solver.iterations": -3})
    assert "usize" not in str(e.value)
    with pytest.raises(ValueError, match=r"mesh\.nope: unknown field `nope`"):
        shapeup.Scene.load(scene, {"mesh.nope": 1})


PINNED_CLOTH = """[mesh]
generate = {{ kind = "cloth", vertices = [9, 9], size = [1.0, 1.0] }}
[solver]
mode = "dynamic"
stiffness = {stiffness}
[[constraints]]
type = "triangle_strain"
weight = 10.0
[[constraints]]
type = "bending"
weight = 10.0
[[constraints]]
type = "position"
vertices = [0, 8]
weight = 100.0
"""


def test_time_steps_stopped_short_warn_once(tmp_path):
    # Stiffness 1e8: 10 iterations a step barely move the cloth, where converged steps swing it.
    scene = tmp_path / "cloth.toml"
    scene.write_text(PINNED_CLOTH.format(stiffness="1e8"))
    with pytest.warns(shapeup.UnconvergedWarning, match=r"cloth.toml: \d+ of the 7 time steps checked") as caught:
        _, report = shapeup.Scene.load(scene).simulate(frames=64)
    assert len(caught) == 1
    assert [r[0] for r in report["residuals"]] == [1, 2, 4, 8, 16, 32, 64]
    assert report["unconverged_steps"] >= 5
    assert [w["kind"] for w in report["warnings"]] == ["unconverged"]

    # The same through Simulation.step: the reports' residuals, one warning for the call.
    V = np.array([[x / 8 - 0.5, 0.0, z / 8 - 0.5] for x in range(9) for z in range(9)])
    F = [[r * 9 + c, (r + 1) * 9 + c, r * 9 + c + 1] for r in range(8) for c in range(8)]
    F += [[r * 9 + c + 1, (r + 1) * 9 + c, (r + 1) * 9 + c + 1] for r in range(8) for c in range(8)]
    import warnings

    for stiffness, short in [(1e8, True), (100.0, False)]:
        sim = shapeup.Simulation(V, F, stiffness=stiffness, iterations=10)
        sim.add("triangle_strain", weight=10.0)
        sim.add("bending", weight=10.0)
        sim.add("position", {"vertices": [0, 8]}, weight=100.0)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            reports = sim.step(16)
        said = [w for w in caught if issubclass(w.category, shapeup.UnconvergedWarning)]
        checked = [k + 1 for k, r in enumerate(reports) if r["residual"] is not None]
        assert checked == [1, 2, 4, 8, 16]
        flagged = sum(r["unconverged"] for r in reports)
        assert all(r["unconverged"] == (r["residual"] is not None and r["residual"] > shapeup._shapeup.DYNAMIC_RESIDUAL_LIMIT) for r in reports)
        if short:
            assert flagged >= 3 and len(said) == 1, reports
            # The command line's words: the settings and the schedule named.
            assert f"{flagged} of the 5 time steps checked (steps 1, 2, 4, …, 64, then every 64th)" in str(said[0].message)
            assert "(10 iterations a step)" in str(said[0].message)
        else:
            assert flagged == 0 and not said, [r["residual"] for r in reports]


@pytest.mark.filterwarnings("ignore::shapeup.UnconvergedWarning")
def test_a_start_shape_is_where_deform_starts(tmp_path, cli):
    # The editor saves the shape on screen as [mesh] start; every door starts there.
    spot = shapeup.read_mesh(EXAMPLES.parent / "data" / "spot.obj")
    start = spot.V * np.array([1.0, 0.7, 1.0]) + np.array([0.0, 0.5, 0.0])
    shapeup.write_mesh(tmp_path / "start.obj", start, spot.F)
    scene = tmp_path / "s.toml"
    scene.write_text(
        f"[mesh]\npath = '{EXAMPLES.parent / 'data' / 'spot.obj'}'\nstart = 'start.obj'\n"
        '[[constraints]]\ntype = "edge_spring"\n[[constraints]]\ntype = "position"\nvertices = [0]\n'
    )
    V, _ = shapeup.Scene.load(scene).deform(iterations=0)
    np.testing.assert_allclose(V, start, rtol=0, atol=1e-12)
    V, _ = shapeup.Scene.load(scene).deform(iterations=5)
    out = tmp_path / "cli.obj"
    subprocess.run([str(cli), "deform", str(scene), "-o", str(out), "--iterations", "5"], check=True, capture_output=True)
    np.testing.assert_allclose(V, shapeup.read_mesh(out).V, rtol=0, atol=1e-12)
    scene.write_text(scene.read_text().replace("start.obj", "missing.obj"))
    with pytest.raises(FileNotFoundError, match=r"\[mesh\] start.*missing.obj"):
        shapeup.Scene.load(scene).deform()
    scene.write_text(scene.read_text().replace("missing.obj", "start.obj"))
    (tmp_path / "few.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    scene.write_text(scene.read_text().replace("start.obj", "few.obj"))
    with pytest.raises(ValueError, match=r"\[mesh\] start.*has 3 vertices where the mesh"):
        shapeup.Scene.load(scene).deform()


def test_a_material_scene_runs_from_python_as_from_the_command_line(tmp_path, cli):
    # [material] is a scene key like any other: Scene.load takes it, and deform gives the
    # command line's shape (same solver, same tolerance).
    scene = tmp_path / "beam.toml"
    text = (EXAMPLES / "cantilever.toml").read_text().replace("cells = [40, 4, 4]", "cells = [20, 2, 2]")
    scene.write_text(text)
    V, _ = shapeup.Scene.load(scene).deform()
    out = tmp_path / "cli.obj"
    subprocess.run([str(cli), "deform", str(scene), "-o", str(out)], check=True, capture_output=True)
    np.testing.assert_allclose(V, shapeup.read_mesh(out).V, rtol=0, atol=1e-12)
    # The free end sags under the beam's own weight (Euler–Bernoulli: 14.7 mm; 20 cubes lock
    # to about half of it).
    tip = V[np.isclose(V[:, 0], V[:, 0].max(), atol=0.02)]
    assert 0.005 < -tip[:, 1].mean() < 0.0147
    scene.write_text(text.replace("poisson_ratio = 0.3", "poisson_ratio = 0.5"))
    with pytest.raises(ValueError, match=r"\[material\].*poisson_ratio"):
        shapeup.Scene.load(scene).deform()


def test_a_balloon_scene_inflates_from_python_as_from_the_command_line(tmp_path, cli):
    # A shell's thickness and [loads] pressure are scene keys like the others.
    scene = tmp_path / "balloon.toml"
    scene.write_text((EXAMPLES / "balloon.toml").read_text().replace("subdivisions = 3", "subdivisions = 2"))
    V, _ = shapeup.Scene.load(scene).deform()
    out = tmp_path / "cli.obj"
    subprocess.run([str(cli), "deform", str(scene), "-o", str(out)], check=True, capture_output=True)
    np.testing.assert_allclose(V, shapeup.read_mesh(out).V, rtol=0, atol=1e-9)
    # 100 mm at rest, about 113 mm at 3 kPa (the membrane's law; the math reference).
    radius = np.linalg.norm(V - V.mean(axis=0), axis=1).mean()
    assert 110.0 < radius < 116.0
    scene.write_text(scene.read_text().replace("pressure = 3000.0", "pressure = 1.0e5"))
    with pytest.raises(shapeup.SolveFailed, match="ran away"):
        shapeup.Scene.load(scene).deform()
