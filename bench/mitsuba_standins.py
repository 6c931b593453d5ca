"""Stand-in assets for Mitsuba scene files whose meshes and images are not at hand: for
every scene file below FOLDER, each file it names (`<string name="filename">`, in it or in
a file it includes) that no folder Mitsuba would search holds is written, generated here,
where Mitsuba looks first (the scene's latest `<path>` folder, else the scene's folder):

- OBJ: a UV sphere of radius 1 (names with "sphere"; with "base", one of radius 0.5 at
  y = -1.2, so that a scene's sphere and its base do not coincide), the rectangle
  [-1, 1]^2 at z = 0 facing +z ("rectangle", "background" the same, 10 times larger), a
  cube of side 1 ("cube"), a torus ("torus"); any other name (a scene of many meshes,
  such as Bitterli's Mesh000.obj ...) a sphere of radius 0.5 centred where the name's
  CRC-32 puts it in [-1.2, 1.2]^3, so that no two such meshes coincide (which would leave
  each renderer's choice between their materials to rounding); each with normals and uv;
- ASCII PLY: the rectangle with normals and uv ("rectangle"), a sphere with a colour per
  vertex, one per face and a weight per face ("attribute"), any other name the placed
  sphere of an OBJ;
  `.serialized`: 8 shapes (for any `shape_index`), each the rectangle ("rectangle") or
  a placed sphere (positions; each shape placed by the name and its index);
- PNG/JPG/BMP: a 64 x 64 pattern of colour gradients and checks (names with "normalmap": a
  wave normal map; with "mask": a soft-edged disk pattern in grey);
- EXR/HDR/PFM: a 64 x 32 equirectangular sky, a gradient with a small bright sun;
- VOL (Mitsuba's grid): 16^3 voxels of a soft ball of density with ripples in it, one
  float32 channel (names with "albedo": three channels of colours in [0.2, 0.9]).

Both renderers then read the same stand-ins, so the comparison still judges how each
reads the scene file; the stand-ins written are listed, and a report made from these
scenes says the assets are stand-ins. Other kinds are left missing (the scene is refused by
the renderer that needs them, with its message).

usage: python bench/mitsuba_standins.py FOLDER   (Mitsuba 3's Python package writes the
images: `pip install mitsuba==3.9.1 numpy`)
"""
import glob
import math
import os
import re
import struct
import sys
import zlib

import mitsuba as mi
import numpy as np

from mitsuba_assets import serialized

mi.set_variant("scalar_rgb")


def sphere_obj(radius=1.0, centre=(0.0, 0.0, 0.0)):
    lines, rings, segs = [], 24, 48
    for i in range(rings + 1):
        th = math.pi * i / rings
        for j in range(segs + 1):
            ph = 2 * math.pi * j / segs
            x, y, z = math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)
            p = [radius * a + c for a, c in zip((x, y, z), centre)]
            lines += [f"v {p[0]:.6f} {p[1]:.6f} {p[2]:.6f}", f"vn {x:.6f} {y:.6f} {z:.6f}", f"vt {j / segs:.6f} {1 - i / rings:.6f}"]
    return "\n".join(lines + grid_faces(rings, segs)) + "\n"


def grid_faces(rows, cols):
    """The OBJ faces of a (rows + 1) x (cols + 1) grid of vertices (each with its normal
    and uv of the same index), two triangles a cell."""
    faces = []
    for i in range(rows):
        for j in range(cols):
            a, b = i * (cols + 1) + j + 1, (i + 1) * (cols + 1) + j + 1
            for t in ((a, b, b + 1), (a, b + 1, a + 1)):
                faces.append("f " + " ".join(f"{k}/{k}/{k}" for k in t))
    return faces


def quad_obj(s=1.0):
    return (f"v {-s} {-s} 0\nv {s} {-s} 0\nv {s} {s} 0\nv {-s} {s} 0\n"
            "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n"
            "f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n")


