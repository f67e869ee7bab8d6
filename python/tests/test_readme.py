"""The README's Python section runs as written (from a folder with the repository's data and
examples beside it)."""

from __future__ import annotations

import os
import re

import numpy as np
import shapeup

from conftest import ROOT


def python_blocks() -> list[str]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text[text.index("## Python") : text.index("## Command line")]
    return re.findall(r"```python\n(.*?)```", section, flags=re.S)


def test_readme_python_section(tmp_path, monkeypatch, capsys):
    blocks = python_blocks()
    assert len(blocks) == 2, "the README's Python section has its example and the batch example"
    assert 'if __name__ == "__main__":' in blocks[1], "Dask's worker processes re-import a script"
    for name in ("data", "examples"):
        os.symlink(ROOT / name, tmp_path / name)
    monkeypatch.chdir(tmp_path)
    exec(compile(blocks[0], "README.md (Python example)", "exec"), {"__name__": "__main__"})
    out = shapeup.read_mesh(tmp_path / "bunny-py.obj")
    moved = np.abs(out.V - shapeup.read_mesh(ROOT / "data" / "stanford-bunny.obj").V).max()
    assert moved > 0.01
    assert "->" in capsys.readouterr().out
    # As a script: under `if __name__ == "__main__":`.
    exec(compile(blocks[1], "README.md (batch example)", "exec"), {"__name__": "__main__"})
    printed = capsys.readouterr().out.strip().splitlines()
    assert len(printed) == 3 and all(" True " in line for line in printed), printed
    for w in (1.0, 10.0, 100.0):
        assert (tmp_path / f"bunny-w{w}.obj").exists()
