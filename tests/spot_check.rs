//! The spot check that guards every GPU render (`wgtrace::spot_check`), proved by fault
//! injection: `--tune perturb=PLACES` changes the GPU side's copy of the records in those
//! placements, as a driver that fetched them wrong would, and the check must catch it,
//! fall back to a safer placement with a note, or refuse the adapter when every placement
//! is wrong. On every scene its verdict is the whole first sample's (so a right driver
//! passes it with no fallback); `wgtrace check` passes and fails the same way.

mod common;

use std::process::Command;

use wgtrace::gpu::GpuError;
use wgtrace::spot_check::{self, MIN_AGREEMENT};
use wgtrace::{Engine, Overrides, Tuning};

fn mesh_scene() -> wgtrace::FlatScene {
    let o = Overrides {
        width: Some(64),
        height: Some(48),
        spp: Some(8),
        ..Default::default()
    };
    wgtrace::load_scene(&common::repo_path("scenes/mesh.toml"), &o)
        .unwrap_or_else(|e| panic!("{e}"))
}

fn engine(scene: &wgtrace::FlatScene, knobs: &str) -> Result<Engine, GpuError> {
    Engine::gpu_tuned(scene, 0, &Tuning::parse(knobs).unwrap())
}

/// On every scene, at its own size and under the default tuning, the spot check's
/// verdict is the whole first sample's: it passes exactly when at least
/// [`MIN_AGREEMENT`] of all the image's pixels agree with the CPU reference. So it does
/// not refuse a right GPU (on a right driver every scene passes with no fallback), and it
/// sees a wrong one: Mesa 22.3.6's lavapipe on an AVX-512 CPU renders the scenes with a
/// BVH wrong unless the nodes are in storage buffers (gltf-spheres: 45% of its pixels
/// agree), which the check, when it rendered only its tiles as small dispatches of their
/// own, passed on all 400 pixels.
#[test]
fn the_spot_check_passes_exactly_where_the_whole_first_sample_agrees() {
    let ctx = std::sync::Arc::new(common::gpu_context());
    let mut worst = (1.0f64, String::new());
    let mut failed = 0;
    // the showcase has a test of its own (common::SHOWCASE says why)
    for path in common::scene_files_but_showcase() {
        let (passed, tiles) = spot_check_verdict_is_the_whole_images(&ctx, &path);
        failed += usize::from(!passed);
        if tiles < worst.0 {
            worst = (tiles, path.display().to_string());
        }
    }
    eprintln!(
        "least agreement {:.4} ({}), bound {MIN_AGREEMENT}; {failed} scenes fall back",
        worst.0, worst.1
    );
}

/// [`the_spot_check_passes_exactly_where_the_whole_first_sample_agrees`] on the showcase.
#[test]
fn the_spot_check_passes_on_the_showcase_exactly_where_its_first_sample_agrees() {
    let ctx = std::sync::Arc::new(common::gpu_context());
    spot_check_verdict_is_the_whole_images(&ctx, &common::repo_path(common::SHOWCASE));
}

/// Asserts that the spot check on `path` passes exactly when the whole first sample agrees;
/// gives whether it passed and the share of its tiles' pixels that agreed.
fn spot_check_verdict_is_the_whole_images(
    ctx: &std::sync::Arc<wgtrace::gpu::GpuContext>,
    path: &std::path::Path,
) -> (bool, f64) {
    let scene = wgtrace::load_scene(path, &Overrides::default()).unwrap_or_else(|e| panic!("{e}"));
    // open_checked falls back exactly when this check fails
    let mut r = wgtrace::gpu::GpuRenderer::new(ctx.clone(), &scene, &Tuning::default()).unwrap();
    let v = spot_check::check(&mut r, &scene).unwrap();
    // the sums hold the first sample the check rendered, the whole image's
    let whole = [scene.full_band()];
    let sums = r.accumulation().unwrap();
    let entries = sums.len() / whole[0].width as usize / whole[0].height as usize;
    let gpu: Vec<[[f32; 4]; 2]> = sums.chunks(entries).map(|e| [e[0], e[1]]).collect();
    let cpu = spot_check::cpu_tiles(&scene, &whole, 0);
    let (agreeing, _) = spot_check::compare(&whole, &gpu, &cpu);
    let share = agreeing as f64 / cpu.len() as f64;
    eprintln!(
        "{}: {}; the whole image: {share:.4} agree",
        path.display(),
        v.describe()
    );
    assert_eq!(
        v.passed(),
        share >= MIN_AGREEMENT,
        "{}: the check says {} but {share:.4} of the whole image agrees",
        path.display(),
        v.describe()
    );
    (v.passed(), v.agreeing as f64 / v.pixels as f64)
}

