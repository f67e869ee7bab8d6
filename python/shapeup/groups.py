"""Constraint groups, shared by :class:`~shapeup.Solver` and :class:`~shapeup.Simulation`:
:class:`Group` and the ``add`` / ``set_targets`` / ``set_weight`` / ``remove`` / ``held`` mixin."""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any, Mapping, Union

import numpy as np

from ._checks import _indices, _json, _name, _number, _selection, _vertices
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
        "radius": r}}``, ``{"physical": "fixed"}`` (a physical group of the ``.msh`` file
        the mesh was read from, by name or tag). Position-like types take ``translate=[dx, dy, dz]``,
        ``rotate={"axis": ..., "angle_deg": ..., "center": ...}``, ``targets=(k, 3) array``
        or ``hard=True``.

        ValueError for an unknown type or option (naming it), a bad option value, a weight
        that is negative or not finite, a name another group has, or a selection the type
        cannot act on; IndexError for an index out of range; TypeError for a name that is not
        a string or a weight that is not a number.

        Types:
{types}
        """
        # The entry in scene keys, the selection apart (the native side takes only selection
        # keys from it); the core names the group (``type``, ``type_2``… after the groups
        # already here), checks the weight and parses the rest, as for a scene file.
        entry: dict[str, Any] = {"type": type}
        if name is not None:
            entry["name"] = _name(name)
        if weight is not None:
            entry["weight"] = _json(_number(weight, "weight"), "weight")
        picked: dict[str, Any] = {}
        if isinstance(selection, Mapping):
            for key, value in selection.items():
                if key == "vertices":
                    value = _indices(value, self._n, "selection")
                picked[str(key)] = _json(value, str(key))
        elif selection is not None:
            picked["vertices"] = _selection(selection, self._n).tolist()
        if "spin" in options:
            raise ValueError(
                "spin turns scene handles in `shapeup simulate`; from Python, move the targets each "
                "step with set_targets(group, targets)"
            )
        for key, value in options.items():
            if key == "vertices":
                value = _indices(value, self._n, "vertices")
            entry[key] = _json(value, key)
        gid, gname, gtype, count = self._native.add(json.dumps(entry), json.dumps(picked))
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
        self._native.set_weight(self._id(group), float(weight))

    def remove(self, group: GroupRef) -> None:
        """Removes a group."""
        gid = self._id(group)
        self._native.remove(gid)
        del self._groups[gid]


# `help(shapeup.Solver.add)` lists every registered type (from the registry, never by hand).
if _Groups.add.__doc__:
    _Groups.add.__doc__ = _Groups.add.__doc__.replace("{types}", _types_doc())
