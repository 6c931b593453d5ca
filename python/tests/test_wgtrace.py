"""The Python module against the command line, with AOVs and denoising.

Run by tests/python.rs under `cargo test` (which builds the module into a virtual
environment with pyoidn and passes the CLI's binary as WGTRACE_BIN), or by hand:
`pip install ./python pytest pyoidn && pytest python/tests`. GPU tests need a Vulkan
adapter (lavapipe: `apt-get install mesa-vulkan-drivers`) and fail without one.
"""

import os
import pickle
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import wgtrace

ROOT = Path(__file__).resolve().parents[2]
CORNELL = ROOT / "scenes" / "cornell.toml"


@pytest.fixture(scope="session")
def cli():
    """The `wgtrace` binary: WGTRACE_BIN, else built here."""
    exe = os.environ.get("WGTRACE_BIN")
    if exe:
        return exe
    subprocess.run(
        ["cargo", "build", "--release", "--quiet", "--bin", "wgtrace"], cwd=ROOT, check=True
    )
    return str(ROOT / "target" / "release" / "wgtrace")


def run_cli(cli, *args, env=None):
    out = subprocess.run([cli, *map(str, args)], capture_output=True, text=True, env=env)
    assert out.returncode == 0, out.stderr
    return out


def test_the_gpu_is_an_adapter():
    # GPU tests fail, never skip, without a Vulkan adapter
    assert wgtrace.adapters(), "the GPU tests need a Vulkan adapter (mesa-vulkan-drivers)"


def test_render_returns_linear_float32_height_width_rgb():
    img = wgtrace.render(CORNELL, spp=4, seed=1, width=40, height=30)
    assert isinstance(img, np.ndarray)
    assert img.dtype == np.float32 and img.shape == (30, 40, 3)
    # the lamp's radiance (17, 12, 4) is seen directly: linear, not clamped
    assert img.max() > 10
    assert np.isfinite(img).all()


@pytest.mark.parametrize("backend", ["gpu", "cpu"])
def test_the_same_pixels_as_the_cli_bit_for_bit(cli, tmp_path, backend):
    exr = tmp_path / "cli.exr"
    run_cli(cli, "render", CORNELL, "--backend", backend, "--width", 48, "--height", 36,
            "--spp", 12, "--seed", 7, "--aov", "albedo,normal,depth,position,variance",
            "-o", exr, "-q")
    file = wgtrace.read_exr(exr)
    scene = wgtrace.load(CORNELL, width=48, height=36)
    out = scene.render(spp=12, seed=7, backend=backend,
                       aovs=["albedo", "normal", "depth", "position", "variance"])
    assert set(out) == set(file) == {"color", "albedo", "normal", "depth", "position", "variance"}
    for name, a in out.items():
        assert a.shape == file[name].shape, name
        assert np.array_equal(a, file[name]), name
    assert out["depth"].shape == (36, 48)
    # the module-level function and the scene's overrides give the same colour
    img = wgtrace.render(CORNELL, width=48, height=36, spp=12, seed=7, backend=backend)
    assert np.array_equal(img, file["color"])


def test_cornell_aovs():
    out = wgtrace.load(CORNELL, width=32, height=32).render(
        spp=8, aovs=["albedo", "normal", "depth"]
    )
    c = 16
    np.testing.assert_allclose(out["albedo"][c, c], [0.73, 0.73, 0.73], atol=1e-5)
    np.testing.assert_allclose(out["normal"][c, c], [0, 0, 1], atol=1e-6)
    # 4.9 from the camera to the back wall, a little more off the axis
    assert 4.9 <= out["depth"][c, c] < 4.91
    np.testing.assert_allclose(out["albedo"][c, 2], [0.65, 0.05, 0.05], atol=1e-5)
    np.testing.assert_allclose(out["normal"][c, 2], [1, 0, 0], atol=1e-6)


def rel_mse_against(x, ref, ref_var):
    """Relative MSE against a reference, less the reference's own noise (its variance of
    the mean, the variance AOV), so that a reference of finite samples measures the
    truth's error without bias."""
    return float(np.mean(((x - ref) ** 2 - ref_var) / (ref**2 + 0.01)))


