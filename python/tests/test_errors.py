"""Bad arguments raise the right exception with one clear line."""

from __future__ import annotations

import numpy as np
import pytest
import shapeup

from conftest import DATA, grid


def solver():
    V, F = grid(3, 3)
    return shapeup.Solver(V, F)


@pytest.mark.parametrize(
    "V, exc, needle",
    [
        (np.zeros((4, 2)), ValueError, "shape (n, 3)"),
        (np.zeros(12), ValueError, "shape (n, 3)"),
        (np.array([["a", "b", "c"]]), TypeError, "dtype"),
        (np.array([[0, 0, np.nan], [1, 0, 0], [0, 1, 0]]), ValueError, "row 0"),
        (np.array([[0, 0, 0], [np.inf, 0, 0], [0, 1, 0]]), ValueError, "row 1"),
    ],
)
def test_bad_vertices(V, exc, needle):
    with pytest.raises(exc, match=None) as e:
        shapeup.Solver(V, [[0, 1, 2]])
    assert needle in str(e.value)


def test_bad_faces():
    V = np.zeros((3, 3))
    with pytest.raises(IndexError, match="index 3"):
        shapeup.Solver(V, [[0, 1, 3]])
    with pytest.raises(IndexError, match="index -1"):
        shapeup.Solver(V, np.array([[0, 1, -1]]))
    with pytest.raises(TypeError, match="integer"):
        shapeup.Solver(V, np.array([[0.0, 1.0, 2.0]]))
    with pytest.raises(ValueError, match="at least 3"):
        shapeup.Solver(V, [[0, 1]])
    # A face that cannot be triangulated is named with the reason.
    with pytest.raises(ValueError, match=r"face 0 \(vertices 0 1 1\).*fewer than 3 distinct corners"):
        shapeup.Solver(np.eye(3), [[0, 1, 1]])


def test_bad_groups():
    s = solver()
    with pytest.raises(ValueError, match="edge_sprin"):
        s.add("edge_sprin")
    with pytest.raises(ValueError, match="strain_fredom"):
        s.add("edge_strain", strain_fredom=0.1)
    with pytest.raises(ValueError, match="weight"):
        s.add("edge_spring", weight=-1.0)
    with pytest.raises(ValueError, match="weight"):
        s.add("edge_spring", weight=float("nan"))
    with pytest.raises(IndexError, match="out of range"):
        s.add("position", [0, 99])
    with pytest.raises(ValueError, match="strain_freedom"):
        s.add("edge_strain", strain_freedom=np.inf)
    with pytest.raises(ValueError, match="min"):
        s.add("angle", min=-1.0)
    with pytest.raises(ValueError):
        s.add("circle", {"vertices": [0, 1]}, whole_selection=True)
    with pytest.raises(ValueError, match="rigid"):
        s.add("rigid", [3])
    g = s.add("position", [0, 1])
    with pytest.raises(ValueError, match="2"):
        s.set_targets(g, np.zeros((3, 3)))
    with pytest.raises(KeyError):
        s.set_weight("nope", 1.0)
    with pytest.raises(ValueError, match="weight"):
        s.set_weight(g, -2)


def test_face_type_on_triangles_is_refused():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=float)
    s = shapeup.Solver(V, [[0, 1, 2]])
    with pytest.raises(ValueError, match="plane"):
        s.add("plane")


def test_solve_errors():
    s = solver()
    with pytest.raises(shapeup.SolveFailed, match="no constraints"):
        s.solve()
    s.add("edge_spring")
    with pytest.raises(shapeup.SolveFailed, match="position"):
        s.solve()
    s.add("position", [0])
    with pytest.raises(ValueError, match="rows"):
        s.solve(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="acceleration"):
        s.solve(acceleration="fast")
    with pytest.raises(TypeError, match="iterations"):
        s.solve(iterations=2.5)


