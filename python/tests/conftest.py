"""Shared fixtures: the repository's meshes and examples, small generated meshes, and the
`shapeup` command-line binary to compare with."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "data"
EXAMPLES = ROOT / "examples"


@pytest.fixture(scope="session")
def cli() -> Path:
    """The `shapeup` binary: $SHAPEUP_EXE, else target/release or target/debug, else built
    (without the editor) into target/release."""
    exe = os.environ.get("SHAPEUP_EXE")
    if exe:
        return Path(exe)
    for profile in ("release", "debug"):
        p = ROOT / "target" / profile / "shapeup"
        if p.exists():
            return p
    cargo = shutil.which("cargo")
    assert cargo, "no shapeup binary and no cargo to build one (set SHAPEUP_EXE)"
    subprocess.run(
        [cargo, "build", "--release", "--locked", "-p", "shapeup", "--no-default-features"], cwd=ROOT, check=True
    )
    return ROOT / "target" / "release" / "shapeup"


def grid(nx: int, ny: int, size: float = 1.0, bump: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """A quad grid in the xz plane ((nx+1)(ny+1) vertices, nx*ny quads), optionally bumped."""
    xs, zs = np.meshgrid(np.linspace(0, size, nx + 1), np.linspace(0, size, ny + 1), indexing="ij")
    ys = bump * np.sin(np.pi * xs / size) * np.sin(np.pi * zs / size)
    V = np.stack([xs.ravel(), ys.ravel(), zs.ravel()], axis=1)
    idx = np.arange((nx + 1) * (ny + 1)).reshape(nx + 1, ny + 1)
    F = np.stack([idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()], axis=1)
    return V, F


def tet_cube() -> tuple[np.ndarray, np.ndarray]:
    """A unit cube split into 5 tetrahedra."""
    V = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)])
    T = np.array([[0, 1, 2, 4], [1, 2, 3, 7], [1, 4, 5, 7], [2, 4, 6, 7], [1, 2, 4, 7]])
    return V, T


@pytest.fixture
def quad_grid():
    return grid(6, 5, bump=0.2)
