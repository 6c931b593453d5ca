"""Writes src/scene/metals.rs: the RGB complex index of refraction (eta, k) of every named
conductor Mitsuba 3 ships, as its RGB mode computes them from the measured spectra
(the spectrum's CIE 1931 XYZ integral turned into linear sRGB, out-of-gamut values
clamped to 0). These are the numbers `type = "conductor"` uses for `material = "Au"`.

usage: python bench/metal_table.py   (needs `pip install mitsuba==3.9.1`)
"""
import os

import mitsuba as mi

mi.set_variant("scalar_rgb")
root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
data = os.path.join(os.path.dirname(mi.__file__), "data", "ior")
names = sorted({f.split(".")[0] for f in os.listdir(data) if f.endswith(".eta.spd")}) + ["none"]


def rgb(v):
    try:
        return [float(v[i]) for i in range(3)]
    except TypeError:
        return [float(v)] * 3


def lit(v):
    return "[" + ", ".join(f"{x:.6}" if x != 0 else "0.0" for x in v) + "]"


rows = []
for n in names:
    p = mi.traverse(mi.load_dict({"type": "conductor", "material": n}))
    rows.append(f'    ("{n}", {lit(rgb(p["eta.value"]))}, {lit(rgb(p["k.value"]))}),')

out = os.path.join(root, "src", "scene", "metals.rs")
with open(out, "w") as f:
    f.write(
        "//! Named conductors: the RGB complex index of refraction (eta, k) of each measured\n"
        "//! material Mitsuba 3 and pbrt-v4 ship, computed from the published spectra as\n"
        "//! Mitsuba 3's RGB mode computes them (the CIE 1931 integral of the spectrum in\n"
        "//! linear sRGB, out-of-gamut values clamped to 0). Written by\n"
        f"//! `bench/metal_table.py` (Mitsuba {mi.__version__}); `none` is a perfect mirror.\n\n"
        "/// (name, eta, k) in name order.\n"
        "#[rustfmt::skip]\n"
        "pub const METALS: &[(&str, [f32; 3], [f32; 3])] = &[\n"
        + "\n".join(rows)
        + "\n];\n\n"
        "/// The index of refraction of the named conductor.\n"
        "pub fn metal(name: &str) -> Option<([f32; 3], [f32; 3])> {\n"
        "    METALS.iter().find(|m| m.0 == name).map(|m| (m.1, m.2))\n"
        "}\n"
    )
print(f"{out}: {len(rows)} conductors")
