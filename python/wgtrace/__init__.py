"""wgtrace: a headless path tracer on Vulkan (wgpu, WGSL compute shaders) with a CPU
reference, from Python.

    import wgtrace
    img = wgtrace.render("scene.toml", spp=64, seed=1)   # float32 (H, W, 3), linear radiance
    scene = wgtrace.load("model.glb", width=512, height=512)
    out = scene.render(spp=16, aovs=["albedo", "normal", "depth"], denoise=True)
    out["color"], out["albedo"], out["normal"], out["depth"]

The pixels are those `wgtrace render` writes for the same settings, bit for bit on the same
backend. See the README's Python section for the whole interface.
"""

from ._wgtrace import (
    DenoiseError,
    SceneError,
    Scene,
    Sums,
    WgtraceError,
    __version__,
    adapters,
    load,
    merge,
    read_exr,
)

__all__ = [
    "DenoiseError",
    "SceneError",
    "Scene",
    "Sums",
    "WgtraceError",
    "__version__",
    "adapters",
    "load",
    "merge",
    "read_exr",
    "render",
]


def render(
    path,
    *,
    spp=None,
    seed=None,
    width=None,
    height=None,
    max_depth=None,
    sampler=None,
    light_sampling=None,
    filter=None,
    background=None,
    camera=None,
    denoise=False,
    progress=None,
    backend="gpu",
    adapter=None,
):
    """Renders a scene file (TOML, or a glTF 2.0 file on its own) and returns its colour:
    a float32 numpy array (H, W, 3) of linear radiance, denoised with `denoise=True`. The
    keywords are the command line's options of the same names; for AOVs, sample ranges or
    several renders of one scene, use `load(...)` and `Scene.render`."""
    scene = load(
        path,
        width=width,
        height=height,
        spp=spp,
        max_depth=max_depth,
        seed=seed,
        sampler=sampler,
        light_sampling=light_sampling,
        filter=filter,
        background=background,
        camera=camera,
    )
    out = scene.render(denoise=denoise, progress=progress, backend=backend, adapter=adapter)
    return out["color"]
