"""Writes bench/generated/bump-height.png, the height map of bench/bump.toml and
bench/bump.xml: 64 x 64 8-bit grey, 0.5 + 0.45 sin(2 pi 4 x / 64) cos(2 pi 3 (y - 31.5) / 64)
plus a ring, symmetric about the middle row so that either uv convention (v up or down)
reads it alike. Needs numpy.

usage: python3 bench/bump_height.py
"""
import os
import struct
import zlib

import numpy as np

root = os.path.dirname(os.path.abspath(__file__))
out = os.path.join(root, "generated", "bump-height.png")
x, y = np.meshgrid(np.arange(64) + 0.5, np.arange(64) + 0.5)
h = 0.5 + 0.3 * np.sin(2 * np.pi * 4 * x / 64) * np.cos(2 * np.pi * 3 * (y - 32) / 64)
r = np.hypot(x - 32, y - 32)
h += 0.2 * np.exp(-((r - 16) ** 2) / 8)
pixels = np.clip(np.round(h * 255), 0, 255).astype(np.uint8)


def chunk(kind, data):
    body = kind + data
    return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)


raw = b"".join(b"\x00" + row.tobytes() for row in pixels)
png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 64, 64, 8, 0, 0, 0, 0))
       + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))
os.makedirs(os.path.dirname(out), exist_ok=True)
with open(out, "wb") as f:
    f.write(png)
print(out)
