//! Performance benchmark: wgtrace on the first Vulkan adapter (lavapipe here) against
//! Mitsuba 3 (`llvm_ad_rgb`) on the Cornell box of `bench/` (the same scene in both
//! formats), then how wgtrace's time scales with resolution, samples, path length and
//! triangle count, its memory at 1080p and 4K, and what each optimization kept gave.
//! Writes `docs/performance.md` and `docs/performance-scaling.svg`.
//!
//! Run: `cargo bench --bench performance` (about 15 minutes on 2 cores). The Mitsuba part
//! needs `pip install mitsuba` and an LLVM of 15 or newer named by `DRJIT_LIBLLVM_PATH`
//! (Debian 12: `apt-get install libllvm19`); without them it is reported as not run. Every
//! figure comes from child processes run in alternating order over ROUNDS rounds, as
//! medians with their range; compare ratios within one report, not across machines.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use wgtrace::converge::rel_mse;
use wgtrace::gpu::bindings::{Slot, UNIFORM_BYTES};
use wgtrace::gpu::render::{ACCUM_BYTES_PER_PIXEL, MAX_DISPATCHES_PER_SUBMISSION, MAX_TILE_PIXELS};
use wgtrace::scene::textures::load_image;

const ROUNDS: usize = 3;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn scratch() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("wgtrace-performance-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    if s.is_empty() {
        return f64::NAN;
    }
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

/// "median (min to max)".
fn spread(v: &[f64], digits: usize) -> String {
    let (lo, hi) = range(v);
    format!("{:.d$} ({:.d$} to {:.d$})", median(v), lo, hi, d = digits)
}

/// The smallest and the largest value.
fn range(v: &[f64]) -> (f64, f64) {
    v.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        })
}

/// One wgtrace process: the summary line's render seconds and rate, the wall time of the
/// whole process, and its peak resident memory where GNU time is installed.
#[derive(Clone, Copy, Debug)]
struct Run {
    render: f64,
    msps: f64,
    wall: f64,
    peak_mib: Option<f64>,
}

fn gnu_time() -> Option<PathBuf> {
    let p = PathBuf::from("/usr/bin/time");
    p.exists().then_some(p)
}

/// Runs `wgtrace render SCENE ARGS -o OUT -q` and parses its summary line.
fn wgtrace(scene: &Path, args: &[&str], out: &Path) -> Run {
    let bin = env!("CARGO_BIN_EXE_wgtrace");
    let report = out.with_extension("time");
    let mut cmd = match gnu_time() {
        Some(t) => {
            let mut c = Command::new(t);
            c.arg("-f").arg("%M").arg("-o").arg(&report).arg(bin);
            c
        }
        None => Command::new(bin),
    };
    cmd.arg("render")
        .arg(scene)
        .args(args)
        .arg("-o")
        .arg(out)
        .arg("-q");
    let start = Instant::now();
    let o = cmd.output().expect("run wgtrace");
    let wall = start.elapsed().as_secs_f64();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "wgtrace {args:?} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    // "OUT: WxH, N spp, S s, R Msamples/s, ..."
    let field = |after: &str| -> f64 {
        let tail = text.split(after).next().unwrap_or("");
        tail.rsplit([' ', ','])
            .find(|s| !s.is_empty())
            .unwrap_or("")
            .parse()
            .unwrap_or(f64::NAN)
    };
    let peak_mib = std::fs::read_to_string(&report)
        .ok()
        .and_then(|s| s.lines().last()?.trim().parse::<f64>().ok())
        .map(|kib| kib / 1024.0);
    Run {
        render: field(" s, "),
        msps: field(" Msamples/s"),
        wall,
        peak_mib,
    }
}

/// One Mitsuba process (bench/mitsuba_render.py): load, first render (kernel compile or
/// cache load), steady render, whole process.
#[derive(Clone, Copy, Debug)]
struct MiRun {
    load: f64,
    first: f64,
    steady: f64,
    wall: f64,
}

fn llvm_path() -> Option<String> {
    std::env::var("DRJIT_LIBLLVM_PATH").ok().or_else(|| {
        [
            "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1",
            "/usr/lib/x86_64-linux-gnu/libLLVM-19.so",
        ]
        .into_iter()
        .find(|p| Path::new(p).exists())
        .map(String::from)
    })
}

