"""Writes src/scene/mitsuba/cie.rs: the CIE 1931 2-degree colour matching functions and the
D65 illuminant at 5 nm from 360 to 830 nm, and the XYZ-to-linear-sRGB matrix, as Mitsuba 3's
RGB mode evaluates them, so that a scene file's wavelength:value spectra become the RGB
values Mitsuba's RGB variants render with. Checks the Rust formula's Python twin against
mi.spectrum_list_to_srgb on random spectra and prints the largest difference.

usage: python bench/cie_table.py   (needs `pip install mitsuba==3.9.1`)
"""
import os
import random

import mitsuba as mi

mi.set_variant("scalar_rgb")
root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
lo, hi = int(mi.MI_CIE_MIN), int(mi.MI_CIE_MAX)
waves = list(range(lo, hi + 1, 5))
xyz = [[float(c) for c in mi.cie1931_xyz(float(w))] for w in waves]
d65 = [float(mi.cie_d65(float(w))) for w in waves]
m = [[float(mi.xyz_to_srgb(mi.Color3f(*(1.0 if j == i else 0.0 for j in range(3))))[r]) for i in range(3)] for r in range(3)]


def interp(table, w):
    t = (w - lo) / 5.0
    i = min(int(t), len(table) - 2)
    f = t - i
    a, b = table[i], table[i + 1]
    return [x * (1 - f) + y * f for x, y in zip(a, b)] if isinstance(a, list) else a * (1 - f) + b * f


def to_srgb(wl, vals, bounded, use_d65):
    acc = [0.0, 0.0, 0.0]
    steps = 1000
    for i in range(steps):
        w = lo + (i / (steps - 1)) * (hi - lo)
        if w < wl[0] or w > wl[-1]:
            continue
        k = max(j for j in range(len(wl) - 1) if wl[j] <= w) if w < wl[-1] else len(wl) - 2
        w0, w1, v0, v1 = wl[k], wl[k + 1], vals[k], vals[k + 1]
        v = ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1)
        c = interp(xyz, w)
        s = interp(d65, w) if use_d65 else 1.0
        acc = [a + ci * v * s for a, ci in zip(acc, c)]
    acc = [a * (hi - lo) / steps * mi.MI_CIE_Y_NORMALIZATION for a in acc]
    rgb = [sum(m[r][i] * acc[i] for i in range(3)) for r in range(3)]
    return [min(max(x, 0.0), 1.0) if bounded else max(x, 0.0) for x in rgb]


worst = 0.0
random.seed(1)
for case in range(40):
    n = random.randint(2, 12)
    wl = sorted(random.sample(range(300, 900), n))
    vals = [random.uniform(0, 2) for _ in wl]
    for bounded, use_d65 in [(True, True), (False, False), (False, True)]:
        ours = to_srgb(wl, vals, bounded, use_d65)
        theirs = mi.spectrum_list_to_srgb([float(w) for w in wl], vals, bounded, use_d65)
        worst = max(worst, max(abs(a - float(b)) for a, b in zip(ours, theirs)))
print(f"largest difference from mi.spectrum_list_to_srgb over 120 random spectra: {worst:.2e}")


def row(v):
    return "    [" + ", ".join(f"{x:.9e}" for x in v) + "],"


out = os.path.join(root, "src", "scene", "mitsuba", "cie.rs")
with open(out, "w") as f:
    f.write(
        "//! The CIE 1931 2-degree colour matching functions (x, y, z) and the D65 illuminant\n"
        f"//! at 5 nm from {lo} to {hi} nm, and the XYZ-to-linear-sRGB matrix, as Mitsuba 3's\n"
        "//! RGB mode evaluates them (linear between the 5 nm samples). Written by\n"
        f"//! `bench/cie_table.py` (Mitsuba {mi.__version__}).\n\n"
        f"pub const CIE_MIN: f64 = {lo}.0;\n"
        f"pub const CIE_MAX: f64 = {hi}.0;\n"
        "/// 1 / the integral of y: what makes a flat spectrum of 1 integrate to Y = 1 (the D65\n"
        "/// column is normalized so that the same factor serves spectra weighted by it).\n"
        f"pub const Y_NORMALIZATION: f64 = {mi.MI_CIE_Y_NORMALIZATION!r};\n\n"
        "/// x, y, z and D65 per 5 nm.\n"
        "#[rustfmt::skip]\n"
        f"pub const CIE_XYZ_D65: [[f64; 4]; {len(waves)}] = [\n"
        + "\n".join(row(c + [d]) for c, d in zip(xyz, d65))
        + "\n];\n\n"
        "/// Linear sRGB from XYZ, row by row.\n"
        "#[rustfmt::skip]\n"
        "pub const XYZ_TO_SRGB: [[f64; 3]; 3] = [\n"
        + "\n".join(row(r) for r in m)
        + "\n];\n"
    )
print(f"{out}: {len(waves)} rows")
