"""The Mitsuba importer on every Mitsuba 3 scene file of bench/ and tests/mitsuba/: each
file rendered by wgtrace as it reads it (`wgtrace render scene.xml`, its default backend)
and by Mitsuba 3 (llvm_ad_rgb) from the same file, RUNS runs of SPP samples per pixel
each, each run with its own seed; judged pixel by pixel as Mitsuba's render tests judge
(each pixel and channel's difference over both standard errors, the Sidak bound at
significance 0.01 over all of them, at least 99.75% within). Writes
docs/bench/mitsuba-import.md; files wgtrace refuses are listed with its message.

With folders after RUNS and SPP, the scene files found in them instead: every
`test_*.xml` below each folder, Mitsuba's render tests' naming (its own test scenes are
mitsuba-data's tests/scenes), and every `*.xml` that holds a <sensor> where no test_ file
is found; writes docs/bench/mitsuba-own-scenes.md (for a folder named `scenes`) or
docs/bench/mitsuba-FOLDER.md (named by the first folder), naming files relative to the
folder's parent. Nothing is copied: the scenes and their assets stay where they are.
`-D NAME=VALUE` (any number, anywhere after SPP) sets a scene parameter for both renderers,
as `wgtrace render -D` and `mitsuba.load_file(..., NAME=VALUE)` do.

usage: python bench/mitsuba_import_report.py [RUNS] [SPP] [-D NAME=VALUE...] [FOLDER...]   (default 16 runs of
128 spp; build target/release/wgtrace first, or name another build in $WGTRACE). Needs `pip install mitsuba==3.9.1 numpy` and
an LLVM named by DRJIT_LIBLLVM_PATH.
"""
import datetime
import glob
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

import mitsuba as mi
import numpy as np

from mitsuba_assets import write_assets

mi.set_variant("llvm_ad_rgb")
root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
runs = int(sys.argv[1]) if len(sys.argv) > 1 else 16
spp = int(sys.argv[2]) if len(sys.argv) > 2 else 128
wgtrace = os.environ.get("WGTRACE") or os.path.join(root, "target", "release", "wgtrace")
tmp = tempfile.mkdtemp()

rest, defines = sys.argv[3:], {}
while "-D" in rest:
    k = rest.index("-D")
    name, value = rest[k + 1].split("=", 1)
    defines[name] = value
    del rest[k:k + 2]
folders = [os.path.abspath(f) for f in rest]


def scene_files(folder):
    tests = sorted(glob.glob(os.path.join(folder, "**", "test_*.xml"), recursive=True))
    if tests:
        return tests
    return sorted(f for f in glob.glob(os.path.join(folder, "**", "*.xml"), recursive=True)
                  if "<sensor" in open(f, errors="replace").read())


if folders:
    files = [f for d in folders for f in scene_files(d)]
    shown_of = {f: os.path.relpath(f, os.path.dirname(d)) for d in folders for f in scene_files(d)}
else:
    # the tests' scenes with their generated assets
    tests_dir = os.path.join(tmp, "tests")
    shutil.copytree(os.path.join(root, "tests", "mitsuba"), tests_dir, ignore=shutil.ignore_patterns("refs"))
    write_assets(tests_dir, lambda path, img: mi.Bitmap(img).write(path))
    files = sorted(glob.glob(os.path.join(root, "bench", "*.xml"))) + sorted(glob.glob(os.path.join(tests_dir, "*.xml")))
    shown_of = {f: os.path.relpath(f, root) if f.startswith(root) else "tests/mitsuba/" + os.path.basename(f)
                for f in files}


def sidak(alpha, n):
    p = 1 - (1 - alpha) ** (1 / n)
    lo, hi = 0.0, 20.0
    for _ in range(80):
        mid = (lo + hi) / 2
        if math.erfc(mid / math.sqrt(2)) > p:
            lo = mid
        else:
            hi = mid
    return hi


