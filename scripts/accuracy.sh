#!/usr/bin/env bash
# Regenerates the measurements behind docs/accuracy.md: `wgtrace converge` on the Cornell
# box (diffuse, area light), lights.toml (glossy floor, glass, small area lights),
# spheres.toml (diffuse, lit by a gradient sky only) and sky.toml (glass and gold lit by an
# HDR sky with a sun only), every sampler x light-sampling strategy, and the Cornell box
# again at path lengths 1 to 16. Renders run on the first Vulkan adapter
# (lavapipe here); references on the CPU, cached in each folder. About 18 minutes on 2
# cores with lavapipe, and 8 more for the denoising studies.
#
#   scripts/accuracy.sh [OUT_DIR]      (default docs/accuracy)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-docs/accuracy}
cargo build --release --quiet
w=target/release/wgtrace
common=(--spp-max 128 --runs 2 --reference-spp 8192 -q)
$w converge scenes/cornell.toml --width 64 --height 64 "${common[@]}" --out "$out/cornell"
$w converge scenes/lights.toml --width 80 --height 50 "${common[@]}" --out "$out/lights"
$w converge scenes/spheres.toml --width 80 --height 45 "${common[@]}" --out "$out/spheres"
$w converge scenes/sky.toml --width 80 --height 45 "${common[@]}" --out "$out/sky"
$w converge scenes/cornell.toml --width 64 --height 64 "${common[@]}" \
    --configs sobol:mis:1,sobol:mis:2,sobol:mis:3,sobol:mis:4,sobol:mis:6,sobol:mis:8,sobol:mis:12,sobol:mis:16 \
    --out "$out/cornell-depth"
# error against time with and without Open Image Denoise (pip install pyoidn, or OIDN_DIR),
# at 64 x 64 as above and at 128 x 128 and 256 x 256 (references on the GPU: the CPU's
# would take most of an hour at these sizes)
for size in 64 128 256; do
    $w converge scenes/cornell.toml --width $size --height $size "${common[@]}" \
        --reference-backend gpu --configs sobol:mis,random:bsdf --denoise \
        --out "$out/cornell-denoise-$size"
done
