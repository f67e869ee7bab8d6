"""shapeup.batch on a 2-worker LocalCluster: the same outputs as sequential runs, and a
broken scene reported while the others finish."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
import shapeup

pytest.importorskip("dask.distributed")
from shapeup.batch import run_scene, run_scenes  # noqa: E402

from conftest import DATA  # noqa: E402


def sweep(tmp_path: Path, tag: str) -> list:
    scene = tmp_path / "sweep.toml"
    scene.write_text(
        f'[mesh]\npath = "{DATA / "stanford-bunny.obj"}"\n[solver]\niterations = 15\n'
        '[[constraints]]\ntype = "edge_spring"\n'
        '[[constraints]]\ntype = "position"\nname = "base"\nbox = { min = [-1, -1, -1], max = [1, 0.037, 1] }\n'
        '[[constraints]]\ntype = "position"\nname = "ears"\nbox = { min = [-1, 0.178, -1], max = [1, 1, 1] }\n'
        "translate = [0.06, 0.02, 0.0]\n"
    )
    (tmp_path / tag).mkdir()
    return [
        (scene, {"constraints.0.weight": w, "output.path": f"{tag}/w{i}.obj", "output.report": f"{tag}/w{i}.json"})
        for i, w in enumerate([1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0])
    ]


def test_batch_equals_sequential_and_survives_a_broken_scene(tmp_path):
    items = sweep(tmp_path, "batch")
    broken = tmp_path / "broken.toml"
    broken.write_text('[mesh]\npath = "missing.obj"\n[[constraints]]\ntype = "edge_spring"\n')
    results = run_scenes(items[:4] + [broken] + items[4:], workers=2, progress=False)
    assert len(results) == 9
    bad = results[4]
    assert not bad.ok and "missing.obj" in bad.error
    good = [r for r in results if r.ok]
    assert len(good) == 8

    for i, (scene, overrides) in enumerate(sweep(tmp_path, "seq")):
        r = run_scene(str(scene), overrides)
        assert r.ok, r.error
        batch_v = shapeup.read_mesh(tmp_path / "batch" / f"w{i}.obj").V
        seq_v = shapeup.read_mesh(tmp_path / "seq" / f"w{i}.obj").V
        np.testing.assert_allclose(batch_v, seq_v, rtol=0, atol=1e-12)
        batch_report = json.loads((tmp_path / "batch" / f"w{i}.json").read_text())
        np.testing.assert_allclose(batch_report["energy"], r.report["energy"], rtol=1e-12)


def test_run_scenes_counts_plainly_without_tqdm(tmp_path, monkeypatch, capsys):
    # Dask installed alone: no tqdm, and the progress is a plain count, not ModuleNotFoundError.
    monkeypatch.setitem(sys.modules, "tqdm", None)
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)
    items = sweep(tmp_path, "plain")[:2]
    results = run_scenes(items, workers=1, progress=True)
    assert [r.ok for r in results] == [True, True], [r.error for r in results]
    assert "shapeup: 2/2 scenes" in capsys.readouterr().err
