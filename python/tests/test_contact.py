"""Colliders and contact from Python: a cloth on a sphere keeps out of it, Simulation.add_collider
runs what a scene's [[colliders]] runs, bad colliders are refused by the core naming the key,
and contact flags come out as numpy."""

from __future__ import annotations

import numpy as np
import pytest

import shapeup

from conftest import tet_cube

CENTER = np.array([0.0, -0.4, 0.0])
RADIUS = 0.3
STEPS = 60


def cloth(n: int = 21, size: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """An n × n grid of vertices in the xz plane centred on the origin, two triangles a square."""
    xs, zs = np.meshgrid(np.linspace(-size / 2, size / 2, n), np.linspace(-size / 2, size / 2, n), indexing="ij")
    V = np.stack([xs.ravel(), np.zeros(n * n), zs.ravel()], axis=1)
    idx = np.arange(n * n).reshape(n, n)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    F = np.concatenate([np.stack([a, b, c], axis=1), np.stack([a, c, d], axis=1)])
    return V, F


def cloth_simulation(mesh: shapeup.Mesh) -> shapeup.Simulation:
    sim = shapeup.Simulation(mesh=mesh, iterations=10)
    sim.add("triangle_strain", weight=1.0)
    sim.add("bending", weight=0.001)
    return sim


def test_cloth_on_a_sphere_never_enters_it():
    V, F = cloth()
    sim = cloth_simulation(shapeup.Mesh.from_arrays(V, F))
    assert sim.add_collider("sphere", center=CENTER, radius=RADIUS, friction=0.3) == 0
    # The default thickness: a quarter of the mean edge length.
    edges = np.unique(np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1), axis=0)
    mean_edge = np.linalg.norm(V[edges[:, 0]] - V[edges[:, 1]], axis=1).mean()
    assert sim.contact_thickness == pytest.approx(0.25 * mean_edge, rel=1e-12)
    touched = 0
    for k in range(STEPS):
        (report,) = sim.step()
        distance = np.linalg.norm(sim.positions - CENTER, axis=1)
        assert distance.min() >= RADIUS - 1e-9, f"step {k}: a vertex {distance.min()} from the centre"
        assert report["contact_vertices"] == int(sim.contact_flags.sum())
        touched = max(touched, report["contacts"])
    assert touched > 0, "the cloth never reached the sphere"
    # It lies on the sphere: the vertices that touch are within the thickness of it.
    flags = sim.contact_flags
    assert flags.any()
    assert np.all(distance[flags] < RADIUS + 2 * sim.contact_thickness)
    # Contact never refactors the matrix.
    assert sim.factorizations == 1


def test_scene_colliders_and_add_collider_give_the_same_trajectory(tmp_path):
    V, F = cloth()
    shapeup.write_mesh(tmp_path / "cloth.obj", V, F)
    scene = tmp_path / "drop.toml"
    scene.write_text(
        f"""
[mesh]
path = "cloth.obj"
normalize = false

[solver]
mode = "dynamic"
iterations = 10
steps = {STEPS}

[[constraints]]
type = "triangle_strain"
weight = 1.0

[[constraints]]
type = "bending"
weight = 0.001

[[colliders]]
type = "sphere"
center = [0.0, -0.4, 0.0]
radius = 0.3
friction = 0.3

[[colliders]]
type = "plane"
point = [0.0, -0.6, 0.0]
normal = [0.0, 1.0, 0.0]

[contact]
friction = 0.1
""",
        encoding="utf-8",
    )
    X, report = shapeup.Scene.load(scene).simulate(STEPS)

    sim = cloth_simulation(shapeup.read_mesh(tmp_path / "cloth.obj"))
    sim.add_collider("sphere", center=CENTER, radius=np.float64(RADIUS), friction=0.3)
    sim.add_collider("plane", point=(0.0, -0.6, 0.0), normal=np.array([0, 1, 0]))
    sim.set_contact(friction=0.1)
    reports = sim.step(STEPS)

    assert np.allclose(sim.positions, X[-1], rtol=0, atol=1e-12)
    assert [r["contacts"] for r in reports] == report["contacts"]
    assert [r["self_contacts"] for r in reports] == report["self_contacts"]
    assert sim.factorizations == report["factorizations"]


