"""Renders bench/cornell.xml with Mitsuba 3 (llvm_ad_rgb) for benches/performance.rs.

usage: mitsuba_render.py SCENE.xml RES SPP SEED OUT.exr [RENDERS]

Renders RENDERS times (default 2) in one process, the first with seed SEED and each next
one with the seed after; writes the last image to OUT.exr and prints one JSON line: seconds
to import and load the scene, and the seconds of each render (the first includes Dr.Jit's
kernel compilation or its load from the on-disk kernel cache). Needs `pip install
mitsuba` and an LLVM of 15 or newer named by DRJIT_LIBLLVM_PATH (Debian 12: `apt-get
install libllvm19`, /usr/lib/x86_64-linux-gnu/libLLVM.so.19.1).
"""
import json
import sys
import time

start = time.perf_counter()
import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402

mi.set_variant("llvm_ad_rgb")
path, res, spp, seed, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
renders = int(sys.argv[6]) if len(sys.argv) > 6 else 2
scene = mi.load_file(path, res=res, spp=spp)
loaded = time.perf_counter() - start
times = []
img = None
for i in range(renders):
    t = time.perf_counter()
    img = mi.render(scene, spp=spp, seed=seed + i)
    dr.eval(img)
    dr.sync_thread()
    times.append(time.perf_counter() - t)
mi.util.write_bitmap(out, img)
print(json.dumps({"load": loaded, "renders": times, "threads": dr.thread_count()}))