def cube_obj():
    out, n = [], 0
    for axis in range(3):
        for sign in (-1, 1):
            u, v = (axis + 1) % 3, (axis + 2) % 3
            corners = []
            for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = [0.0, 0.0, 0.0]
                p[axis], p[u], p[v] = 0.5 * sign, 0.5 * a * sign, 0.5 * b
                corners.append(p)
            nrm = [0, 0, 0]
            nrm[axis] = sign
            for p, t in zip(corners, ("0 0", "1 0", "1 1", "0 1")):
                out += [f"v {p[0]} {p[1]} {p[2]}", f"vt {t}"]
            out.append(f"vn {nrm[0]} {nrm[1]} {nrm[2]}")
            k = len([l for l in out if l.startswith("vn")])
            out += [f"f {n + 1}/{n + 1}/{k} {n + 2}/{n + 2}/{k} {n + 3}/{n + 3}/{k}",
                    f"f {n + 1}/{n + 1}/{k} {n + 3}/{n + 3}/{k} {n + 4}/{n + 4}/{k}"]
            n += 4
    return "\n".join(out) + "\n"


def torus_obj(R=1.0, r=0.3):
    lines, nu, nv = [], 48, 16
    for i in range(nu + 1):
        a = 2 * math.pi * i / nu
        for j in range(nv + 1):
            b = 2 * math.pi * j / nv
            c = [math.cos(a) * math.cos(b), math.sin(a) * math.cos(b), math.sin(b)]
            p = [R * math.cos(a) + r * c[0], R * math.sin(a) + r * c[1], r * c[2]]
            lines += [f"v {p[0]:.6f} {p[1]:.6f} {p[2]:.6f}", f"vn {c[0]:.6f} {c[1]:.6f} {c[2]:.6f}",
                      f"vt {i / nu:.6f} {j / nv:.6f}"]
    return "\n".join(lines + grid_faces(nu, nv)) + "\n"


def quad_ply():
    return ("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
            "property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n"
            "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
            "-1 -1 0 0 0 1 0 0\n1 -1 0 0 0 1 1 0\n1 1 0 0 0 1 1 1\n-1 1 0 0 0 1 0 1\n3 0 1 2\n3 0 2 3\n")


def attribute_sphere_ply():
    """A UV sphere of radius 1 as ASCII PLY with the attributes `vertex_color`,
    `face_color` and `face_weight`, named as Mitsuba's `Mesh.write_ply` names them (float
    `color_0`, `color_1`, `color_2` per vertex and per face, and `weight_0` per face, after
    the face's indices; triangles only, none degenerate: one vertex at each pole)."""
    rings, segs = 12, 24
    points = [(0.0, 0.0, 1.0)]
    for i in range(1, rings):
        th = math.pi * i / rings
        points += [(math.sin(th) * math.cos(2 * math.pi * j / segs), math.sin(th) * math.sin(2 * math.pi * j / segs),
                    math.cos(th)) for j in range(segs)]
    points.append((0.0, 0.0, -1.0))
    ring = lambda i, j: 1 + (i - 1) * segs + j % segs
    tris = [(0, ring(1, j), ring(1, j + 1)) for j in range(segs)]
    for i in range(1, rings - 1):
        for j in range(segs):
            a, b, c, d = ring(i, j), ring(i + 1, j), ring(i + 1, j + 1), ring(i, j + 1)
            tris += [(a, b, c), (a, c, d)]
    tris += [(ring(rings - 1, j), len(points) - 1, ring(rings - 1, j + 1)) for j in range(segs)]
    verts = ["%.6f %.6f %.6f %.6f %.6f %.6f" % (p + tuple(0.5 + 0.5 * a for a in p)) for p in points]
    faces = ["3 %d %d %d %.4f %.4f %.4f %.4f" % (t + ((n * 7) % 5 / 4, (n * 3) % 4 / 3, n % 2, (n * 5) % 7 / 6))
             for n, t in enumerate(tris)]
    color = ["property float color_0", "property float color_1", "property float color_2"]
    head = ["ply", "format ascii 1.0", f"element vertex {len(verts)}",
            "property float x", "property float y", "property float z", *color,
            f"element face {len(faces)}", "property list uchar int vertex_indices", *color,
            "property float weight_0", "end_header"]
    return "\n".join(head + verts + faces) + "\n"


