"""Projective Dynamics on one mesh: :class:`Simulation`."""

from __future__ import annotations

import json
from typing import Any, Sequence

import numpy as np

from . import _shapeup
from ._checks import _count, _indices, _json, _vertices, _warn_unconverged
from .contact import _Contact
from .groups import _Groups
from .mesh import Mesh, _mesh_of


class Simulation(_Groups, _Contact):
    """Projective Dynamics (Bouaziz et al., SIGGRAPH 2014) on one mesh: implicit Euler time
    steps, each a local-global solve of inertia + constraints, in the mesh's units.

    Settings (None: the scene files' defaults): ``time_step`` h in s (1/60), ``gravity`` in
    units/s² ((0, −9.81, 0)), ``stiffness`` k (100), ``damping`` d in [0, 1) (0), ``density``
    ρ (1; lumped masses ρ·area/3 per vertex, ρ·volume/4 on tetrahedra), ``iterations`` per step
    (10), ``tolerance`` (0), ``acceleration`` ("lbfgs").

    Contact: :meth:`add_collider` (spheres, planes, capsules, boxes, meshes) and
    :meth:`set_contact` (thickness, self-collision), as a scene's ``[[colliders]]`` and
    ``[contact]``; with contact a step runs plain iterations (no tolerance, no acceleration)
    and :attr:`contact_flags` says which vertices touch."""

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
        step's report: ``energy`` (E when the iterations computed it, else None),
        ``iterations``, ``rejected``, timings in seconds (``local_s``, ``global_s``,
        ``setup_s``, ``total_s``, ``contact_s``) and contact counts at the end of the step
        (0 without contact): ``contacts`` (touching contacts), ``self_contacts`` (of those,
        the surface with itself), ``contact_candidates`` (detected), ``contact_vertices``
        (vertices touching), ``crossings_stopped`` (vertices whose motion the self-collision
        crossing check changed) and ``ended_inside`` (vertices left inside a collider:
        squeezed between two, or held back where a moving collider came over them).
        Steps 1, 2, 4, …, 64 and every 64th after are checked for stopping short: ``residual``
        is the share of the converged step's motion the step misses (None on steps not
        checked, and in a simulation with colliders or self-collision), ``unconverged`` whether it
        is above ``shapeup._shapeup.DYNAMIC_RESIDUAL_LIMIT`` (0.5), and ``check_s`` the check's
        seconds (steps that a ``tolerance`` ended are checked too: a stiff step's energy stalls
        long before it is converged). A call
        whose steps stopped short warns once (:class:`UnconvergedWarning`). ``lost_groups``
        describes the groups whose weights the factorization cannot resolve (10¹³ and more below
        the others where they act), which warns once too (:class:`RoundOffWarning`)."""
        out = json.loads(self._native.step(_count(n, "n")))
        _warn_unconverged(out)
        return out["reports"]

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
