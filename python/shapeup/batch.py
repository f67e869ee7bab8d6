"""Scene files over a Dask ``distributed`` cluster: parameter sweeps and data sets of deformed
shapes beyond one process.

>>> from shapeup.batch import run_scenes
>>> results = run_scenes(["a.toml", ("a.toml", {"constraints.0.weight": 3.0,
...                                             "output.path": "out/a-w3.obj"})])  # doctest: +SKIP

In a script, call it under ``if __name__ == "__main__":``: the local cluster starts worker
processes, which import the script again.

Each scene runs as the command line runs it: a static scene is deformed (``shapeup deform``),
a dynamic one simulated for its ``steps`` (``shapeup simulate``). Results land where the
scene's ``[output]`` table says (``path``: the mesh, or the frames' folder; ``report``: the
JSON report); a scene without one writes nothing and its report comes back in the result.

A real cluster: start a scheduler and workers (``dask scheduler``, ``dask worker
tcp://host:8786`` on each machine, each with ``pip install`` of this package and the scene
files and meshes at the same paths, e.g. a shared file system), then pass
``client="tcp://host:8786"`` or a ``dask.distributed.Client``.
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence, Union

SceneItem = Union[str, "os.PathLike[str]", tuple[Union[str, "os.PathLike[str]"], Mapping[str, Any]]]


@dataclass
class SceneResult:
    """What one scene of a batch gave."""

    scene: str
    """The scene file."""
    overrides: dict[str, Any]
    """The overrides it ran with."""
    ok: bool
    """False when it failed (``error`` says why)."""
    error: str | None = None
    """The one-line message of the failure (the library's), or None."""
    output: str | None = None
    """The mesh (static) or the frames' folder (dynamic) written, or None."""
    report_path: str | None = None
    """The report written, or None."""
    report: dict[str, Any] = field(default_factory=dict)
    """The report (as ``--report`` writes it)."""


def run_scene(scene: str, overrides: Mapping[str, Any] | None = None) -> SceneResult:
    """Runs one scene in this process (what each Dask task does)."""
    import shapeup

    overrides = dict(overrides or {})
    try:
        s = shapeup.Scene.load(scene, overrides)
        out = s.output_path
        rep = s.report_path
        if s.mode == "dynamic":
            _, report = s.simulate(output=out, report=rep)
        else:
            _, report = s.deform(output=out, report=rep)
        return SceneResult(
            scene=str(scene),
            overrides=overrides,
            ok=True,
            output=None if out is None else str(out),
            report_path=None if rep is None else str(rep),
            report=report,
        )
    except Exception as e:  # noqa: BLE001 - a failed scene is a result, not the batch's end
        return SceneResult(scene=str(scene), overrides=overrides, ok=False, error=f"{type(e).__name__}: {e}")


def _items(paths: Iterable[SceneItem]) -> list[tuple[str, dict[str, Any]]]:
    items = []
    for p in paths:
        if isinstance(p, tuple):
            scene, overrides = p
            items.append((os.fspath(scene), dict(overrides)))
        else:
            items.append((os.fspath(p), {}))
    return items


class _PlainProgress:
    """Progress without tqdm: ``shapeup: k/n scenes`` on stderr, one line redrawn."""

    def __init__(self, total: int) -> None:
        self.total, self.done = total, 0

    def update(self, n: int) -> None:
        self.done += n
        print(f"\rshapeup: {self.done}/{self.total} scenes", end="", file=sys.stderr, flush=True)

    def close(self) -> None:
        print(file=sys.stderr, flush=True)


def run_scenes(
    paths: Iterable[SceneItem],
    client: Any = None,
    *,
    progress: bool = True,
    workers: int | None = None,
) -> list[SceneResult]:
    """Runs scene files (or ``(scene, overrides)`` pairs, see :meth:`shapeup.Scene.load`) on
    a Dask cluster and returns one :class:`SceneResult` per item, in the order given.

    ``client``: None starts a ``LocalCluster`` on this machine (``workers`` processes, default
    the core count, one thread each, with the local step single-threaded so that workers do
    not oversubscribe the cores) and closes it afterwards; a scheduler address
    (``"tcp://host:8786"``) or a ``dask.distributed.Client`` uses that cluster.

    A failing scene is reported in its result (``ok=False``, ``error``) while the others
    finish. ``progress``: a tqdm bar of completed scenes on stderr (a plain count when tqdm
    is not installed)."""
    from dask.distributed import Client, LocalCluster, as_completed

    items = _items(paths)
    own_cluster = None
    if client is None:
        n = workers or os.cpu_count() or 1
        own_cluster = LocalCluster(
            n_workers=n,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            env={"RAYON_NUM_THREADS": "1"},
        )
        client = Client(own_cluster)
    elif isinstance(client, str):
        client = Client(client)
    try:
        # Absolute paths: workers may start in another folder.
        futures = [
            client.submit(run_scene, str(Path(scene).resolve()), overrides, pure=False) for scene, overrides in items
        ]
        index = {f.key: i for i, f in enumerate(futures)}
        results: list[SceneResult | None] = [None] * len(items)
        bar = None
        if progress:
            try:
                from tqdm.auto import tqdm

                bar = tqdm(total=len(items), unit="scene", desc="shapeup")
            except ImportError:
                # Dask installed without tqdm (it is in the "batch" extra, not required).
                bar = _PlainProgress(len(items))
        for future in as_completed(futures):
            i = index[future.key]
            try:
                results[i] = future.result()
            except Exception as e:  # noqa: BLE001 - a worker that died
                scene, overrides = items[i]
                results[i] = SceneResult(scene=scene, overrides=overrides, ok=False, error=f"{type(e).__name__}: {e}")
            if bar is not None:
                bar.update(1)
        if bar is not None:
            bar.close()
        return [r for r in results if r is not None]
    finally:
        if own_cluster is not None:
            client.close()
            own_cluster.close()


__all__ = ["SceneResult", "run_scene", "run_scenes"]
