"""What the Python door costs around a solve on the bunny: wall-clock time of
``Solver.solve`` against the time the library spends inside it (setup + local + global steps,
from the report), best of several rounds. Target: overhead ≤ 5 % of the solve.

    python python/benchmarks/overhead.py [--iterations 50] [--rounds 7]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import shapeup

ROOT = Path(__file__).resolve().parents[2]


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--mesh", default=str(ROOT / "data" / "stanford-bunny.obj"))
    parser.add_argument("--iterations", type=int, default=50)
    parser.add_argument("--rounds", type=int, default=7)
    args = parser.parse_args()

    mesh = shapeup.read_mesh(args.mesh)
    V = mesh.V
    solver = shapeup.Solver(V, mesh.F)
    solver.add("iso_one_ring")
    solver.add("position", V[:, 1] < V[:, 1].min() + 0.01, name="base")
    top = solver.add("position", V[:, 1] > V[:, 1].max() - 0.04, name="top", translate=[0.03, 0.01, 0.0])
    solver.solve(iterations=1)  # the first solve factors the matrix; time the iterations
    held = solver.held(top)
    rows = []
    for r in range(args.rounds):
        # A new target each round, as a script dragging a handle would (no refactorization).
        solver.set_targets(top, V[held] + [0.03 + 0.001 * r, 0.01, 0.0])
        start = time.perf_counter()
        q, report = solver.solve(iterations=args.iterations)
        wall = time.perf_counter() - start
        t = report["timings"]
        inside = t["setup_s"] + t["local_s"] + t["global_s"]
        rows.append((wall, inside))
    wall, inside = min(rows, key=lambda w: w[0])
    print(f"bunny: {len(V)} vertices, {args.iterations} iterations, best of {args.rounds}")
    print(f"  Solver.solve wall    {wall * 1e3:9.2f} ms")
    print(f"  inside the library   {inside * 1e3:9.2f} ms (setup + local + global)")
    print(f"  Python overhead      {(wall - inside) * 1e3:9.2f} ms = {100 * (wall - inside) / inside:.2f} % of the solve")
    start = time.perf_counter()
    for _ in range(100):
        shapeup._checks._vertices(V)
    print(f"  V check (no copy)    {(time.perf_counter() - start) * 10:9.3f} ms per call")
    assert np.isfinite(q).all()


if __name__ == "__main__":
    main()