def test_denoising_cuts_the_16_spp_error_at_least_4x():
    size = 128
    scene = wgtrace.load(CORNELL, width=size, height=size)
    ref = scene.render(spp=1024, seed=12345, aovs=["variance"])
    out = scene.render(spp=16, seed=1, denoise=True)
    assert set(out) == {"color", "noisy"}
    noisy = rel_mse_against(out["noisy"], ref["color"], ref["variance"])
    clean = rel_mse_against(out["color"], ref["color"], ref["variance"])
    print(f"16 spp relMSE: noisy {noisy:.3e}, denoised {clean:.3e}, {noisy / clean:.1f}x")
    assert noisy / clean >= 4, (noisy, clean)


def test_the_cli_denoises_and_converge_draws_the_denoised_curve(cli, tmp_path):
    # the CLI finds pyoidn through the python3 on its path, this environment's
    env = dict(os.environ, PATH=str(Path(sys.executable).parent) + os.pathsep + os.environ["PATH"])
    exr = tmp_path / "d.exr"
    run_cli(cli, "render", CORNELL, "--width", 32, "--height", 32, "--spp", 4, "--denoise",
            "-o", exr, "-q", env=env)
    layers = wgtrace.read_exr(exr)
    assert set(layers) == {"color", "noisy"}
    assert not np.array_equal(layers["color"], layers["noisy"])
    out = tmp_path / "study"
    run_cli(cli, "converge", CORNELL, "--width", 32, "--height", 32, "--spp-max", 4,
            "--runs", 1, "--configs", "sobol:mis", "--reference-spp", 64, "--denoise",
            "-q", "--out", out, env=env)
    rows = (out / "results.csv").read_text().splitlines()
    assert sum(r.startswith("sobol:mis +oidn,") for r in rows) == 3, rows
    assert "sobol:mis +oidn" in (out / "report.md").read_text()


def test_a_missing_denoiser_is_one_error_saying_how_to_install_it(cli, tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("OIDN_DIR", "VIRTUAL_ENV")}
    env["PATH"] = "/nonexistent"
    out = subprocess.run([cli, "render", str(CORNELL), "--spp", "1", "--width", "8",
                          "--height", "8", "--denoise", "-o", str(tmp_path / "x.png")],
                         capture_output=True, text=True, env=env)
    assert out.returncode != 0
    assert "pip install pyoidn" in out.stderr and "OIDN_DIR" in out.stderr
    assert "panicked" not in out.stderr


def test_errors_name_what_is_wrong(tmp_path):
    scene = wgtrace.load(CORNELL, width=8, height=8)
    with pytest.raises(TypeError, match="spp2"):
        scene.render(spp2=3)
    with pytest.raises(TypeError, match="spp: expected an int, got str"):
        scene.render(spp="many")
    with pytest.raises(ValueError, match="spp=-1"):
        scene.render(spp=-1)
    with pytest.raises(ValueError, match='unknown AOV "shadow"'):
        scene.render(aovs=["shadow"])
    with pytest.raises(TypeError, match="aovs"):
        scene.render(aovs="albedo")
    with pytest.raises(ValueError, match="backend"):
        scene.render(backend="tpu")
    with pytest.raises(ValueError, match="samples=\\(0, 9\\)"):
        scene.render(spp=8, samples=(0, 9))
    with pytest.raises(ValueError, match="sampler=\"best\""):
        wgtrace.load(CORNELL, sampler="best")
    with pytest.raises(TypeError, match="width"):
        wgtrace.load(CORNELL, width="wide")
    with pytest.raises(TypeError, match="unexpected keyword argument 'colour'"):
        wgtrace.render(CORNELL, colour=True)
    bad = tmp_path / "bad.toml"
    bad.write_text(CORNELL.read_text().replace("spp = 64", "spp = 0"))
    # the CLI's located message: file, line, key
    with pytest.raises(wgtrace.SceneError, match=r"bad\.toml:7:1: render\.spp: must be in"):
        wgtrace.load(bad)
    with pytest.raises(ValueError):  # SceneError is a ValueError
        wgtrace.load(tmp_path / "missing.toml")
    with pytest.raises(wgtrace.WgtraceError, match="no-such-gpu"):
        scene.render(adapter="no-such-gpu")


def test_progress_is_called_and_the_gil_is_released():
    scene = wgtrace.load(CORNELL, width=96, height=96)
    calls = []
    ticks = []
    done = threading.Event()

    def tick():
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=tick)
    t.start()
    start = time.perf_counter()
    scene.render(spp=64, progress=lambda d, n: calls.append((d, n)), backend="cpu")
    end = time.perf_counter()
    done.set()
    t.join()
    assert calls and calls[-1] == (64, 64)
    assert all(a[0] < b[0] for a, b in zip(calls, calls[1:]))
    # another thread ran all along the render: the GIL was not held
    during = [x for x in ticks if start < x < end]
    assert len(during) >= 0.03 * (end - start) / 0.001, (len(during), end - start)