def pattern(name):
    y, x = np.mgrid[0:64, 0:64] / 63.0
    if "normalmap" in name:
        t = 0.35 * np.sin(2 * math.pi * 3 * x)
        n = np.stack([-t, np.zeros_like(t), np.ones_like(t)], -1)
        n /= np.linalg.norm(n, axis=-1, keepdims=True)
        return (0.5 * n + 0.5).astype(np.float32)
    if "mask" in name:
        d = np.hypot((x * 4) % 1 - 0.5, (y * 4) % 1 - 0.5)
        g = np.clip((0.4 - d) * 10, 0, 1)
        return np.repeat(g[..., None], 3, -1).astype(np.float32)
    check = ((np.floor(x * 8) + np.floor(y * 8)) % 2)[..., None]
    rgb = np.stack([0.2 + 0.7 * x, 0.2 + 0.6 * y, 0.9 - 0.7 * x * y], -1)
    return (rgb * (0.55 + 0.45 * check)).astype(np.float32)


def bmp_bytes(rgb):
    """A 24-bit BMP of 8-bit RGB rows (top row first)."""
    h, w, _ = rgb.shape
    row = (3 * w + 3) // 4 * 4
    body = b"".join(rgb[y, :, ::-1].tobytes().ljust(row, b"\0") for y in range(h - 1, -1, -1))
    return (b"BM" + struct.pack("<IHHI", 54 + len(body), 0, 0, 54)
            + struct.pack("<IiiHHIIiiII", 40, w, h, 1, 24, 0, len(body), 2835, 2835, 0, 0) + body)


def sky():
    v, u = np.mgrid[0:32, 0:64]
    th = (v + 0.5) / 32 * math.pi
    ph = (u + 0.5) / 64 * 2 * math.pi
    up = np.cos(th)[..., None]
    img = np.where(up > 0, 0.3 + 0.7 * up * np.array([0.5, 0.7, 1.0]), 0.2 * np.array([0.6, 0.5, 0.4]))
    d = np.hypot(th - 0.8, np.minimum(abs(ph - 2.0), 2 * math.pi - abs(ph - 2.0)))
    img = img + (d < 0.15)[..., None] * np.array([40.0, 36.0, 30.0])
    return img.astype(np.float32)


def placed(name):
    """The centre of a stand-in named `name` that is neither a sphere nor a rectangle, cube
    or torus: each coordinate a byte of the name's CRC-32 spread over [-1.2, 1.2]."""
    h = zlib.crc32(name.encode())
    return tuple(((h >> (8 * k)) & 0xFF) / 255 * 2.4 - 1.2 for k in range(3))


def sphere_ply(radius, centre):
    """sphere_obj's sphere as ASCII PLY (positions, normals, uv; the OBJ's triangles)."""
    text = sphere_obj(radius, centre).splitlines()
    pick = lambda tag: [l.split()[1:] for l in text if l.startswith(tag + " ")]
    v, n, t, f = pick("v"), pick("vn"), pick("vt"), pick("f")
    head = ("ply\nformat ascii 1.0\n" f"element vertex {len(v)}\n"
            + "".join(f"property float {c}\n" for c in ("x", "y", "z", "nx", "ny", "nz", "u", "v"))
            + f"element face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n")
    rows = [" ".join(a + b + c) for a, b, c in zip(v, n, t)]
    faces = ["3 " + " ".join(str(int(k.split("/")[0]) - 1) for k in tri) for tri in f]
    return head + "\n".join(rows + faces) + "\n"


def vol_grid(albedo, n=16):
    """A Mitsuba .vol grid of n^3 voxels: a soft ball with ripples (one channel), or
    colours in [0.2, 0.9] (three channels)."""
    c = (np.arange(n) + 0.5) / n
    z, y, x = np.meshgrid(c, c, c, indexing="ij")
    r = np.sqrt((x - 0.5) ** 2 + (y - 0.5) ** 2 + (z - 0.5) ** 2)
    ball = np.clip(1.0 - 2.0 * r, 0.0, 1.0) * (0.75 + 0.25 * np.sin(9 * x) * np.cos(7 * y + 2 * z))
    if albedo:
        data = np.stack([0.2 + 0.7 * x, 0.2 + 0.7 * y, 0.9 - 0.7 * z], axis=-1)
    else:
        data = ball[..., None]
    head = b"VOL" + bytes([3]) + struct.pack("<5i", 1, n, n, n, data.shape[-1]) + struct.pack("<6f", 0, 0, 0, 1, 1, 1)
    return head + data.astype("<f4").tobytes()