def test_contact_flags_are_a_bool_array_of_length_n():
    V, F = cloth(5)
    sim = cloth_simulation(shapeup.Mesh.from_arrays(V, F))
    flags = sim.contact_flags
    assert isinstance(flags, np.ndarray) and flags.dtype == np.bool_ and flags.shape == (len(V),)
    assert not flags.any()
    assert sim.contact_thickness is None
    (report,) = sim.step()
    assert report["contacts"] == 0 and report["contact_vertices"] == 0
    sim.add_collider("plane", point=[0, -0.1, 0], normal=[0, 1, 0])
    sim.step(10)
    flags = sim.contact_flags
    # The cloth lies flat on the plane: every vertex touches it.
    assert flags.dtype == np.bool_ and flags.shape == (len(V),) and flags.all()
    assert sim.positions[:, 1] == pytest.approx(-0.1 + sim.contact_thickness)


@pytest.mark.parametrize(
    ("type", "keys", "message"),
    [
        ("sphere", dict(center=[0, 0, 0], radius=-1), "colliders[0]: `radius` must be a finite number > 0, found -1"),
        ("sphere", dict(center=[0, 0, 0]), "colliders[0]: a sphere collider needs `radius`"),
        ("sphere", dict(center=[0, 0, 0], radius=1, size=2), "colliders[0]: unknown key `size` for a sphere collider"),
        ("sphere", dict(center=[0, 0, 0], radius=float("nan")), "colliders[0]: `radius` must be a finite number"),
        ("sphere", dict(center=[0, 0], radius=1), "colliders[0]: `center`"),
        ("sphere", dict(center=[0, 0, 0], radius=1, friction=-0.5), "colliders[0]: `friction`"),
        ("cube", {}, 'colliders[0]: unknown collider type "cube"'),
        ("plane", dict(point=[0, 0, 0], normal=[0, 0, 0]), "colliders[0]: `normal`"),
        ("capsule", dict(a=[0, 0, 0], b=[0, 0, 0], radius=1), "colliders[0]:"),
        ("box", dict(min=[1, 1, 1], max=[0, 0, 0]), "colliders[0]:"),
        ("mesh", dict(path="no-such-collider.obj"), "no-such-collider.obj"),
    ],
)
def test_bad_collider_raises_value_error_naming_the_key(type, keys, message):
    V, F = cloth(5)
    for native in (cloth_simulation(shapeup.Mesh.from_arrays(V, F)), shapeup.Solver(V, F)):
        with pytest.raises(ValueError) as e:
            native.add_collider(type, **keys)
        assert message in str(e.value)
        assert "\n" not in str(e.value)
        # Nothing was added.
        assert native.colliders == []


def test_bad_contact_settings_raise():
    V, F = cloth(5)
    sim = cloth_simulation(shapeup.Mesh.from_arrays(V, F))
    with pytest.raises(ValueError, match="contact: thickness must be a finite number"):
        sim.set_contact(thickness=-1.0)
    with pytest.raises(ValueError, match="contact: friction must be a finite number"):
        sim.set_contact(friction=-0.1)
    with pytest.raises(TypeError, match="self_collision must be a bool"):
        sim.set_contact(self_collision="yes")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="thickness must be a number"):
        sim.set_contact(thickness="thick")  # type: ignore[arg-type]
    # Self-collision refuses a thickness over the mean edge length (colliders alone take it).
    with pytest.raises(ValueError, match=r"contact\]: thickness 10 is over the mean edge length"):
        sim.set_contact(self_collision=True, thickness=10.0)
    assert sim.contact == {"self_collision": False, "thickness": None, "friction": 0.0}
    sim.set_contact(self_collision=True, thickness=0.01)
    assert sim.contact == {"self_collision": True, "thickness": 0.01, "friction": 0.0}
    assert sim.contact_thickness == 0.01
    # With a collider, a thickness over a quarter of the mesh's size (its bounding-box
    # diagonal, 1.41 here) is refused and the settings stay.
    sim.add_collider("plane", point=[0, -1, 0], normal=[0, 1, 0])
    with pytest.raises(ValueError, match=r"contact\]: thickness 5 is over 0.25 of the mesh's size"):
        sim.set_contact(thickness=5.0)
    assert sim.contact_thickness == 0.01


def test_a_later_collider_keeps_the_earlier_ones_and_index(tmp_path):
    V, F = cloth(5)
    sim = cloth_simulation(shapeup.Mesh.from_arrays(V, F))
    assert sim.add_collider("plane", point=[0, -1, 0], normal=[0, 1, 0]) == 0
    with pytest.raises(ValueError, match=r"colliders\[1\]"):
        sim.add_collider("sphere", center=[0, 0, 0], radius=0)
    assert sim.add_collider("box", min=[-1, -3, -1], max=[1, -2, 1], friction=0.5) == 1
    assert [c["type"] for c in sim.colliders] == ["plane", "box"]


