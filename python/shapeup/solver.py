"""The ShapeUp solver on one mesh: :class:`Solver`."""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from . import _shapeup
from ._checks import _count, _vertices, _warn_unconverged
from .contact import _Contact
from .groups import _Groups
from .mesh import Mesh, _mesh_of


class Solver(_Groups, _Contact):
    """The ShapeUp solver (Bouaziz et al., SGP 2012) on one mesh: constraint groups and a
    prefactored sparse Cholesky global step. Works in the mesh's own coordinates (no
    normalization, unlike scene files' default).

    ``Solver(V, F, T=None)`` or ``Solver(mesh=read_mesh(...))``. ``F`` may be triangles
    (m, 3), polygons (m, k) or a list of polygons; face types (plane, circle, rectangle…) act
    on polygons as given.

    Contact: :meth:`add_collider` and :meth:`set_contact`, as a scene's ``[[colliders]]``
    and ``[contact]`` (static: colliders do not move).

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
        (> 0). ``acceleration``: "lbfgs" (default), "anderson" or "none". With a collider
        or self-collision, the iterations are plain ones in chunks of 10, each detecting
        contact again from where the last left the surface, as ``shapeup deform`` runs a scene
        with contact: ``tolerance`` and ``acceleration`` do not apply; ``energy`` holds E after
        each iteration.

        Returns ``(q, report)``: the new positions float64 (n, 3) and a dict with
        ``iterations``, ``initial_energy``, ``energy`` (E after each iteration),
        ``relative_change``, ``rejected``, ``timings`` (seconds), ``residual`` (when all the
        iterations ran: ‖∇E(q)‖ over ‖∇E‖ where the solve began, else None) and
        ``unconverged`` (the residual above ``STATIC_RESIDUAL_LIMIT``, 0.01: the solve stopped short of its minimum,
        which also warns, :class:`UnconvergedWarning`) and ``warnings`` (that one, as a scene's
        report lists it).

        The GIL is released while it runs; Ctrl+C stops it (KeyboardInterrupt).
        :class:`SolveFailed` when the system cannot be solved (e.g. nothing anchors it)."""
        iterations = _count(iterations, "iterations")
        tolerance = float(tolerance)
        if not (math.isfinite(tolerance) and tolerance >= 0):
            raise ValueError(f"tolerance must be a finite number >= 0, found {tolerance}")
        x = None if q is None else self._positions(q)
        out, text = self._native.solve(x, iterations, tolerance, acceleration)
        report = json.loads(text)
        _warn_unconverged(report)
        return out, report

    def energy(self, q: Any) -> dict[str, Any]:
        """E(q) = Σ w_i ‖C_i q − p_i(q)‖²: ``{"total": E, "groups": {name: E_group}}``.
        :class:`SolveFailed` when E is not a finite number (coordinates or weights too large
        for float64), rather than inf."""
        x = self._positions(q)
        total, per_group = self._native.energy(x)
        return {"total": total, "groups": {self._groups[g].name: e for g, e in per_group if g in self._groups}}
