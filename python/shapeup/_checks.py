"""Argument checks shared by the API modules (as polyscope's ``common.py``): each converts one
argument to what the native module takes, or raises with one line naming the argument.

Conventions (those of libigl, trimesh and meshio): ``V`` float64 ``(n, 3)`` vertex positions,
``F`` int ``(m, 3)`` triangles or a list of polygons (index arrays of any length), ``T`` int
``(t, 4)`` tetrahedra. Indices are 0-based. Lengths are in the mesh's own units; time in
seconds.
"""

from __future__ import annotations

import math
import os
from typing import Any, Mapping, Sequence, Union

import numpy as np

PathLike = Union[str, "os.PathLike[str]"]


class UnconvergedWarning(UserWarning):
    """A static solve stopped at its iteration cap short of its minimum (its relative residual,
    the report's ``residual``, above ``STATIC_RESIDUAL_LIMIT``): raise ``iterations``, with a
    ``tolerance`` to stop once converged. Or time steps stopped short of the converged step
    (the share of its motion a checked step misses above ``DYNAMIC_RESIDUAL_LIMIT``: the
    simulate report's ``residuals``, the step reports' ``residual``): raise ``iterations``, or
    lower ``stiffness`` or ``time_step``."""


class MeshWarning(UserWarning):
    """Arrays given as a mesh (``Mesh.from_arrays``, ``Solver(V, F)``) whose faces the solver
    takes otherwise than given, said once with a count (also in ``Mesh.warnings``): faces on
    the same vertices as an earlier face (kept: constraints on faces act there twice), faces
    that cannot be triangulated (left out of the solver), polygons too tangled to ear-clip
    (fanned)."""


# The kinds of Mesh.warnings that MeshWarning raises for arrays (quads triangulated for the
# solver are expected, not a warning).
_ARRAY_WARNINGS = ("duplicate_faces", "faces_not_triangulated", "polygons_fanned")


def _warn_of_arrays(native: Any) -> None:
    """One :class:`MeshWarning` per warning of ``_ARRAY_WARNINGS`` that building a mesh from
    arrays, or reading it from a file, gave."""
    import warnings

    for kind, text in zip(native.warning_kinds, native.warnings):
        if kind in _ARRAY_WARNINGS:
            warnings.warn(text, MeshWarning, stacklevel=3)


class RoundOffWarning(UserWarning):
    """Groups whose weights are so far below the others' where they act (10¹³ and more) that
    the factorization cannot resolve them: what they hold is left to round-off
    (``groups_lost_to_round_off``);
    bring the weights within 1e12 of each other. In a time step the inertia m / (stiffness ·
    time_step²) may be the term lost, or the one that dwarfs a group: change ``stiffness`` or
    ``time_step``."""


# The kinds of a solve report's warnings raised in Python, and as what.
_SOLVE_WARNINGS = {"unconverged": UnconvergedWarning, "groups_lost_to_round_off": RoundOffWarning}


def _warn_unconverged(report: Mapping[str, Any]) -> None:
    """One :class:`UnconvergedWarning` per ``unconverged`` entry of a solve's
    ``report["warnings"]`` (a scene's or ``Solver.solve``'s: the command line's line, once), and
    one :class:`RoundOffWarning` per ``groups_lost_to_round_off`` entry."""
    import warnings

    for w in report.get("warnings", []):
        category = _SOLVE_WARNINGS.get(w.get("kind"))
        if category is not None:
            file = f"{w['file']}: " if w.get("file") else ""
            first = f" (first: {w['first']})" if w.get("first") else ""
            warnings.warn(f"{file}{w['count']} {w['message']}{first}", category, stacklevel=3)


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


def _number(value: Any, name: str) -> float:
    """``value`` as a float; TypeError naming ``name`` when it is not a number. (Its range is
    the core's to check.)"""
    try:
        return float(value)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a number, found {value!r}") from None


def _name(value: Any) -> str:
    """A group name: TypeError unless it is a string. (Whether it is free is the core's to
    say.)"""
    if not isinstance(value, str):
        raise TypeError(f"name must be a string, found {value!r}")
    return value


def _selection(selection: Any, n: int) -> np.ndarray:
    """A vertex selection given as an array: int64 indices from an index array or a boolean
    mask of length ``n``. ValueError for a wrong shape, IndexError out of range."""
    a = np.asarray(selection)
    if a.dtype == np.bool_:
        if a.shape != (n,):
            raise ValueError(f"a boolean selection must have shape ({n},), found {a.shape}")
        a = np.flatnonzero(a)
    elif a.ndim != 1:
        raise ValueError(f"selection must be a 1-D array of vertex indices, found shape {a.shape}")
    return _indices(a, n, "selection")


def _count(value: Any, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an integer, found {value!r}")
    if value < 0:
        raise ValueError(f"{name} must be >= 0, found {value}")
    return int(value)
