"""Renders the Mitsuba 3 reference images of the importer's tests: every scene of
tests/mitsuba/*.xml with Mitsuba 3 (llvm_ad_rgb), RUNS runs of SPP samples per pixel, each
with its own seed, into tests/mitsuba/refs/NAME.mean.exr (the mean of the runs) and
NAME.se.exr (its standard error per pixel and channel). tests/mitsuba_import.rs renders the
same files with wgtrace and judges each pixel against these, as Mitsuba's render tests do.
The scenes' generated assets are written by bench/mitsuba_assets.py with the values the
tests write.

usage: python bench/mitsuba_refs.py [RUNS] [SPP] [NAME...]   (default 32 runs of 256 spp: enough runs that their
standard error is itself well estimated, so the z-test holds its significance)
Needs `pip install mitsuba==3.9.1 numpy` and an LLVM named by DRJIT_LIBLLVM_PATH.
"""
import math
import os
import shutil
import sys
import tempfile

import mitsuba as mi
import numpy as np

from mitsuba_assets import write_assets

mi.set_variant("llvm_ad_rgb")
root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
src = os.path.join(root, "tests", "mitsuba")
runs = int(sys.argv[1]) if len(sys.argv) > 1 else 32
spp = int(sys.argv[2]) if len(sys.argv) > 2 else 256
names = sys.argv[3:] or sorted(f[:-4] for f in os.listdir(src) if f.endswith(".xml"))


tmp = tempfile.mkdtemp()
work = os.path.join(tmp, "mitsuba")
shutil.copytree(src, work, ignore=shutil.ignore_patterns("refs"))
write_assets(work, lambda path, img: mi.Bitmap(img).write(path))
out = os.path.join(src, "refs")
os.makedirs(out, exist_ok=True)
for name in names:
    scene = mi.load_file(os.path.join(work, name + ".xml"), spp=spp)
    imgs = np.stack([np.array(mi.render(scene, spp=spp, seed=1000 * s + 1))[..., :3] for s in range(runs)]).astype(np.float64)
    mean = imgs.mean(axis=0)
    se = imgs.std(axis=0, ddof=1) / math.sqrt(runs)
    mi.Bitmap(mean.astype(np.float32)).write(os.path.join(out, name + ".mean.exr"))
    mi.Bitmap(se.astype(np.float32)).write(os.path.join(out, name + ".se.exr"))
    print(f"{name}: {mean.shape[1]} x {mean.shape[0]}, {runs} x {spp} spp, mean {mean.mean():.4f}, "
          f"median relative standard error {np.median(se / np.maximum(mean, 1e-6)):.4f}")
