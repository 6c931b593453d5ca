"""Compares wgtrace with Mitsuba 3 on one scene given in both formats, and writes a report.

usage: [WGTRACE_ARGS="--filter tent"] [MITSUBA_PARAMS=filter=tent,...] \
       compare_mitsuba.py SCENE.toml SCENE.xml OUT.md [RUNS] [SPP]

Renders the scene RUNS times (default 8) with each renderer at SPP samples per pixel
(default 1024), each run with its own seed: wgtrace with target/release/wgtrace (build it
first) on its default backend, Mitsuba 3 with its llvm_ad_rgb variant. The runs' spread
gives each renderer's standard error; the report compares the two mean images over 8 x 8
pixel tiles (the difference in each tile and channel against both standard errors), pixel
by pixel (the z-test of Mitsuba's render tests: at least 99.75% of pixels within the Sidak
bound at significance 0.01) and
over regions of the image named in the TOML file's comments as `# region NAME x0 y0 x1 y1`
(pixels, exclusive ends); its comment lines `# report: TEXT` are copied under the figures.
WGTRACE_ARGS adds options to each `wgtrace render`, MITSUBA_PARAMS sets the XML file's
`<default>` values (comma-separated NAME=VALUE), so one scene pair serves several settings.
Needs `pip install mitsuba numpy` and an LLVM of 15 or newer named
by DRJIT_LIBLLVM_PATH (Debian 12: `apt-get install libllvm19`,
/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1).
"""
import datetime
import math
import os
import subprocess
import sys
import tempfile

import mitsuba as mi
import numpy as np

toml, xml, out = sys.argv[1], sys.argv[2], sys.argv[3]
runs = int(sys.argv[4]) if len(sys.argv) > 4 else 8
spp = int(sys.argv[5]) if len(sys.argv) > 5 else 1024
root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
wgtrace = os.path.join(root, "target", "release", "wgtrace")
wgtrace_args = os.environ.get("WGTRACE_ARGS", "").split()
mitsuba_params = dict(kv.split("=", 1) for kv in os.environ.get("MITSUBA_PARAMS", "").split(",") if kv)

mi.set_variant("llvm_ad_rgb")
tmp = tempfile.mkdtemp()


def load(path):
    return np.array(mi.Bitmap(path))[..., :3].astype(np.float64)


def render_wgtrace(seed):
    path = os.path.join(tmp, f"w{seed}.exr")
    subprocess.run([wgtrace, "render", toml, "--spp", str(spp), "--seed", str(seed), "-o", path, *wgtrace_args],
                   check=True, capture_output=True)
    return load(path)


def render_mitsuba(scene, seed):
    return np.array(mi.render(scene, spp=spp, seed=seed))[..., :3].astype(np.float64)


w_runs = np.stack([render_wgtrace(s) for s in range(runs)])
height, width = w_runs.shape[1:3]
scene = mi.load_file(xml, res=width, spp=spp, **mitsuba_params)
m_runs = np.stack([render_mitsuba(scene, 1000 + s) for s in range(runs)])


def tiles(img, t=8):
    h, w = img.shape[-3] // t, img.shape[-2] // t
    return img[..., : h * t, : w * t, :].reshape(*img.shape[:-3], h, t, w, t, 3).mean(axis=(-4, -2))


def mean_se(r):
    return r.mean(axis=0), r.std(axis=0, ddof=1) / math.sqrt(len(r))


wt, wse = mean_se(tiles(w_runs))
mt, mse = mean_se(tiles(m_runs))
z = (wt - mt) / np.sqrt(wse**2 + mse**2 + 1e-12)
regions = []
for line in open(toml):
    f = line.split()
    if len(f) == 7 and f[0] == "#" and f[1] == "region":
        regions.append((f[2], *map(int, f[3:])))
rows = []
for name, x0, y0, x1, y1 in [("whole image", 0, 0, width, height)] + regions:
    wm, ws = mean_se(w_runs[:, y0:y1, x0:x1].mean(axis=(1, 2)))
    mm, ms = mean_se(m_runs[:, y0:y1, x0:x1].mean(axis=(1, 2)))
    for c, ch in enumerate("RGB"):
        d = wm[c] - mm[c]
        rows.append(f"| {name} | {ch} | {wm[c]:.5f} ± {ws[c]:.5f} | {mm[c]:.5f} ± {ms[c]:.5f} "
                    f"| {d / mm[c] * 100:+.2f}% | {d / math.hypot(ws[c], ms[c]):+.1f} |")
