"""The generated assets of tests/mitsuba's scenes, written with the values
tests/mitsuba_import.rs writes: generated/sky.exr, generated/pyramid.serialized,
generated/octahedron.obj, generated/waves.exr and generated/plume.vol (a copy of
scenes/volumes/plume.vol, which bench/plume_grid.py writes). Used by
bench/mitsuba_refs.py and bench/mitsuba_import_report.py."""
import math
import os
import shutil
import struct
import zlib

import numpy as np


def sky():
    """The environment image of tests/mitsuba/environment.xml (as tests/mitsuba_import.rs
    writes it): 128 x 64, a vertical gradient and a bright spot, every texel in [0, 1]."""
    w, h = 128, 64
    img = np.zeros((h, w, 3), dtype=np.float32)
    for y in range(h):
        for x in range(w):
            u, v = (x + 0.5) / w, (y + 0.5) / h
            spot = math.exp(-((u - 0.3) ** 2 + (v - 0.3) ** 2) / 0.005)
            img[y, x] = [0.1 + 0.5 * (1 - v) + 0.35 * spot, 0.1 + 0.45 * (1 - v) + 0.3 * spot,
                         0.15 + 0.6 * (1 - v) + 0.2 * spot]
    return img


def texels():
    """The environment image of tests/mitsuba/envmap-texels.xml (as tests/mitsuba_import.rs
    writes it): 16 x 8 texels, checkered 1 and 0.1 times a colour that changes along each
    row and down each column."""
    img = np.zeros((8, 16, 3), np.float32)
    for j in range(8):
        for i in range(16):
            k = 1.0 if (i + j) % 2 == 0 else 0.1
            img[j, i] = [k * (0.5 + i / 30), k * (0.5 + j / 14), k]
    return img


def waves():
    """The normal map of tests/mitsuba/normalmap.xml (as tests/mitsuba_import.rs writes
    it): 64 x 64, the normals of a height 0.015 sin(2 pi 3 u) sin(2 pi 2 v) as colours
    (n + 1) / 2."""
    w = h = 64
    img = np.zeros((h, w, 3), dtype=np.float32)
    for y in range(h):
        for x in range(w):
            u, v = (x + 0.5) / w, (y + 0.5) / h
            du = 0.015 * 2 * math.pi * 3 * math.cos(2 * math.pi * 3 * u) * math.sin(2 * math.pi * 2 * v)
            dv = 0.015 * 2 * math.pi * 2 * math.sin(2 * math.pi * 3 * u) * math.cos(2 * math.pi * 2 * v)
            n = np.array([-du, -dv, 1.0])
            n /= np.linalg.norm(n)
            img[y, x] = (n + 1) / 2
    return img


def serialized(meshes):
    """A version 4 .serialized file (as wgtrace's mesh::write_serialized writes it): each
    mesh positions, triangles and optionally uvs (v as stored)."""
    out, offsets = b"", []
    for positions, triangles, *uvs in meshes:
        uvs = uvs[0] if uvs else []
        offsets.append(len(out))
        flags = 0x1000 | (0x0002 if uvs else 0)
        raw = struct.pack("<I", flags) + b"mesh\0" + struct.pack("<QQ", len(positions), len(triangles))
        raw += b"".join(struct.pack("<3f", *p) for p in positions)
        raw += b"".join(struct.pack("<2f", *uv) for uv in uvs)
        raw += b"".join(struct.pack("<3I", *t) for t in triangles)
        out += struct.pack("<HH", 0x041C, 4) + zlib.compress(raw)
    return out + b"".join(struct.pack("<Q", o) for o in offsets) + struct.pack("<I", len(meshes))


