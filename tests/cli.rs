//! The `wgtrace` binary as a user runs it: formats, overrides, previews, errors, `info`.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::wgtrace;

fn tmp_dir(name: &str) -> PathBuf {
    common::tmp_dir(&format!("cli-{name}"))
}

fn cornell() -> String {
    common::repo_path("scenes/cornell.toml")
        .display()
        .to_string()
}

/// Runs `wgtrace ARGS -o OUT` and fails the test unless it succeeds.
fn run_ok(args: &[&str], out: &Path) {
    let o = Command::new(env!("CARGO_BIN_EXE_wgtrace"))
        .args(args)
        .arg("-o")
        .arg(out)
        .output()
        .expect("run wgtrace");
    assert!(
        o.status.success(),
        "wgtrace {args:?} failed:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

fn render_to(out: &Path, extra: &[&str]) -> Output {
    let out_s = out.display().to_string();
    let scene = cornell();
    let mut args = vec![
        "render", &scene, "-o", &out_s, "--width", "40", "--height", "30", "--spp", "4", "-q",
    ];
    args.extend_from_slice(extra);
    let o = wgtrace(&args);
    assert!(
        o.status.success(),
        "wgtrace {args:?} failed:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

#[test]
fn renders_png_exr_and_ppm_of_the_requested_size_and_reports() {
    let dir = tmp_dir("formats");
    for ext in ["png", "exr", "ppm"] {
        let out = dir.join(format!("cornell.{ext}"));
        let o = render_to(&out, &[]);
        let img = image::open(&out).unwrap_or_else(|e| panic!("{ext}: {e}"));
        assert_eq!((img.width(), img.height()), (40, 30), "{ext}");
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(
            stdout.contains("40x30, 4 spp") && stdout.contains("Msamples/s"),
            "{stdout}"
        );
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(stderr.contains("device: "), "{stderr}");
        // a render that succeeds says nothing that reads as an error (Mesa's device-select
        // layer used to print `error: XDG_RUNTIME_DIR is invalid ...` on headless machines)
        assert!(
            !stderr
                .lines()
                .any(|l| l.to_ascii_lowercase().contains("error")),
            "{stderr}"
        );
    }
    // EXR holds linear radiance; PNG and PPM hold its sRGB encoding.
    let exr = image::open(dir.join("cornell.exr")).unwrap().to_rgb32f();
    let png = image::open(dir.join("cornell.png")).unwrap().to_rgb8();
    let ppm = image::open(dir.join("cornell.ppm")).unwrap().to_rgb8();
    assert_eq!(png, ppm);
    for (l, s) in exr.pixels().zip(png.pixels()) {
        for c in 0..3 {
            let expected = (wgtrace::image_io::linear_to_srgb(l[c]) * 255.0 + 0.5) as u8;
            assert_eq!(s[c], expected);
        }
    }
    // The light is visible, so some EXR values exceed 1 (not clamped).
    assert!(exr.pixels().any(|p| p[0] > 1.0));
}

#[test]
fn cpu_backend_and_overrides_work_and_preview_rewrites_the_file() {
    let dir = tmp_dir("cpu");
    let out = dir.join("c.png");
    let o = render_to(
        &out,
        &[
            "--backend",
            "cpu",
            "--max-depth",
            "2",
            "--seed",
            "5",
            "--preview-every",
            "1",
            "--light-sampling",
            "mixture",
            "--sampler",
            "hammersley",
        ],
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("CPU reference"));
    assert_eq!(image::open(&out).unwrap().width(), 40);
    // No temporary files left behind.
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
}

#[test]
fn bad_input_gives_a_clear_error_and_nonzero_exit() {
    let dir = tmp_dir("errors");
    let scene = cornell();
    let o = wgtrace(&[
        "render",
        &scene,
        "-o",
        &dir.join("x.jpg").display().to_string(),
    ]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("x.jpg: unknown image extension"), "{e}");

    let o = wgtrace(&["render", "no/such/scene.toml"]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("no/such/scene.toml: cannot read scene"), "{e}");

    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        "[camera]\nlook_from = [0, 0, 1]\nlook_at = [0, 0, 0]\nfov = 3\n",
    )
    .unwrap();
    let o = wgtrace(&["render", &bad.display().to_string()]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("bad.toml:4:1") && e.contains("fov"), "{e}");
    assert!(!e.contains("panicked"), "{e}");

    // past the largest side accepted (large images render in bands; see `tiled_...`)
    let big = dir.join("big.png").display().to_string();
    let o = wgtrace(&["render", &scene, "-o", &big, "--width", "16385"]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("render.width (from --width): must be in 1..=16384, got 16385"),
        "{e}"
    );
    assert!(!e.contains("panicked"), "{e}");

    let o = wgtrace(&["render", &scene, "--light-sampling", "nee"]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("[possible values: bsdf, mixture, mis]"), "{e}");

    let ok_out = dir.join("x.png").display().to_string();
    let o = wgtrace(&["render", &scene, "--spp", "0", "-o", &ok_out]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("render.spp"));

    // an output or checkpoint that cannot be written is refused before the render starts
    // (no device opened), with the cause said once
    let missing = dir.join("no-such-folder");
    for (args, what) in [
        (
            vec![
                "-o".to_string(),
                missing.join("x.png").display().to_string(),
            ],
            "cannot write image",
        ),
        (
            vec![
                "-o".to_string(),
                ok_out.clone(),
                "--checkpoint".to_string(),
                missing.join("x.ckpt").display().to_string(),
            ],
            "cannot write checkpoint",
        ),
        (
            vec![
                "-o".to_string(),
                ok_out.clone(),
                "--error-map".to_string(),
                missing.join("e.exr").display().to_string(),
            ],
            "cannot write image",
        ),
    ] {
        let mut all = vec!["render".to_string(), scene.clone()];
        all.extend(args);
        let o = wgtrace(&all.iter().map(String::as_str).collect::<Vec<_>>());
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{e}");
        assert!(e.contains("no-such-folder") && e.contains(what), "{e}");
        assert!(
            !e.contains("device:"),
            "refused only after opening the device: {e}"
        );
        assert_eq!(e.matches("No such file or directory").count(), 1, "{e}");
    }
}

/// Without any Vulkan driver (the loader pointed at no ICD), `render` says so in one line
/// and renders on the CPU; `info` says there is none.
#[test]
fn without_vulkan_render_falls_back_to_the_cpu_in_one_line() {
    let dir = tmp_dir("novulkan");
    let out = dir.join("c.png").display().to_string();
    let scene = cornell();
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_wgtrace"))
            .args(args)
            .env("VK_ICD_FILENAMES", dir.join("none.json"))
            .env("VK_DRIVER_FILES", dir.join("none.json"))
            .output()
            .unwrap()
    };
    let o = run(&[
        "render", &scene, "-o", &out, "--spp", "1", "--width", "16", "--height", "16", "-q",
    ]);
    assert!(o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    let notes: Vec<&str> = e
        .lines()
        .filter(|l| l.contains("no Vulkan adapter"))
        .collect();
    assert_eq!(notes.len(), 1, "{e}");
    assert!(notes[0].contains("rendering on the CPU instead"), "{e}");
    assert!(e.contains("device: CPU reference"), "{e}");
    assert_eq!(image::open(&out).unwrap().width(), 16);
    let o = run(&["info"]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("no Vulkan adapter found"));
}

#[test]
fn info_lists_the_vulkan_adapters() {
    let o = wgtrace(&["info"]);
    assert!(o.status.success());
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(
        s.starts_with("[0] "),
        "no Vulkan adapter listed (install mesa-vulkan-drivers):\n{s}"
    );
    assert!(s.contains("Vulkan"), "{s}");
}

/// `features` lists what a scene uses and the shader sizes; `--tune no-specialize` renders
/// with the full shader, and an unknown knob is refused with the list of knobs.
#[test]
fn features_lists_the_scene_and_no_specialize_renders() {
    let scene = cornell();
    let o = wgtrace(&["features", &scene]);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    for line in [
        "triangle         yes",
        "sphere           yes",
        "box              -",
        "metal            -",
    ] {
        assert!(text.contains(line), "{text}");
    }
    // the Cornell box (MIS, no textures, few enough primitives for the plain loop) has its
    // records written into its shader: it binds 3 of the 9 scene bindings
    assert!(
        text.contains("bvh              -")
            && text.contains("primitive_loop   yes")
            && text.contains("trace shader: specialized")
            && text.contains("3 bindings; full")
            && text.contains("records written into the shader: primitives, materials, emitters"),
        "{text}"
    );
    let out = tmp_dir("full").join("f.png");
    let o = render_to(&out, &["--tune", "no-specialize,no-russian-roulette"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = wgtrace(&["render", &scene, "--tune", "fast"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && err.contains("unknown tuning knob \"fast\"")
            && err.contains("no-bvh"),
        "{err}"
    );
}

/// `--tune lane-stats` counts the GPU's live lanes with subgroup operations: every share
/// of a scene with a BVH is a fraction of the subgroup above 0, with steps per sample; the
/// CPU backend refuses it.
#[test]
fn lane_stats_report_the_share_of_live_lanes() {
    let scene = common::repo_path("scenes/mesh.toml").display().to_string();
    let scene = scene.as_str();
    let out = tmp_dir("lanes").join("l.exr");
    let o = wgtrace(&[
        "render",
        scene,
        "--width",
        "32",
        "--height",
        "24",
        "--spp",
        "2",
        "--tune",
        "lane-stats",
        "-o",
        out.to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let line = text
        .lines()
        .find(|l| l.starts_with("live lanes"))
        .expect("no live-lane line");
    // "bounce loop 75.3% (1.56), BVH node steps 41.4% (6.38), BVH primitive tests ..."
    let shares: Vec<f64> = line
        .split('%')
        .filter_map(|s| s.rsplit(' ').next()?.parse().ok())
        .collect();
    assert_eq!(shares.len(), 3, "{line}");
    assert!(shares.iter().all(|&s| s > 0.0 && s <= 100.0), "{line}");
    let o = wgtrace(&["render", scene, "--backend", "cpu", "--tune", "lane-stats"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--backend gpu"));
}

/// A render saves the driver's pipeline cache in `WGTRACE_CACHE_DIR` when the adapter
/// offers one (lavapipe does), whole (no temporary file left); `off` saves nothing.
#[test]
fn the_pipeline_cache_is_saved_where_wgtrace_cache_dir_says() {
    let ctx = wgtrace::gpu::GpuContext::shared(0)
        .unwrap_or_else(|e| panic!("GPU tests need a Vulkan adapter: {e}"));
    let offered = ctx
        .adapter
        .features()
        .contains(wgpu::Features::PIPELINE_CACHE);
    let dir = tmp_dir("pipeline-cache");
    let out = dir.join("c.png");
    let render = |cache: &Path| {
        let o = Command::new(env!("CARGO_BIN_EXE_wgtrace"))
            .args([
                "render",
                &cornell(),
                "--width",
                "8",
                "--height",
                "8",
                "--spp",
                "1",
            ])
            .arg("-o")
            .arg(&out)
            .env("WGTRACE_CACHE_DIR", cache)
            .output()
            .expect("run wgtrace");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    let files = |d: &Path| -> Vec<String> {
        std::fs::read_dir(d)
            .map(|r| {
                r.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                    .collect()
            })
            .unwrap_or_default()
    };
    let cache = dir.join("cache");
    render(&cache);
    let saved = files(&cache);
    if offered {
        assert_eq!(saved.len(), 1, "{saved:?}");
        assert!(
            saved[0].starts_with("wgpu_pipeline_cache_vulkan_") && saved[0].ends_with(".bin"),
            "{saved:?}"
        );
        // a second run loads it and saves it again
        render(&cache);
        assert_eq!(files(&cache), saved);
    } else {
        assert!(saved.is_empty(), "{saved:?}");
    }
    // `off` is a word, not a folder name: no folder `off` appears beside the test
    render(Path::new("off"));
    assert!(!Path::new("off").exists());
}

/// Ctrl-C (SIGINT) stops a render after the current pass, writes the image and a
/// checkpoint, exits 130 and says how to resume; `--resume` with more samples then gives
/// the same file, byte for byte, as one uninterrupted render, on each backend.
#[test]
fn an_interrupted_render_resumes_to_the_uninterrupted_image() {
    for backend in ["gpu", "cpu"] {
        let dir = tmp_dir(&format!("resume-{backend}"));
        let (ckpt, resumed, whole) = (dir.join("r.ckpt"), dir.join("r.exr"), dir.join("w.exr"));
        let base = [
            "render",
            &cornell(),
            "--backend",
            backend,
            "--width",
            "8",
            "--height",
            "8",
            "-q",
        ];
        let child = Command::new(env!("CARGO_BIN_EXE_wgtrace"))
            .args(base)
            .args([
                "--spp",
                "1000000",
                "--checkpoint-every",
                "0",
                "--checkpoint",
            ])
            .arg(&ckpt)
            .arg("-o")
            .arg(&resumed)
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("run wgtrace");
        let start = std::time::Instant::now();
        while !ckpt.exists() {
            assert!(start.elapsed().as_secs() < 120, "no checkpoint appeared");
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        // the shell's own kill: no procps needed
        let kill = Command::new("sh")
            .args(["-c", &format!("kill -INT {}", child.id())])
            .status()
            .expect("run sh");
        assert!(kill.success());
        let out = child.wait_with_output().expect("wait for wgtrace");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(130), "{stderr}");
        assert!(stderr.contains("--resume") && resumed.exists(), "{stderr}");
        let held = wgtrace::checkpoint::Checkpoint::read(&ckpt)
            .unwrap()
            .samples;
        assert_eq!(held.len(), 1, "{held:?}");
        let passes = held[0].end;
        assert!(passes >= 1);
        let spp = (passes + 8).to_string();
        let run = |extra: &[&str], out: &Path| {
            run_ok(&[&base[..], &["--spp", &spp], extra].concat(), out)
        };
        run(&["--resume", &ckpt.display().to_string()], &resumed);
        run(&[], &whole);
        assert!(
            std::fs::read(&resumed).unwrap() == std::fs::read(&whole).unwrap(),
            "{backend}: resumed after {passes} passes differs from the uninterrupted render"
        );
    }
}

/// A checkpoint that is not whole, or from another scene, settings, size or version, or
/// with more samples than asked for, is refused with a message naming it.
#[test]
fn a_corrupt_or_mismatched_checkpoint_is_refused() {
    let dir = tmp_dir("bad-checkpoint");
    let ckpt = dir.join("c.ckpt");
    let out = dir.join("c.png");
    let render_sized = |scene: &str, width: &str, extra: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_wgtrace"))
            .args([
                "render",
                scene,
                "--width",
                width,
                "--height",
                "8",
                "-q",
                "--backend",
            ])
            .args(["cpu", "-o"])
            .arg(&out)
            .args(extra)
            .output()
            .expect("run wgtrace");
        (
            o.status.success(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let render = |scene: &str, extra: &[&str]| render_sized(scene, "8", extra);
    let c = ckpt.display().to_string();
    let (ok, _) = render(&cornell(), &["--spp", "4", "--checkpoint", &c]);
    assert!(ok);
    let good = std::fs::read(&ckpt).unwrap();
    let refused = |extra: &[&str], scene: &str, needle: &str| {
        let (ok, err) = render(scene, extra);
        assert!(!ok && err.contains(&c) && err.contains(needle), "{err}");
    };
    let resume = ["--resume", c.as_str()];
    let spheres = common::repo_path("scenes/spheres.toml")
        .display()
        .to_string();
    refused(&resume, &spheres, "different scene");
    refused(
        &[&resume[..], &["--seed", "5"]].concat(),
        &cornell(),
        "different scene",
    );
    let (ok, err) = render_sized(&cornell(), "9", &resume);
    assert!(
        !ok && err.contains("holds a 8x8 image, the render is 9x8"),
        "{err}"
    );
    refused(
        &[&resume[..], &["--spp", "2"]].concat(),
        &cornell(),
        "already holds samples up to index 4",
    );
    std::fs::write(&ckpt, &good[..good.len() - 1]).unwrap();
    refused(&resume, &cornell(), "truncated");
    std::fs::write(&ckpt, b"not a checkpoint").unwrap();
    refused(&resume, &cornell(), "no checkpoint header");
    let mut other = good.clone();
    let at = other.windows(7).position(|w| w == b"version").unwrap();
    let end = at + other[at..].iter().position(|&b| b == b'\n').unwrap();
    other.splice(at..end, b"version = 0.0.0".iter().copied());
    std::fs::write(&ckpt, &other).unwrap();
    refused(&resume, &cornell(), "written by wgtrace 0.0.0");
    // the good one still resumes (to 8 spp)
    std::fs::write(&ckpt, &good).unwrap();
    let (ok, err) = render(&cornell(), &[&resume[..], &["--spp", "8"]].concat());
    assert!(ok, "{err}");
}

/// Four sample ranges rendered apart and merged give the image of one render of all the
/// samples, up to the rounding of adding the sums in another order (each pixel a sum of 16
/// samples: within 16 x 4 f32 epsilons, relative); overlapping ranges and checkpoints of
/// another scene are refused.
#[test]
fn merged_sample_ranges_equal_one_render() {
    let dir = tmp_dir("merge");
    let scene = cornell();
    let base = |extra: &[&str], out: &Path| {
        let args = ["render", &scene, "--width", "12", "--height", "8", "-q"];
        run_ok(&[&args[..], &["--spp", "16"], extra].concat(), out)
    };
    let mut parts = Vec::new();
    for (i, range) in ["0..4", "4..8", "8..12", "12..16"].iter().enumerate() {
        let ckpt = dir.join(format!("part{i}.ckpt"));
        let c = ckpt.display().to_string();
        base(
            &["--sample-range", range, "--checkpoint", &c],
            &dir.join(format!("part{i}.exr")),
        );
        parts.push(c);
    }
    let whole = dir.join("whole.exr");
    base(&[], &whole);
    let merged = dir.join("merged.exr");
    let merge = |inputs: &[&str], out: &Path| {
        Command::new(env!("CARGO_BIN_EXE_wgtrace"))
            .arg("merge")
            .args(inputs)
            .arg("-o")
            .arg(out)
            .output()
            .expect("run wgtrace")
    };
    // in any order
    let order: Vec<&str> = [3, 0, 2, 1].iter().map(|&i| parts[i].as_str()).collect();
    let o = merge(&order, &merged);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        stdout.contains("16 spp (samples 0..16) from 4 checkpoints"),
        "{stdout}"
    );
    let read = |p: &Path| image::open(p).unwrap().to_rgb32f().into_raw();
    let (a, b) = (read(&merged), read(&whole));
    assert_eq!(a.len(), b.len());
    let bound = 16.0 * 4.0 * f32::EPSILON;
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() <= bound * y.abs().max(1e-6), "{x} vs {y}");
    }
    // overlap: 0..4 twice
    let o = merge(&[&parts[0], &parts[0]], &merged);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("overlap"), "{err}");
    // another scene
    let other = dir.join("other.ckpt");
    let o = Command::new(env!("CARGO_BIN_EXE_wgtrace"))
        .args([
            "render",
            &common::repo_path("scenes/spheres.toml")
                .display()
                .to_string(),
        ])
        .args(["--width", "12", "--height", "8", "-q", "--spp", "16"])
        .args(["--sample-range", "4..8", "-o"])
        .arg(dir.join("other.png"))
        .arg("--checkpoint")
        .arg(&other)
        .output()
        .expect("run wgtrace");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = merge(&[&parts[0], &other.display().to_string()], &merged);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("scene"), "{err}");
}

/// An image split into bands of one row, each with its own accumulation buffer (as an
/// image larger than one storage binding is), gives the same file, byte for byte, as one
/// band; so does a checkpoint written and resumed in bands. With splatted samples too
/// (Mitsuba's Gaussian, `reconstruction = "splat"`), whose gather reads the samples of
/// the bands above and below each one.
#[test]
fn banded_and_whole_renders_are_identical() {
    let dir = tmp_dir("bands");
    let splat = dir.join("cornell-splat.toml");
    let src = std::fs::read_to_string(cornell()).unwrap();
    std::fs::write(
        &splat,
        src.replacen(
            "[render]\n",
            "[render]\nfilter = \"gaussian\"\nreconstruction = \"splat\"\n",
            1,
        ),
    )
    .unwrap();
    for scene in [cornell(), splat.display().to_string()] {
        let run = |rows: bool, extra: &[&str], out: &Path| {
            let mut cmd = Command::new(env!("CARGO_BIN_EXE_wgtrace"));
            cmd.args(["render", &scene, "--width", "64", "--height", "48", "-q"])
                .args(extra)
                .arg("-o")
                .arg(out);
            if rows {
                // 100 pixels per band at most: 48 bands of one row
                cmd.args(["--tune", "band-pixels=100"]);
            }
            let o = cmd.output().expect("run wgtrace");
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        };
        let (whole, banded, resumed) = (dir.join("w.exr"), dir.join("b.exr"), dir.join("r.exr"));
        run(false, &["--spp", "4"], &whole);
        run(true, &["--spp", "4"], &banded);
        let ckpt = dir.join("r.ckpt").display().to_string();
        run(true, &["--spp", "2", "--checkpoint", &ckpt], &resumed);
        run(true, &["--spp", "4", "--resume", &ckpt], &resumed);
        let bytes = |p: &Path| std::fs::read(p).unwrap();
        assert!(bytes(&whole) == bytes(&banded), "{scene}: banded differs");
        assert!(
            bytes(&whole) == bytes(&resumed),
            "{scene}: banded resume differs"
        );
    }
}

/// While the driver compiles a shader no sample is in flight: the render says it is
/// waiting, and a first Ctrl-C ends it at once (exit 130), writing nothing. The full
/// shader, with every cache off, keeps llvmpipe compiling for minutes.
#[test]
fn ctrl_c_while_the_driver_compiles_ends_at_once() {
    use std::io::{BufRead, BufReader};
    let dir = tmp_dir("compile-interrupt");
    let png = dir.join("c.png");
    let mut child = Command::new(env!("CARGO_BIN_EXE_wgtrace"))
        .args([
            "render",
            &cornell(),
            "--tune",
            "no-specialize",
            "--spp",
            "1",
        ])
        .args(["--width", "8", "--height", "8", "-o"])
        .arg(&png)
        .env("WGTRACE_CACHE_DIR", "off")
        .env("MESA_SHADER_CACHE_DISABLE", "true")
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run wgtrace");
    let mut stderr = BufReader::new(child.stderr.take().unwrap());
    let mut seen = String::new();
    loop {
        let mut line = String::new();
        if stderr.read_line(&mut line).unwrap() == 0 {
            panic!("wgtrace ended without a compile notice:\n{seen}");
        }
        seen += &line;
        if line.contains("waiting for the driver to compile") {
            break;
        }
    }
    assert!(seen.contains("Ctrl-C ends at once"), "{seen}");
    let kill = Command::new("sh")
        .args(["-c", &format!("kill -INT {}", child.id())])
        .status()
        .expect("run sh");
    assert!(kill.success());
    let sent = std::time::Instant::now();
    let status = child.wait().expect("wait for wgtrace");
    let took = sent.elapsed();
    assert_eq!(status.code(), Some(130), "{seen}");
    assert!(took.as_secs_f64() < 5.0, "it took {took:?} to end");
    assert!(!png.exists(), "an image was written");
}
