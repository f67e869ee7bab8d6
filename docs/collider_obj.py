#!/usr/bin/env python3
"""Write a scene's colliders as one OBJ, appended to a frame, for the README's contact pictures.

    python3 docs/collider_obj.py SCENE.toml FRAME.obj OUT.obj [--no-planes]

Spheres and capsules become UV spheres and capsules, planes a 3 x 3 quad around the point,
boxes their 6 faces, meshes their own faces (the renderer draws one mesh per panel, so the
frame and its colliders go into one file). Only numpy-free standard Python.
"""
import math
import os
import sys
import tomllib


def read_obj(path):
    v, f = [], []
    for line in open(path):
        p = line.split()
        if not p:
            continue
        if p[0] == "v":
            v.append(tuple(map(float, p[1:4])))
        elif p[0] == "f":
            f.append([int(x.split("/")[0]) for x in p[1:]])
    return v, f


def sphere(c, r, a=None, b=None, n=24):
    """A UV sphere of radius r at c, or a capsule from a to b (its caps' centres)."""
    v, f = [], []
    if a is None:
        for i in range(n + 1):
            th = math.pi * i / n
            for j in range(n):
                ph = 2 * math.pi * j / n
                v.append([c[0] + r * math.sin(th) * math.cos(ph), c[1] + r * math.cos(th), c[2] + r * math.sin(th) * math.sin(ph)])
        for i in range(n):
            for j in range(n):
                k0, k1 = i * n + j, i * n + (j + 1) % n
                f.append([k0 + 1, k0 + n + 1, k1 + n + 1, k1 + 1])
        return v, f
    axis = [b[i] - a[i] for i in range(3)]
    for i in range(n + 1):
        th = math.pi * i / n
        end = a if i <= n // 2 else b
        for j in range(n):
            ph = 2 * math.pi * j / n
            d = (math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph))
            # Capsule: the y of the UV sphere runs along the axis.
            length = math.sqrt(sum(x * x for x in axis)) or 1.0
            u = [x / length for x in axis] if length else [0, 1, 0]
            t = [1, 0, 0] if abs(u[0]) < 0.9 else [0, 1, 0]
            w = [u[1] * t[2] - u[2] * t[1], u[2] * t[0] - u[0] * t[2], u[0] * t[1] - u[1] * t[0]]
            wl = math.sqrt(sum(x * x for x in w))
            w = [x / wl for x in w]
            s = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]]
            p = [end[k] + r * (d[1] * u[k] + d[0] * w[k] + d[2] * s[k]) for k in range(3)]
            v.append(p)
    for i in range(n):
        for j in range(n):
            k0, k1 = i * n + j, i * n + (j + 1) % n
            f.append([k0 + 1, k1 + 1, k1 + n + 1, k0 + n + 1])
    return v, f


def main():
    scene_path, frame, out = sys.argv[1:4]
    planes = "--no-planes" not in sys.argv[4:]
    scene = tomllib.load(open(scene_path, "rb"))
    v, f = read_obj(frame)
    for c in scene.get("colliders", []):
        kind = c["type"]
        if kind == "sphere":
            cv, cf = sphere(c["center"], c["radius"])
        elif kind == "capsule":
            cv, cf = sphere(None, c["radius"], c["a"], c["b"])
        elif kind == "plane" and not planes:
            continue
        elif kind == "plane":
            p, nrm = c["point"], c["normal"]
            t = [1, 0, 0] if abs(nrm[0]) < 0.9 else [0, 1, 0]
            u = [nrm[1] * t[2] - nrm[2] * t[1], nrm[2] * t[0] - nrm[0] * t[2], nrm[0] * t[1] - nrm[1] * t[0]]
            ul = math.sqrt(sum(x * x for x in u))
            u = [x / ul for x in u]
            w = [nrm[1] * u[2] - nrm[2] * u[1], nrm[2] * u[0] - nrm[0] * u[2], nrm[0] * u[1] - nrm[1] * u[0]]
            cv = [[p[k] + 0.9 * (sx * u[k] + sy * w[k]) for k in range(3)] for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
            cf = [[1, 4, 3, 2]]
        elif kind == "box":
            lo, hi = c["min"], c["max"]
            cv = [[(hi if (i >> k) & 1 else lo)[k] for k in range(3)] for i in range(8)]
            cf = [[1, 3, 4, 2], [5, 6, 8, 7], [1, 2, 6, 5], [3, 7, 8, 4], [1, 5, 7, 3], [2, 4, 8, 6]]
        else:
            cv, cf = read_obj(os.path.join(os.path.dirname(scene_path), c["path"]))
        base = len(v)
        v += [tuple(p) for p in cv]
        f += [[i + base for i in face] for face in cf]
    with open(out, "w") as o:
        o.writelines(f"v {p[0]} {p[1]} {p[2]}\n" for p in v)
        o.writelines("f " + " ".join(map(str, face)) + "\n" for face in f)


if __name__ == "__main__":
    main()
