#!/usr/bin/env python3
"""Writes the seed corpus fuzz/corpus/<target>/ (small valid files, the binary ones packed here).

Run from anywhere: python3 fuzz/make-corpus.py. Files it does not write (regression seeds from
findings, named regress-*) are left alone; its own seeds are rewritten. Python 3.11+, standard
library only.
"""

import json
import struct
import tomllib
from pathlib import Path

FUZZ = Path(__file__).resolve().parent
CORPUS = FUZZ / "corpus"
EXAMPLES = FUZZ.parent / "examples"

# The unit cube: 8 vertices, 6 outward quads (0-based), and 5 tetrahedra (oriented below).
CUBE = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
QUADS = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
TETS = [(0, 1, 3, 4), (1, 2, 3, 6), (1, 4, 5, 6), (3, 4, 6, 7), (1, 3, 4, 6)]
# A tetrahedron: 4 vertices, 4 outward triangles.
TET_V = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
TET_F = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]


def det(t, v=CUBE):
    a, b, c, d = (v[i] for i in t)
    u, w, x = ([b[k] - a[k] for k in range(3)], [c[k] - a[k] for k in range(3)], [d[k] - a[k] for k in range(3)])
    return u[0] * (w[1] * x[2] - w[2] * x[1]) - u[1] * (w[0] * x[2] - w[2] * x[0]) + u[2] * (w[0] * x[1] - w[1] * x[0])


TETS = [t if det(t) > 0 else (t[0], t[2], t[1], t[3]) for t in TETS]


def put(target, name, data):
    folder = CORPUS / target
    folder.mkdir(parents=True, exist_ok=True)
    (folder / name).write_bytes(data.encode() if isinstance(data, str) else data)