fn mitsuba(res: u32, spp: u32, seed: u32, out: &Path, renders: u32) -> Result<MiRun, String> {
    let llvm = llvm_path().ok_or("no LLVM >= 15 found (DRJIT_LIBLLVM_PATH)")?;
    let start = Instant::now();
    let o = Command::new("python3")
        .arg(root().join("bench/mitsuba_render.py"))
        .arg(root().join("bench/cornell.xml"))
        .args([res.to_string(), spp.to_string(), seed.to_string()])
        .arg(out)
        .arg(renders.to_string())
        .env("DRJIT_LIBLLVM_PATH", llvm)
        .output()
        .map_err(|e| format!("python3: {e}"))?;
    let wall = start.elapsed().as_secs_f64();
    if !o.status.success() {
        let err = String::from_utf8_lossy(&o.stderr);
        return Err(err.lines().last().unwrap_or("failed").to_string());
    }
    let text = String::from_utf8_lossy(&o.stdout);
    let line = text.lines().last().unwrap_or("");
    let num = |key: &str| -> f64 {
        line.split(&format!("\"{key}\": "))
            .nth(1)
            .and_then(|s| s.split([',', '}']).next())
            .and_then(|s| s.trim_start_matches('[').parse().ok())
            .unwrap_or(f64::NAN)
    };
    let renders: Vec<f64> = line
        .split("\"renders\": [")
        .nth(1)
        .and_then(|s| s.split(']').next())
        .map(|s| s.split(',').filter_map(|x| x.trim().parse().ok()).collect())
        .unwrap_or_default();
    Ok(MiRun {
        load: num("load"),
        first: renders.first().copied().unwrap_or(f64::NAN),
        steady: renders.last().copied().unwrap_or(f64::NAN),
        wall,
    })
}

fn rgb(path: &Path) -> Vec<f32> {
    let img = load_image(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    img.texels.iter().flat_map(|t| [t[0], t[1], t[2]]).collect()
}

/// The bench Cornell box with its first sphere replaced by an icosphere of `level`
/// subdivisions (20 * 4^level triangles), written by the `gen_mesh` example.
fn mesh_scene(dir: &Path, level: u32) -> PathBuf {
    let obj = dir.join(format!("ico{level}.obj"));
    let status = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .current_dir(root())
        .args(["run", "--release", "--quiet", "--example", "gen_mesh", "--"])
        .args(["icosphere", "--subdivisions", &level.to_string(), "-o"])
        .arg(&obj)
        .stdout(std::process::Stdio::null())
        .status()
        .expect("run gen_mesh");
    assert!(status.success(), "gen_mesh failed");
    let src = std::fs::read_to_string(root().join("bench/cornell.toml")).unwrap();
    let sphere = "type = \"sphere\"\ncenter = [-0.4, -0.62, -0.35]\nradius = 0.38";
    assert!(src.contains(sphere));
    // a unit icosphere moved where the sphere was (meshes are baked into world space)
    let src = src.replace(
        sphere,
        &format!(
            "type = \"mesh\"\npath = \"{}\"\ntransform = {{ scale = 0.38, translate = [-0.4, -0.62, -0.35] }}",
            obj.display()
        ),
    );
    let path = dir.join(format!("ico{level}.toml"));
    std::fs::write(&path, src).unwrap();
    path
}

fn main() {
    let dir = scratch();
    let scene = root().join("bench/cornell.toml");
    let mut md = String::new();
    let _ = writeln!(md, "# Performance\n");
    let _ = writeln!(
        md,
        "Written by `cargo bench --bench performance` (benches/performance.rs) on {}; every \
         figure is the median of {ROUNDS} child processes run in alternating order, with \
         their range in parentheses. lavapipe is Mesa's software Vulkan driver: it runs the \
         shader on the CPU, here on the same 2 cores Mitsuba uses.\n",
        adapter_line()
    );

    // Warm Mesa's shader cache for every variant measured below, so that no row pays a
    // first compile the others do not.
    for args in variants() {
        let mut a: Vec<&str> = vec!["--spp", "1", "--width", "16", "--height", "16"];
        a.extend(args.1.iter());
        wgtrace(&scene, &a, &dir.join("warm.png"));
    }

    comparison(&mut md, &dir, &scene);
    optimizations(&mut md, &dir, &scene);
    scaling(&mut md, &dir, &scene);
    memory(&mut md, &dir, &scene);
    let _ = writeln!(
        md,
        "\n## On a real GPU\n\nNot measured: the device tool reported `can_start_another: \
         false` for this task, so no GPU was lent. `wgtrace render bench/cornell.toml` on a \
         machine with one prints its samples per second."
    );
    let path = root().join("docs/performance.md");
    std::fs::write(&path, md).expect("write docs/performance.md");
    println!("wrote {}", path.display());
}

fn adapter_line() -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_wgtrace"))
        .arg("info")
        .output();
    o.ok()
        .and_then(|o| {
            String::from_utf8_lossy(&o.stdout)
                .lines()
                .next()
                .map(|l| l.trim_start_matches("[0] ").to_string())
        })
        .unwrap_or_else(|| "an unknown adapter".into())
}

