//! BVH benchmark: samples per second for height-field meshes of about 1k, 10k, 100k and 1M
//! triangles, with the BVH and with brute force (every triangle tested on every ray), on the
//! first Vulkan adapter and on the CPU reference. Writes `docs/bench/bvh.md`.
//!
//! Run: `cargo bench --bench bvh` (meshes are generated once into `target/bench-meshes/` by
//! `cargo run --release --example gen_mesh`). Timings come from one run on whatever machine
//! runs it; compare ratios within the report, not across machines.

mod common;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use common::samples_per_second;
use glam::Vec3;
use wgtrace::scene::bvh::{self, Aabb};
use wgtrace::{Engine, Overrides, Tuning};

/// Triangle counts asked of the generator (2 N^2 for an N x N grid).
const SIZES: [u64; 4] = [1_000, 10_000, 100_000, 1_000_000];
/// Image side: every primary ray hits the terrain.
const SIDE: u32 = 32;
/// Passes are timed until this much time has passed (after one untimed warm-up pass).
const MIN_TIME: Duration = Duration::from_millis(1500);

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Generates (once) a height field of about `triangles` triangles.
fn mesh(triangles: u64) -> PathBuf {
    let dir = root().join("target/bench-meshes");
    std::fs::create_dir_all(&dir).expect("target/bench-meshes");
    let path = dir.join(format!("heightfield-{triangles}.obj"));
    if !path.exists() {
        let status = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
            .current_dir(root())
            .args(["run", "--release", "--quiet", "--example", "gen_mesh", "--"])
            .args(["heightfield", "--triangles", &triangles.to_string(), "-o"])
            .arg(&path)
            .status()
            .expect("run gen_mesh");
        assert!(status.success(), "gen_mesh failed");
    }
    path
}

fn scene_text(mesh: &Path) -> String {
    format!(
        "[render]\nwidth = {SIDE}\nheight = {SIDE}\nspp = 1\nmax_depth = 2\n\
         [camera]\nlook_from = [0, 3, 1.5]\nlook_at = [0, 0, 0]\nvfov = 40\n\
         [background]\ncolor = [0.7, 0.8, 1.0]\n\
         [materials]\nground = {{ type = \"lambertian\", albedo = [0.5, 0.5, 0.5] }}\n\
         [[objects]]\ntype = \"mesh\"\npath = \"{}\"\nmaterial = \"ground\"\n",
        mesh.display()
    )
}

struct Row {
    triangles: usize,
    load: f64,
    /// `bvh::build` alone over the triangles' boxes.
    build: f64,
    nodes: usize,
    depth: u32,
    /// GPU and CPU, with and without the BVH, in samples per second; None where the GPU
    /// refuses the work (llvmpipe's loop limit, see `gpu::limits::LLVMPIPE_LOOP_LIMIT`).
    rates: [Option<f64>; 4],
}

fn main() {
    let mut rows = Vec::new();
    let mut device = String::new();
    for &n in &SIZES {
        let path = mesh(n);
        let src = scene_text(&path);
        let load = |no_bvh: bool| {
            let knobs = if no_bvh { "no-bvh" } else { "" };
            wgtrace::scene::load_str(
                &src,
                Path::new("bench.toml"),
                &Overrides::default(),
                Tuning::parse(knobs).unwrap().build(),
            )
            .expect("bench scene")
        };
        let start = Instant::now();
        let with = load(false);
        let load_time = start.elapsed().as_secs_f64();
        let without = load(true);
        let boxes: Vec<Aabb> = with
            .primitives
            .iter()
            .map(|p| {
                let [a, b, c] = [p.a, p.b, p.c].map(|v| Vec3::from_slice(&v));
                Aabb {
                    lo: a.min(b).min(c),
                    hi: a.max(b).max(c),
                }
            })
            .collect();
        let start = Instant::now();
        let tree = bvh::build(&boxes);
        let build = start.elapsed().as_secs_f64();
        assert_eq!(tree.nodes.len(), with.bvh_node_count());
        let mut rates = [None; 4];
        for (k, scene) in [&with, &without].into_iter().enumerate() {
            match Engine::gpu(scene, 0) {
                Ok(gpu) => {
                    device = gpu.name();
                    rates[k] = Some(samples_per_second(gpu, scene, MIN_TIME));
                }
                Err(e @ wgtrace::gpu::GpuError::LoopLimit { .. }) => eprintln!("GPU: {e}"),
                Err(e) => panic!("the benchmark needs a Vulkan adapter: {e}"),
            }
            rates[2 + k] = Some(samples_per_second(Engine::cpu(scene), scene, MIN_TIME));
        }
        let row = Row {
            triangles: with.primitives.len(),
            load: load_time,
            build,
            nodes: with.bvh_node_count(),
            depth: with.bvh_depth,
            rates,
        };
        eprintln!(
            "{:>9} triangles: load {:.2} s, GPU {} / {} samples/s, CPU {} / {} samples/s (BVH / brute force)",
            row.triangles,
            row.load,
            rate(rates[0]),
            rate(rates[1]),
            rate(rates[2]),
            rate(rates[3])
        );
        rows.push(row);
    }
    let report = report(&rows, &device);
    let out = root().join("docs/bench/bvh.md");
    std::fs::write(&out, report).expect("write docs/bench/bvh.md");
    eprintln!("wrote {}", out.display());
}