def test_file_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.obj"):
        shapeup.read_mesh(tmp_path / "nope.obj")
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nf 1 2 7\n")
    with pytest.raises(ValueError, match="bad.obj"):
        shapeup.read_mesh(bad)
    with pytest.raises(FileNotFoundError, match="nope.toml"):
        shapeup.Scene.load(tmp_path / "nope.toml")
    scene = tmp_path / "s.toml"
    scene.write_text(f'[mesh]\npath = "{DATA / "stanford-bunny.obj"}"\n[solver]\niteratons = 3\n')
    with pytest.raises(ValueError, match="iteratons"):
        shapeup.Scene.load(scene)
    V, F = grid(2, 2)
    with pytest.raises(OSError):
        shapeup.write_mesh(tmp_path / "no-such-folder" / "x.obj", V, F)
    assert not (tmp_path / "no-such-folder").exists()
    # A folder given where a mesh file is wanted is said to be one.
    folder = tmp_path / "results"
    folder.mkdir()
    cloth = tmp_path / "cloth.toml"
    cloth.write_text('[mesh]\ngenerate = { kind = "cloth", vertices = [3, 3], size = [1.0, 1.0] }\n'
                     '[[constraints]]\ntype = "edge_spring"\n')
    with pytest.raises(IsADirectoryError, match="is a folder"):
        shapeup.Scene.load(cloth).deform(output=folder)
    assert list(folder.iterdir()) == []
    # A result never replaces the run's inputs: the scene's mesh, the scene file.
    mesh = tmp_path / "tri.obj"
    mesh.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    on_mesh = tmp_path / "on_mesh.toml"
    on_mesh.write_text('[mesh]\npath = "tri.obj"\n[[constraints]]\ntype = "edge_spring"\n'
                       '[[constraints]]\ntype = "position"\nvertices = [0]\n')
    before = mesh.read_bytes()
    with pytest.raises(ValueError, match="the scene's mesh.*never replaces its inputs"):
        shapeup.Scene.load(on_mesh).deform(output=tmp_path / "." / "tri.obj")
    as_json = tmp_path / "scene.json"
    as_json.write_text('{"mesh": {"path": "tri.obj"}, "constraints": [{"type": "edge_spring"}, '
                       '{"type": "position", "vertices": [0]}]}')
    scene_text = as_json.read_bytes()
    with pytest.raises(ValueError, match="the scene file"):
        shapeup.Scene.load(as_json).deform(output=tmp_path / "out.obj", report=as_json)
    assert mesh.read_bytes() == before and as_json.read_bytes() == scene_text
    assert not (tmp_path / "out.obj").exists()
    # A TOML nan in an entry is refused at its line, not read as null.
    cloth.write_text(cloth.read_text() + "weight = nan\n")
    with pytest.raises(ValueError, match="line 5.*numbers must be finite, found nan"):
        shapeup.Scene.load(cloth)


def test_spin_and_keyword_vertices_are_checked():
    s = solver()
    with pytest.raises(ValueError, match="set_targets"):
        s.add("position", [0], spin={"axis": [1, 0, 0], "deg_per_s": 60})
    with pytest.raises(IndexError, match="out of range"):
        s.add("position", vertices=[0, 99])
    with pytest.raises(TypeError, match="integer"):
        s.add("position", vertices=[0.5])
    with pytest.raises(IndexError, match="18446744073709551615"):
        s.add("position", np.array([2**64 - 1], dtype=np.uint64))
    with pytest.raises(TypeError, match="shapeup.Mesh"):
        shapeup.Solver(mesh="x.obj")


def test_the_energy_of_huge_coordinates_is_an_error_not_inf():
    V, F = grid(4, 4)
    s = shapeup.Solver(V, F)
    s.add("edge_spring")
    assert np.isfinite(s.energy(V * 2.0)["total"])
    with pytest.raises(shapeup.SolveFailed, match="not a finite number"):
        s.energy(V * 1e200)


def test_simulation_settings_errors_name_the_key_in_plain_words():
    # Not serde's Rust type and a position in the package's internal JSON.
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    with pytest.raises(ValueError, match=r"iterations: .*expected a whole number ≥ 0") as caught:
        shapeup.Simulation(V, [[0, 1, 2]], iterations=-1)
    assert "usize" not in str(caught.value) and "column" not in str(caught.value)
    # A time step and stiffness whose inertia scale f64 cannot hold: said as such.
    with pytest.raises(ValueError, match=r"time_step 1.00e-300 and stiffness 100 put stiffness · time_step² at"):
        shapeup.Simulation(V, [[0, 1, 2]], time_step=1e-300)
    # A collider's and a rotation's fields: the field inside, in plain words.
    sim = shapeup.Simulation(V, [[0, 1, 2]])
    with pytest.raises(ValueError, match=r"radius.*expected a number") as caught:
        sim.add_collider("sphere", center=[0, 0, 0], radius="1")
    assert "f64" not in str(caught.value)
    with pytest.raises(ValueError, match=r"angle_deg: invalid type: string \"x\", expected a number"):
        sim.add("position", [0], rotate={"axis": [0, 1, 0], "angle_deg": "x"})