/// The optimization toggles, cumulative: (label, `--tune` knobs turned off).
fn variants() -> Vec<(&'static str, Vec<&'static str>)> {
    let tuned = |knobs: &'static str| -> Vec<&'static str> {
        if knobs.is_empty() {
            Vec::new()
        } else {
            vec!["--tune", knobs]
        }
    };
    vec![
        (
            "before: storage buffers, BVH, no Russian roulette",
            tuned("no-uniform-records,no-texture-records,bvh,no-russian-roulette,no-baked-records,no-sample-groups"),
        ),
        (
            "+ uniform-buffer records",
            tuned("bvh,no-russian-roulette,no-baked-records,no-sample-groups"),
        ),
        (
            "+ plain loop for small scenes",
            tuned("no-russian-roulette,no-baked-records,no-sample-groups"),
        ),
        (
            "+ Russian roulette",
            tuned("no-baked-records,no-sample-groups"),
        ),
        (
            "+ records written into the shader",
            tuned("no-sample-groups"),
        ),
        ("+ sample groups (all kept)", tuned("")),
    ]
}

fn comparison(md: &mut String, dir: &Path, scene: &Path) {
    let _ = writeln!(md, "## Against Mitsuba 3\n");
    let _ = writeln!(
        md,
        "The Cornell box of `bench/cornell.toml` and its Mitsuba twin `bench/cornell.xml`: \
         path tracing with emitter sampling and MIS, max depth 8, Russian roulette from the \
         fourth ray (survival min(1, max throughput) in wgtrace, min(0.95, max throughput) \
         in Mitsuba), independent random samples, box pixel filter, the same spp for both. \
         Mitsuba 3 runs its `llvm_ad_rgb` variant (Dr.Jit's LLVM backend, all cores). \
         *Samples/s* is the steady rate: wgtrace's render time as it reports it, \
         Mitsuba's second render in its process (the first compiles or loads its kernels). \
         *Process* is the whole command, start-up, scene loading and shader compilation \
         included (wgtrace with Mesa's shader cache warm, Mitsuba with Dr.Jit's kernel \
         cache warm after the first round).\n"
    );
    // the shared reference: both renderers at high spp, averaged
    let ref_spp = 512;
    let wref = dir.join("ref-wgtrace.exr");
    let mref = dir.join("ref-mitsuba.exr");
    let probe = mitsuba(256, ref_spp, 1000, &mref, 1);
    if let Err(e) = &probe {
        let _ = writeln!(md, "Not run: Mitsuba 3 could not render ({e}).\n");
        return;
    }
    wgtrace(
        scene,
        &["--spp", &ref_spp.to_string(), "--seed", "1000"],
        &wref,
    );
    let (w, m) = (rgb(&wref), rgb(&mref));
    let reference: Vec<f32> = w.iter().zip(&m).map(|(a, b)| 0.5 * (a + b)).collect();
    let floor = rel_mse(&w, &m);
    let mut rows = Vec::new();
    for (res, spp) in [(256u32, 64u32), (1024, 16)] {
        let (mut wr, mut mr) = (Vec::new(), Vec::new());
        let (mut werr, mut merr) = (Vec::new(), Vec::new());
        for round in 0..ROUNDS {
            let seed = round as u32;
            let wout = dir.join(format!("w{res}.exr"));
            let mout = dir.join(format!("m{res}.exr"));
            let args = [
                "--width".to_string(),
                res.to_string(),
                "--height".to_string(),
                res.to_string(),
                "--spp".to_string(),
                spp.to_string(),
                "--seed".to_string(),
                seed.to_string(),
            ];
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            let mut run_w = || {
                let r = wgtrace(scene, &args, &wout);
                if res == 256 {
                    werr.push(rel_mse(&rgb(&wout), &reference));
                }
                wr.push(r);
            };
            let mut run_m = || {
                let r = mitsuba(res, spp, seed, &mout, 2).expect("mitsuba ran before");
                if res == 256 {
                    merr.push(rel_mse(&rgb(&mout), &reference));
                }
                mr.push(r);
            };
            if round % 2 == 0 {
                run_w();
                run_m();
            } else {
                run_m();
                run_w();
            }
        }
        let samples = (res * res * spp) as f64 / 1e6;
        let w_rate: Vec<f64> = wr.iter().map(|r| r.msps).collect();
        let m_rate: Vec<f64> = mr.iter().map(|r| samples / r.steady).collect();
        let w_wall: Vec<f64> = wr.iter().map(|r| r.wall).collect();
        let m_wall: Vec<f64> = mr.iter().map(|r| r.wall).collect();
        let m_first: Vec<f64> = mr.iter().map(|r| r.load + r.first).collect();
        let w_render: Vec<f64> = wr.iter().map(|r| r.render).collect();
        let m_steady: Vec<f64> = mr.iter().map(|r| r.steady).collect();
        rows.push((
            res,
            spp,
            w_rate.clone(),
            m_rate.clone(),
            w_wall,
            m_wall,
            m_first,
        ));
        if res == 256 {
            // time to equal error: relMSE falls as 1/time for both, so the time to reach
            // any error e is relMSE x seconds / e; the ratio of those products is the
            // ratio of times to equal error
            let we = median(&werr) * median(&w_render);
            let me = median(&merr) * median(&m_steady);
            let _ = writeln!(
                md,
                "Error at 256 x 256 and 64 spp against a shared reference (the mean of \
                 wgtrace's and Mitsuba's {ref_spp}-spp renders; they differ from each other \
                 by a relMSE of {floor:.2e}): wgtrace {} in {} s, Mitsuba {} in {} s. \
                 **Time to equal error, wgtrace / Mitsuba: {:.2}** (relMSE x seconds, which \
                 is constant while the error is noise).\n",
                spread_e(&werr),
                spread(&w_render, 2),
                spread_e(&merr),
                spread(&m_steady, 2),
                we / me
            );
        }
    }
    let _ = writeln!(
        md,
        "| size | spp | wgtrace Msamples/s | Mitsuba Msamples/s | ratio | wgtrace process s | Mitsuba process s | Mitsuba load + first render s |\n|---|---|---|---|---|---|---|---|"
    );
    for (res, spp, w, m, ww, mw, mf) in rows {
        let _ = writeln!(
            md,
            "| {res} x {res} | {spp} | {} | {} | **{:.2}** | {} | {} | {} |",
            spread(&w, 3),
            spread(&m, 3),
            median(&w) / median(&m),
            spread(&ww, 2),
            spread(&mw, 2),
            spread(&mf, 2)
        );
    }
    let _ = writeln!(md);
}

