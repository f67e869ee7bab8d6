"""Scene files, run as the command line runs them: :class:`Scene`."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from . import _shapeup
from ._checks import PathLike, _count, _json, _warn_unconverged


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

        The file is read and the overrides applied by the core, as ``shapeup deform`` and
        ``shapeup simulate`` read scenes (UTF-8 or UTF-16 text). FileNotFoundError when the
        scene is missing; KeyError for an override whose key names no entry (``"constraints.9.weight"``
        with fewer groups); ValueError naming the file and the entry (unknown key, bad value,
        bad selection) otherwise."""
        # Absolute, so that a later os.chdir does not move the scene's mesh.
        path = Path(os.path.abspath(os.fspath(path)))
        if not overrides:
            return Scene(_shapeup._Scene(str(path)))
        # Applied by the core, to the file as it reads it (any encoding it reads): a list of
        # [key, value] pairs, in the order given.
        pairs = [[str(key), _json(value, str(key))] for key, value in overrides.items()]
        return Scene(_shapeup._Scene(str(path), json.dumps(pairs)))

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
        """``shapeup deform``: the static solve from the rest shape, or from the scene's
        ``[mesh] start`` shape when it has one (``iterations`` default:
        the scene's steps × iterations). Returns ``(V, report)``: the result in the input's
        frame float64 (n, 3), bit for bit what the command line writes, and the report the
        command line writes with ``--report``. Writes ``output`` (a mesh file, with the
        input's faces and attributes) and ``report`` (JSON) when given. A solve that stops at its
        iteration cap short of its minimum warns (:class:`UnconvergedWarning`, as the command
        line's warning; ``report["residual"]``). ValueError, before any work, when either is one of the run's inputs (the scene file, its mesh, a mesh
        collider's file) under any name; IsADirectoryError when ``output`` is a folder."""
        if iterations is not None:
            iterations = _count(iterations, "iterations")
        mesh, text = self._native.deform(
            iterations,
            None if output is None else os.fspath(output),
            None if report is None else os.fspath(report),
        )
        rep = json.loads(text)
        _warn_unconverged(rep)
        return mesh.vertices, rep

    def simulate(
        self,
        frames: int | None = None,
        every: int = 1,
        output: PathLike | None = None,
        format: str = "obj",
        report: PathLike | None = None,
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """``shapeup simulate``: ``frames`` time steps (default the scene's steps) from rest (in
        the scene's ``[mesh] start`` shape when it has one).
        Returns ``(X, report)``: X float64 (k, n, 3) holds frame 0, every ``every``-th frame
        and the last (their numbers in ``report["frame_numbers"]``), as the command line's
        frame files hold them; writes them to the folder ``output`` in ``format`` (obj, ply,
        off, stl, vtu, msh) when given, as the command line does: through a staging folder
        beside it, moved in when the run completes (an error or ``KeyboardInterrupt`` writes
        nothing), replacing an earlier run's frames there (warning ``earlier_frames_removed``);
        the folder that ``output`` goes in must exist (``FileNotFoundError``). Time steps that
        stop short of the converged step warn once
        (:class:`UnconvergedWarning`, as the command line's warning; ``report["residuals"]``
        lists each checked step's share of its motion missed)."""
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
        _warn_unconverged(rep)
        return np.stack(arrays), rep
