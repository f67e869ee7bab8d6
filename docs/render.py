#!/usr/bin/env python3
"""Render OBJ meshes side by side into one PNG (used for the pictures in the README).

Each mesh becomes one panel, flat shaded (Lambert, fixed light) by a small numpy z-buffer
rasterizer with supersampling. Every panel uses the same orthographic camera and the same scale,
so a deformed mesh can be compared directly with its rest shape in the first panel.

    python3 docs/render.py --out docs/images/bunny-springs.png --view 0.15,0.2,1 --ghost \\
        --title "rest" data/stanford-bunny.obj --title "deformed" /tmp/bunny-springs.obj

Options:
  --view X,Y,Z          direction from the model towards the camera (0,0,1 shows the +z side)
  --up X,Y,Z            world "up" direction on screen (default 0,1,0)
  --title TEXT          caption; the k-th --title goes with the k-th mesh (default: file name)
  --highlight-box B     xmin,ymin,zmin,xmax,ymax,zmax in the FIRST mesh's coordinates; those
                        vertices are coloured in every panel (matched by vertex index, so all
                        meshes must share the vertex order). May be given several times.
                        Write --highlight-box=-1,... (with "=") when the value starts with "-".
  --ghost               draw the first mesh's silhouette faintly behind the other panels
  --size W,H            output size in pixels (default 1200,500)
  --ssaa N              supersampling factor per axis (default 3)
  --colors N            palette size of the PNG (default 256, keeps files small; 0 = full RGB)

Only numpy and matplotlib are needed (`pip install numpy matplotlib`; the PNG is written with
Pillow, which matplotlib installs). OBJ support: `v` and `f` lines (polygons are split into
fans; `v/vt/vn` and negative indices are accepted); everything else is ignored.
"""

import argparse
import os
import sys

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

BASE_COLOR = np.array([0.70, 0.78, 0.90])  # light grey-blue
HIGHLIGHT_COLORS = [
    np.array([0.95, 0.55, 0.20]),  # orange
    np.array([0.35, 0.75, 0.40]),  # green
    np.array([0.85, 0.35, 0.45]),  # red
    np.array([0.65, 0.50, 0.85]),  # purple
]
GHOST_FILL = np.array([0.92, 0.92, 0.92])  # rest silhouette behind deformed panels (--ghost)
GHOST_LINE = np.array([0.62, 0.62, 0.62])
# Light direction in camera space (x right, y up, z towards the viewer): upper left, in front.
LIGHT_CAM = np.array([-0.45, 0.6, 1.0])
AMBIENT = 0.28


def load_obj_polygons(path):
    """Return (vertices (n,3) float, faces: lists of 0-based corner indices) from an OBJ file."""
    verts, faces = [], []
    with open(path) as fh:
        for line in fh:
            if line.startswith("v "):
                verts.append([float(t) for t in line.split()[1:4]])
            elif line.startswith("f "):
                idx = []
                for tok in line.split()[1:]:
                    i = int(tok.split("/")[0])
                    idx.append(i - 1 if i > 0 else len(verts) + i)
                faces.append(idx)
    return np.asarray(verts, dtype=np.float64), faces


def load_obj(path):
    """Return (vertices (n,3) float, triangles (m,3) int) from an OBJ file (polygons as fans)."""
    verts, faces = load_obj_polygons(path)
    tris = [(f[0], f[k], f[k + 1]) for f in faces for k in range(1, len(f) - 1)]
    if not len(verts) or not tris:
        sys.exit(f"render.py: {path}: no vertices or faces")
    return verts, np.asarray(tris, dtype=np.int64)


def camera_basis(view, up):
    """Orthonormal (right, up, back) rows; `back` points from the model to the camera."""
    back = view / np.linalg.norm(view)
    right = np.cross(up, back)
    if np.linalg.norm(right) < 1e-9:
        sys.exit("render.py: --view is parallel to --up")
    right /= np.linalg.norm(right)
    return np.stack([right, np.cross(back, right), back])