def write(path):
    name = os.path.basename(path).lower()
    ext = os.path.splitext(name)[1]
    os.makedirs(os.path.dirname(path), exist_ok=True)
    if ext == ".obj":
        text = (quad_obj(10.0) if "background" in name else quad_obj() if "rectangle" in name
                else cube_obj() if "cube" in name else torus_obj() if "torus" in name
                # a "base" beside a sphere of the same scene: below it, not in its place
                else sphere_obj(0.5, (0.0, -1.2, 0.0)) if "base" in name
                else sphere_obj() if "sphere" in name else sphere_obj(0.5, placed(name)))
        open(path, "w").write(text)
    elif ext == ".ply":
        open(path, "w").write(attribute_sphere_ply() if "attribute" in name else quad_ply() if "rectangle" in name
                              else sphere_ply(0.5, placed(name)))
    elif ext == ".serialized":
        def sphere(k):
            text = sphere_obj(0.5, placed(f"{name}#{k}")).splitlines()
            v = [tuple(map(float, l.split()[1:])) for l in text if l.startswith("v ")]
            f = [tuple(int(k.split("/")[0]) - 1 for k in l.split()[1:]) for l in text if l.startswith("f ")]
            return (v, f)
        if "rectangle" in name:
            meshes = [([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], [(0, 1, 2), (0, 2, 3)])] * 8
        else:
            meshes = [sphere(k) for k in range(8)]
        # as many shapes as a file's shape_index may name
        open(path, "wb").write(serialized(meshes))
    elif ext in (".png", ".jpg", ".jpeg", ".bmp"):
        img = pattern(name)
        bmp = mi.Bitmap(img).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, True)
        if ext == ".bmp":
            open(path, "wb").write(bmp_bytes(np.array(bmp)))
        else:
            bmp.write(path)
    elif ext in (".exr", ".hdr", ".pfm"):
        mi.Bitmap(sky()).write(path)
    elif ext == ".vol":
        open(path, "wb").write(vol_grid("albedo" in name))
    else:
        return False
    return True


def refs(path, seen):
    """(filename, the file naming it) of `path` and the files it includes."""
    if path in seen or not os.path.exists(path):
        return []
    seen.add(path)
    text = open(path, errors="replace").read()
    out = [(m, path) for m in re.findall(r'name="filename"\s+value="([^"$]+)"', text)]
    for inc in re.findall(r'<include\s+filename="([^"]+)"', text):
        out += refs(os.path.join(os.path.dirname(path), inc), seen)
        out += refs(os.path.join(os.path.dirname(seen_root[0]), inc), seen)
    return out


folder = os.path.abspath(sys.argv[1])
written, left = set(), set()
xmls = sorted(glob.glob(os.path.join(folder, "**", "*.xml"), recursive=True))
# files another one includes are read as part of it, not as scenes of their own
included = {os.path.normpath(os.path.join(os.path.dirname(x), inc)) for x in xmls
            for inc in re.findall(r'<include\s+filename="([^"]+)"', open(x, errors="replace").read())}
for scene in xmls:
    text = open(scene, errors="replace").read()
    if ("<sensor" not in text and "<include" not in text) or os.path.normpath(scene) in included:
        continue
    here = os.path.dirname(scene)
    paths = [os.path.normpath(os.path.join(here, p)) for p in re.findall(r'<path\s+value="([^"]+)"', text)][::-1]
    search = [p for p in paths if os.path.isdir(p)] + [here]
    seen_root = [scene]
    for name, by in refs(scene, set()):
        if os.path.isabs(name) or name.endswith(".xml"):
            continue
        # where Mitsuba's resolver looks (not beside an included file)
        if any(os.path.exists(os.path.join(d, name)) for d in search):
            continue
        target = os.path.normpath(os.path.join(search[0], name))
        if write(target):
            written.add(os.path.relpath(target, folder))
        else:
            left.add(os.path.relpath(target, folder))
print("stand-ins written:", *sorted(written), sep="\n  ")
print("left missing:", *sorted(left), sep="\n  ")
