"""Colliders and contact, shared by :class:`~shapeup.Solver` and :class:`~shapeup.Simulation`:
the ``add_collider`` / ``set_contact`` / ``contact_flags`` mixin."""

from __future__ import annotations

import json
import os
from typing import Any

import numpy as np

from ._checks import _json, _number


class _Contact:
    """add_collider / set_contact / colliders / contact_flags over a native object with the
    same."""

    _native: Any

    def add_collider(self, type: str, **keys: Any) -> int:
        """Adds a collider: a rigid shape the mesh cannot enter (vertices keep at least the
        contact thickness from it). ``type`` and ``keys`` are those of a scene's
        ``[[colliders]]`` entry (``docs/scenes-and-cli.md``), in the mesh's units; vectors may
        be lists, tuples or numpy arrays of 3 numbers. Returns the collider's index.

        - ``type="plane"``: ``point``, ``normal`` (the half-space below the plane is solid);
        - ``type="sphere"``: ``center``, ``radius`` > 0;
        - ``type="capsule"``: ``a``, ``b`` (≠ a), ``radius`` > 0;
        - ``type="box"``: ``min``, ``max`` (≥ min), ``rotate={"axis": ..., "angle_deg": ...,
          "center": ...}`` (centre default: the box's);
        - ``type="mesh"``: ``path`` (any mesh file shapeup reads, relative to the current
          directory; a str or os.PathLike), ``closed`` (default: whether every edge has two
          triangles), ``thickness`` (an open mesh's depth behind its front; default the
          contact thickness), ``translate`` and ``rotate={"axis": ..., "angle_deg": ...,
          "center": ...}`` (its placement: p ↦ c + R (p − c) + translate, c in the file's
          coordinates, default its origin).

        Every type takes ``friction`` (Coulomb μ ≥ 0, default 0) and, in a
        :class:`Simulation`, ``velocity`` (units/s, default 0) and ``spin={"axis": ...,
        "deg_per_s": ..., "center": ...}`` (a :class:`Solver` solves at t = 0: they do not
        move it).

        The collider is checked, and the contact model built again (its per-step state starts
        afresh), at once. ValueError ``"colliders[i]: ..."`` with the scene parser's message
        naming the key (an unknown type or key, a missing key, a radius ≤ 0, a zero normal, a
        mesh file that cannot be read…); TypeError for a value that is not a number, boolean,
        string, list or dict."""
        i = len(self.colliders)
        entry: dict[str, Any] = {"type": type}
        try:
            for key, value in keys.items():
                if key == "path" and isinstance(value, os.PathLike):
                    value = os.fspath(value)
                entry[key] = _json(value, f"`{key}`")
        except ValueError as e:
            raise ValueError(f"colliders[{i}]: {e}") from None
        except TypeError as e:
            raise TypeError(f"colliders[{i}]: {e}") from None
        return self._native.add_collider(json.dumps(entry))

    def set_contact(
        self,
        *,
        self_collision: bool = False,
        thickness: float | None = None,
        friction: float = 0.0,
    ) -> None:
        """Sets the contact settings (a scene's ``[contact]`` table; a keyword left out takes
        its default): ``self_collision`` (the surface collides with itself; default False),
        ``thickness`` (the distance kept from colliders and between parts of the surface, in
        the mesh's units ≥ 0; default None: 0.25 × the rest shape's mean edge length),
        ``friction`` (Coulomb μ ≥ 0 of self contact; default 0). Builds the contact model
        again. ValueError ``"contact: ..."`` for a negative or non-finite value."""
        if not isinstance(self_collision, (bool, np.bool_)):
            raise TypeError(f"self_collision must be a bool, found {self_collision!r}")
        settings: dict[str, Any] = {
            "self_collision": bool(self_collision),
            "friction": _json(_number(friction, "friction"), "friction"),
        }
        if thickness is not None:
            settings["thickness"] = _json(_number(thickness, "thickness"), "thickness")
        self._native.set_contact(json.dumps(settings))

    @property
    def colliders(self) -> list[dict[str, Any]]:
        """The colliders, as scene entries (a mesh's path made absolute), in the order added."""
        return json.loads(self._native.colliders)

    @property
    def contact(self) -> dict[str, Any]:
        """The contact settings: ``self_collision``, ``thickness`` (None: the default),
        ``friction``."""
        return json.loads(self._native.contact_settings)

    @property
    def contact_thickness(self) -> float | None:
        """The contact thickness in use, in the mesh's units (None while there is no collider
        and no self-collision)."""
        return self._native.contact_thickness

    @property
    def contact_flags(self) -> np.ndarray:
        """Per vertex, whether it touched a collider or the surface at the end of the last
        step (or solve): bool (n,), all False without contact or before the first step."""
        return self._native.contact_flags

    @property
    def factorizations(self) -> int:
        """Numeric factorizations of the global matrix so far (a new weight, a new contact
        model or a changed time step refactors; moving targets never do)."""
        return self._native.factorizations