n_tiles = z.size
# Sidak-corrected two-sided bound at significance 1e-3 over all tiles and channels
p = 1 - (1 - 1e-3) ** (1 / n_tiles)
bound = math.sqrt(2) * 1.0
lo, hi = 0.0, 10.0
for _ in range(60):
    mid = (lo + hi) / 2
    if math.erfc(mid / math.sqrt(2)) > p:
        lo = mid
    else:
        hi = mid
bound = hi
outside = int((np.abs(z) > bound).sum())
worst = [f"tile ({x}, {y}) {'RGB'[c]}: {wt[y, x, c]:.4f} against {mt[y, x, c]:.4f} (z {z[y, x, c]:+.1f})"
         for y, x, c in zip(*np.nonzero(np.abs(z) > bound))]
# per pixel, as Mitsuba's render tests judge an image: each pixel's difference over both
# standard errors, against the two-sided bound at significance 0.01 over all pixels and
# channels (Sidak); the image agrees when at least 99.75% of them are within it


def sidak_bound(alpha, n):
    p = 1 - (1 - alpha) ** (1 / n)
    lo, hi = 0.0, 20.0
    for _ in range(80):
        mid = (lo + hi) / 2
        if math.erfc(mid / math.sqrt(2)) > p:
            lo = mid
        else:
            hi = mid
    return hi


wp, wpse = mean_se(w_runs)
mp, mpse = mean_se(m_runs)
# a pixel without variance (one that sees only an emitter) differs by the rounding of each
# run's f32 sum: spp values summed in f32 are within spp x 2^-24 of it, relatively
rounding = spp * 2.0**-24 * np.maximum(np.abs(wp), np.abs(mp))
zp = (wp - mp) / np.sqrt(wpse**2 + mpse**2 + rounding**2 + 1e-12)
pixel_bound = sidak_bound(0.01, zp.size)
within = float((np.abs(zp) <= pixel_bound).mean())
worst_pixels = [f"pixel ({x}, {y}) {'RGB'[c]}: {wp[y, x, c]:.4f} against {mp[y, x, c]:.4f} (z {zp[y, x, c]:+.1f})"
                for y, x, c in sorted(zip(*np.nonzero(np.abs(zp) > pixel_bound)), key=lambda i: -abs(zp[i]))[:8]]
name = os.path.relpath(toml, root)
env = "".join(f'{k}="{v}" ' for k, v in [("WGTRACE_ARGS", " ".join(wgtrace_args)),
                                        ("MITSUBA_PARAMS", os.environ.get("MITSUBA_PARAMS", ""))] if v)
report = f"""# wgtrace against Mitsuba 3: `{name}`

Written by `{env}bench/compare_mitsuba.py {name} {os.path.relpath(xml, root)} {os.path.relpath(out, root)} {runs} {spp}`
on {datetime.date.today()}: {runs} runs of {spp} spp per renderer, {width} x {height} pixels, each
run with its own seed; wgtrace on its default backend, Mitsuba 3 {mi.__version__} (`llvm_ad_rgb`). Means
± their standard errors over the runs; *z* is the difference over both standard errors.

| region | channel | wgtrace | Mitsuba 3 | difference | z |
|---|---|---|---|---|---|
""" + "\n".join(rows) + f"""

Over {z.shape[0]} x {z.shape[1]} tiles of 8 x 8 pixels and 3 channels ({n_tiles} tests), {outside} differ by
more than {bound:.2f} standard errors (significance 1e-3 over all tests, Sidak); the largest |z| is
{np.abs(z).max():.2f}.{"" if not worst else " Those outside (tile x, y counted from the top left):"}
""" + "".join(f"\n- {w}" for w in worst) + ("\n" if worst else "") + f"""
Pixel by pixel, as Mitsuba's render tests judge an image (each pixel's difference over both
standard errors, bound {pixel_bound:.2f} at significance 0.01 over {zp.size} tests, Sidak):
{within * 100:.2f}% of pixels and channels are within the bound ({"agrees" if within >= 0.9975 else "DIFFERS"}: the
test asks for 99.75%); the largest |z| is {np.abs(zp).max():.2f}.{"" if not worst_pixels else " The farthest outside (x, y from the top left):"}
""" + "".join(f"\n- {w}" for w in worst_pixels) + ("\n" if worst_pixels else "")
notes = [line.split("# report:", 1)[1].strip() for line in open(toml) if line.startswith("# report:")]
if notes:
    report += "\n" + " ".join(notes) + "\n"
open(out, "w").write(report)
print(report)