fn spread_e(v: &[f64]) -> String {
    let (lo, hi) = range(v);
    format!("{:.3e} ({lo:.2e} to {hi:.2e})", median(v))
}

fn optimizations(md: &mut String, dir: &Path, scene: &Path) {
    let _ = writeln!(
        md,
        "## What each optimization gave\n\nCornell (`bench/cornell.toml`) at 256 x 256, 16 \
         spp, on lavapipe, each optimization added to the ones above it (the `--tune` \
         knobs turn each back off). Russian roulette adds noise, so its row also gives relMSE x \
         seconds against a 256-spp render without it (lower is better).\n"
    );
    let reference = dir.join("opt-ref.exr");
    wgtrace(
        scene,
        &[
            "--spp",
            "256",
            "--seed",
            "77",
            "--tune",
            "no-russian-roulette",
        ],
        &reference,
    );
    let reference = rgb(&reference);
    let vars = variants();
    let mut rates = vec![Vec::new(); vars.len()];
    let mut cost = vec![Vec::new(); vars.len()];
    for round in 0..ROUNDS {
        let order: Vec<usize> = if round % 2 == 0 {
            (0..vars.len()).collect()
        } else {
            (0..vars.len()).rev().collect()
        };
        for i in order {
            let out = dir.join(format!("opt{i}.exr"));
            let seed = round.to_string();
            let mut args = vec!["--spp", "16", "--seed", &seed];
            args.extend(vars[i].1.iter());
            let r = wgtrace(scene, &args, &out);
            rates[i].push(r.msps);
            cost[i].push(rel_mse(&rgb(&out), &reference) * r.render);
        }
    }
    let _ = writeln!(
        md,
        "| configuration | flags | Msamples/s | x before | relMSE x s |\n|---|---|---|---|---|"
    );
    let base = median(&rates[0]);
    for (i, (label, flags)) in vars.iter().enumerate() {
        let _ = writeln!(
            md,
            "| {label} | `{}` | {} | {:.2} | {} |",
            if flags.is_empty() {
                "(default)".to_string()
            } else {
                flags.join(" ")
            },
            spread(&rates[i], 3),
            median(&rates[i]) / base,
            spread_e(&cost[i])
        );
    }
    let _ = writeln!(
        md,
        "\nMeasured by hand, not by this command: the 8 x 8 workgroup against 4 x 4 and \
         16 x 16 (0.73, 0.38 and 0.68 Msamples/s on the same render), and the naga bounds \
         checks and loop bounding turned off (`create_shader_module_trusted`, no change: \
         lavapipe checks bounds itself), and lavapipe's `LP_NUM_THREADS` (1: 0.41 to 0.44, \
         2, the default on 2 cores: 0.78 to 0.90, 4: 0.78 to 0.81 Msamples/s). The per-scene shader specialization has its own \
         report, [specialization.md](specialization.md).\n\n\
         Shader code without flags, so measured by hand too: the sphere and triangle tests \
         and direct lighting without early returns (llvmpipe runs both sides of every branch \
         under a mask, so a return saves nothing and costs a masked update of every live \
         value), shadow rays searching for any hit, and `choose_light` counting the running \
         sums instead of a binary search. `bench/jit-loop-size.sh` counts the instructions of \
         the bounce loop in lavapipe's JIT code, a measure that does not drift with the \
         machine's load: 5325 before, 4540 after; alternating renders of the Cornell box at \
         48 spp took 0.82 s before and 0.67 s after (median of 5).\n"
    );
}