/// The spot check's pass is the render's first sample, kept in its sums: a render the
/// check opened has the sums of one opened without it, bit for bit (AOVs and sample
/// groups included), its rate leaves that sample out (it is not in the render's time), and
/// samples that do not follow the kept one start from cleared sums.
#[test]
fn the_checked_first_sample_is_the_renders_own() {
    let o = Overrides {
        width: Some(40),
        height: Some(24),
        spp: Some(12),
        ..Default::default()
    };
    let mut scene = wgtrace::load_scene(&common::repo_path("scenes/cornell.toml"), &o)
        .unwrap_or_else(|e| panic!("{e}"));
    scene.aovs = true;
    let checked = common::render(engine(&scene, "").unwrap(), &scene);
    let unchecked = common::render(engine(&scene, "no-spot-check").unwrap(), &scene);
    assert!(checked == unchecked, "the checked render's sums differ");
    // the kept sample is not in the render's time, nor in its rate
    for (knobs, untimed) in [("", scene.pixels()), ("no-spot-check", 0)] {
        let mut session = wgtrace::Session::with_engine(
            scene.clone(),
            engine(&scene, knobs).unwrap(),
            wgtrace::SessionOptions::default(),
        )
        .unwrap();
        let done = session.run(&wgtrace::StopRule::default(), |_| {}).unwrap();
        assert_eq!(done.progress.samples, 12 * scene.pixels(), "{knobs}");
        assert_eq!(done.progress.untimed, untimed, "{knobs}");
    }
    let ctx = std::sync::Arc::new(common::gpu_context());
    let open = || wgtrace::gpu::GpuRenderer::new(ctx.clone(), &scene, &Tuning::default()).unwrap();
    let mut kept = open();
    kept.render_first_sample().unwrap();
    kept.render_samples(3..5).unwrap();
    let mut fresh = open();
    fresh.render_samples(3..5).unwrap();
    assert_eq!(kept.accumulation().unwrap(), fresh.accumulation().unwrap());
    let mut again = open();
    let first = again.render_first_sample().unwrap();
    assert!(first.iter().any(|e| e[3] > 0.0), "no sample counted");
    again.render_samples(0..5).unwrap();
    let mut whole = open();
    whole.render_samples(0..5).unwrap();
    assert_eq!(again.accumulation().unwrap(), whole.accumulation().unwrap());
}

/// Record textures read wrong (the fault of Mesa 22.3.6's lavapipe on AVX-512 CPUs) are
/// caught: the render falls back to storage buffers, says so, and its image matches the
/// CPU reference's.
#[test]
fn wrong_record_textures_are_caught_and_the_render_falls_back() {
    let scene = mesh_scene();
    // the mesh scene keeps its primitives in textures: the fault reaches the render
    let e = engine(&scene, "no-spot-check").unwrap();
    let Engine::Gpu(g) = &e else {
        panic!("a GPU engine")
    };
    assert!(
        spot_check::placements(g.plan()).contains("in textures"),
        "{}",
        spot_check::placements(g.plan())
    );
    let e = engine(&scene, "perturb=texture").expect("a fallback, not a refusal");
    let note = e.note().expect("a note about the fallback").to_string();
    eprintln!("{note}");
    assert!(
        note.contains("in textures") && note.contains("differ"),
        "{note}"
    );
    let Engine::Gpu(g) = &e else {
        panic!("a GPU engine")
    };
    assert!(!spot_check::placements(g.plan()).contains("in textures"));
    let gpu = common::render(e, &scene);
    let cpu = common::render_cpu(&scene);
    let c = common::compare(&gpu, &cpu, 8);
    assert!(c.failed_tiles.is_empty(), "{}", c.failed_tiles.join("\n"));
    assert!(
        c.agree_fraction >= 0.99,
        "{:.4} of pixels agree",
        c.agree_fraction
    );
}

/// Without the spot check the perturbed render is wrong, so the check is what catches it
/// (the fault injection reaches the image), and with every placement perturbed nothing
/// agrees: the adapter is refused, with what differed and the ways out.
#[test]
fn a_gpu_wrong_in_every_placement_is_refused() {
    let scene = mesh_scene();
    let wrong = common::render(
        engine(&scene, "perturb=texture,no-spot-check").unwrap(),
        &scene,
    );
    let cpu = common::render_cpu(&scene);
    let c = common::compare(&wrong, &cpu, 8);
    assert!(
        c.agree_fraction < 0.9,
        "the perturbed render agrees on {:.4} of pixels: the fault does not reach it",
        c.agree_fraction
    );
    for scene in [
        mesh_scene(),
        common::scene_from_file_str(
            include_str!("../scenes/cornell.toml"),
            "scenes/cornell.toml",
        ),
    ] {
        match engine(&scene, "perturb=all") {
            Err(e @ GpuError::WrongResults { .. }) => {
                let m = e.to_string();
                eprintln!("{m}");
                for part in [
                    "llvmpipe",
                    "differ",
                    "--backend cpu",
                    "Mesa",
                    "wgtrace check",
                ] {
                    assert!(m.contains(part), "{part:?} missing from: {m}");
                }
            }
            Err(e) => panic!("another error: {e}"),
            Ok(_) => panic!("a GPU wrong in every placement was accepted"),
        }
    }
}