@pytest.fixture
def ctrl_c():
    """Python's own SIGINT handler, as an interactive session has it: a process started
    in the background (a CI job) inherits SIGINT ignored, and Python then installs none."""
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, old)


def test_ctrl_c_raises_keyboard_interrupt_after_the_current_pass(ctrl_c):
    scene = wgtrace.load(CORNELL, width=64, height=64)
    calls = []

    def progress(done, total):
        calls.append(done)
        if len(calls) == 1:
            signal.raise_signal(signal.SIGINT)

    with pytest.raises(KeyboardInterrupt):
        scene.render(spp=256, progress=progress, backend="cpu")
    # stopped at the next look after the signal, long before the end
    assert len(calls) <= 2 and calls[-1] < 256


def test_ctrl_c_from_the_terminal_stops_a_render_without_a_callback(ctrl_c):
    # SIGINT as a terminal sends it, to the process, while the render runs with the GIL
    # released: the module looks for it after each batch of passes
    scene = wgtrace.load(CORNELL, width=64, height=64)
    timer = threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT))
    start = time.perf_counter()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            scene.render(spp=1 << 16, backend="cpu")
    finally:
        timer.cancel()
    # 65536 passes would take minutes; it stopped within a few batches of the signal
    assert time.perf_counter() - start < 30


def test_a_callback_that_raises_stops_the_render():
    scene = wgtrace.load(CORNELL, width=16, height=16)

    def progress(done, total):
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        scene.render(spp=64, progress=progress, backend="cpu")


def test_sample_ranges_merge_as_the_cli_merges(cli, tmp_path):
    scene = wgtrace.load(CORNELL, width=24, height=24)
    a = scene.accumulate(spp=8, samples=(0, 3), aovs=True)
    b = scene.accumulate(spp=8, samples=(3, 8), aovs=True)
    assert a.samples == [(0, 3)] and b.aovs
    # Ray and multiprocessing pickle them
    b2 = pickle.loads(pickle.dumps(b))
    merged = wgtrace.merge([a, b2])
    assert merged.samples == [(0, 8)]
    whole = scene.render(spp=8, aovs=["albedo", "depth"])
    img = merged.image(aovs=["albedo", "depth"])
    for k in whole:
        np.testing.assert_allclose(img[k], whole[k], rtol=1e-5, atol=1e-6)
    # a saved part merges with the CLI's
    a.save(tmp_path / "a.ckpt")
    run_cli(cli, "render", CORNELL, "--width", 24, "--height", 24, "--spp", 8,
            "--sample-range", "3..8", "--aov", "albedo", "--checkpoint", tmp_path / "b.ckpt",
            "-o", tmp_path / "b.exr", "-q")
    run_cli(cli, "merge", tmp_path / "a.ckpt", tmp_path / "b.ckpt", "--aov", "albedo,depth",
            "-o", tmp_path / "m.exr")
    m = wgtrace.read_exr(tmp_path / "m.exr")
    for k in whole:
        np.testing.assert_allclose(m[k], whole[k], rtol=1e-5, atol=1e-6)
    both = wgtrace.merge([str(tmp_path / "a.ckpt"), str(tmp_path / "b.ckpt")])
    assert both.samples == [(0, 8)]
    with pytest.raises(wgtrace.WgtraceError, match="overlap"):
        wgtrace.merge([a, a])


def test_one_device_serves_every_render_of_a_process():
    # the second render of a scene reuses the device and its compiled pipeline
    scene = wgtrace.load(CORNELL, width=16, height=16)
    scene.render(spp=1)
    start = time.perf_counter()
    scene.render(spp=1)
    assert time.perf_counter() - start < 5


def test_the_scheduler_s_variable_is_read(tmp_path):
    # on a machine without NVIDIA's Vulkan driver, CUDA_VISIBLE_DEVICES renders on the
    # default adapter with a note; with an NVIDIA adapter, on the one it names
    code = (
        "import wgtrace; s = wgtrace.load(%r, width=8, height=8); s.render(spp=1); "
        "print('ok')" % str(CORNELL)
    )
    env = dict(os.environ, CUDA_VISIBLE_DEVICES="0")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert out.returncode == 0 and "ok" in out.stdout, out.stderr