# ------------------------------------------------------------------------------------------- OBJ
TETRA_OBJ = "# tetrahedron\n" + "".join(f"v {x} {y} {z}\n" for x, y, z in TET_V) + "".join(
    f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in TET_F
)
QUAD_OBJ = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"
TEXTURED_QUAD_OBJ = (
    "mtllib quad.mtl\no quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1 0.5\n"
    "vn 0 0 1\nusemtl paper\ns 1\nf 1/1/1 2/2/1 3/3/1 4/4/1\n"
)
CUBE_OBJ = (
    "# cube: colours, w, groups, negative and v//vn indices, a line element\r\n"
    + "".join(f"v {x} {y} {z} {x} {y} {z}\r\n" for x, y, z in CUBE)
    + "vn 0 0 -1\r\nvn 0 0 1\r\ng bottom top\r\n"
    + "f -8//1 -5//1 -6//1 -7//1\r\nf 5//2 6//2 7//2 8//2\r\ng sides\r\n"
    + "".join(f"f {' '.join(str(i + 1) for i in q)}\r\n" for q in QUADS[2:])
    + "l 1 7\r\n"
)
# A square with a square hole, joined by a bridge edge: corners 1 and 5 appear twice.
BRIDGE_OBJ = (
    "v 0 0 0\nv 3 0 0\nv 3 3 0\nv 0 3 0\nv 1 1 0\nv 1 2 0\nv 2 2 0\nv 2 1 0\n"
    "f 1 2 3 4 1 5 6 7 8 5\n"
)
put("obj", "tetrahedron.obj", TETRA_OBJ)
put("obj", "quad.obj", QUAD_OBJ)
put("obj", "textured-quad.obj", TEXTURED_QUAD_OBJ)
put("obj", "cube-crlf.obj", CUBE_OBJ)
put("obj", "bridge-hole.obj", BRIDGE_OBJ)
put("obj", "bom-continuation.obj", b"\xef\xbb\xbf" + b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 \\\n 2 3\n")
put("obj", "utf16le.obj", b"\xff\xfe" + TETRA_OBJ.encode("utf-16-le"))
put("obj", "utf16be.obj", b"\xfe\xff" + QUAD_OBJ.encode("utf-16-be"))

# ------------------------------------------------------------------------------------------- PLY
PLY_VERTEX = [
    ("float", "x"), ("float", "y"), ("float", "z"), ("double", "nx"), ("double", "ny"), ("double", "nz"),
    ("uchar", "red"), ("uchar", "green"), ("uchar", "blue"), ("float", "u"), ("float", "v"), ("short", "quality"),
]  # fmt: skip
PLY_FACES = [(0, 1, 2, 3)]
PACK = {"char": "b", "uchar": "B", "short": "h", "ushort": "H", "int": "i", "uint": "I", "float": "f", "double": "d"}


def quad_rows():
    for i, (x, y) in enumerate([(0, 0), (1, 0), (1, 1), (0, 1)]):
        yield [x, y, 0, 0, 0, 1, 255 * x, 255 * y, 128, x, y, -i]


def ply(encoding):
    header = [
        "ply", f"format {encoding} 1.0", "comment made by make-corpus.py", "obj_info a quad",
        "element vertex 4", *(f"property {t} {n}" for t, n in PLY_VERTEX),
        "element face 1", "property list uchar int vertex_indices", "property uchar flags",
        "element edge 1", "property int vertex1", "property int vertex2", "end_header",
    ]  # fmt: skip
    head = ("\n".join(header) + "\n").encode()
    if encoding == "ascii":
        body = "".join(" ".join(str(v) for v in row) + "\n" for row in quad_rows())
        body += "".join(f"{len(f)} {' '.join(map(str, f))} 7\n" for f in PLY_FACES) + "0 2\n"
        return head + body.encode()
    e = "<" if encoding == "binary_little_endian" else ">"
    body = b"".join(struct.pack(e + "".join(PACK[t] for t, _ in PLY_VERTEX), *row) for row in quad_rows())
    for f in PLY_FACES:
        body += struct.pack(e + "B" + "i" * len(f) + "B", len(f), *f, 7)
    return head + body + struct.pack(e + "ii", 0, 2)


PLY_ASCII = ply("ascii")
PLY_LE = ply("binary_little_endian")
PLY_BE = ply("binary_big_endian")
PLY_STRIPS = (
    "ply\nformat ascii 1.0\nelement vertex 5\nproperty double x\nproperty double y\nproperty double z\n"
    "element tristrips 1\nproperty list int int vertex_indices\nend_header\n"
    "0 0 0\n1 0 0\n0 1 0\n1 1 0\n2 1 0\n8 0 1 2 3 -1 1 4 3\n"
)
put("ply", "quad-ascii.ply", PLY_ASCII)
put("ply", "quad-binary-le.ply", PLY_LE)
put("ply", "quad-binary-be.ply", PLY_BE)
put("ply", "tristrips.ply", PLY_STRIPS)

# ------------------------------------------------------------------------------------------- STL
def stl_ascii(vertices, faces):
    s = "solid tetra\n"
    for f in faces:
        s += " facet normal 0 0 0\n  outer loop\n"
        s += "".join("   vertex {} {} {}\n".format(*vertices[i]) for i in f)
        s += "  endloop\n endfacet\n"
    return s + "endsolid tetra\n"


def stl_binary(vertices, faces, header=b"binary tetrahedron"):
    out = header.ljust(80, b" ") + struct.pack("<I", len(faces))
    for f in faces:
        out += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *vertices[i]) for i in f) + b"\0\0"
    return out


put("stl", "tetra-ascii.stl", stl_ascii(TET_V, TET_F))
put("stl", "tetra-binary.stl", stl_binary(TET_V, TET_F))
# A binary file whose header starts with "solid", as some exporters write it.
put("stl", "tetra-binary-solid-header.stl", stl_binary(TET_V, TET_F[:2], b"solid exported by a CAD program"))

# ------------------------------------------------------------------------------------------- OFF
CUBE_OFF = (
    "OFF\n# the unit cube\n8 6 12\n"
    + "".join(f"{x} {y} {z}\n" for x, y, z in CUBE)
    + "".join(f"4 {' '.join(map(str, q))}\n" for q in QUADS)
)
COFF = (
    "COFF\n4 1 0\n"
    + "".join(f"{x} {y} 0 {x} {y} 0.5 1\n" for x, y in [(0, 0), (1, 0), (1, 1), (0, 1)])
    + "4 0 1 2 3 255 0 0\n"
)
STNOFF = (
    "STNOFF\n3 1 3\n0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n0 1 0 0 0 1 0 1\n3 0 1 2\n"
)
put("off", "cube.off", CUBE_OFF)
put("off", "quad.coff", COFF)
put("off", "triangle.stnoff", STNOFF)
# Face indices continued over lines and the keyword glued to the counts (libigl, trimesh read both).
put("off", "multiline.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1\n 2 3\n")
put("off", "glued.off", "OFF3 1 0\n0 0 0 1 0 0 0 1 0\n3 0 1 2\n")
put("off", "utf16le.off", b"\xff\xfe" + CUBE_OFF.encode("utf-16-le"))

