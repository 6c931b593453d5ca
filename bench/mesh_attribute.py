"""Writes the meshes of bench/mesh-attribute.toml and bench/mesh-attribute.xml into
bench/generated/: vertex-colours.ply, a 6 x 6 grid of quads (two triangles each) (a 1.6 x 1.6 square in
z = 0 facing +z) whose vertex colours are 0 or 1 per channel, floats (values every renderer
reads alike, whether it decodes them from sRGB or not; Mitsuba 3 takes integer colours as
they are, 0 to 255), and face-colours.ply, the same grid
with a colour per face instead. Plain Python.

usage: python3 bench/mesh_attribute.py
"""
import os

root = os.path.dirname(os.path.abspath(__file__))
n = 6
verts = [(-0.8 + 1.6 * i / n, -0.8 + 1.6 * j / n) for j in range(n + 1) for i in range(n + 1)]
quads = [(j * (n + 1) + i, j * (n + 1) + i + 1, (j + 1) * (n + 1) + i + 1, (j + 1) * (n + 1) + i)
         for j in range(n) for i in range(n)]


def colour(k):
    return tuple((k >> b) & 1 for b in range(3))


def write(name, vertex_colours):
    lines = ["ply", "format ascii 1.0", f"element vertex {len(verts)}",
             "property float x", "property float y", "property float z"]
    if vertex_colours:
        lines += ["property float red", "property float green", "property float blue"]
    lines.append(f"element face {2 * len(quads)}")
    # the face's colour before its indices (Mitsuba 3's reader wants them so)
    if not vertex_colours:
        lines += ["property float red", "property float green", "property float blue"]
    lines.append("property list uchar int vertex_indices")
    lines.append("end_header")
    for k, (x, y) in enumerate(verts):
        c = " %d %d %d" % colour(k * 5 + 1) if vertex_colours else ""
        lines.append(f"{x:.6f} {y:.6f} 0{c}")
    # each quad as two triangles of its colour (Mitsuba 3's reader takes triangles only)
    for k, (a, b, c_, d) in enumerate(quads):
        c = "" if vertex_colours else "%d %d %d " % colour(k * 3 + 2)
        lines.append("%s3 %d %d %d" % (c, a, b, c_))
        lines.append("%s3 %d %d %d" % (c, a, c_, d))
    os.makedirs(os.path.join(root, "generated"), exist_ok=True)
    path = os.path.join(root, "generated", name)
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    print(path)


write("vertex-colours.ply", True)
write("face-colours.ply", False)
