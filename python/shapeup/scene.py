"""Scene files, run as the command line runs them: :class:`Scene`."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from . import _shapeup
from ._checks import PathLike, _count, _json


# ---------------------------------------------------------------------------------------------
# A second scene reader, kept until shapeup-core applies dotted overrides itself (then delete
# this block and pass the overrides to Rust): with overrides, the file is read here (TOML or
# JSON, UTF-8 with or without a BOM), changed, and handed to Rust as JSON text.


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


# ---------------------------------------------------------------------------------------------


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
