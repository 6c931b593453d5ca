"""Renders one scene over many Ray tasks: each task renders a range of sample indices into
`wgtrace.Sums` (pickled back to the driver), and `wgtrace.merge` adds them, as
`wgtrace merge` adds checkpoints. The image equals one render of all the samples up to the
order of the additions.

    pip install ./python ray
    python python/examples/ray_render.py scenes/cornell.toml --spp 1024 --tasks 16 -o cornell.exr

On a Ray cluster, pass `--address auto` and `--gpus-per-task 1`: Ray gives each task its
own GPU through CUDA_VISIBLE_DEVICES, which wgtrace maps to that GPU's Vulkan adapter. The
scene file (and what it names) must be readable at the same path on every node.
"""

import argparse
import time

import ray

import wgtrace


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--spp", type=int, default=None, help="samples per pixel (default: the scene's)")
    ap.add_argument("--tasks", type=int, default=8, help="sample ranges, one Ray task each")
    ap.add_argument("--gpus-per-task", type=float, default=0,
                    help="GPUs Ray reserves per task (1 on a GPU cluster; 0 renders on "
                         "whatever adapter a task finds, lavapipe included)")
    ap.add_argument("--cpus-per-task", type=float, default=1)
    ap.add_argument("--aov", default="", help="AOVs to write (EXR), comma-separated")
    ap.add_argument("--denoise", action="store_true", help="denoise the merged image (pyoidn)")
    ap.add_argument("--address", default=None, help="a Ray cluster's address (default: local)")
    ap.add_argument("-o", "--output", required=True, help="image (.exr, .png, .ppm)")
    ap.add_argument("--checkpoint", help="also keep the merged sums here (`wgtrace render --resume`)")
    args = ap.parse_args()

    aovs = [a for a in args.aov.split(",") if a]
    # the scene is loaded here too, to check it before any task starts and to learn its spp
    spp = args.spp or wgtrace.load(args.scene).spp
    tasks = min(args.tasks, spp)
    bounds = [spp * i // tasks for i in range(tasks + 1)]

    ray.init(address=args.address)

    @ray.remote(num_gpus=args.gpus_per_task, num_cpus=args.cpus_per_task)
    def render_range(path, spp, start, end, keep_aovs):
        return wgtrace.load(path).accumulate(spp=spp, samples=(start, end), aovs=keep_aovs)

    keep = bool(aovs) or args.denoise
    t0 = time.perf_counter()
    parts = ray.get([render_range.remote(args.scene, spp, a, b, keep)
                     for a, b in zip(bounds, bounds[1:])])
    merged = wgtrace.merge(parts)
    merged.write_image(args.output, aovs=aovs, denoise=args.denoise)
    if args.checkpoint:
        merged.save(args.checkpoint)
    print(f"{args.output}: {merged.width}x{merged.height}, {spp} spp "
          f"(samples {merged.samples}) from {tasks} Ray tasks in {time.perf_counter() - t0:.2f} s")


if __name__ == "__main__":
    main()
