//! Spot-check cost benchmark: for every scene of the benchmark suite (`bench/*.toml`, the
//! real meshes of `../shared/meshes` included) at 256 x 256, the spot check every GPU render
//! runs before it accumulates (`wgtrace::spot_check`: the first sample of the image on the
//! GPU, in the render's own dispatches, against 400 of its pixels on the CPU reference), against the render it guards, 64 samples per pixel, in one
//! run on the first Vulkan adapter. The pipeline is compiled before either is timed (a
//! render compiles it whether or not it is checked). Writes `docs/bench/spot-check.md`.
//!
//! Run: `cargo bench --bench spot_check`. Medians of ROUNDS; compare the ratios within the
//! report, not its seconds across machines.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use wgtrace::gpu::GpuContext;
use wgtrace::spot_check;
use wgtrace::{Overrides, Tuning};

const SIZE: u32 = 256;
const SPP: u32 = 64;
const ROUNDS: usize = 3;

fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v[v.len() / 2]
}

fn main() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<PathBuf> = std::fs::read_dir(root.join("bench"))
        .expect("bench/")
        .map(|e| e.expect("bench/ entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    // the suite's generated inputs (a 1M-triangle heightfield, texture maps), written by
    // the performance benchmark when missing
    if !root.join("bench/generated/terrain-1m.obj").exists() {
        let ok = std::process::Command::new(env!("CARGO"))
            .args(["bench", "--bench", "performance", "--", "--generate"])
            .current_dir(&root)
            .status()
            .expect("running cargo");
        assert!(ok.success(), "generating the suite's inputs failed");
    }
    let ctx = GpuContext::shared(0).unwrap_or_else(|e| panic!("{e}"));
    let device = wgtrace::gpu::context::describe(&ctx.info);
    let o = Overrides {
        width: Some(SIZE),
        height: Some(SIZE),
        spp: Some(SPP),
        ..Default::default()
    };
    let mut table = String::new();
    let mut shares = Vec::new();
    let mut fallbacks = Vec::new();
    for path in &files {
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        let scene = wgtrace::load_scene(path, &o).unwrap_or_else(|e| panic!("{e}"));
        // the renderer a render gets: where the driver renders the default placements
        // wrong, the check's fallback (timed below on the placement it settles on); its
        // first dispatch waited on the driver's compile, not the check's cost
        let mut r = spot_check::open_checked(ctx.clone(), &scene, &Tuning::default())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        if r.note().is_some() {
            fallbacks.push(name.clone());
        }
        let zero = vec![[0.0; 4]; r.accumulation().unwrap().len()];
        let (mut gpu, mut cpu, mut total, mut pass, mut render) =
            (vec![], vec![], vec![], vec![], vec![]);
        for _ in 0..ROUNDS {
            let start = Instant::now();
            let v = spot_check::check(&mut r, &scene).unwrap();
            total.push(start.elapsed());
            gpu.push(v.gpu_time);
            cpu.push(v.cpu_time);
            // the check's GPU pass is the render's first sample, which the render keeps:
            // what it costs the render is the check less that pass
            r.set_accumulation(&zero).unwrap();
            let start = Instant::now();
            r.render_samples(0..1).unwrap();
            r.accumulation().unwrap();
            pass.push(start.elapsed());
            let start = Instant::now();
            r.set_accumulation(&zero).unwrap();
            r.render_samples(0..SPP).unwrap();
            r.accumulation().unwrap();
            render.push(start.elapsed());
        }
        let (gpu, cpu, total, pass, render) = (
            median(gpu),
            median(cpu),
            median(total),
            median(pass),
            median(render),
        );
        let net = total.saturating_sub(pass);
        let share = net.as_secs_f64() / render.as_secs_f64();
        shares.push((share, name.clone(), total));
        eprintln!(
            "{name}: spot check {:.1} ms (GPU {:.1}, CPU {:.1}; the first sample's pass {:.1}), \
             render {:.2} s: {:.2}%",
            total.as_secs_f64() * 1e3,
            gpu.as_secs_f64() * 1e3,
            cpu.as_secs_f64() * 1e3,
            pass.as_secs_f64() * 1e3,
            render.as_secs_f64(),
            100.0 * share
        );
        writeln!(
            table,
            "| {name} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.2} | {:.2}% |",
            scene.primitives.len(),
            gpu.as_secs_f64() * 1e3,
            cpu.as_secs_f64() * 1e3,
            total.as_secs_f64() * 1e3,
            pass.as_secs_f64() * 1e3,
            net.as_secs_f64() * 1e3,
            render.as_secs_f64(),
            100.0 * share
        )
        .unwrap();
    }
    let geo = (shares.iter().map(|s| s.0.max(1e-6).ln()).sum::<f64>() / shares.len() as f64).exp();
    let worst = shares
        .iter()
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .expect("scenes");
    let slowest = shares.iter().map(|s| s.2).max().expect("scenes");
    let report = format!(
        "# The spot check's cost\n\n\
         Written on {} by `cargo bench --bench spot_check` on {device}.\n\n\
         Every GPU render first renders its first sample on the GPU, the whole image in the \
         render's own dispatches, and {} of its pixels ({} x {} tiles of {} x {}) on the CPU \
         reference, and compares them (`src/spot_check.rs`); the render keeps that pass as its \
         first sample, so the check costs it the check's time less the pass's (`net`). Here it \
         is timed against the render it guards, {SIZE} x {SIZE} at {SPP} samples per pixel, on \
         every scene of the benchmark suite, medians of {ROUNDS} rounds in one run, after the \
         pipeline's compile (which a render pays with or without the check).\n\n\
         | scene | primitives | GPU ms | CPU ms | check ms | first sample's pass ms | net ms | render s | net / render |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---:|\n{table}\n\
         Geometric mean of net / render: {:.2}%; worst: {:.2}% ({}); longest check: {:.0} ms.\n\n\
         Scenes whose render fell back to safer record placements (timed on the placement it \
         settled on; its first checks come on top): {}.\n",
        wgtrace::report::today(),
        spot_check::GRID * spot_check::GRID * spot_check::TILE * spot_check::TILE,
        spot_check::GRID,
        spot_check::GRID,
        spot_check::TILE,
        spot_check::TILE,
        100.0 * geo,
        100.0 * worst.0,
        worst.1,
        slowest.as_secs_f64() * 1e3,
        if fallbacks.is_empty() {
            "none".to_string()
        } else {
            fallbacks.join(", ")
        }
    );
    let out = root.join("docs/bench/spot-check.md");
    std::fs::write(&out, &report).unwrap();
    eprintln!("{report}wrote {}", out.display());
}