fn scaling(md: &mut String, dir: &Path, scene: &Path) {
    let _ = writeln!(
        md,
        "## How time scales\n\nwgtrace on lavapipe, `bench/cornell.toml` with one setting \
         changed at a time from 256 x 256, 4 spp, max depth 8; render seconds as wgtrace \
         reports them (median of {ROUNDS}). For triangles, the first sphere is replaced by \
         an icosphere mesh (20 x 4^k triangles; past 16 primitives the BVH is walked).\n"
    );
    let base = ["--width", "256", "--height", "256", "--spp", "4"];
    let time = |args: &[String], scene: &Path| -> f64 {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        median(
            &(0..ROUNDS)
                .map(|_| wgtrace(scene, &args, &dir.join("scale.png")).render)
                .collect::<Vec<_>>(),
        )
    };
    let with = |key: &str, value: String| -> Vec<String> {
        let mut a: Vec<String> = base.iter().map(|s| s.to_string()).collect();
        if let Some(i) = a.iter().position(|s| s == key) {
            a[i + 1] = value;
        } else {
            a.push(key.to_string());
            a.push(value);
        }
        if key == "--width" {
            let v = a[a.iter().position(|s| s == "--width").unwrap() + 1].clone();
            let i = a.iter().position(|s| s == "--height").unwrap();
            a[i + 1] = v;
        }
        a
    };
    let mut series: Vec<(&str, Vec<(f64, f64)>)> = Vec::new();
    let res: Vec<(f64, f64)> = [128u32, 256, 512, 1024]
        .iter()
        .map(|&r| ((r * r) as f64, time(&with("--width", r.to_string()), scene)))
        .collect();
    series.push(("pixels", res));
    let spp: Vec<(f64, f64)> = [1u32, 4, 16, 64]
        .iter()
        .map(|&s| (s as f64, time(&with("--spp", s.to_string()), scene)))
        .collect();
    series.push(("samples per pixel", spp));
    let depth: Vec<(f64, f64)> = [1u32, 2, 4, 8, 16]
        .iter()
        .map(|&d| (d as f64, time(&with("--max-depth", d.to_string()), scene)))
        .collect();
    series.push(("max depth", depth));
    let tris: Vec<(f64, f64)> = [1u32, 2, 3, 4, 5, 6]
        .iter()
        .map(|&k| {
            let s = mesh_scene(dir, k);
            (
                20.0 * 4f64.powi(k as i32),
                time(&with("--spp", "4".into()), &s),
            )
        })
        .collect();
    series.push(("triangles", tris));
    for (name, pts) in &series {
        let slope = loglog_slope(pts);
        let cells: Vec<String> = pts
            .iter()
            .map(|(x, t)| format!("{x:.0}: {t:.3} s"))
            .collect();
        let _ = writeln!(
            md,
            "- **{name}** (log-log slope {slope:.2}): {}",
            cells.join(", ")
        );
    }
    let _ = writeln!(
        md,
        "\n![time against each setting, log-log](performance-scaling.svg)\n"
    );
    plot(&series, &root().join("docs/performance-scaling.svg"));
}