def uses_spp(path):
    """Whether the file (or one beside or below it, which it may include) has a $spp: the
    sample count is then also given as the parameter (both renderers refuse an unused
    one)."""
    folder = os.path.dirname(path)
    texts = [path] + glob.glob(os.path.join(folder, "**", "*.xml"), recursive=True)
    return any("$spp" in open(f, errors="replace").read() for f in texts)


rows, refused = [], []
for path in files:
    shown = shown_of[path]
    spp_define = {"spp": str(spp)} if uses_spp(path) else {}
    out = os.path.join(tmp, "w.exr")
    w_runs, t_w = [], 0.0
    error = None
    for s in range(runs):
        t0 = time.time()
        # -D spp as mi.load_file(path, spp=...) sets it (for files whose $spp has no default)
        r = subprocess.run([wgtrace, "render", path, "--spp", str(spp), "--seed", str(s), "-o", out]
                           + [a for k, v in {**spp_define, **defines}.items() for a in ("-D", f"{k}={v}")],
                           capture_output=True, text=True)
        t_w += time.time() - t0
        if r.returncode != 0:
            error = r.stderr.strip().splitlines()[-1]
            break
        w_runs.append(np.array(mi.Bitmap(out))[..., :3].astype(np.float64))
    if error:
        for d in folders:
            error = error.replace(os.path.dirname(d) + "/", "")
        refused.append((shown, error.replace(tmp, "").replace(root + "/", "")))
        print(shown, "refused:", error)
        continue
    try:
        t0 = time.time()
        scene = mi.load_file(path, **spp_define, **defines)
        m_runs = [np.array(mi.render(scene, spp=spp, seed=1000 + s))[..., :3].astype(np.float64) for s in range(runs)]
        t_m = time.time() - t0
    except Exception as e:
        refused.append((shown, f"Mitsuba: {str(e).splitlines()[-1]}"))
        continue
    w, m = np.stack(w_runs), np.stack(m_runs)
    wm, ws = w.mean(0), w.std(0, ddof=1) / math.sqrt(runs)
    mm, ms = m.mean(0), m.std(0, ddof=1) / math.sqrt(runs)
    # a pixel without variance (one that sees only an emitter) differs by the rounding of
    # each run's f32 sum: spp values summed in f32 are within spp x 2^-24 of it, relatively
    rounding = spp * 2.0**-24 * np.maximum(np.abs(wm), np.abs(mm))
    z = (wm - mm) / np.sqrt(ws**2 + ms**2 + rounding**2 + 1e-12)
    bound = sidak(0.01, z.size)
    within = float((np.abs(z) <= bound).mean())
    whole = (f"{(wm.mean() - mm.mean()) / mm.mean() * 100:+.2f}%" if mm.mean() > 0
             else "black in both" if wm.mean() == 0 else f"{wm.mean():.3g} against 0")
    rows.append(f"| `{shown}` | {w.shape[2]} x {w.shape[1]} | {within * 100:.2f}% | "
                f"{'agrees' if within >= 0.9975 else 'DIFFERS'} | {whole} | {np.abs(z).max():.1f} |")
    print(rows[-1])

# why a file differs, where it is known
MASK = ("every pixel outside the bound is on the two masked rectangles, lit before a black "
        "background, where Mitsuba 3.9.1's `path` integrator gives a mask's opacity squared and "
        "its own `direct` and `volpath` give the opacity, as wgtrace does "
        "(docs/bench/mitsuba-mask-integrators.md); rendered by Mitsuba's `volpath`, the file "
        "agrees with wgtrace (99.98% for test_pointlight, 99.99% for test_arealight).")
MASKED_SPHERE = ("every pixel outside the bound (63 pixels and channels at 16 x 128 spp) is on the "
                 "masked sphere, front row right, lit by the point light and the sky: Mitsuba 3.9.1's "
                 "`path` darkens a mask as in test_pointlight and test_arealight "
                 "(docs/bench/mitsuba-mask-integrators.md); rendered by Mitsuba's `volpath` the masked "
                 "sphere agrees, and the differing pixels move to the rough and thin glass spheres "
                 "instead, where the two Mitsuba integrators differ from each other.")
