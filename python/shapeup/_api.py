"""The Python API over the native module: argument checks, numpy conversions, docstrings.

Conventions (those of libigl, trimesh and meshio): ``V`` float64 ``(n, 3)`` vertex positions,
``F`` int ``(m, 3)`` triangles or a list of polygons (index arrays of any length), ``T`` int
``(t, 4)`` tetrahedra. Indices are 0-based. Lengths are in the mesh's own units; time in
seconds.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence, Union

import numpy as np

from . import _shapeup
from ._shapeup import SolveFailed

PathLike = Union[str, "os.PathLike[str]"]
GroupRef = Union["Group", int, str]


# ---------------------------------------------------------------------------------------------
# Argument checks: each raises with one line naming the argument.


def _vertices(V: Any, name: str = "V") -> np.ndarray:
    """``V`` as a C-contiguous float64 (n, 3) array: the same object when it already is one
    (no copy), else converted. TypeError for a non-numeric dtype, ValueError for a wrong shape
    or a NaN/inf."""
    if isinstance(V, np.ndarray) and V.dtype == np.float64 and V.flags.c_contiguous:
        a = V
    else:
        a = np.asarray(V)
        if a.dtype.kind not in "fiu":
            raise TypeError(f"{name} must hold real numbers (float64), found dtype {a.dtype}")
        a = np.ascontiguousarray(a, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name} must have shape (n, 3), found {a.shape}")
    if a.shape[0] == 0:
        raise ValueError(f"{name} has no rows")
    finite = np.isfinite(a)
    if not finite.all():
        row = int(np.argwhere(~finite)[0][0])
        raise ValueError(f"{name} has a NaN or infinite coordinate in row {row}")
    return a


def _indices(values: Any, n: int, name: str, kind: str = "vertex") -> np.ndarray:
    """Integer indices in [0, n) as int64. TypeError for non-integers, IndexError out of range."""
    a = np.asarray(values)
    if a.size == 0:
        return np.zeros(a.shape, dtype=np.int64)
    if a.dtype.kind not in "iu":
        raise TypeError(f"{name} must hold integer {kind} indices, found dtype {a.dtype}")
    # Checked before the cast, so that a huge unsigned index is not reported wrapped.
    bad = (a >= n) if a.dtype.kind == "u" else (a < 0) | (a >= n)
    if bad.any():
        at = tuple(int(i) for i in np.argwhere(bad)[0])
        where = at[0] if len(at) == 1 else at
        plural = "vertices" if kind == "vertex" else f"{kind}s"
        raise IndexError(
            f"{name}: {kind} index {int(a[at])} at {where} is out of range (there are {n} {plural}: 0..{n - 1})"
        )
    return a.astype(np.int64, copy=False)


def _polygons(F: Any, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``F`` as (corner indices, offsets): an (m, k) integer array, or a list of index
    sequences of any length (polygons)."""
    if isinstance(F, np.ndarray) or (
        isinstance(F, Sequence) and len(F) > 0 and not isinstance(F[0], (Sequence, np.ndarray))
    ):
        a = np.asarray(F)
        if a.ndim != 2:
            raise ValueError(f"F must have shape (m, 3) (or (m, k), or be a list of polygons), found {a.shape}")
        if a.shape[1] < 3:
            raise ValueError(f"F's faces need at least 3 corners, found shape {a.shape}")
        a = _indices(a, n, "F")
        offsets = np.arange(0, a.size + 1, a.shape[1], dtype=np.int64)
        return np.ascontiguousarray(a.reshape(-1)), offsets
    polys = [np.asarray(p) for p in F]
    for i, p in enumerate(polys):
        if p.ndim != 1 or p.size < 3:
            raise ValueError(f"F: polygon {i} must be a list of at least 3 vertex indices, found shape {p.shape}")
    flat = np.concatenate(polys) if polys else np.zeros(0, dtype=np.int64)
    flat = _indices(flat, n, "F")
    offsets = np.zeros(len(polys) + 1, dtype=np.int64)
    offsets[1:] = np.cumsum([p.size for p in polys])
    return np.ascontiguousarray(flat), offsets