fn wgtrace(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_wgtrace"))
        .args(args)
        .output()
        .expect("running wgtrace")
}

/// `wgtrace check` on this adapter prints a row per class and placement and passes
/// exactly when every row agrees (on a right driver it passes; Mesa 22.3.6's lavapipe on
/// an AVX-512 CPU fails the rows with a BVH outside storage buffers, and exits non-zero
/// saying how many); its storage-buffer rows, where renders fall back to, agree. It fails,
/// naming the rows and exiting non-zero, when every placement is perturbed; `render`
/// refuses such a GPU the same way.
#[test]
fn wgtrace_check_fails_exactly_on_rows_that_differ() {
    let o = wgtrace(&["check"]);
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    eprintln!("{out}{err}");
    let placements = ["shader", "uniform", "texture", "storage"];
    let rows: Vec<&str> = out
        .lines()
        .filter(|l| {
            let mut w = l.split_whitespace();
            ["list", "bvh", "mesh"].contains(&w.next().unwrap_or(""))
                && placements.contains(&w.next().unwrap_or(""))
        })
        .collect();
    assert_eq!(rows.len(), 12, "{out}");
    for placement in placements {
        assert!(
            rows.iter()
                .any(|r| r.split_whitespace().nth(1) == Some(placement)),
            "no {placement} row: {out}"
        );
    }
    let failing = rows.iter().filter(|r| r.contains("FAIL")).count();
    assert!(
        rows.iter()
            .filter(|r| r.split_whitespace().nth(1) == Some("storage"))
            .all(|r| !r.contains("FAIL")),
        "{out}"
    );
    if failing == 0 {
        assert!(
            o.status.success() && out.contains("all 12 rows agree"),
            "{out}{err}"
        );
    } else {
        assert!(!o.status.success(), "{out}");
        assert!(
            err.contains(&format!("{failing} of 12 rows differ")),
            "{err}"
        );
    }

    let o = wgtrace(&["check", "--tune", "perturb=all"]);
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(!o.status.success(), "a wrong GPU passed the check:\n{out}");
    assert!(err.contains("12 of 12 rows differ"), "{err}");
    assert!(
        out.contains("FAIL") && out.contains("first ray that differs"),
        "{out}"
    );

    let dir = tempfile_dir("refused");
    let png = dir.join("out.png");
    let o = wgtrace(&[
        "render",
        common::repo_path("scenes/cornell.toml").to_str().unwrap(),
        "--spp",
        "1",
        "--width",
        "32",
        "--height",
        "32",
        "--tune",
        "perturb=all",
        "-o",
        png.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success(),
        "a render on a wrong GPU succeeded: {err}"
    );
    assert!(
        err.contains("--backend cpu") && !err.contains("panicked"),
        "{err}"
    );
    assert!(!png.exists(), "a refused render wrote an image");
    let _ = std::fs::remove_dir_all(&dir);
}

fn tempfile_dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("wgtrace-spot-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The spot check's tiles lie inside the image, never overlap, and cover 400 pixels of an
/// image that holds them, fewer of a small one (a 1 x 1 image: its one pixel).
#[test]
fn the_spot_check_tiles_fit_any_image() {
    for (w, h) in [
        (1, 1),
        (2, 3),
        (3, 200),
        (9, 9),
        (10, 13),
        (20, 20),
        (21, 19),
        (64, 48),
        (1920, 1080),
    ] {
        let tiles = spot_check::tiles(w, h);
        let mut seen = std::collections::HashSet::new();
        for t in &tiles {
            assert!(t.x + t.width <= w && t.y + t.height <= h, "{w}x{h}: {t:?}");
            for y in t.y..t.y + t.height {
                for x in t.x..t.x + t.width {
                    assert!(seen.insert((x, y)), "{w}x{h}: pixel ({x}, {y}) twice");
                }
            }
        }
        let full = spot_check::GRID * spot_check::TILE;
        if w >= full && h >= full {
            assert_eq!(seen.len(), (full * full) as usize, "{w}x{h}");
        }
        assert!(!seen.is_empty(), "{w}x{h}: no pixels");
        eprintln!("{w}x{h}: {} tiles, {} pixels", tiles.len(), seen.len());
    }
}