def rasterize(sx, sy, depth, tris, width, height):
    """Z-buffer rasterization of triangles given in pixel coordinates.

    sx, sy: per-vertex pixel coordinates (pixel centres at integer + 0.5, y downwards);
    depth: per-vertex depth, larger = closer to the camera.
    Returns (face id per pixel or -1, barycentric coordinates (h, w, 3)).
    """
    x = sx[tris]
    y = sy[tris]
    z = depth[tris]
    # Signed area; drop degenerate triangles. Both orientations are rasterized (two-sided).
    area = (x[:, 1] - x[:, 0]) * (y[:, 2] - y[:, 0]) - (x[:, 2] - x[:, 0]) * (y[:, 1] - y[:, 0])
    x0 = np.clip(np.floor(x.min(1) - 0.5).astype(np.int64) + 1, 0, width)
    x1 = np.clip(np.floor(x.max(1) - 0.5).astype(np.int64), -1, width - 1)
    y0 = np.clip(np.floor(y.min(1) - 0.5).astype(np.int64) + 1, 0, height)
    y1 = np.clip(np.floor(y.max(1) - 0.5).astype(np.int64), -1, height - 1)
    ext = np.maximum(x1 - x0, y1 - y0) + 1  # bounding box side in pixels (<= 0: covers none)
    keep = (np.abs(area) > 1e-12) & (ext > 0)

    best_z = np.full(width * height, -np.inf)
    best_f = np.full(width * height, -1, dtype=np.int64)
    best_b = np.zeros((width * height, 3))

    # Group triangles by bounding-box size (powers of two) and test all pixels of each box at once.
    order = np.nonzero(keep)[0]
    bucket = np.ceil(np.log2(np.maximum(ext[order], 1))).astype(np.int64)
    for b in np.unique(bucket):
        k = 1 << int(b)
        faces = order[bucket == b]
        oy, ox = np.mgrid[0:k, 0:k]
        ox = ox.ravel()
        oy = oy.ravel()
        chunk = max(1, 4_000_000 // (k * k))
        for s in range(0, len(faces), chunk):
            f = faces[s : s + chunk]
            px = x0[f, None] + ox[None, :]
            py = y0[f, None] + oy[None, :]
            inside = (px <= x1[f, None]) & (py <= y1[f, None])
            cx = px + 0.5
            cy = py + 0.5
            xf, yf, a = x[f], y[f], area[f, None]
            # Barycentric coordinates of the pixel centres.
            w0 = ((xf[:, 1, None] - cx) * (yf[:, 2, None] - cy) - (xf[:, 2, None] - cx) * (yf[:, 1, None] - cy)) / a
            w1 = ((xf[:, 2, None] - cx) * (yf[:, 0, None] - cy) - (xf[:, 0, None] - cx) * (yf[:, 2, None] - cy)) / a
            w2 = 1.0 - w0 - w1
            eps = -1e-9
            inside &= (w0 >= eps) & (w1 >= eps) & (w2 >= eps)
            ti, pi = np.nonzero(inside)
            if len(ti) == 0:
                continue
            bary = np.stack([w0[ti, pi], w1[ti, pi], w2[ti, pi]], axis=1)
            fz = (bary * z[f[ti]]).sum(1)
            pix = py[ti, pi] * width + px[ti, pi]
            # Closest fragment per pixel within this batch, then merge with the z-buffer.
            srt = np.lexsort((-fz, pix))
            pix, fz, bary, ff = pix[srt], fz[srt], bary[srt], f[ti[srt]]
            first = np.ones(len(pix), dtype=bool)
            first[1:] = pix[1:] != pix[:-1]
            pix, fz, bary, ff = pix[first], fz[first], bary[first], ff[first]
            win = fz > best_z[pix]
            pix = pix[win]
            best_z[pix] = fz[win]
            best_f[pix] = ff[win]
            best_b[pix] = bary[win]
    return best_f.reshape(height, width), best_b.reshape(height, width, 3)


def shade(verts, tris, basis, face_id, bary, vertex_colors):
    """RGB image (h, w, 3) in [0, 1] with a white background, plus the coverage mask."""
    v = verts[tris]
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
    light = basis.T @ (LIGHT_CAM / np.linalg.norm(LIGHT_CAM))  # camera -> world
    view = basis[2]
    # Two-sided: flip normals that face away from the camera (open meshes, holes).
    n *= np.where((n @ view) < 0, -1.0, 1.0)[:, None]
    lam = AMBIENT + (1.0 - AMBIENT) * np.clip(n @ light, 0.0, 1.0)

    mask = face_id >= 0
    img = np.ones(face_id.shape + (3,))
    f = face_id[mask]
    col = (bary[mask][:, :, None] * vertex_colors[tris[f]]).sum(1)
    img[mask] = col * lam[f, None]
    return img, mask


def outline(mask, width):
    """Pixels of `mask` within `width` pixels of its boundary."""
    inner = mask.copy()
    for _ in range(width):
        eroded = inner.copy()
        eroded[1:] &= inner[:-1]
        eroded[:-1] &= inner[1:]
        eroded[:, 1:] &= inner[:, :-1]
        eroded[:, :-1] &= inner[:, 1:]
        inner = eroded
    return mask & ~inner


def downsample(img, s):
    h, w = img.shape[0] // s, img.shape[1] // s
    return img[: h * s, : w * s].reshape(h, s, w, s, -1).mean(axis=(1, 3))


def save_png(path, rgb, colors):
    """Write an 8-bit RGB array as PNG; with colors > 0 as an optimized palette image."""
    from PIL import Image  # Pillow is a dependency of matplotlib

    img = Image.fromarray(rgb)
    if colors > 0:
        img = img.quantize(colors=colors, method=Image.Quantize.MEDIANCUT,
                           dither=Image.Dither.FLOYDSTEINBERG)
    img.save(path, optimize=True)


def parse_vec(text, n, what):
    try:
        vals = [float(t) for t in text.split(",")]
    except ValueError:
        vals = []
    if len(vals) != n:
        sys.exit(f"render.py: {what} expects {n} comma-separated numbers, got {text!r}")
    return np.array(vals)


def main():
    ap = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument("--out", required=True, help="output PNG path")
    ap.add_argument("--view", default="0,0,1", help="direction from the model to the camera")
    ap.add_argument("--up", default="0,1,0", help="world up direction (default 0,1,0)")
    ap.add_argument("--size", default="1200,500", help="output width,height in pixels")
    ap.add_argument("--ssaa", type=int, default=3, help="supersampling factor (default 3)")
    ap.add_argument("--colors", type=int, default=256,
                    help="palette size of the PNG, 0 for full RGB (default 256: smaller files)")
    ap.add_argument("--margin", type=float, default=0.06, help="blank border, fraction of a panel")
    ap.add_argument("--highlight-box", action="append", default=[], metavar="BOX",
                    help="xmin,ymin,zmin,xmax,ymax,zmax in the first mesh's coordinates")
    ap.add_argument("--ghost", action="store_true",
                    help="show the first mesh's silhouette faintly behind the other panels")
    ap.add_argument("--title", action="append", default=[], help="caption; the k-th --title goes with the k-th mesh")
    ap.add_argument("meshes", nargs="+", help="OBJ files, one per panel")

    # The k-th --title captions the k-th mesh (options and files may be interleaved).
    args = ap.parse_intermixed_args()
    if len(args.title) > len(args.meshes):
        sys.exit("render.py: more --title options than meshes")
    titles = args.title + [os.path.basename(m) for m in args.meshes[len(args.title):]]

    width, height = (int(t) for t in parse_vec(args.size, 2, "--size"))
    basis = camera_basis(parse_vec(args.view, 3, "--view"), parse_vec(args.up, 3, "--up"))
    meshes = [load_obj(p) for p in args.meshes]
    nv = len(meshes[0][0])
    for p, (v, _) in zip(args.meshes, meshes):
        if args.highlight_box and len(v) != nv:
            sys.exit(f"render.py: {p}: vertex count differs from the first mesh (needed for --highlight-box)")

    # Per-vertex colours from the highlight boxes (taken on the first, i.e. rest, mesh).
    vcol = np.tile(BASE_COLOR, (nv, 1))
    for k, text in enumerate(args.highlight_box):
        b = parse_vec(text, 6, "--highlight-box")
        sel = np.all((meshes[0][0] >= b[:3]) & (meshes[0][0] <= b[3:]), axis=1)
        vcol[sel] = HIGHLIGHT_COLORS[k % len(HIGHLIGHT_COLORS)]

    # One camera for all panels: fit the union of all projected meshes into a panel.
    n = len(meshes)
    s = max(1, args.ssaa)
    caption_h = 0.09  # fraction of the figure height reserved for captions
    pw, ph = (width // n) * s, int(height * (1 - caption_h)) * s
    proj = [v @ basis.T for v, _ in meshes]
    lo = np.min([p.min(0) for p in proj], axis=0)
    hi = np.max([p.max(0) for p in proj], axis=0)
    usable = 1 - 2 * args.margin
    scale = min(usable * pw / (hi[0] - lo[0]), usable * ph / (hi[1] - lo[1]))
    cx, cy = (lo[:2] + hi[:2]) / 2

    panels, ghost = [], None
    for (verts, tris), p in zip(meshes, proj):
        sx = (p[:, 0] - cx) * scale + pw / 2
        sy = ph / 2 - (p[:, 1] - cy) * scale
        fid, bary = rasterize(sx, sy, p[:, 2], tris, pw, ph)
        cols = vcol if len(verts) == nv else np.tile(BASE_COLOR, (len(verts), 1))
        img, mask = shade(verts, tris, basis, fid, bary, cols)
        if ghost is None:
            ghost, ghost_edge = mask, outline(mask, s)
        elif args.ghost:
            img[ghost & ~mask] = GHOST_FILL
            img[ghost_edge & ~mask] = GHOST_LINE
        panels.append(downsample(img, s))

    dpi = 100
    fig = plt.figure(figsize=(width / dpi, height / dpi), dpi=dpi, facecolor="white")
    for k, (img, title) in enumerate(zip(panels, titles)):
        ax = fig.add_axes([k / n, caption_h, 1 / n, 1 - caption_h])
        ax.imshow(np.clip(img, 0, 1), interpolation="antialiased")
        ax.set_axis_off()
        fig.text((k + 0.5) / n, caption_h * 0.5, title, ha="center", va="center", fontsize=15,
                 color="#333333")
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    fig.canvas.draw()
    rgb = np.asarray(fig.canvas.buffer_rgba())[:, :, :3].copy()
    plt.close(fig)
    save_png(args.out, rgb, args.colors)
    print(f"wrote {args.out} ({os.path.getsize(args.out) // 1024} KB)")


if __name__ == "__main__":
    main()