# mesh 0 a decoy triangle, mesh 1 a square pyramid (base 0.8 at y = 0, apex at 0.9)
PYRAMID = [
    ([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [(0, 1, 2)]),
    ([(-0.4, 0, -0.4), (0.4, 0, -0.4), (0.4, 0, 0.4), (-0.4, 0, 0.4), (0, 0.9, 0)],
     [(0, 1, 2), (0, 2, 3), (0, 4, 1), (1, 4, 2), (2, 4, 3), (3, 4, 0)]),
]


# the quads of mesh-uvs.xml, [-1, 1]^2 at z = 0: mesh 0 without uvs, wound toward -z; mesh
# 1 with uvs ((x + 1) / 2, (y + 1) / 2), wound toward +z
QUAD = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]
QUADS = [
    (QUAD, [(0, 2, 1), (0, 3, 2)]),
    (QUAD, [(0, 1, 2), (0, 2, 3)], [(0, 0), (1, 0), (1, 1), (0, 1)]),
]
# the PLY quad of mesh-uvs.xml: the same square with normals +z and the same uvs
QUAD_PLY = ("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
            "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
            "property float u\nproperty float v\nelement face 2\n"
            "property list uchar int vertex_indices\nend_header\n"
            "-1 -1 0 0 0 1 0 0\n1 -1 0 0 0 1 1 0\n1 1 0 0 0 1 1 1\n-1 1 0 0 0 1 0 1\n"
            "3 0 1 2\n3 0 2 3\n")

# the PLY octahedron of mesh-attributes.xml: Mitsuba's write_ply names (colour per vertex,
# colour and weight per face)
ATTRIBUTES_PLY = ('ply\n'
                  'format ascii 1.0\n'
                  'element vertex 6\n'
                  'property float x\n'
                  'property float y\n'
                  'property float z\n'
                  'property float color_0\n'
                  'property float color_1\n'
                  'property float color_2\n'
                  'element face 8\n'
                  'property list uchar int vertex_indices\n'
                  'property float color_0\n'
                  'property float color_1\n'
                  'property float color_2\n'
                  'property float weight_0\n'
                  'end_header\n'
                  '1 0 0 0.9 0.2 0.1\n'
                  '-1 0 0 0.1 0.8 0.2\n'
                  '0 1 0 0.2 0.3 0.9\n'
                  '0 -1 0 0.9 0.9 0.1\n'
                  '0 0 1 0.5 0.5 0.5\n'
                  '0 0 -1 0.1 0.1 0.1\n'
                  '3 0 2 4 0.8 0.1 0.1 0\n'
                  '3 2 1 4 0.1 0.7 0.1 0.25\n'
                  '3 1 3 4 0.1 0.2 0.8 0.5\n'
                  '3 3 0 4 0.7 0.7 0.1 0.75\n'
                  '3 2 0 5 0.1 0.6 0.6 1\n'
                  '3 1 2 5 0.6 0.1 0.6 0.1\n'
                  '3 3 1 5 0.9 0.5 0.2 0.6\n'
                  '3 0 3 5 0.3 0.3 0.3 0.9\n')


def write_assets(folder, write_exr):
    """Writes the assets under folder/generated; write_exr(path, float32 array) writes EXR."""
    os.makedirs(os.path.join(folder, "generated"), exist_ok=True)
    write_exr(os.path.join(folder, "generated", "sky.exr"), sky())
    write_exr(os.path.join(folder, "generated", "waves.exr"), waves())
    write_exr(os.path.join(folder, "generated", "texels.exr"), texels())
    with open(os.path.join(folder, "generated", "pyramid.serialized"), "wb") as f:
        f.write(serialized(PYRAMID))
    with open(os.path.join(folder, "generated", "quads.serialized"), "wb") as f:
        f.write(serialized(QUADS))
    with open(os.path.join(folder, "generated", "quad.ply"), "w") as f:
        f.write(QUAD_PLY)
    with open(os.path.join(folder, "generated", "attributes.ply"), "w") as f:
        f.write(ATTRIBUTES_PLY)
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    shutil.copy(os.path.join(root, "scenes", "volumes", "plume.vol"), os.path.join(folder, "generated", "plume.vol"))
    with open(os.path.join(folder, "generated", "octahedron.obj"), "w") as f:
        f.write("v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n")
        f.write("vn 1 0 0\nvn -1 0 0\nvn 0 1 0\nvn 0 -1 0\nvn 0 0 1\nvn 0 0 -1\n")
        for a, b, c in [(1, 3, 5), (3, 2, 5), (2, 4, 5), (4, 1, 5), (3, 1, 6), (2, 3, 6), (4, 2, 6), (1, 4, 6)]:
            f.write(f"f {a}//{a} {b}//{b} {c}//{c}\n")
