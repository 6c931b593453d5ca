//! Specialization benchmark: for every scene in `scenes/`, the trace shader specialized to
//! the scene's features against the full shader (`--tune no-specialize`), side by side in one
//! run on the first Vulkan adapter: shader size, bindings bound, pipeline compile time, time
//! to the first image, and samples per second. Then what the caches on disk give a second
//! process. Writes `docs/specialization.md`.
//!
//! Run: `cargo bench --bench specialization`. The two shaders of a scene are measured in
//! alternating order over ROUNDS rounds and medians are reported; timings come from one run
//! on whatever machine runs it, so compare ratios within the report, not across machines.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use wgtrace::gpu::plan::{scene_features, Feature, GpuPlan};
use wgtrace::gpu::{GpuContext, GpuRenderer};
use wgtrace::session::Passes;
use wgtrace::{FlatScene, Overrides, Session, SessionOptions, StopRule, Tuning};

/// Image width of every measurement (height keeps the scene's aspect).
const WIDTH: u32 = 128;
/// Rounds of (specialized, full) or (full, specialized), alternating.
const ROUNDS: usize = 3;
/// Passes after the first are timed until this much time has passed.
const MIN_TIME: Duration = Duration::from_millis(1000);

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn scene_files() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(root().join("scenes"))
        .expect("scenes/")
        .map(|e| e.expect("scenes/ entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
}

/// One shader's figures on one scene, from one child process.
#[derive(Clone, Copy, Default)]
struct Measure {
    /// Opening the device.
    open: f64,
    /// Creating the pipeline (assembling, validating, wgpu and the driver's compile step).
    compile: f64,
    /// Creating the pipeline, uploading the scene, one pass, readback.
    first_image: f64,
    /// Samples per second over the passes after the first.
    rate: f64,
    /// Time to first image of a second render of the scene in the same process.
    second: f64,
    bytes: usize,
    bindings: usize,
    /// Size of wgtrace's pipeline cache file after the run.
    wgpu_cache_bytes: u64,
}

/// The child: opens the device (Mesa's shader cache is where the parent says), then
/// measures the scene with one shader and prints one line of figures.
fn child(scene_path: &Path, full: bool) {
    let start = Instant::now();
    let ctx = GpuContext::shared(0)
        .unwrap_or_else(|e| panic!("the benchmark needs a Vulkan adapter: {e}"));
    let open = start.elapsed().as_secs_f64();
    let scene = load(scene_path);
    let tuning = if full {
        Tuning::parse("no-specialize").unwrap()
    } else {
        Tuning::default()
    };
    let start = Instant::now();
    let plan = GpuPlan::new(&scene, &ctx.fit(), &tuning);
    let pipeline = ctx
        .trace_pipeline(&plan.shader)
        .expect("compile the trace pipeline");
    let compile = pipeline.compile_time.as_secs_f64();
    let session = |scene: &FlatScene| {
        let r = GpuRenderer::new(ctx.clone(), scene, &tuning).expect("renderer");
        let engine = wgtrace::Engine::Gpu(Box::new(r));
        let opts = SessionOptions {
            passes: Passes::Uncapped,
            ..Default::default()
        };
        Session::with_engine(scene.clone(), engine, opts).expect("session")
    };
    let one = StopRule {
        until: Some(1),
        ..Default::default()
    };
    let mut s = session(&scene);
    s.run(&one, |_| {}).expect("first pass");
    let first_image = start.elapsed().as_secs_f64();
    // passes for MIN_TIME, in the session's own batches
    let timed = StopRule {
        time_limit: Some(MIN_TIME),
        ..Default::default()
    };
    let rate = s
        .run(&timed, |_| {})
        .expect("passes")
        .progress
        .samples_per_second();
    let start = Instant::now();
    session(&scene).run(&one, |_| {}).expect("pass");
    let second = start.elapsed().as_secs_f64();
    println!(
        "RESULT {open} {compile} {first_image} {rate} {second} {} {}",
        pipeline.shader_bytes,
        pipeline.slots.len()
    );
}

/// Runs the child for `scene` with Mesa's shader cache in `cache` and reads its figures.
fn run_child(scene: &Path, full: bool, cache: &Path) -> Measure {
    let out = Command::new(std::env::current_exe().expect("own path"))
        .arg("--child")
        .arg(scene)
        .arg(if full { "full" } else { "specialized" })
        .env("MESA_SHADER_CACHE_DIR", cache)
        .env_remove("MESA_SHADER_CACHE_DISABLE")
        .env("WGTRACE_CACHE_DIR", cache.join("wgtrace"))
        .stderr(std::process::Stdio::null())
        .output()
        .expect("run the child");
    assert!(out.status.success(), "child failed on {}", scene.display());
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text
        .lines()
        .find_map(|l| l.strip_prefix("RESULT "))
        .unwrap_or_else(|| panic!("no figures from the child: {text}"));
    let v: Vec<f64> = line
        .split_whitespace()
        .map(|x| x.parse().expect("a number"))
        .collect();
    Measure {
        open: v[0],
        compile: v[1],
        first_image: v[2],
        rate: v[3],
        second: v[4],
        bytes: v[5] as usize,
        bindings: v[6] as usize,
        wgpu_cache_bytes: std::fs::read_dir(cache.join("wgtrace"))
            .map(|d| {
                d.filter_map(|e| e.ok()?.metadata().ok())
                    .map(|m| m.len())
                    .sum()
            })
            .unwrap_or(0),
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Medians over rounds.
fn medians(runs: &[Measure]) -> Measure {
    let m = |f: fn(&Measure) -> f64| median(runs.iter().map(f).collect());
    Measure {
        open: m(|r| r.open),
        compile: m(|r| r.compile),
        first_image: m(|r| r.first_image),
        rate: m(|r| r.rate),
        second: m(|r| r.second),
        bytes: runs[0].bytes,
        bindings: runs[0].bindings,
        wgpu_cache_bytes: runs.iter().map(|r| r.wgpu_cache_bytes).max().unwrap_or(0),
    }
}

struct Row {
    name: String,
    width: u32,
    height: u32,
    features: Vec<String>,
    /// Specialized with an empty shader cache (cold), specialized with the cache the cold
    /// run filled (warm), full with a warm cache.
    cold: Measure,
    warm: Measure,
    full: Measure,
}

/// The scene at [`WIDTH`].
fn load(path: &Path) -> FlatScene {
    let probe = wgtrace::load_scene(path, &Overrides::default()).expect("scene");
    let height = ((WIDTH as f64 * probe.height as f64 / probe.width as f64).round() as u32).max(1);
    wgtrace::load_scene(
        path,
        &Overrides {
            width: Some(WIDTH),
            height: Some(height),
            ..Default::default()
        },
    )
    .expect("scene")
}

/// A fresh, empty folder for one child's caches.
fn fresh_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("wgtrace-spec-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("cache folder");
    dir
}

/// Every scene's rows: in each round, specialized cold then warm and full warm (in
/// alternating order), each in its own process.
fn scene_row(path: &Path, full_cache: &Path) -> Row {
    let scene = load(path);
    let mut runs: [Vec<Measure>; 3] = Default::default();
    for round in 0..ROUNDS {
        let cache = fresh_dir("scene");
        let full_first = round % 2 == 1;
        if full_first {
            runs[2].push(run_child(path, true, full_cache));
        }
        runs[0].push(run_child(path, false, &cache));
        runs[1].push(run_child(path, false, &cache));
        if !full_first {
            runs[2].push(run_child(path, true, full_cache));
        }
        let _ = std::fs::remove_dir_all(&cache);
    }
    let row = Row {
        name: path.file_name().unwrap().to_string_lossy().into_owned(),
        width: scene.width,
        height: scene.height,
        features: scene_features(&scene).iter().map(Feature::name).collect(),
        cold: medians(&runs[0]),
        warm: medians(&runs[1]),
        full: medians(&runs[2]),
    };
    eprintln!(
        "{}: first image {:.3} s cold / {:.3} s warm / {:.3} s full warm, {:.0} / {:.0} samples/s (specialized / full)",
        row.name,
        row.cold.first_image,
        row.warm.first_image,
        row.full.first_image,
        row.warm.rate,
        row.full.rate
    );
    row
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(i) = args.iter().position(|a| a == "--child") {
        child(Path::new(&args[i + 1]), args[i + 2] == "full");
        return;
    }
    let scenes = scene_files();
    // the full shader is the same for every scene: its cold compile is measured once per
    // round, on the first scene, and its cache then serves every scene's full runs
    let full_cache = fresh_dir("full");
    let mut full_cold = Vec::new();
    for _ in 0..ROUNDS {
        let cache = fresh_dir("full-cold");
        full_cold.push(run_child(&scenes[0], true, &cache));
        let _ = std::fs::remove_dir_all(&cache);
    }
    run_child(&scenes[0], true, &full_cache);
    let full_cold = medians(&full_cold);
    eprintln!(
        "full shader, cold: first image {:.1} s on {}",
        full_cold.first_image,
        scenes[0].display()
    );
    let rows: Vec<Row> = scenes.iter().map(|p| scene_row(p, &full_cache)).collect();
    let _ = std::fs::remove_dir_all(&full_cache);
    let ctx = GpuContext::shared(0)
        .unwrap_or_else(|e| panic!("the benchmark needs a Vulkan adapter: {e}"));
    let device = wgtrace::gpu::context::describe(&ctx.info);
    let report = report(&rows, &full_cold, &scenes[0], &device, ctx.has_disk_cache());
    let out = root().join("docs/specialization.md");
    std::fs::write(&out, report).expect("write docs/specialization.md");
    eprintln!("wrote {}", out.display());
}

fn report(rows: &[Row], full_cold: &Measure, first: &Path, device: &str, disk: bool) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Per-scene shader specialization, measured\n");
    let _ = writeln!(
        s,
        "Written on {} by `cargo bench --bench specialization` on {device}. For each scene in \
         `scenes/`, at {WIDTH} pixels wide (the scene's aspect), the trace shader assembled \
         for the scene's features (*spec.*) is measured against the full shader that \
         `--tune no-specialize` uses (*full*: all {} feature defines; sampler, light sampling and \
         BVH chosen at run time). Each figure comes from its own process, the median of \
         {ROUNDS} rounds in alternating order. *cold*: Mesa's shader cache starts empty; \
         *warm*: a second process with the cache the first one filled. Pipeline: creating \
         the pipeline (assembling, naga validation, wgpu, the driver's pipeline call). First \
         image: pipeline, upload, one sample per pixel, readback. Samples/s: the passes after \
         the first, for at least {:.1} s, one submission per pass. One run on one shared \
         machine: compare ratios within a table.\n",
        wgtrace::report::today(),
        Feature::all().count(),
        MIN_TIME.as_secs_f64()
    );
    let _ = writeln!(
        s,
        "| scene | size | features | shader KB spec. / full | bindings spec. / full | pipeline (s) spec. / full | first image cold (s) spec. | first image warm (s) spec. / full | samples/s spec. / full | speed-up |"
    );
    let _ = writeln!(s, "|---|---|---|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {}x{} | {} | {:.1} / {:.1} | {} / {} | {:.3} / {:.3} | {:.2} | {:.3} / {:.3} | {:.0} / {:.0} | {:.2}x |",
            r.name,
            r.width,
            r.height,
            r.features.join(" "),
            r.warm.bytes as f64 / 1024.0,
            r.full.bytes as f64 / 1024.0,
            r.warm.bindings,
            r.full.bindings,
            r.warm.compile,
            r.full.compile,
            r.cold.first_image,
            r.warm.first_image,
            r.full.first_image,
            r.warm.rate,
            r.full.rate,
            r.warm.rate / r.full.rate
        );
    }
    let summary = |v: Vec<f64>| {
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(0.0, f64::max);
        format!("{:.2}x (from {lo:.2}x to {hi:.2}x)", median(v))
    };
    let _ = writeln!(
        s,
        "\nMedian over the scenes, specialized against full: {} the samples per second, \
         pipeline creation {} faster, first image with a warm cache {} sooner.\n",
        summary(rows.iter().map(|r| r.warm.rate / r.full.rate).collect()),
        summary(
            rows.iter()
                .map(|r| r.full.compile / r.warm.compile)
                .collect()
        ),
        summary(
            rows.iter()
                .map(|r| r.full.first_image / r.warm.first_image)
                .collect()
        ),
    );
    let colds: Vec<f64> = rows.iter().map(|r| r.cold.first_image).collect();
    let _ = writeln!(
        s,
        "**Cold start.** The full shader is the same for every scene; with an empty cache its \
         first image took {:.1} s ({}), almost all of it llvmpipe compiling the shader to \
         machine code at the first dispatch (creating the pipeline took {:.2} s). The \
         specialized shaders' cold first images took {:.2} s (median; {:.2} to {:.2} s): each \
         feature set is compiled once per machine, then served from Mesa's cache.\n",
        full_cold.first_image,
        first.file_name().unwrap().to_string_lossy(),
        full_cold.compile,
        median(colds.clone()),
        colds.iter().copied().fold(f64::INFINITY, f64::min),
        colds.iter().copied().fold(0.0, f64::max),
    );
    let seconds: Vec<f64> = rows.iter().map(|r| r.warm.second).collect();
    let _ = writeln!(
        s,
        "**Within a process.** One device per adapter serves every render of a process and \
         keeps one pipeline per feature set: a second render of the same scene got its first \
         image in {:.3} s (median; {:.3} to {:.3} s), with no pipeline to create.\n",
        median(seconds.clone()),
        seconds.iter().copied().fold(f64::INFINITY, f64::min),
        seconds.iter().copied().fold(0.0, f64::max),
    );
    let _ =
        writeln!(
        s,
        "**Across processes.** wgtrace keeps wgpu's pipeline cache (a Vulkan `VkPipelineCache`) \
         in `~/.cache/wgtrace` (`WGTRACE_CACHE_DIR` moves it; `off` disables it) on adapters \
         that offer it; this adapter {}. What makes a second process start fast on lavapipe \
         is Mesa's own shader cache (`~/.cache/mesa_shader_cache`): lavapipe's pipeline cache \
         holds only a header ({} bytes here), so wgpu's cache adds nothing on lavapipe; on \
         drivers that fill it, it saves the driver's compile.\n",
        if disk {
            "offers it"
        } else {
            "does not offer it"
        },
        rows.iter().map(|r| r.cold.wgpu_cache_bytes).max().unwrap_or(0)
    );
    let _ = writeln!(s, "## Where specialization does not pay\n");
    let slow: Vec<String> = rows
        .iter()
        .filter(|r| r.warm.rate < 1.05 * r.full.rate)
        .map(|r| format!("{} ({:.2}x)", r.name, r.warm.rate / r.full.rate))
        .collect();
    if slow.is_empty() {
        let _ = writeln!(
            s,
            "- In samples per second, nowhere here: every scene ran at least 5% faster with \
             its specialized shader."
        );
    } else {
        let _ = writeln!(
            s,
            "- Samples per second within 5% of the full shader, or lower: {}.",
            slow.join(", ")
        );
    }
    // how long a render with the (cached) full shader must run before the specialized
    // shader's cold compile is paid back by its higher rate
    let payback: Vec<(String, f64)> = rows
        .iter()
        .filter(|r| r.warm.rate > r.full.rate)
        .map(|r| {
            let extra = r.cold.first_image - r.full.first_image;
            (
                r.name.clone(),
                (extra / (1.0 - r.full.rate / r.warm.rate)).max(0.0),
            )
        })
        .collect();
    let longest = payback
        .iter()
        .cloned()
        .fold((String::new(), 0.0), |a, b| if b.1 > a.1 { b } else { a });
    let _ = writeln!(
        s,
        "- The first render of a feature set on a machine whose Mesa cache already holds the \
         full shader: the specialized shader's cold compile is then an extra cost. It is \
         paid back from the first image on {} of {} scenes (the cold compile is quicker than \
         the full shader's warm start); the longest wait is {}'s: a render with the full \
         shader would have to run {:.0} s before the specialized one, compile included, \
         finishes first. Each feature set is a pipeline and a cold compile of its own: \
         `wgtrace converge`, which runs every sampler with every light-sampling strategy, \
         compiles one pipeline per combination where the full shader would compile once.\n\
         - On a real GPU, where untaken branches cost little, the gain in samples per second \
         is expected to be smaller than on llvmpipe, which runs both sides of a branch \
         under a mask; no GPU was available for this run.",
        payback.iter().filter(|p| p.1 == 0.0).count(),
        rows.len(),
        longest.0,
        longest.1
    );
    s
}
