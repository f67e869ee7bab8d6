"""Meshes: :class:`Mesh` (positions, polygons, tetrahedra and what the file carries),
:func:`read_mesh` and :func:`write_mesh`."""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from . import _shapeup
from ._checks import PathLike, _polygons, _tetrahedra, _vertices, _warn_of_arrays


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
        and ``T`` int (t, 4). ValueError / IndexError / TypeError for bad arrays; faces the
        solver takes otherwise than given (duplicates, faces it cannot triangulate) are kept
        and said once each as a :class:`MeshWarning` (and in :attr:`warnings`)."""
        V = _vertices(V)
        n = V.shape[0]
        polygons = None if F is None else _polygons(F, n)
        tets = None if T is None else _tetrahedra(T, n)
        if polygons is None and tets is None:
            raise ValueError("give F (faces) or T (tetrahedra)")
        native = _shapeup.mesh_from_arrays(V, polygons, tets)
        _warn_of_arrays(native)
        return Mesh(native)

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
    opened; ValueError (naming the file and line) when it is malformed. Faces the solver takes
    otherwise than the file gives them (duplicates, faces it cannot triangulate, polygons
    fanned) are kept and said once each as a :class:`MeshWarning`, as the command line says
    them; every warning of reading is in :attr:`Mesh.warnings`."""
    native = _shapeup.read_mesh(os.fspath(path))
    _warn_of_arrays(native)
    return Mesh(native)


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