def test_mesh_collider_path_is_relative_to_the_current_directory(tmp_path, monkeypatch):
    # A floor made of two triangles (open: one-sided, its front up).
    floor = np.array([[-2.0, -0.2, -2.0], [2.0, -0.2, -2.0], [2.0, -0.2, 2.0], [-2.0, -0.2, 2.0]])
    shapeup.write_mesh(tmp_path / "floor.obj", floor, np.array([[0, 2, 1], [0, 3, 2]]))
    monkeypatch.chdir(tmp_path)
    V, F = cloth(9)
    sim = cloth_simulation(shapeup.Mesh.from_arrays(V, F))
    sim.add_collider("mesh", path="floor.obj")
    assert sim.colliders[0]["path"] == str(tmp_path / "floor.obj")
    sim.step(40)
    assert sim.positions[:, 1].min() >= -0.2 - 1e-9
    assert sim.contact_flags.any()


def test_tetrahedra_touch_with_their_boundary():
    V, T = tet_cube()
    sim = shapeup.Simulation(V + [0.0, 0.4, 0.0], T=T, iterations=10)
    sim.add("tet_strain", weight=10.0)
    sim.add_collider("plane", point=[0, 0, 0], normal=[0, 1, 0])
    # Above the thickness (0.28 here), so that the first step does not push it out.
    assert sim.contact_thickness < 0.4
    for _ in range(40):
        sim.step()
        assert sim.positions[:, 1].min() >= -1e-9
    flags = sim.contact_flags
    assert flags[[0, 1, 4, 5]].all() and not flags[[2, 3, 6, 7]].any()  # the bottom face touches


def test_static_solver_keeps_a_dragged_handle_out_of_a_sphere():
    V, F = cloth(11)
    solver = shapeup.Solver(V, F)
    solver.add("triangle_strain")
    # The middle vertex pulled down through a sphere below the cloth, the corners held.
    middle = len(V) // 2
    corners = [0, 10, 110, 120]
    solver.add("position", corners, weight=10.0)
    solver.add("position", [middle], weight=1.0, translate=[0.0, -1.0, 0.0])
    center, radius = np.array([0.0, -0.35, 0.0]), 0.25
    solver.add_collider("sphere", center=center, radius=radius)
    q, report = solver.solve(iterations=100)
    assert report["iterations"] == 100 and report["acceleration"] == "none"
    assert len(report["energy"]) == 100  # E after every iteration
    distance = np.linalg.norm(q - center, axis=1)
    assert distance.min() >= radius - 1e-9
    assert solver.contact_flags[middle]
    # Without the collider the handle goes through where the sphere was.
    free = shapeup.Solver(V, F)
    free.add("triangle_strain")
    free.add("position", corners, weight=10.0)
    free.add("position", [middle], weight=1.0, translate=[0.0, -1.0, 0.0])
    q_free, _ = free.solve(iterations=100)
    assert np.linalg.norm(q_free - center, axis=1).min() < radius


def test_static_scene_with_a_collider_and_solver_add_collider_agree(tmp_path):
    V, F = cloth(11)
    shapeup.write_mesh(tmp_path / "cloth.obj", V, F)
    scene = tmp_path / "press.toml"
    scene.write_text(
        """
[mesh]
path = "cloth.obj"
normalize = false

[[constraints]]
type = "triangle_strain"
weight = 1.0

[[constraints]]
type = "position"
vertices = [0, 10, 110, 120]
weight = 10.0

[[constraints]]
type = "position"
vertices = [60]
weight = 1.0
translate = [0.0, -1.0, 0.0]

[[colliders]]
type = "sphere"
center = [0.0, -0.35, 0.0]
radius = 0.25
""",
        encoding="utf-8",
    )
    X, _ = shapeup.Scene.load(scene).deform(iterations=100)

    solver = shapeup.Solver(mesh=shapeup.read_mesh(tmp_path / "cloth.obj"))
    solver.add("triangle_strain", weight=1.0)
    solver.add("position", [0, 10, 110, 120], weight=10.0)
    solver.add("position", [60], weight=1.0, translate=[0.0, -1.0, 0.0])
    solver.add_collider("sphere", center=[0.0, -0.35, 0.0], radius=0.25)
    q, _ = solver.solve(iterations=100)
    assert np.allclose(q, X, rtol=0, atol=1e-12)
