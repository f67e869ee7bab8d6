"""Deform a mesh loaded by trimesh with shapeup, and show it with polyscope.

    pip install ".[batch]" trimesh polyscope
    python examples/python/trimesh_polyscope.py [MESH] [--screenshot OUT.png]

The lowest 2 % of the mesh (in y) stays where it is, the highest 5 % moves sideways and up,
and the rest follows as rigidly as it can (isometric one-rings). With --screenshot it renders
one frame without a window (polyscope's EGL backend) and writes the PNG.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import polyscope as ps
import shapeup
import trimesh

ROOT = Path(__file__).resolve().parents[2]


def deform(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, dict]:
    """V float64 (n, 3), F int (m, 3) -> the deformed V and the solver's report."""
    y = V[:, 1]
    height = np.ptp(y)
    diagonal = np.linalg.norm(np.ptp(V, axis=0))
    solver = shapeup.Solver(V, F)
    solver.add("iso_one_ring")
    solver.add("position", y < y.min() + 0.02 * height, name="base")
    solver.add("position", y > y.max() - 0.05 * height, name="top", translate=[0.25 * diagonal, 0.1 * diagonal, 0])
    return solver.solve(iterations=100)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mesh", nargs="?", default=str(ROOT / "data" / "stanford-bunny.obj"))
    parser.add_argument("--screenshot", metavar="OUT.png")
    args = parser.parse_args()

    # process=False, maintain_order=True: trimesh keeps every vertex in file order (no merging,
    # unreferenced vertices kept), as shapeup does, so indices match the file's.
    mesh = trimesh.load(args.mesh, process=False, maintain_order=True, force="mesh")
    V, F = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    q, report = deform(V, F)
    print(f"{len(V)} vertices: E {report['initial_energy']:.3e} -> {report['energy'][-1]:.3e} "
          f"in {report['iterations']} iterations")

    if args.screenshot:
        ps.set_allow_headless_backends(True)
        ps.init("openGL3_egl")
    else:
        ps.init()
    ps.set_up_dir("y_up")
    ps.set_ground_plane_mode("shadow_only")
    offset = np.array([1.1 * np.ptp(V[:, 0]), 0.0, 0.0])
    ps.register_surface_mesh("rest", V - offset / 2, F, color=(0.75, 0.75, 0.78), smooth_shade=True)
    ps.register_surface_mesh("deformed", q + offset / 2, F, color=(0.35, 0.55, 0.85), smooth_shade=True)
    if args.screenshot:
        ps.look_at((0.0, 0.6 * np.ptp(V[:, 1]), 3.2 * np.ptp(V[:, 0])), (0.0, V[:, 1].mean(), 0.0))
        ps.screenshot(args.screenshot, transparent_bg=False)
        print(f"wrote {args.screenshot}")
    else:
        ps.show()


if __name__ == "__main__":
    main()