fn rate(r: Option<f64>) -> String {
    r.map_or("n/a".into(), |r| format!("{r:.0}"))
}

fn ratio(a: Option<f64>, b: Option<f64>) -> String {
    match (a, b) {
        (Some(a), Some(b)) => format!("{:.0}x", a / b),
        _ => "n/a".into(),
    }
}

fn report(rows: &[Row], device: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# BVH: cost versus triangle count\n");
    let _ = writeln!(
        s,
        "Written on {} by `cargo bench --bench bvh`. Height-field meshes (`gen_mesh heightfield`), \
         {SIDE}x{SIDE} pixels, max_depth 2 (a primary ray and one bounce toward a uniform sky), \
         samples per second over at least {:.1} s after one warm-up pass. Load: reading the OBJ, \
         flattening and building the BVH; BVH build: `bvh::build` alone. GPU: {device}. \
         CPU reference: {} threads. One run on one machine: compare ratios within this table.\n",
        wgtrace::report::today(),
        MIN_TIME.as_secs_f64(),
        rayon::current_num_threads()
    );
    let _ = writeln!(
        s,
        "| triangles | load (s) | BVH build (s) | BVH nodes | depth | GPU BVH (samples/s) | GPU brute force | GPU speed-up | CPU BVH (samples/s) | CPU brute force | CPU speed-up | GPU us/sample / log2 n |"
    );
    let _ = writeln!(
        s,
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    for r in rows {
        let per_log = r.rates[0].map(|g| 1e6 / g / (r.triangles as f64).log2());
        let _ = writeln!(
            s,
            "| {} | {:.2} | {:.3} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.triangles,
            r.load,
            r.build,
            r.nodes,
            r.depth,
            rate(r.rates[0]),
            rate(r.rates[1]),
            ratio(r.rates[0], r.rates[1]),
            rate(r.rates[2]),
            rate(r.rates[3]),
            ratio(r.rates[2], r.rates[3]),
            per_log.map_or("n/a".into(), |v| format!("{v:.3}"))
        );
    }
    let (first, last) = (&rows[0], &rows[rows.len() - 1]);
    let growth = |k: usize| match (first.rates[k], last.rates[k]) {
        (Some(a), Some(b)) => format!("{:.1}x", a / b),
        _ => "n/a".into(),
    };
    let _ = writeln!(
        s,
        "\nFrom {} to {} triangles ({:.0}x more), a sample with the BVH costs {} more on the \
         GPU and {} more on the CPU, while log2 n grows {:.1}x; with brute force a CPU sample \
         costs {} more.",
        first.triangles,
        last.triangles,
        last.triangles as f64 / first.triangles as f64,
        growth(0),
        growth(2),
        (last.triangles as f64).log2() / (first.triangles as f64).log2(),
        growth(3)
    );
    let _ = writeln!(
        s,
        "\nn/a: llvmpipe (lavapipe) runs at most {} loop iterations per shader invocation, \
         counted over all loops together, and then silently ends them, so brute force over \
         more primitives than that (times max_depth) cannot run there; the renderer refuses \
         it (`GpuError::LoopLimit`) instead of returning a wrong image.",
        wgtrace::gpu::limits::LLVMPIPE_LOOP_LIMIT
    );
    s
}