def _tetrahedra(T: Any, n: int) -> np.ndarray:
    a = np.asarray(T)
    if a.ndim != 2 or a.shape[1] != 4:
        raise ValueError(f"T must have shape (t, 4), found {a.shape}")
    return np.ascontiguousarray(_indices(a, n, "T"))


def _json(value: Any, key: str) -> Any:
    """A JSON-able copy of an option value (numpy arrays and scalars to lists and numbers),
    refusing NaN and infinity by name."""
    if isinstance(value, np.ndarray):
        value = value.tolist()
    elif isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, (int, float)):
        if isinstance(value, float) and not math.isfinite(value):
            raise ValueError(f"{key} must be a finite number, found {value}")
        return value
    if isinstance(value, Mapping):
        return {str(k): _json(v, f"{key}.{k}") for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json(v, key) for v in value]
    raise TypeError(f"{key}: cannot pass a {type(value).__name__} (use numbers, booleans, lists or dicts)")


# ---------------------------------------------------------------------------------------------
# Meshes


class Mesh:
    """A mesh as shapeup holds it: positions, polygon faces kept as they are (and their
    triangulation), tetrahedra and what the file carries (texture coordinates, normals,
    colours, per-vertex scalars), vertex for vertex in file order.

    Get one from :func:`read_mesh` or :meth:`Mesh.from_arrays`; write it (moved) with
    :func:`write_mesh`.
    """

    __slots__ = ("_native",)

    def __init__(self, native: Any) -> None:
        self._native = native

    @staticmethod
    def from_arrays(V: Any, F: Any = None, T: Any = None) -> "Mesh":
        """A mesh from ``V`` float64 (n, 3), ``F`` int (m, 3) / (m, k) or a list of polygons,
        and ``T`` int (t, 4). ValueError / IndexError / TypeError for bad arrays."""
        V = _vertices(V)
        n = V.shape[0]
        polygons = None if F is None else _polygons(F, n)
        tets = None if T is None else _tetrahedra(T, n)
        if polygons is None and tets is None:
            raise ValueError("give F (faces) or T (tetrahedra)")
        return Mesh(_shapeup.mesh_from_arrays(V, polygons, tets))

    @property
    def V(self) -> np.ndarray:
        """Vertex positions, float64 (n, 3) (a new array)."""
        return self._native.vertices

    @property
    def F(self) -> np.ndarray:
        """Triangles, int64 (m, 3): the polygons' triangulation (ear clipping; see docs/math.md)."""
        return self._native.triangles

    @property
    def T(self) -> np.ndarray:
        """Tetrahedra, int64 (t, 4) (empty for a surface)."""
        return self._native.tetrahedra

    @property
    def polygons(self) -> list[np.ndarray]:
        """The faces as the file has them: one int64 index array per polygon."""
        indices, offsets = self._native.polygon_arrays
        flat = np.asarray(indices, dtype=np.int64)
        return [flat[offsets[i] : offsets[i + 1]] for i in range(len(offsets) - 1)]

    @property
    def texcoords(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Texture coordinates: (values float64 (k, 2), value index per polygon corner int64,
        -1 where a corner has none; corners in the order of :attr:`polygons`), or None."""
        t = self._native.texcoords
        if t is None:
            return None
        values, corners = t
        return np.asarray(values, dtype=np.float64).reshape(-1, 2), np.asarray(corners, dtype=np.int64)

    @property
    def vertex_colors(self) -> np.ndarray | None:
        """Per-vertex colours, float64 (n, 3) in [0, 1], or None."""
        c = self._native.vertex_colors
        return None if c is None else np.asarray(c, dtype=np.float64)

    @property
    def vertex_scalars(self) -> dict[str, np.ndarray]:
        """Per-vertex scalar properties (e.g. PLY ``quality``): {name: float64 (n,)}."""
        return {name: np.asarray(v, dtype=np.float64) for name, v in self._native.vertex_scalars}

    @property
    def attributes(self) -> list[str]:
        """What the mesh carries besides positions and faces, one description each."""
        return list(self._native.attributes)

    @property
    def warnings(self) -> list[str]:
        """What reading or building changed or left out (each said once, with a count)."""
        return list(self._native.warnings)

    def with_vertices(self, V: Any) -> "Mesh":
        """The same mesh (faces, attributes, tetrahedra) at positions ``V`` float64 (n, 3)."""
        V = _vertices(V)
        return Mesh(self._native.with_vertices(V))

    def __len__(self) -> int:
        return len(self._native)

    def __repr__(self) -> str:
        return (
            f"shapeup.Mesh({len(self)} vertices, {len(self._native.polygon_arrays[1]) - 1} polygons, "
            f"{self.T.shape[0]} tetrahedra)"
        )


def read_mesh(path: PathLike) -> Mesh:
    """Reads a mesh file (.obj .ply .off .stl, .msh .vtu .node/.ele for tetrahedra) as the
    command line does: every vertex in file order, polygons kept, attributes kept.

    ``V, F = m.V, m.F`` gives the arrays. FileNotFoundError / OSError when the file cannot be
    opened; ValueError (naming the file and line) when it is malformed."""
    return Mesh(_shapeup.read_mesh(os.fspath(path)))


def write_mesh(path: PathLike, V: Any, F: Any = None, T: Any = None, *, like: Mesh | None = None) -> list[str]:
    """Writes a mesh atomically (format from the extension: .obj .ply .off .stl .vtu .msh).

    - ``write_mesh(path, V, like=mesh)``: ``mesh`` (from :func:`read_mesh`) moved to ``V``:
      its polygons, texture coordinates and attributes come back out.
    - ``write_mesh(path, V, F, T)``: a mesh from arrays.

    Returns what writing said (what the format cannot store, with a count). Raises as
    :meth:`Mesh.from_arrays`, and OSError when the file cannot be written."""
    if like is not None:
        if not isinstance(like, Mesh):
            raise TypeError(f"like must be a shapeup.Mesh (from read_mesh), found {type(like).__name__}")
        if F is not None or T is not None:
            raise ValueError("give either like= (a mesh to move) or F/T, not both")
        mesh = like.with_vertices(V)
    else:
        mesh = Mesh.from_arrays(V, F, T)
    return list(_shapeup.write_mesh(os.fspath(path), mesh._native))


# ---------------------------------------------------------------------------------------------
# Constraint types


@dataclass(frozen=True)
class ConstraintType:
    """A registered constraint type: what :meth:`Solver.add` and scene files take."""

    name: str
    acts_on: str
    default_weight: float
    summary: str
    has_targets: bool
    options: tuple[tuple[str, str, str], ...]
    """(key, "`key` = default and range", meaning) per option."""


def constraint_types() -> list[ConstraintType]:
    """Every registered constraint type, in the order of ``shapeup types``."""
    return [
        ConstraintType(name, on, weight, summary, targets, tuple(tuple(o) for o in options))
        for name, on, weight, summary, targets, options in _shapeup.constraint_types()
    ]


def _types_doc() -> str:
    lines = []
    for t in constraint_types():
        opts = "; ".join(text.replace("`", "") for _, text, _ in t.options) or "no options"
        if t.has_targets:
            opts += "; targets: translate, rotate, targets, hard"
        lines.append(f"        {t.name:<24}{t.acts_on}, weight {t.default_weight:g}: {t.summary} ({opts})")
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# Groups, shared by Solver and Simulation


@dataclass(frozen=True)
class Group:
    """A constraint group in a :class:`Solver` or :class:`Simulation`: its id, name, type and
    number of constraints. Methods take it, its id or its name."""

    id: int
    name: str
    type: str
    constraints: int

    def __int__(self) -> int:
        return self.id


_SELECTION_KEYS = ("vertices", "faces", "box", "sphere")


class _Groups:
    """add / set_targets / set_weight / remove / held over a native object with the same."""

    _native: Any
    _n: int

    def _init_groups(self) -> None:
        self._groups: dict[int, Group] = {}

    def add(
        self,
        type: str,
        selection: Any = None,
        weight: float | None = None,
        *,
        name: str | None = None,
        **options: Any,
    ) -> Group:
        """Adds a constraint group of ``type`` on ``selection`` with multiplier ``weight``
        (default: the type's) and the type's ``options``, with the names and meanings of scene
        files (``docs/scenes-and-cli.md``). Returns the :class:`Group`.

        ``selection``: None (every vertex, and every face), an int array of vertex indices, a
        boolean mask of length n, or a dict in scene keys: ``{"faces": [...]}``,
        ``{"box": {"min": [x, y, z], "max": [...]}}``, ``{"sphere": {"center": [...],
        "radius": r}}``. Position-like types take ``translate=[dx, dy, dz]``,
        ``rotate={"axis": ..., "angle_deg": ..., "center": ...}``, ``targets=(k, 3) array``
        or ``hard=True``.

        ValueError for an unknown type or option (naming it), a bad option value, a weight
        that is negative or not finite, or a selection the type cannot act on; IndexError for
        an index out of range.

        Types:
{types}
        """
        entry: dict[str, Any] = {"type": type}
        if name is not None:
            if not isinstance(name, str):
                raise TypeError(f"name must be a string, found {name!r}")
            if any(g.name == name for g in self._groups.values()):
                raise ValueError(f"a group named {name!r} exists already")
            entry["name"] = name
        elif any(g.name == type for g in self._groups.values()):
            k = 2
            while any(g.name == f"{type}_{k}" for g in self._groups.values()):
                k += 1
            entry["name"] = f"{type}_{k}"
        if weight is not None:
            try:
                w = float(weight)
            except (TypeError, ValueError):
                raise TypeError(f"weight must be a number, found {weight!r}") from None
            if not (math.isfinite(w) and w >= 0):
                raise ValueError(f"weight must be a finite number >= 0, found {weight!r}")
            entry["weight"] = w
        if selection is not None:
            if isinstance(selection, Mapping):
                for key, value in selection.items():
                    if key not in _SELECTION_KEYS:
                        raise ValueError(f"unknown selection key {key!r} (one of: {', '.join(_SELECTION_KEYS)})")
                    if key == "vertices":
                        value = _indices(value, self._n, "selection")
                    entry[key] = _json(value, key)
            else:
                a = np.asarray(selection)
                if a.dtype == np.bool_:
                    if a.shape != (self._n,):
                        raise ValueError(f"a boolean selection must have shape ({self._n},), found {a.shape}")
                    a = np.flatnonzero(a)
                elif a.ndim != 1:
                    raise ValueError(f"selection must be a 1-D array of vertex indices, found shape {a.shape}")
                entry["vertices"] = _indices(a, self._n, "selection").tolist()
        if "spin" in options:
            raise ValueError(
                "spin turns scene handles in `shapeup simulate`; from Python, move the targets each "
                "step with set_targets(group, targets)"
            )
        for key, value in options.items():
            if key in entry:
                raise ValueError(f"{key} given twice")
            if key == "vertices":
                value = _indices(value, self._n, "vertices")
            entry[key] = _json(value, key)
        gid, gname, gtype, count = self._native.add(json.dumps(entry))
        group = Group(gid, gname, gtype, count)
        self._groups[gid] = group
        return group

    def _id(self, group: GroupRef) -> int:
        if isinstance(group, Group):
            group = group.id
        if isinstance(group, str):
            for g in self._groups.values():
                if g.name == group:
                    return g.id
            raise KeyError(f"no group named {group!r} (groups: {', '.join(g.name for g in self._groups.values())})")
        gid = int(group)
        if gid not in self._groups:
            raise KeyError(f"no group {gid}")
        return gid

    @property
    def groups(self) -> list[Group]:
        """The groups, in the order they were added."""
        return list(self._groups.values())

    def held(self, group: GroupRef) -> np.ndarray:
        """The vertices a group with targets holds, int64 (k,), in the order
        :meth:`set_targets` takes."""
        return np.asarray(self._native.held(self._id(group)), dtype=np.int64)

    def set_targets(self, group: GroupRef, targets: Any) -> None:
        """Moves a handle: ``targets`` float64 (k, 3), one per held vertex (:meth:`held`).
        Only the projection changes: no refactorization."""
        self._native.set_targets(self._id(group), _vertices(targets, "targets"))

    def set_weight(self, group: GroupRef, weight: float) -> None:
        """Changes a group's multiplier (≥ 0; refactors the matrix on the next solve)."""
        w = float(weight)
        if not (math.isfinite(w) and w >= 0):
            raise ValueError(f"weight must be a finite number >= 0, found {weight!r}")
        self._native.set_weight(self._id(group), w)

    def remove(self, group: GroupRef) -> None:
        """Removes a group."""
        gid = self._id(group)
        self._native.remove(gid)
        del self._groups[gid]


def _mesh_of(V: Any, F: Any, T: Any, mesh: Mesh | None) -> Mesh:
    if mesh is not None and not isinstance(mesh, Mesh):
        raise TypeError(f"mesh must be a shapeup.Mesh (from read_mesh or Mesh.from_arrays), found {type(mesh).__name__}")
    if mesh is not None:
        if V is not None or F is not None or T is not None:
            raise ValueError("give either mesh= or V/F/T, not both")
        return mesh
    if V is None:
        raise ValueError("give V (and F or T), or mesh=")
    return Mesh.from_arrays(V, F, T)


class Solver(_Groups):
    """The ShapeUp solver (Bouaziz et al., SGP 2012) on one mesh: constraint groups and a
    prefactored sparse Cholesky global step. Works in the mesh's own coordinates (no
    normalization, unlike scene files' default).

    ``Solver(V, F, T=None)`` or ``Solver(mesh=read_mesh(...))``. ``F`` may be triangles
    (m, 3), polygons (m, k) or a list of polygons; face types (plane, circle, rectangle…) act
    on polygons as given.

    One thread at a time: a call from another thread while it solves raises RuntimeError
    ("Already borrowed"); give each thread its own Solver."""

    def __init__(self, V: Any = None, F: Any = None, T: Any = None, *, mesh: Mesh | None = None) -> None:
        self.mesh = _mesh_of(V, F, T, mesh)
        self._native = _shapeup._Solver(self.mesh._native)
        self._n = len(self.mesh)
        self._init_groups()

    def _positions(self, q: Any) -> np.ndarray:
        """``q`` checked as :func:`_vertices`, with one row per vertex of the mesh."""
        x = _vertices(q, "q")
        if x.shape[0] != self._n:
            raise ValueError(f"q has {x.shape[0]} rows but the mesh has {self._n} vertices")
        return x

    def solve(
        self,
        q: Any = None,
        iterations: int = 10,
        tolerance: float = 0.0,
        acceleration: str = "lbfgs",
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Runs ``iterations`` local-global iterations from ``q`` float64 (n, 3) (default: the
        rest shape), stopping early when the relative energy change is below ``tolerance``
        (> 0). ``acceleration``: "lbfgs" (default), "anderson" or "none".

        Returns ``(q, report)``: the new positions float64 (n, 3) and a dict with
        ``iterations``, ``initial_energy``, ``energy`` (E after each iteration),
        ``relative_change``, ``rejected`` and ``timings`` (seconds).

        The GIL is released while it runs; Ctrl+C stops it (KeyboardInterrupt).
        :class:`SolveFailed` when the system cannot be solved (e.g. nothing anchors it)."""
        iterations = _count(iterations, "iterations")
        tolerance = float(tolerance)
        if not (math.isfinite(tolerance) and tolerance >= 0):
            raise ValueError(f"tolerance must be a finite number >= 0, found {tolerance}")
        x = None if q is None else self._positions(q)
        out, report = self._native.solve(x, iterations, tolerance, acceleration)
        return out, json.loads(report)

    def energy(self, q: Any) -> dict[str, Any]:
        """E(q) = Σ w_i ‖C_i q − p_i(q)‖²: ``{"total": E, "groups": {name: E_group}}``."""
        x = self._positions(q)
        total, per_group = self._native.energy(x)
        return {"total": total, "groups": {self._groups[g].name: e for g, e in per_group if g in self._groups}}


def _count(value: Any, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an integer, found {value!r}")
    if value < 0:
        raise ValueError(f"{name} must be >= 0, found {value}")
    return int(value)


class Simulation(_Groups):
    """Projective Dynamics (Bouaziz et al., SIGGRAPH 2014) on one mesh: implicit Euler time
    steps, each a local-global solve of inertia + constraints, in the mesh's units.

    Settings (None: the scene files' defaults): ``time_step`` h in s (1/60), ``gravity`` in
    units/s² ((0, −9.81, 0)), ``stiffness`` k (100), ``damping`` d in [0, 1) (0), ``density``
    ρ (1; lumped masses ρ·area/3 per vertex, ρ·volume/4 on tetrahedra), ``iterations`` per step
    (10), ``tolerance`` (0), ``acceleration`` ("lbfgs")."""

    def __init__(
        self,
        V: Any = None,
        F: Any = None,
        T: Any = None,
        *,
        mesh: Mesh | None = None,
        time_step: float | None = None,
        gravity: Sequence[float] | None = None,
        stiffness: float | None = None,
        damping: float | None = None,
        density: float | None = None,
        iterations: int | None = None,
        tolerance: float | None = None,
        acceleration: str | None = None,
    ) -> None:
        self.mesh = _mesh_of(V, F, T, mesh)
        settings = {
            k: _json(v, k)
            for k, v in dict(
                time_step=time_step,
                gravity=gravity,
                stiffness=stiffness,
                damping=damping,
                density=density,
                iterations=iterations,
                tolerance=tolerance,
                acceleration=acceleration,
            ).items()
            if v is not None
        }
        self._native = _shapeup._Simulation(self.mesh._native, json.dumps(settings))
        self._n = len(self.mesh)
        self._init_groups()

    def step(self, n: int = 1) -> list[dict[str, Any]]:
        """Advances ``n`` time steps (GIL released; Ctrl+C stops between steps). Returns each
        step's report (energy when computed, iterations, timings)."""
        return json.loads(self._native.step(_count(n, "n")))

    @property
    def positions(self) -> np.ndarray:
        """x, float64 (n, 3)."""
        return self._native.positions

    @property
    def velocities(self) -> np.ndarray:
        """v in units per second, float64 (n, 3)."""
        return self._native.velocities

    @property
    def masses(self) -> np.ndarray:
        """Lumped masses, float64 (n,)."""
        return np.asarray(self._native.masses)

    @property
    def time(self) -> float:
        """Simulated seconds (steps × h)."""
        return self._native.time

    @property
    def steps(self) -> int:
        """Time steps taken."""
        return self._native.steps

    @property
    def kinetic_energy(self) -> float:
        """½ Σ m_i |v_i|²."""
        return self._native.kinetic_energy

    def energy(self) -> float:
        """The constraints' E at the current positions."""
        return self._native.energy()

    def set_state(self, positions: Any, velocities: Any) -> None:
        """Replaces (x, v), both float64 (n, 3)."""
        self._native.set_state(_vertices(positions, "positions"), _vertices(velocities, "velocities"))

    def set_external_forces(self, forces: Any) -> None:
        """Per-vertex forces float64 (n, 3) (mass × units/s²) added every step; None clears."""
        self._native.set_external_forces(None if forces is None else _vertices(forces, "forces"))

    def grab(self, vertices: Any, targets: Any, strength: float = 0.5) -> None:
        """Pulls ``vertices`` towards ``targets`` float64 (k, 3): each step closes the fraction
        ``strength`` in (0, 1] of the gap (a force, no refactorization), as the editor's drag."""
        idx = _indices(vertices, self._n, "vertices").astype(np.uint32).tolist()
        self._native.grab(idx, _vertices(targets, "targets"), float(strength))

    def release(self) -> None:
        """Ends a grab."""
        self._native.release()


# ---------------------------------------------------------------------------------------------
# Scenes


def _read_scene_dict(path: Path) -> dict[str, Any]:
    text = path.read_text(encoding="utf-8-sig")
    if path.suffix.lower() == ".json":
        return json.loads(text)
    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        import tomli as tomllib  # type: ignore[no-redef]
    return tomllib.loads(text)


def _apply_overrides(raw: dict[str, Any], overrides: Mapping[str, Any]) -> dict[str, Any]:
    """Dotted keys into the scene: ``"solver.iterations"``, ``"constraints.1.weight"``,
    ``"output.path"``."""
    for dotted, value in overrides.items():
        parts = dotted.split(".")
        node: Any = raw
        for i, part in enumerate(parts[:-1]):
            if isinstance(node, list):
                if not part.isdigit() or int(part) >= len(node):
                    raise KeyError(f"override {dotted!r}: {'.'.join(parts[: i + 1])} is not an entry of the scene")
                node = node[int(part)]
            else:
                node = node.setdefault(part, {})
        last = parts[-1]
        if isinstance(node, list):
            if not last.isdigit() or int(last) >= len(node):
                raise KeyError(f"override {dotted!r}: no such entry")
            node[int(last)] = _json(value, dotted)
        else:
            node[last] = _json(value, dotted)
    return raw


class Scene:
    """A scene file (TOML or JSON: a mesh, solver settings, constraint groups; see
    ``docs/scenes-and-cli.md``), run exactly as ``shapeup deform`` / ``shapeup simulate``
    run it."""

    def __init__(self, native: Any) -> None:
        self._native = native

    @staticmethod
    def load(path: PathLike, overrides: Mapping[str, Any] | None = None) -> "Scene":
        """Reads a scene. ``overrides``: dotted keys replacing values of the file, for
        parameter sweeps, e.g. ``{"solver.iterations": 50, "constraints.0.weight": 3.0,
        "output.path": "out/run3.obj"}`` (paths relative to the scene file).

        FileNotFoundError when the scene is missing; ValueError naming the file and the entry
        (unknown key, bad value, bad selection) otherwise."""
        # Absolute, so that a later os.chdir does not move the scene's mesh.
        path = Path(os.path.abspath(os.fspath(path)))
        if not overrides:
            return Scene(_shapeup._Scene(str(path)))
        try:
            raw = _read_scene_dict(path)
        except FileNotFoundError:
            raise FileNotFoundError(f"cannot read scene {path}: no such file") from None
        except (ValueError, UnicodeDecodeError) as e:
            raise ValueError(f"{path}: {e}") from None
        raw = _apply_overrides(raw, overrides)
        return Scene(_shapeup._Scene(str(path), json.dumps(raw)))

    @property
    def path(self) -> Path:
        """The scene file."""
        return Path(self._native.path)

    @property
    def mode(self) -> str:
        """"static" or "dynamic"."""
        return self._native.mode

    @property
    def output_path(self) -> Path | None:
        """``[output] path`` (resolved), or None."""
        p = self._native.output_path
        return None if p is None else Path(p)

    @property
    def report_path(self) -> Path | None:
        """``[output] report`` (resolved), or None."""
        p = self._native.report_path
        return None if p is None else Path(p)

    def to_toml(self) -> str:
        """The scene (with its overrides) as TOML text."""
        return self._native.to_toml()

    def deform(
        self,
        iterations: int | None = None,
        output: PathLike | None = None,
        report: PathLike | None = None,
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """``shapeup deform``: the static solve from the rest shape (``iterations`` default:
        the scene's steps × iterations). Returns ``(V, report)``: the result in the input's
        frame float64 (n, 3), bit for bit what the command line writes, and the report the
        command line writes with ``--report``. Writes ``output`` (a mesh file, with the
        input's faces and attributes) and ``report`` (JSON) when given."""
        if iterations is not None:
            iterations = _count(iterations, "iterations")
        mesh, text = self._native.deform(
            iterations,
            None if output is None else os.fspath(output),
            None if report is None else os.fspath(report),
        )
        return mesh.vertices, json.loads(text)

    def simulate(
        self,
        frames: int | None = None,
        every: int = 1,
        output: PathLike | None = None,
        format: str = "obj",
        report: PathLike | None = None,
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """``shapeup simulate``: ``frames`` time steps (default the scene's steps) from rest.
        Returns ``(X, report)``: X float64 (k, n, 3) holds frame 0, every ``every``-th frame
        and the last (their numbers in ``report["frame_numbers"]``), as the command line's
        frame files hold them; writes them to the folder ``output`` in ``format`` (obj, ply,
        off, stl, vtu, msh) when given."""
        frames = self._native.steps if frames is None else _count(frames, "frames")
        if frames < 1:
            raise ValueError("frames must be at least 1")
        arrays, numbers, text = self._native.simulate(
            frames,
            _count(every, "every"),
            None if output is None else os.fspath(output),
            format,
            None if report is None else os.fspath(report),
        )
        rep = json.loads(text)
        rep["frame_numbers"] = list(numbers)
        return np.stack(arrays), rep


__all__ = [
    "ConstraintType",
    "Group",
    "Mesh",
    "Scene",
    "Simulation",
    "SolveFailed",
    "Solver",
    "constraint_types",
    "read_mesh",
    "write_mesh",
]

# `help(shapeup.Solver.add)` lists every registered type (from the registry, never by hand).
if _Groups.add.__doc__:
    _Groups.add.__doc__ = _Groups.add.__doc__.replace("{types}", _types_doc())
