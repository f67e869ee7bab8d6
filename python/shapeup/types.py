"""The constraint types of the registry: :class:`ConstraintType` and :func:`constraint_types`."""

from __future__ import annotations

from dataclasses import dataclass

from . import _shapeup


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
        ConstraintType(t.name, t.acts_on, t.default_weight, t.summary, t.has_targets, tuple(tuple(o) for o in t.options))
        for t in _shapeup.constraint_types()
    ]


def _types_doc() -> str:
    lines = []
    for t in constraint_types():
        opts = "; ".join(text.replace("`", "") for _, text, _ in t.options) or "no options"
        if t.has_targets:
            opts += "; targets: translate, rotate, targets, hard"
        lines.append(f"        {t.name:<24}{t.acts_on}, weight {t.default_weight:g}: {t.summary} ({opts})")
    return "\n".join(lines)
