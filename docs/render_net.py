#!/usr/bin/env python3
"""Draws a patch of a quad mesh from above (y up) with the circle through the first three corners of
each quad (so a circular quad has its fourth corner on its circle), before and after:
    python3 docs/render_net.py --out PNG --rows 44,52 --cols 44,52 --grid 100 BEFORE.obj AFTER.obj
(`pip install numpy matplotlib`). The faces must be a row-major grid of `--grid` quads per row.
"""
import argparse
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from render import load_obj_polygons  # docs/render.py, beside this script


def circle_through(a, b, c, samples=90):
    """Points of the circle through a, b, c (3D), or None when they are collinear."""
    u, w = b - a, c - a
    n = np.cross(u, w)
    nn = n @ n
    if nn < 1e-30:
        return None
    centre = a + (np.cross(n, u) * (w @ w) + np.cross(w, n) * (u @ u)) / (2 * nn)
    r = np.linalg.norm(a - centre)
    e1 = (a - centre) / r
    e2 = np.cross(n / np.sqrt(nn), e1)
    t = np.linspace(0, 2 * np.pi, samples)
    return centre + r * (np.outer(np.cos(t), e1) + np.outer(np.sin(t), e2))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    ap.add_argument("--rows", default="44,52")
    ap.add_argument("--cols", default="44,52")
    ap.add_argument("--grid", type=int, default=100)
    ap.add_argument("--title", action="append", default=[])
    ap.add_argument("meshes", nargs="+")
    a = ap.parse_intermixed_args()
    r0, r1 = map(int, a.rows.split(","))
    c0, c1 = map(int, a.cols.split(","))
    fig, axes = plt.subplots(1, len(a.meshes), figsize=(6 * len(a.meshes), 6))
    for k, (ax, path) in enumerate(zip(np.atleast_1d(axes), a.meshes)):
        v, faces = load_obj_polygons(path)
        for i in range(r0, r1):
            for j in range(c0, c1):
                p = v[faces[i * a.grid + j]]
                loop = np.vstack([p, p[:1]])
                ax.plot(loop[:, 0], loop[:, 2], color="#333333", lw=1.2)
                circle = circle_through(p[0], p[1], p[2])
                if circle is not None:
                    ax.plot(circle[:, 0], circle[:, 2], color="#d95f02", lw=0.7)
        ax.set_aspect("equal")
        ax.axis("off")
        if k < len(a.title):
            ax.set_title(a.title[k])
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    print("wrote", a.out)


if __name__ == "__main__":
    main()