# ------------------------------------------------------------------------------------------- MSH
def msh22_ascii():
    s = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n3 1 \"solid\"\n$EndPhysicalNames\n"
    s += f"$Nodes\n{len(CUBE)}\n" + "".join(f"{i + 1} {x} {y} {z}\n" for i, (x, y, z) in enumerate(CUBE))
    s += f"$EndNodes\n$Elements\n{len(TETS) + 2}\n1 15 2 0 1 1\n2 2 2 0 1 1 2 3\n"
    s += "".join(f"{i + 3} 4 2 1 1 {' '.join(str(v + 1) for v in t)}\n" for i, t in enumerate(TETS))
    return s + "$EndElements\n"


def msh41_ascii(tets=True):
    s = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
    s += "$Entities\n0 0 1 1\n1 0 0 0 1 1 1 0 0\n1 0 0 0 1 1 1 0 1 1\n$EndEntities\n"
    # Sparse node tags in two blocks.
    s += "$Nodes\n2 8 10 80\n3 1 0 4\n" + "".join(f"{10 * (i + 1)}\n" for i in range(4))
    s += "".join(f"{x} {y} {z}\n" for x, y, z in CUBE[:4])
    s += "2 1 0 4\n" + "".join(f"{10 * (i + 5)}\n" for i in range(4))
    s += "".join(f"{x} {y} {z}\n" for x, y, z in CUBE[4:]) + "$EndNodes\n"
    tags = lambda t: " ".join(str(10 * (v + 1)) for v in t)  # noqa: E731
    blocks = [f"2 1 2 {len(QUADS)}\n" + "".join(f"{i + 1} {tags(q[:3])}\n" for i, q in enumerate(QUADS))]
    if tets:
        blocks.append(f"3 1 4 {len(TETS)}\n" + "".join(f"{i + 100} {tags(t)}\n" for i, t in enumerate(TETS)))
    n = len(QUADS) + (len(TETS) if tets else 0)
    s += f"$Elements\n{len(blocks)} {n} 1 {104 if tets else 6}\n" + "".join(blocks) + "$EndElements\n"
    return s


def msh41_binary():
    size_t = lambda *v: struct.pack(f"<{len(v)}Q", *v)  # noqa: E731
    ints = lambda *v: struct.pack(f"<{len(v)}i", *v)  # noqa: E731
    s = b"$MeshFormat\n4.1 1 8\n" + ints(1) + b"\n$EndMeshFormat\n"
    s += b"$Entities\n" + size_t(0, 0, 0, 1) + ints(1) + struct.pack("<6d", 0, 0, 0, 1, 1, 1) + size_t(0, 0)
    s += b"\n$EndEntities\n"
    s += b"$Nodes\n" + size_t(1, 8, 1, 8) + ints(3, 1, 0) + size_t(8) + size_t(*range(1, 9))
    s += b"".join(struct.pack("<3d", *p) for p in CUBE) + b"\n$EndNodes\n"
    s += b"$Elements\n" + size_t(1, len(TETS), 1, len(TETS)) + ints(3, 1, 4) + size_t(len(TETS))
    s += b"".join(size_t(i + 1, *(v + 1 for v in t)) for i, t in enumerate(TETS)) + b"\n$EndElements\n"
    return s


def msh22_binary():
    ints = lambda *v: struct.pack(f"<{len(v)}i", *v)  # noqa: E731
    s = b"$MeshFormat\n2.2 1 8\n" + ints(1) + b"\n$EndMeshFormat\n"
    s += b"$Nodes\n8\n" + b"".join(ints(i + 1) + struct.pack("<3d", *p) for i, p in enumerate(CUBE))
    s += b"\n$EndNodes\n$Elements\n5\n" + ints(4, len(TETS), 2)
    s += b"".join(ints(i + 1, 0, 1, *(v + 1 for v in t)) for i, t in enumerate(TETS)) + b"\n$EndElements\n"
    return s