/// Least-squares slope of log t against log x.
fn loglog_slope(pts: &[(f64, f64)]) -> f64 {
    let n = pts.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = pts.iter().map(|&(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx).powi(2)).sum();
    sxy / sxx
}

fn plot(series: &[(&str, Vec<(f64, f64)>)], path: &Path) {
    use plotters::prelude::*;
    let root = SVGBackend::new(path, (900, 620)).into_drawing_area();
    root.fill(&WHITE).unwrap();
    let areas = root.split_evenly((2, 2));
    for ((name, pts), area) in series.iter().zip(areas.iter()) {
        let (x0, x1) = pts
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.0), b.max(p.0)));
        let (y0, y1) = pts
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.1), b.max(p.1)));
        let mut chart = ChartBuilder::on(area)
            .caption(format!("render seconds against {name}"), ("sans-serif", 16))
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(50)
            .build_cartesian_2d(
                (x0 * 0.8..x1 * 1.25).log_scale(),
                (y0 * 0.8..y1 * 1.25).log_scale(),
            )
            .unwrap();
        chart
            .configure_mesh()
            .x_desc(*name)
            .y_desc("s")
            .draw()
            .unwrap();
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), &BLUE))
            .unwrap();
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 3, BLUE.filled())))
            .unwrap();
    }
    root.present().unwrap();
}

fn memory(md: &mut String, dir: &Path, scene: &Path) {
    let _ = writeln!(
        md,
        "## Memory at 1080p and 4K\n\n`bench/cornell.toml`, 1 spp. Peak host memory is the \
         process's maximum resident set (GNU time); lavapipe's GPU memory is host memory \
         too, so it is included. GPU buffers are what wgtrace allocates: the accumulation \
         (32 bytes per pixel, in bands of at most 2^18 pixels), the readback buffer of one \
         band, the per-dispatch parameters (256 blocks of 256 bytes) and the scene's \
         records (64 KiB per uniform record array).\n"
    );
    let _ = writeln!(
        md,
        "| size | peak host MiB | GPU buffers MiB | render s |\n|---|---|---|---|"
    );
    for (w, h, name) in [(1920u32, 1080u32, "1080p"), (3840, 2160, "4K")] {
        let args = [
            "--width".to_string(),
            w.to_string(),
            "--height".to_string(),
            h.to_string(),
            "--spp".to_string(),
            "1".to_string(),
        ];
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let runs: Vec<Run> = (0..ROUNDS)
            .map(|_| wgtrace(scene, &args, &dir.join("mem.png")))
            .collect();
        let peak: Vec<f64> = runs.iter().filter_map(|r| r.peak_mib).collect();
        let pixels = w as f64 * h as f64;
        // the same sizes as gpu::render allocates (a parameter block of 256 bytes, the
        // stride on this adapter)
        let per_pixel = ACCUM_BYTES_PER_PIXEL as f64;
        let band = pixels.min(MAX_TILE_PIXELS as f64);
        let params = MAX_DISPATCHES_PER_SUBMISSION as f64 * 256.0;
        let records = Slot::RECORDS.len() as f64 * UNIFORM_BYTES as f64;
        let gpu = (per_pixel * (pixels + band) + params + records) / (1u64 << 20) as f64;
        let _ = writeln!(
            md,
            "| {name} ({w} x {h}) | {} | {gpu:.1} | {} |",
            if peak.is_empty() {
                "not measured (no /usr/bin/time)".into()
            } else {
                spread(&peak, 0)
            },
            spread(&runs.iter().map(|r| r.render).collect::<Vec<_>>(), 2)
        );
    }
}