BORDER = ("its film samples the border (`sample_border`), so wgtrace draws each pixel's samples "
          "from its filter, which gives Mitsuba's expected image, where Mitsuba splats them: the "
          "pixels outside the bound lie along the floor's far edge and the rectangles' sides, where a "
          "pixel whose filter barely reaches a surface sees it in none of wgtrace's samples (a mean "
          "and standard error of 0) and Mitsuba's splatted neighbours give it a small, nearly "
          "noiseless value. Rendered by splatting instead (the converted file with "
          "`reconstruction = \"splat\"`, `sample_border = false`; 8 runs of 64 spp), 99.97% are "
          "within, largest z 7.5, against 97.46% and 40.7 drawn; wgtrace does not yet splat samples "
          "from beyond the image")
WHY = {
    "bench/filter.xml": BORDER,
    "tests/mitsuba/materials.xml": MASKED_SPHERE,
    "scenes/bsdf_spheres/test_pointlight.xml": MASK,
    "scenes/bsdf_spheres/test_arealight.xml": MASK,
}
agree = sum("agrees" in r for r in rows)
STANDINS = """

Where the folders lacked meshes or images, `bench/mitsuba_standins.py` wrote stand-ins
(spheres, rectangles, cubes, tori, patterns, a sky): both renderers read the same ones, so
a row judges how each reads the scene file, not the image Mitsuba's own assets would
make."""
BITTERLI = """

The files are the public copies of Bitterli's scenes in Mitsuba form that
bench/bitterli-sources.md lists (each edited by whoever keeps it, most without their meshes),
prepared by bench/bitterli_prepare.py: the integrator back to `path` where a copy names one
of its own, the film a quarter of the size. The stand-in meshes of a scene are spheres
placed apart, so a row judges each renderer's reading of the file's materials, lights,
camera and integrator, not Bitterli's image."""
source = ("every Mitsuba 3\nscene file of `bench/` and `tests/mitsuba/`" if not folders else
          "the scene files of\n" + ", ".join(f"`{os.path.basename(d)}/`" for d in folders) + " (named from there)")
command = " ".join(["bench/mitsuba_import_report.py", str(runs), str(spp)]
                   + [a for k, v in defines.items() for a in ("-D", f"{k}={v}")]
                   + [os.path.basename(d) for d in folders])
report = f"""# The Mitsuba importer against Mitsuba 3

Written by `{command}` on {datetime.date.today()}: {source}, rendered by wgtrace from the file itself
(`wgtrace render scene.xml`, default backend) and by Mitsuba {mi.__version__} (`llvm_ad_rgb`) from the
same file, {runs} runs of {spp} spp each, each run with its own seed. *Pixels within*: the share of
pixels and channels whose difference of the two means is within the Sidak bound (significance
0.01 over all of them) of both standard errors, as Mitsuba's render tests judge; they ask
for 99.75%. (Each run's f32 sum of {spp} values may round by {spp} x 2^-24 of the pixel's value:
that is added to the errors, for pixels without variance, such as those that see only an
emitter.) *Whole image*: wgtrace's mean over Mitsuba's, less 1.

{agree} of {len(rows)} rendered files agree; {len(refused)} refused.{STANDINS if folders else ""}{BITTERLI if any(os.path.basename(d) == "bitterli" for d in folders) else ""}

| file | size | pixels within | verdict | whole image | largest z |
|---|---|---|---|---|---|
""" + "\n".join(rows) + "\n"
known = [f"- `{n}`: {w}\n" for n, w in WHY.items() if any(f"`{n}`" in r and "DIFFERS" in r for r in rows)]
if known:
    report += "\nWhy a file differs:\n\n" + "".join(known)
if refused:
    report += "\nRefused (wgtrace's message):\n\n" + "".join(f"- `{n}`: {e}\n" for n, e in refused)
name = ("mitsuba-import.md" if not folders else "mitsuba-own-scenes.md"
        if os.path.basename(folders[0]) == "scenes" else f"mitsuba-{os.path.basename(folders[0])}.md")
open(os.path.join(root, "docs", "bench", name), "w").write(report)
print(report)