put("msh", "cube-2.2.msh", msh22_ascii())
put("msh", "cube-4.1.msh", msh41_ascii())
put("msh", "cube-surface-4.1.msh", msh41_ascii(tets=False))
put("msh", "cube-4.1-binary.msh", msh41_binary())
put("msh", "cube-2.2-binary.msh", msh22_binary())
# Physical groups ("fixed": a face's triangles; "solid": the tetrahedra), a line element, sparse
# node tags and $Entities (4.1), and CRLF line endings (2.2): what .msh -> .msh keeps.
GROUPS_41 = (
    '$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n2 1 "fixed"\n3 2 "solid"\n$EndPhysicalNames\n'
    "$Entities\n0 1 1 1\n1 0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 1 1 0\n1 0 0 0 1 1 1 1 2 0\n$EndEntities\n"
    "$Nodes\n2 8 10 80\n3 1 0 4\n" + "".join(f"{10 * (i + 1)}\n" for i in range(4))
    + "".join(f"{x} {y} {z}\n" for x, y, z in CUBE[:4])
    + "3 1 0 4\n" + "".join(f"{10 * (i + 5)}\n" for i in range(4))
    + "".join(f"{x} {y} {z}\n" for x, y, z in CUBE[4:]) + "$EndNodes\n"
    + f"$Elements\n3 {len(TETS) + 3} 100 {100 + len(TETS) + 2}\n3 1 4 {len(TETS)}\n"
    + "".join(f"{100 + i} {' '.join(str(10 * (v + 1)) for v in t)}\n" for i, t in enumerate(TETS))
    + f"2 1 2 2\n{100 + len(TETS)} 10 40 80\n{101 + len(TETS)} 10 80 50\n"
    + f"1 1 1 1\n{102 + len(TETS)} 10 50\n$EndElements\n"
)
GROUPS_22 = (
    '$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n2 1 "fixed"\n3 2 "solid"\n$EndPhysicalNames\n'
    f"$Nodes\n{len(CUBE)}\n" + "".join(f"{10 * (i + 1)} {x} {y} {z}\n" for i, (x, y, z) in enumerate(CUBE))
    + f"$EndNodes\n$Elements\n{len(TETS) + 3}\n"
    + "".join(f"{100 + i} 4 2 2 1 {' '.join(str(10 * (v + 1)) for v in t)}\n" for i, t in enumerate(TETS))
    + "200 2 2 1 1 10 40 80\n201 2 2 1 1 10 80 50\n202 1 2 0 1 10 50\n$EndElements\n"
).replace("\n", "\r\n")
put("msh", "cube-groups-4.1.msh", GROUPS_41)
put("msh", "cube-groups-2.2-crlf.msh", GROUPS_22)

# ---------------------------------------------------------------------------------------- TetGen
# The .node file, a 0x00 byte, the .ele file.
NODE = "# cube\n8 3 1 1\n" + "".join(f"{i + 1} {x} {y} {z} 0.5 {i % 2}\n" for i, (x, y, z) in enumerate(CUBE))
ELE = "5 4 1\n" + "".join(f"{i + 1} {' '.join(str(v + 1) for v in t)} 7\n" for i, t in enumerate(TETS)) + "# end\n"
NODE0 = "4 3 0 0\n" + "".join(f"{i} {x} {y} {z}\n" for i, (x, y, z) in enumerate(TET_V))
ELE0 = "1 4 0\n0 0 1 2 3\n"
put("tetgen", "cube-1-based", NODE + "\0" + ELE)
put("tetgen", "tetra-0-based", NODE0 + "\0" + ELE0)

# ------------------------------------------------------------------------------ attribute round trip
# First byte: b % 3 picks OBJ (0), PLY (1), OFF (2); for PLY b / 3 % 4 the encoding written
# (1: the file's own, 4: ascii, 7: binary little endian, 10: binary big endian).
for name, selector, data in [
    ("textured-quad.obj", 0, TEXTURED_QUAD_OBJ),
    ("cube-crlf.obj", 0, CUBE_OBJ),
    ("bridge-hole.obj", 0, BRIDGE_OBJ),
    ("quad-ascii-own.ply", 1, PLY_ASCII),
    ("quad-ascii-to-le.ply", 7, PLY_ASCII),
    ("quad-le-to-ascii.ply", 4, PLY_LE),
    ("quad-be-to-le.ply", 7, PLY_BE),
    ("quad-le-to-be.ply", 10, PLY_LE),
    ("tristrips.ply", 1, PLY_STRIPS),
    ("cube.off", 2, CUBE_OFF),
    ("quad.coff", 2, COFF),
    ("triangle.stnoff", 2, STNOFF),
]:
    put("attribute_roundtrip", name, bytes([selector]) + (data.encode() if isinstance(data, str) else data))

