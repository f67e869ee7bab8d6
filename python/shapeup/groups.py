"""Constraint groups, shared by :class:`~shapeup.Solver` and :class:`~shapeup.Simulation`:
:class:`Group` and the ``add`` / ``set_targets`` / ``set_weight`` / ``remove`` / ``held`` mixin."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any, Mapping, Union

import numpy as np

from ._checks import _indices, _json, _vertices
from .types import _types_doc

GroupRef = Union["Group", int, str]


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


# ---------------------------------------------------------------------------------------------
# What the core also decides, kept here until shapeup-core offers it (then delete this block):
# - the selection keys of a scene entry (the scene parser knows them as well);
# - names: a given name must be new, an unnamed group whose type names another group already
#   gets "type_2", "type_3"… (scene files and the editor name unnamed groups otherwise);
# - a weight must be finite and >= 0 (the scene parser and System::set_multiplier check it too).

_SELECTION_KEYS = ("vertices", "faces", "box", "sphere")


def _group_name(type: str, name: Any, taken: list[str]) -> str | None:
    """The name a new group of ``type`` asks for: ``name`` when given (a string no group in
    ``taken`` has), else ``type_2``, ``type_3``… when a group is named ``type`` already, else
    None (the core names it after its type)."""
    if name is not None:
        if not isinstance(name, str):
            raise TypeError(f"name must be a string, found {name!r}")
        if name in taken:
            raise ValueError(f"a group named {name!r} exists already")
        return name
    if type in taken:
        k = 2
        while f"{type}_{k}" in taken:
            k += 1
        return f"{type}_{k}"
    return None


def _checked_weight(w: float, weight: Any) -> float:
    """``w`` (``weight`` as a float) when finite and >= 0, else ValueError quoting ``weight``."""
    if not (math.isfinite(w) and w >= 0):
        raise ValueError(f"weight must be a finite number >= 0, found {weight!r}")
    return w


# ---------------------------------------------------------------------------------------------


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
        group_name = _group_name(type, name, [g.name for g in self._groups.values()])
        if group_name is not None:
            entry["name"] = group_name
        if weight is not None:
            try:
                w = float(weight)
            except (TypeError, ValueError):
                raise TypeError(f"weight must be a number, found {weight!r}") from None
            entry["weight"] = _checked_weight(w, weight)
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
        w = _checked_weight(float(weight), weight)
        self._native.set_weight(self._id(group), w)

    def remove(self, group: GroupRef) -> None:
        """Removes a group."""
        gid = self._id(group)
        self._native.remove(gid)
        del self._groups[gid]


# `help(shapeup.Solver.add)` lists every registered type (from the registry, never by hand).
if _Groups.add.__doc__:
    _Groups.add.__doc__ = _Groups.add.__doc__.replace("{types}", _types_doc())
