#!/usr/bin/env python3
"""Writes scenes/volumes/plume.vol: a procedural smoke plume as a Mitsuba .vol density
grid (one float32 channel), the grid of the gallery's smoke scene and of the Mitsuba
comparison tests/mitsuba/smoke.xml. Pure Python, deterministic.

    python3 bench/plume_grid.py [OUT] [RES_X RES_Y RES_Z]

The plume rises along y from a source near the floor, drifting and widening as it goes,
its density modulated by a sum of sines (wisps) and fading at the top.
"""
import math
import struct
import sys


def density(x, y, z):
    # x, y, z in [0, 1]; the column's centre drifts with height
    cx = 0.5 + 0.18 * math.sin(3.1 * y + 0.4) * y
    cz = 0.5 + 0.12 * math.cos(2.3 * y + 1.1) * y
    radius = 0.08 + 0.22 * y
    r2 = ((x - cx) ** 2 + (z - cz) ** 2) / (radius * radius)
    core = math.exp(-1.5 * r2)
    wisps = 0.55 + 0.45 * math.sin(17.0 * x + 5.0 * y) * math.sin(13.0 * z - 7.0 * y) * math.cos(11.0 * y + 3.0 * x)
    fade = min(1.0, y / 0.08) * max(0.0, 1.0 - y) ** 0.7
    return max(0.0, core * wisps * fade)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "scenes/volumes/plume.vol"
    res = [int(v) for v in sys.argv[2:5]] if len(sys.argv) >= 5 else [32, 48, 32]
    nx, ny, nz = res
    values = []
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                values.append(density((i + 0.5) / nx, (j + 0.5) / ny, (k + 0.5) / nz))
    with open(out, "wb") as f:
        f.write(b"VOL\x03")
        f.write(struct.pack("<5i", 1, nx, ny, nz, 1))
        f.write(struct.pack("<6f", 0, 0, 0, 1, 1, 1))
        f.write(struct.pack("<%df" % len(values), *values))
    print(f"{out}: {nx} x {ny} x {nz} voxels, max density {max(values):.3f}")


if __name__ == "__main__":
    main()