# ---------------------------------------------------------------------------------------- scenes
# The example scenes, and small ones on each kind of mesh file the scene targets provide
# (mesh.obj, .ply, .off, .stl, .msh, .node next to the scene; ../data/*.obj for the examples).
SCENES = {
    "obj-selections.toml": """
[mesh]
path = "mesh.obj"
normalize = false

[solver]
iterations = 5
acceleration = "anderson"
anderson_window = 3

[[constraints]]
type = "plane"
faces = [0, 1]
weight = 2.0

[[constraints]]
type = "edge_strain"
strain_freedom = 0.1

[[constraints]]
type = "position"
name = "corner"
vertices = [0, 6]
targets = [[0.0, 0.0, 0.0], [1.5, 1.5, 1.5]]

[[constraints]]
type = "position"
sphere = { center = [1.0, 1.0, 1.0], radius = 0.2 }
rotate = { axis = [0.0, 0.0, 1.0], angle_deg = 30.0 }
translate = [0.0, 0.0, 0.5]
""",
    "ply-types.toml": """
[mesh]
path = "mesh.ply"

[solver]
factorization = "simplicial"

[[constraints]]
type = "circle"
whole_selection = true
box = { min = [-1.0, -1.0, -1.0], max = [1.0, 1.0, 0.0] }

[[constraints]]
type = "rigid"
faces = [2]

[[constraints]]
type = "floor"
height = -0.5

[[constraints]]
type = "gravity"
""",
    "off-dynamic.toml": """
[mesh]
path = "mesh.off"

[solver]
mode = "dynamic"
steps = 3
time_step = 0.01
gravity = [0.0, -9.8, 0.0]
damping = 0.1
density = 2.0

[[constraints]]
type = "hinge_bending"

[[constraints]]
type = "bending"
prevent_flips = true

[[constraints]]
type = "position"
vertices = [0]
spin = { axis = [0.0, 1.0, 0.0], deg_per_s = 90.0 }
""",
    "msh-physical.toml": """
[mesh]
path = "mesh.msh"

[[constraints]]
type = "tet_strain"
physical = "solid"

[[constraints]]
type = "position"
vertices = [0]
""",
    "msh-tets.toml": """
[mesh]
path = "mesh.msh"

[[constraints]]
type = "tet_strain"
strain_freedom = 0.2

[[constraints]]
type = "volume"
min = 0.95
max = 1.05

[[constraints]]
type = "position"
vertices = [0, 1, 2, 3]
""",
    "tetgen-stl.toml": """
[mesh]
path = "mesh.node"

[[constraints]]
type = "similarity"

[[constraints]]
type = "force"
force = [0.0, 0.0, -1.0]
vertices = [7]
""",
    "stl-output.toml": """
[mesh]
path = "mesh.stl"

[output]
path = "out.obj"
report = "report.json"

[[constraints]]
type = "laplacian_displacement"

[[constraints]]
type = "surface_closeness"
""",
    "generated-small.toml": """
[mesh]
generate = { kind = "tet_box", cells = [2, 1, 1], size = [2.0, 1.0, 1.0] }

[[constraints]]
type = "tet_strain"

[[constraints]]
type = "position"
box = { min = [-1.1, -1.0, -1.0], max = [-0.9, 1.0, 1.0] }
""",
}
# Left out: spot-drop (tetrahedralize needs TetGen, not in the fuzz build) and spot-smoothing (its
# sphere selects nothing on the stand-in mesh).
for path in sorted(p for p in EXAMPLES.glob("*.toml") if p.stem not in ("spot-drop", "spot-smoothing")):
    text = path.read_text()
    SCENES[path.name] = "\n".join(line for line in text.splitlines() if not line.startswith("#")).strip() + "\n"
for name, text in SCENES.items():
    put("scene_toml", name, text.lstrip())
    put("scene_json", name.replace(".toml", ".json"), json.dumps(tomllib.loads(text), separators=(",", ":")))
