//! Performance benchmark: wgtrace on the first Vulkan adapter (lavapipe here) against
//! Mitsuba 3 (`llvm_ad_rgb`) on the suite of `bench/` (each scene in both formats: the
//! Cornell box, the Cornell box of triangles, spot.obj in mirror and glass, the Nefertiti
//! scan, a 1M-triangle heightfield under an HDR sky; the meshes from `../shared/meshes/`
//! and gen_mesh), then render time against triangle count, the memory of the 1M-triangle
//! scene, what each optimization kept gave, how time scales with resolution, samples and
//! path length, and memory at 1080p and 4K. Writes `docs/performance.md` and
//! `docs/performance-scaling.svg`.
//!
//! Run: `cargo bench --bench performance` (about 40 minutes on 2 cores). The Mitsuba part
//! needs `pip install mitsuba` (in the Python `$MITSUBA_PYTHON` names, else `python3`) and
//! an LLVM of 15 or newer named by `DRJIT_LIBLLVM_PATH` (Debian 12: `apt-get install
//! libllvm19`); without them it is reported as not run. Every
//! figure comes from child processes run in alternating order over ROUNDS rounds, as
//! medians with their range; compare ratios within one report, not across machines.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use wgtrace::converge::rel_mse;
use wgtrace::gpu::bindings::{Slot, UNIFORM_BYTES};
use wgtrace::gpu::render::{ACCUM_BYTES_PER_PIXEL, MAX_DISPATCHES_PER_SUBMISSION};
use wgtrace::scene::textures::load_image;
use wgtrace::tuning::MAX_BAND_PIXELS;

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

/// One Mitsuba process (bench/mitsuba_render.py): the steady render (the last of its
/// renders; the first compiles or loads Dr.Jit's kernels) and the whole process.
#[derive(Clone, Copy, Debug)]
struct MiRun {
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

/// The Python that has Mitsuba 3: `$MITSUBA_PYTHON`, else `python3`.
fn python() -> String {
    std::env::var("MITSUBA_PYTHON").unwrap_or_else(|_| "python3".into())
}

/// Renders Mitsuba twin `xml` (relative to the repository root) at width `res`.
fn mitsuba(
    xml: &str,
    res: u32,
    spp: u32,
    seed: u32,
    out: &Path,
    renders: u32,
) -> Result<MiRun, String> {
    let llvm = llvm_path().ok_or("no LLVM >= 15 found (DRJIT_LIBLLVM_PATH)")?;
    let start = Instant::now();
    let o = Command::new(python())
        .arg(root().join("bench/mitsuba_render.py"))
        .arg(root().join(xml))
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
    let renders: Vec<f64> = line
        .split("\"renders\": [")
        .nth(1)
        .and_then(|s| s.split(']').next())
        .map(|s| s.split(',').filter_map(|x| x.trim().parse().ok()).collect())
        .unwrap_or_default();
    Ok(MiRun {
        steady: renders.last().copied().unwrap_or(f64::NAN),
        wall,
    })
}

fn rgb(path: &Path) -> Vec<f32> {
    let img = load_image(path, true).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    img.linear()
        .iter()
        .flat_map(|t| [t[0], t[1], t[2]])
        .collect()
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
    // `cargo bench --bench performance -- --generate`: only write the generated inputs of
    // the suite's scenes (bench/generated/), to render them by hand
    if std::env::args().any(|a| a == "--generate") {
        SUITE.iter().for_each(generate);
        return;
    }
    let dir = scratch();
    let scene = root().join("bench/cornell.toml");
    let mut md = String::new();
    let _ = writeln!(md, "# Performance\n");
    let _ = writeln!(
        md,
        "Written on {} by `cargo bench --bench performance` (benches/performance.rs) on {}; every \
         figure is the median of {ROUNDS} child processes run in alternating order, with \
         their range in parentheses. lavapipe is Mesa's software Vulkan driver: it runs the \
         shader on the CPU, here on the same 2 cores Mitsuba uses.\n",
        wgtrace::report::today(),
        adapter_line()
    );

    // the report is written after each part, so a part that fails keeps the ones before.
    // WGTRACE_BENCH_OUT: another report (relative to the repository); WGTRACE_BENCH_PARTS:
    // a comma-separated list of the parts below, for another driver's run of the suite
    let out = std::env::var("WGTRACE_BENCH_OUT").unwrap_or_else(|_| "docs/performance.md".into());
    let parts = std::env::var("WGTRACE_BENCH_PARTS").ok();
    let part = |name: &str| {
        parts
            .as_deref()
            .is_none_or(|p| p.split(',').any(|q| q.trim() == name))
    };
    if let Some(p) = &parts {
        let icd = std::env::var("VK_ICD_FILENAMES")
            .map(|f| format!("; the Vulkan driver is the one `VK_ICD_FILENAMES` names ({f})"))
            .unwrap_or_default();
        let _ = writeln!(
            md,
            "This report holds only the parts `{p}` (`WGTRACE_BENCH_PARTS`){icd}.\n"
        );
    }
    let path = root().join(&out);
    let save = |md: &String| std::fs::write(&path, md).expect("write the report");
    if part("comparison") {
        comparison(&mut md, &dir);
        save(&md);
    }
    if part("media") {
        media(&mut md, &dir);
        save(&md);
    }
    if part("lanes") {
        lanes(&mut md);
        save(&md);
    }
    if part("cornell-large") {
        cornell_large(&mut md, &dir);
        save(&md);
    }
    if part("triangles") {
        triangle_scaling(&mut md, &dir);
        save(&md);
    }
    if part("memory") {
        mesh_memory(&mut md, &dir);
        save(&md);
    }
    if part("optimizations") {
        optimizations(&mut md, &dir);
        save(&md);
    }
    if part("scaling") {
        scaling(&mut md, &dir, &scene);
        save(&md);
        memory(&mut md, &dir, &scene);
        save(&md);
    }
    if parts.is_none() {
        let _ = writeln!(
            md,
            "\n## On a real GPU\n\nNot measured: the device tool reported `can_start_another: \
             false` for this task, so no GPU was lent. `wgtrace render bench/cornell.toml` on a \
             machine with one prints its samples per second."
        );
    }
    save(&md);
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

/// One scene of the suite: its wgtrace file and Mitsuba twin (relative to the repository
/// root), its image size, the spp of the measured renders and of the shared reference.
struct Case {
    name: &'static str,
    toml: &'static str,
    xml: &'static str,
    width: u32,
    height: u32,
    spp: u32,
    ref_spp: u32,
    what: &'static str,
}

/// The benchmark suite: scenes that look like real work, each in both formats with the
/// same settings (path tracing with emitter sampling and MIS, max depth 8, Russian
/// roulette from the fourth ray, independent random samples, box pixel filter).
const SUITE: [Case; 6] = [
    Case {
        name: "cornell",
        toml: "bench/cornell.toml",
        xml: "bench/cornell.xml",
        width: 256,
        height: 256,
        spp: 64,
        ref_spp: 512,
        what: "14 primitives: quads and two spheres",
    },
    Case {
        name: "cornell-triangles",
        toml: "bench/cornell-triangles.toml",
        xml: "bench/cornell-triangles.xml",
        width: 256,
        height: 256,
        spp: 64,
        ref_spp: 512,
        what: "36 triangles: walls, lamp, two boxes",
    },
    Case {
        name: "spot",
        toml: "bench/spot.toml",
        xml: "bench/spot.xml",
        width: 256,
        height: 256,
        spp: 16,
        ref_spp: 256,
        what: "spot.obj twice, mirror and glass: 11,724 triangles",
    },
    Case {
        name: "textured",
        toml: "bench/textured.toml",
        xml: "bench/textured.xml",
        width: 256,
        height: 256,
        spp: 16,
        ref_spp: 256,
        what: "spot.obj twice, textured pbr (base colour, metallic-roughness): 11,724 triangles",
    },
    Case {
        name: "nefertiti",
        toml: "bench/nefertiti.toml",
        xml: "bench/nefertiti.xml",
        width: 256,
        height: 256,
        spp: 16,
        ref_spp: 256,
        what: "nefertiti.obj, a scan: 99,950 triangles",
    },
    Case {
        name: "heightfield",
        toml: "bench/heightfield.toml",
        xml: "bench/heightfield.xml",
        width: 256,
        height: 144,
        spp: 16,
        ref_spp: 256,
        what: "999,698 triangles under the HDR sky",
    },
];

/// Writes the generated files a scene of the suite reads, if they are missing.
fn generate(case: &Case) {
    match case.name {
        "heightfield" => {
            heightfield_obj(1_000_000);
        }
        "textured" => tiles_textures(),
        _ => {}
    }
}

/// The maps of bench/textured.toml and its twin, in bench/generated/ if they are not there
/// yet: 8 x 8 tiles of 64 x 64 texels, mirrored about v = 0.5 (row r and 7 - r alike), a
/// colour per tile (sRGB), a roughness (0.15 to 0.85) and a metallic (0 or 1) per tile,
/// packed as glTF's metallic-roughness texture (green, blue) for wgtrace and as two grey
/// images for Mitsuba.
fn tiles_textures() {
    let dir = root().join("bench/generated");
    let names = [
        "tiles-color.png",
        "tiles-mr.png",
        "tiles-roughness.png",
        "tiles-metallic.png",
    ];
    if names.iter().all(|n| dir.join(n).exists()) {
        return;
    }
    std::fs::create_dir_all(&dir).unwrap();
    let side = 512u32;
    let tile = |x: u32, y: u32| {
        let (i, r) = (x / 64, y / 64);
        (i, r.min(7 - r))
    };
    let color = image::RgbImage::from_fn(side, side, |x, y| {
        let (i, j) = tile(x, y);
        let h = (i * 5 + j * 3) % 8;
        let palette = [
            [200, 60, 50],
            [230, 170, 60],
            [90, 160, 80],
            [60, 110, 190],
            [180, 180, 170],
            [120, 70, 150],
            [210, 120, 140],
            [70, 70, 70],
        ];
        image::Rgb(palette[h as usize])
    });
    let roughness = |x, y| {
        let (i, j) = tile(x, y);
        (0.15 + 0.1 * ((i + j) % 8) as f32).min(0.85)
    };
    let metallic = |x, y| {
        let (i, j) = tile(x, y);
        ((i + 2 * j) % 3 == 0) as u8
    };
    let byte = |v: f32| (v * 255.0).round() as u8;
    let mr = image::RgbImage::from_fn(side, side, |x, y| {
        image::Rgb([0, byte(roughness(x, y)), 255 * metallic(x, y)])
    });
    let rough = image::GrayImage::from_fn(side, side, |x, y| image::Luma([byte(roughness(x, y))]));
    let metal = image::GrayImage::from_fn(side, side, |x, y| image::Luma([255 * metallic(x, y)]));
    color.save(dir.join(names[0])).unwrap();
    mr.save(dir.join(names[1])).unwrap();
    rough.save(dir.join(names[2])).unwrap();
    metal.save(dir.join(names[3])).unwrap();
}

/// The heightfield of `triangles` (about) written by gen_mesh into bench/generated/, if
/// it is not there yet; its path.
fn heightfield_obj(triangles: u64) -> PathBuf {
    let name = if triangles == 1_000_000 {
        "terrain-1m.obj".to_string()
    } else {
        format!("terrain-{triangles}.obj")
    };
    let obj = root().join("bench/generated").join(name);
    if !obj.exists() {
        std::fs::create_dir_all(obj.parent().unwrap()).unwrap();
        let status = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
            .current_dir(root())
            .args(["run", "--release", "--quiet", "--example", "gen_mesh", "--"])
            .args(["heightfield", "--triangles", &triangles.to_string()])
            .args(["--size", "10", "--height", "1.2", "-o"])
            .arg(&obj)
            .stdout(std::process::Stdio::null())
            .status()
            .expect("run gen_mesh");
        assert!(status.success(), "gen_mesh failed");
    }
    obj
}

/// A scene's figures from one run of the suite.
struct Measured {
    w_rate: Vec<f64>,
    m_rate: Vec<f64>,
    w_wall: Vec<f64>,
    m_wall: Vec<f64>,
    /// relMSE x seconds of each renderer (constant while the error is noise): their
    /// ratio is the ratio of times to equal error.
    w_cost: Vec<f64>,
    m_cost: Vec<f64>,
    /// relMSE between the two references (what they disagree on).
    floor: f64,
}

/// Where the lanes go: each scene of the suite rendered once with `--tune lane-stats`
/// (subgroup operations count the lanes that take part in each step).
fn lanes(md: &mut String) {
    let _ = writeln!(
        md,
        "\n## Where the lanes go\n\nEach scene of the suite at its size and spp, rendered \
         once with `--tune lane-stats`: the GPU counts with `subgroupAdd` how many lanes of \
         the subgroup take part in each turn of the bounce loop, each step of the BVH walk's \
         node loop and each primitive test of its leaf loop (closest-hit and shadow rays \
         together). *Share* is the mean share of the subgroup's lanes that did work in a \
         step; *per sample* the lane steps one sample took. The rest of the lanes wait, \
         masked: llvmpipe runs a loop until its last lane leaves it.\n\n\
         | scene | bounce loop: share, per sample | BVH node steps | BVH primitive tests |\n\
         |---|---|---|---|"
    );
    for case in &SUITE {
        generate(case);
        let o = Command::new(env!("CARGO_BIN_EXE_wgtrace"))
            .arg("render")
            .arg(root().join(case.toml))
            .args([
                "--width",
                &case.width.to_string(),
                "--height",
                &case.height.to_string(),
            ])
            .args([
                "--spp",
                &case.spp.to_string(),
                "--tune",
                "lane-stats",
                "-q",
                "-o",
            ])
            .arg(scratch().join("lanes.exr"))
            .output()
            .expect("run wgtrace");
        let text = String::from_utf8_lossy(&o.stdout);
        let Some(line) = text.lines().find(|l| l.starts_with("live lanes")) else {
            let _ = writeln!(
                md,
                "| `{}` | failed: {} | | |",
                case.name,
                String::from_utf8_lossy(&o.stderr).trim()
            );
            continue;
        };
        // "... bounce loop 87.0% (3.42), BVH node steps 30.6% (24.36), ..."
        let cells: Vec<String> = line
            .split("), ")
            .map(|part| {
                let mut words = part.rsplit(' ');
                let per = words.next().unwrap_or("").trim_matches(['(', ')']);
                let share = words.next().unwrap_or("");
                format!("{share}, {per}")
            })
            .collect();
        let mut row = cells.join(" | ");
        if line.contains("BVH node steps 0.0% (0.00)") {
            row = format!("{} | no BVH (the plain loop) | -", cells[0]);
        }
        let _ = writeln!(md, "| `{}` | {row} |", case.name);
    }
    let _ = writeln!(
        md,
        "\nThe bounce loop keeps most lanes busy: a lane whose path ends starts its next \
         sample (sample groups), so only the last samples of a group leave lanes idle. The \
         BVH walk does not: a ray's node steps and leaf tests differ from its neighbours' \
         (incoherent bounce and shadow rays, shadow rays that stop at their first hit), and \
         each loop runs as long as its slowest lane, so most of the lanes of a walk's \
         step wait. Issue 44 tried three ways to put them to work (the subgroup walking \
         one ray at a time, a walk refilled with the path's next ray, the node loop ended \
         once most lanes hold a leaf; docs/performance.md, \"What each optimization \
         gave\", fifth round): none was faster on llvmpipe, where a subgroup operation is a loop over \
         the lanes and every fetch a load per lane, so the cost of a step, not the lanes \
         it leaves idle, is what pays to cut.\n"
    );
}

/// wgtrace's reference render of `case` (`ref_spp`, seed 1000) in `dir`, rendered the
/// first time it is asked for.
fn wgtrace_reference(case: &Case, dir: &Path) -> PathBuf {
    let path = dir.join(format!("{}-ref-w.exr", case.name));
    if !path.exists() {
        let spp = case.ref_spp.to_string();
        wgtrace(
            &root().join(case.toml),
            &["--spp", &spp, "--seed", "1000"],
            &path,
        );
    }
    path
}

/// Renders `case` with both renderers: a shared reference (the mean of each renderer's
/// `ref_spp` render), then ROUNDS rounds of one render each, in alternating order.
fn measure(case: &Case, dir: &Path) -> Result<Measured, String> {
    let scene = root().join(case.toml);
    let (w, h) = (case.width, case.height);
    let mref = dir.join(format!("{}-ref-m.exr", case.name));
    mitsuba(case.xml, w, case.ref_spp, 1000, &mref, 1)?;
    let spp = |n: u32| n.to_string();
    let wref = wgtrace_reference(case, dir);
    let (wr, mr) = (rgb(&wref), rgb(&mref));
    let reference: Vec<f32> = wr.iter().zip(&mr).map(|(a, b)| 0.5 * (a + b)).collect();
    let mut m = Measured {
        w_rate: Vec::new(),
        m_rate: Vec::new(),
        w_wall: Vec::new(),
        m_wall: Vec::new(),
        w_cost: Vec::new(),
        m_cost: Vec::new(),
        floor: rel_mse(&wr, &mr),
    };
    let samples = (w * h * case.spp) as f64 / 1e6;
    for round in 0..ROUNDS {
        let seed = round as u32;
        let wout = dir.join(format!("{}-w.exr", case.name));
        let mout = dir.join(format!("{}-m.exr", case.name));
        let run_w = |m: &mut Measured| {
            let r = wgtrace(
                &scene,
                &["--spp", &spp(case.spp), "--seed", &seed.to_string()],
                &wout,
            );
            m.w_rate.push(r.msps);
            m.w_wall.push(r.wall);
            m.w_cost.push(rel_mse(&rgb(&wout), &reference) * r.render);
        };
        let run_m = |m: &mut Measured| -> Result<(), String> {
            let r = mitsuba(case.xml, w, case.spp, seed, &mout, 2)?;
            m.m_rate.push(samples / r.steady);
            m.m_wall.push(r.wall);
            m.m_cost.push(rel_mse(&rgb(&mout), &reference) * r.steady);
            Ok(())
        };
        if round % 2 == 0 {
            run_w(&mut m);
            run_m(&mut m)?;
        } else {
            run_m(&mut m)?;
            run_w(&mut m);
        }
    }
    Ok(m)
}

fn geomean(v: &[f64]) -> f64 {
    (v.iter().map(|x| x.ln()).sum::<f64>() / v.len() as f64).exp()
}

fn comparison(md: &mut String, dir: &Path) {
    let _ = writeln!(md, "## Against Mitsuba 3\n");
    let _ = writeln!(
        md,
        "Every scene of `bench/` in wgtrace's format and in Mitsuba 3's (`bench/NAME.toml` \
         and `bench/NAME.xml`, rendered by `bench/mitsuba_render.py`): path tracing with \
         emitter sampling and MIS, max depth 8, Russian roulette from the fourth ray \
         (survival min(1, max throughput) in wgtrace, min(0.95, max throughput) in \
         Mitsuba), independent random samples, box pixel filter, the same spp for both. \
         Mitsuba 3 runs its `llvm_ad_rgb` variant (Dr.Jit's LLVM backend, all cores, \
         Embree for rays). *Msamples/s* is the steady rate: wgtrace's render time as it \
         reports it, Mitsuba's second render in its process (the first compiles or loads \
         its kernels). *Equal error* is the time wgtrace needs for the error Mitsuba \
         reaches in a second, as a fraction of Mitsuba's: relMSE x seconds against a \
         shared reference (the mean of both renderers' high-spp renders; *disagree* is \
         the relMSE between those two), which is constant while the error is noise; lower \
         is better. *Process* is the whole command (start-up, loading, shader or kernel \
         compilation from warm caches).\n"
    );
    let Some(rows) = measure_all(md, dir, &SUITE.iter().collect::<Vec<_>>()) else {
        return;
    };
    let (ratios, errors) = suite_table(md, &rows);
    let worst = |v: &[(f64, &str)], high_is_good: bool| {
        let w = v
            .iter()
            .copied()
            .min_by(|a, b| {
                if high_is_good {
                    a.0.total_cmp(&b.0)
                } else {
                    b.0.total_cmp(&a.0)
                }
            })
            .unwrap();
        format!("{:.2} (`{}`)", w.0, w.1)
    };
    let g = geomean(&ratios.iter().map(|r| r.0).collect::<Vec<_>>());
    let ge = geomean(&errors.iter().map(|r| r.0).collect::<Vec<_>>());
    let _ = writeln!(
        md,
        "\n**wgtrace / Mitsuba in samples per second: geometric mean {g:.2}, worst {}. Time \
         to equal error, wgtrace / Mitsuba: geometric mean {ge:.2}, worst {}.**\n",
        worst(&ratios, true),
        worst(&errors, false)
    );
}

/// Figures by scene.
type Ratios<'a> = Vec<(f64, &'a str)>;

/// Each case measured, in order (its generated files written first); None, with a line in
/// the report saying why, when Mitsuba cannot render one.
fn measure_all<'a>(
    md: &mut String,
    dir: &Path,
    cases: &[&'a Case],
) -> Option<Vec<(&'a Case, Measured)>> {
    let mut rows = Vec::new();
    for &case in cases {
        generate(case);
        eprintln!("measuring: {}", case.name);
        match measure(case, dir) {
            Ok(m) => rows.push((case, m)),
            Err(e) => {
                let _ = writeln!(
                    md,
                    "Not run: Mitsuba 3 could not render {} ({e}).\n",
                    case.xml
                );
                return None;
            }
        }
    }
    Some(rows)
}

/// The table of measured scenes (each renderer's rate, their ratio, the ratio of times to
/// equal error, the processes' times); returns the ratios and the equal-error ratios by
/// scene.
fn suite_table<'a>(md: &mut String, rows: &[(&'a Case, Measured)]) -> (Ratios<'a>, Ratios<'a>) {
    let _ = writeln!(
        md,
        "| scene | what | size, spp | wgtrace Msamples/s | Mitsuba Msamples/s | ratio | equal error, wgtrace / Mitsuba | disagree | wgtrace process s | Mitsuba process s |\n|---|---|---|---|---|---|---|---|---|---|"
    );
    let (mut ratios, mut errors) = (Vec::new(), Vec::new());
    for (case, m) in rows {
        let ratio = median(&m.w_rate) / median(&m.m_rate);
        let equal = median(&m.w_cost) / median(&m.m_cost);
        ratios.push((ratio, case.name));
        errors.push((equal, case.name));
        let _ = writeln!(
            md,
            "| `{}` | {} | {} x {}, {} | {} | {} | **{ratio:.2}** | {equal:.2} | {:.1e} | {} | {} |",
            case.name,
            case.what,
            case.width,
            case.height,
            case.spp,
            spread(&m.w_rate, 3),
            spread(&m.m_rate, 3),
            m.floor,
            spread(&m.w_wall, 2),
            spread(&m.m_wall, 2)
        );
    }
    (ratios, errors)
}

/// The cost of participating media: the Cornell box of the suite and the same box in a
/// fog that fills the world (`bench/fog-cornell.toml`, its twin rendered by Mitsuba's
/// volpath), measured as the suite is in one run.
fn media(md: &mut String, dir: &Path) {
    const FOG: Case = Case {
        name: "fog-cornell",
        toml: "bench/fog-cornell.toml",
        xml: "bench/fog-cornell.xml",
        width: 256,
        height: 256,
        spp: 64,
        ref_spp: 512,
        what:
            "`cornell` in a homogeneous fog (sigma_t 0.25, albedo 0.9, g 0.3) that fills the world",
    };
    let _ = writeln!(md, "## Participating media\n");
    let _ = writeln!(
        md,
        "`bench/cornell.toml` and `bench/fog-cornell.toml` (the same box in a fog that the \
         camera sits in; its Mitsuba 3 twin rendered by `volpath`), measured as the suite \
         is, in one run: what media cost each renderer, and wgtrace against Mitsuba 3 on \
         a scene with media.\n"
    );
    let Some(rows) = measure_all(md, dir, &[&SUITE[0], &FOG]) else {
        return;
    };
    let (ratios, _) = suite_table(md, &rows);
    let rate = |i: usize, w: bool| {
        let m = &rows[i].1;
        median(if w { &m.w_rate } else { &m.m_rate })
    };
    let _ = writeln!(
        md,
        "\n**The fog costs wgtrace {:.2}x its samples per second without it, Mitsuba 3 \
         {:.2}x; in the fog wgtrace renders {:.2}x Mitsuba's samples per second (without \
         it {:.2}x).**\n",
        rate(0, true) / rate(1, true),
        rate(0, false) / rate(1, false),
        ratios[1].0,
        ratios[0].0
    );
}

/// The Cornell box at 1024 x 1024 on both renderers (the figure a real GPU is compared
/// by).
fn cornell_large(md: &mut String, dir: &Path) {
    let scene = root().join("bench/cornell.toml");
    let (mut w, mut m) = (Vec::new(), Vec::new());
    for round in 0..ROUNDS {
        let seed = round.to_string();
        let r = wgtrace(
            &scene,
            &[
                "--width", "1024", "--height", "1024", "--spp", "16", "--seed", &seed,
            ],
            &dir.join("large-w.exr"),
        );
        w.push(r.msps);
        match mitsuba(
            "bench/cornell.xml",
            1024,
            16,
            round as u32,
            &dir.join("large-m.exr"),
            2,
        ) {
            Ok(r) => m.push(1024.0 * 1024.0 * 16.0 / 1e6 / r.steady),
            Err(_) => return,
        }
    }
    let _ = writeln!(
        md,
        "`bench/cornell.toml` at 1024 x 1024 and 16 spp: wgtrace {} Msamples/s, Mitsuba {} \
         (**{:.2}**).\n",
        spread(&w, 3),
        spread(&m, 3),
        median(&w) / median(&m)
    );
}

/// Render time against triangle count: the heightfield of the suite at 1,000 to 1,000,000
/// triangles, the same camera and sky.
fn triangle_scaling(md: &mut String, dir: &Path) {
    let src = std::fs::read_to_string(root().join("bench/heightfield.toml")).unwrap();
    let mut pts = Vec::new();
    for n in [1_000u64, 10_000, 100_000, 1_000_000] {
        let obj = heightfield_obj(n);
        let sky = root().join("scenes/textures/sky.hdr");
        let text = src
            .replace(
                "path = \"generated/terrain-1m.obj\"",
                &format!("path = \"{}\"", obj.display()),
            )
            .replace(
                "path = \"../scenes/textures/sky.hdr\"",
                &format!("path = \"{}\"", sky.display()),
            );
        assert!(
            text.contains(&obj.display().to_string()) && text.contains(&sky.display().to_string())
        );
        let scene = dir.join(format!("terrain-{n}.toml"));
        std::fs::write(&scene, text).unwrap();
        wgtrace(&scene, &["--spp", "1"], &dir.join("tri.exr"));
        let t: Vec<f64> = (0..ROUNDS)
            .map(|_| wgtrace(&scene, &["--spp", "16"], &dir.join("tri.exr")).render)
            .collect();
        pts.push((n, median(&t)));
    }
    let cells: Vec<String> = pts.iter().map(|(n, t)| format!("{n}: {t:.2} s")).collect();
    let _ = writeln!(
        md,
        "## Render time against triangles\n\nThe heightfield of `bench/heightfield.toml` \
         (256 x 144, 16 spp, under its sky) at four sizes, median of {ROUNDS}: {}. \
         **1,000,000 triangles take {:.2}x the time of 1,000.**\n",
        cells.join(", "),
        pts[3].1 / pts[0].1
    );
}

/// GPU bytes per triangle and peak host memory of the 1,000,000-triangle heightfield.
fn mesh_memory(md: &mut String, dir: &Path) {
    heightfield_obj(1_000_000);
    let path = root().join("bench/heightfield.toml");
    let scene = wgtrace::load_scene(&path, &Default::default()).expect("bench scene");
    let tris = scene
        .primitives
        .iter()
        .filter(|p| p.tag == wgtrace::scene::primitives::PrimitiveKind::Triangle.tag())
        .count();
    let bytes = [Slot::Primitives, Slot::Bvh, Slot::ShapeData]
        .iter()
        .map(|s| s.bytes(&scene).len())
        .sum::<usize>();
    let peak: Vec<f64> = (0..ROUNDS)
        .filter_map(|_| wgtrace(&path, &["--spp", "1"], &dir.join("mem1m.exr")).peak_mib)
        .collect();
    let _ = writeln!(
        md,
        "## Memory of a large mesh\n\n`bench/heightfield.toml` ({tris} triangles): the \
         primitives, BVH nodes and vertex attributes the GPU holds take **{:.1} bytes per \
         triangle** ({:.1} MiB); the whole process peaks at {} MiB of host memory (GNU \
         time; lavapipe's GPU memory is host memory too).\n",
        bytes as f64 / tris as f64,
        bytes as f64 / (1u64 << 20) as f64,
        if peak.is_empty() {
            "(not measured: no /usr/bin/time)".to_string()
        } else {
            spread(&peak, 0)
        }
    );
}

/// The optimizations kept: what each is, and the `--tune` knob that turns it off.
const KNOBS: [(&str, &str); 8] = [
    ("shader assembled for the scene's features", "no-specialize"),
    (
        "records of at most 64 KiB in uniform buffers",
        "no-uniform-records",
    ),
    (
        "primitives and BVH nodes in read-only storage textures",
        "no-texture-records",
    ),
    ("plain loop for at most 64 primitives", "bvh"),
    (
        "a small scene's records written into the shader",
        "no-baked-records",
    ),
    ("sample groups", "no-sample-groups"),
    ("the BVH walk's stack in registers", "no-register-stack"),
    ("Russian roulette", "no-russian-roulette"),
];

/// The ablation of every kept optimization on the whole suite: each scene rendered with
/// the defaults and with one knob of KNOBS turned off at a time, ROUNDS rounds in
/// alternating order; per optimization, samples per second and time to equal error (relMSE
/// x seconds against wgtrace's reference of the suite) with it against without it, per
/// scene, in geometric mean and at worst.
fn optimizations(md: &mut String, dir: &Path) {
    // every knob wgtrace has is in the table but no-bvh (the plain loop on scenes of any
    // size, which llvmpipe's loop limit refuses on the meshes), the lane-stats diagnostic
    // and band-pixels (the tests hold it to change no image)
    for (knob, _) in wgtrace::tuning::KNOBS {
        assert!(
            ["no-bvh", "lane-stats", "band-pixels=N"].contains(knob)
                || KNOBS.iter().any(|(_, k)| k == knob),
            "the bench does not measure --tune {knob}"
        );
    }
    let configs: Vec<Vec<&str>> = std::iter::once(Vec::new())
        .chain(KNOBS.iter().map(|(_, knob)| vec!["--tune", *knob]))
        .collect();
    // per scene, per configuration: the rates and the costs of the rounds
    let mut speed = Vec::new();
    let mut efficiency = Vec::new();
    for case in &SUITE {
        eprintln!("optimizations: {}", case.name);
        generate(case);
        let scene = root().join(case.toml);
        let reference = rgb(&wgtrace_reference(case, dir));
        // the first image of a configuration compiles its shader (llvmpipe compiles at
        // the first dispatch): warm Mesa's cache so that no row pays it
        for args in &configs {
            let mut a = vec!["--spp", "1", "--width", "16", "--height", "16"];
            a.extend(args);
            wgtrace(&scene, &a, &dir.join("warm.exr"));
        }
        let spp = case.spp.min(16).to_string();
        let mut rates = vec![Vec::new(); configs.len()];
        let mut cost = vec![Vec::new(); configs.len()];
        for round in 0..ROUNDS {
            let mut order: Vec<usize> = (0..configs.len()).collect();
            if round % 2 == 1 {
                order.reverse();
            }
            for i in order {
                let out = dir.join(format!("opt{i}.exr"));
                let seed = round.to_string();
                let mut args = vec!["--spp", &spp, "--seed", &seed];
                args.extend(&configs[i]);
                let r = wgtrace(&scene, &args, &out);
                rates[i].push(r.msps);
                cost[i].push(rel_mse(&rgb(&out), &reference) * r.render);
            }
        }
        let (r, c): (Vec<f64>, Vec<f64>) = (0..configs.len())
            .map(|i| (median(&rates[i]), median(&cost[i])))
            .unzip();
        // with the optimization against without it: higher is better for both
        speed.push((1..configs.len()).map(|i| r[0] / r[i]).collect::<Vec<_>>());
        efficiency.push((1..configs.len()).map(|i| c[i] / c[0]).collect::<Vec<_>>());
    }
    let _ = writeln!(
        md,
        "## What each optimization gave\n\nEvery scene of the suite at its size and at most \
         16 spp, rendered with the defaults and with one optimization turned off by its \
         `--tune` knob (median of {ROUNDS} rounds in alternating order, the Mesa shader \
         cache warmed for each). Each cell is *with / without*, higher is better: samples \
         per second, and time to equal error (relMSE x seconds against wgtrace's \
         reference render of the suite, the one of the comparison above), which also \
         counts the noise Russian roulette adds. An optimization that does not apply to a \
         scene (the plain loop and written-in records past 64 primitives) measures noise \
         there, about 1.00.\n"
    );
    for (title, table) in [
        ("samples per second", &speed),
        ("time to equal error", &efficiency),
    ] {
        let names: Vec<&str> = SUITE.iter().map(|c| c.name).collect();
        let _ = writeln!(
            md,
            "| {title}, with / without | knob | `{}` | geometric mean | worst |\n|---|---|{}---|---|",
            names.join("` | `"),
            "---|".repeat(names.len())
        );
        for (k, (what, knob)) in KNOBS.iter().enumerate() {
            let per_scene: Vec<f64> = table.iter().map(|s| s[k]).collect();
            let (worst, at) = per_scene
                .iter()
                .zip(&names)
                .min_by(|a, b| a.0.total_cmp(b.0))
                .unwrap();
            let cells: Vec<String> = per_scene.iter().map(|x| format!("{x:.2}")).collect();
            let _ = writeln!(
                md,
                "| {what} | `{knob}` | {} | **{:.2}** | {worst:.2} (`{at}`) |",
                cells.join(" | "),
                geomean(&per_scene)
            );
        }
        let _ = writeln!(md);
    }
    let _ = writeln!(
        md,
        "Choices without a knob were decided by hand, each on the one scene named (single \
         runs or medians of a few on a shared machine, about 15% noise); they are how a \
         choice was made, not figures of the suite. The 8 x 8 workgroup against 4 x 4 and \
         16 x 16 (0.73, 0.38 and 0.68 Msamples/s on the same render), and the naga bounds \
         checks and loop bounding turned off (`create_shader_module_trusted`, no change: \
         lavapipe checks bounds itself), and lavapipe's `LP_NUM_THREADS` (1: 0.41 to 0.44, \
         2, the default on 2 cores: 0.78 to 0.90, 4: 0.78 to 0.81 Msamples/s), all on the \
         Cornell box. The per-scene shader specialization has its own report over the \
         scenes of `scenes/`, [specialization.md](specialization.md).\n\n\
         Kept in the shader's code, on the Cornell box: the sphere and triangle tests \
         and direct lighting without early returns (llvmpipe runs both sides of every branch \
         under a mask, so a return saves nothing and costs a masked update of every live \
         value), shadow rays searching for any hit, and `choose_light` counting the running \
         sums instead of a binary search; `bench/jit-loop-size.sh` counts the instructions of \
         the bounce loop in lavapipe's JIT code, a measure that does not drift with the \
         machine's load: 5325 before, 4540 after; alternating renders of the Cornell box at \
         48 spp took 0.82 s before and 0.67 s after (median of 5).\n\n\
         For meshes (issue 21), on `bench/nefertiti.toml` at 16 spp unless said otherwise: \
         a perf profile (cpu-clock samples mapped onto lavapipe's JIT code) put 68% of the \
         time in record fetches, most of it waiting on memory, which the storage textures \
         of the tables above address (storage buffers 0.083, storage textures 0.199 and \
         sampled textures, whose fetch also computes mip offsets per lane, 0.095 \
         Msamples/s). Kept: the two children of a node side by side \
         (`pair_layout`: one cache line per step, the same visits; no change within noise \
         alone, kept for the fewer lines; replaced in the fourth round); an any-hit search for shadow rays \
         (0.199 to 0.225 Msamples/s); 64 primitives as the limit of the plain loop (an \
         80-triangle icosphere in the Cornell box: BVH 0.37, loop 0.92 Msamples/s; 320 \
         triangles: 0.37 and 0.14). Tried and not kept: the subgroup walking the BVH \
         together (a node entered when any lane's ray enters it, so every fetch is the \
         same for all lanes: 0.18 to 0.14, and camera rays alone 1.94 to 1.63 \
         Msamples/s); leaves of up to 8 primitives and a traversal cost of 2 in the SAH \
         (no change within noise). A traversal stack of 8 entries instead of 32 was 25% \
         faster (wrong for deep trees, but it shows what the per-lane stack arrays cost: a \
         stackless walk would win that). Per ray the BVH visits about 16 nodes and tests \
         2.4 triangles (camera and diffuse rays alike), so the rest of the gap is the cost \
         of each visit on llvmpipe: a fetch is a load per lane, and the 8 lanes wait for \
         the slowest.\n\n\
         Second round on meshes, by hand: Msamples/s at 16 spp, median of 3 renders \
         alternating with the binary before, and the size of nefertiti's bounce loop in \
         the JIT code (`bench/jit-loop-size.sh`). llvmpipe runs a loop's body at least once \
         even when no lane enters it, so what sat behind a branch that is never taken still \
         cost a pass of its loop. Kept, in order: (1) stack entries that hold the popped \
         node's offset and count, so a pop fetches nothing (its box was tested by its \
         parent): nefertiti 0.179 to 0.191; (2) leaves postponed (Aila and Laine 2009's \
         while-while: a lane that reaches a leaf waits until every lane of its subgroup \
         has one, then the leaves are tested together, so the leaf loop runs once per \
         leaf instead of once per node visit): 0.190 to 0.261; (3) the slab test's min \
         and max as selects (slab distances are never NaN; llvmpipe's min and max handle \
         NaN with two more instructions): the walk's inner loop 642 to 594 instructions; \
         (4) leaves of untransformed triangles tested without the tag's switch \
         (`BOUNDED_TRIANGLES_ONLY`): 0.250 to 0.263; (5) `occluded` without a second, \
         never-taken closest-hit walk when the shader has no plain loop, and the plane \
         loops only in shaders with planes: bounce loop 14349 to 9342 instructions, \
         nefertiti 0.313 to 0.342. All five against the binary before them, one run: \
         spot 0.262 to 0.348 (1.33x), nefertiti 0.202 to 0.342 (1.69x), heightfield \
         0.237 to 0.358 (1.51x); the visits are the same, so are the images. Tried and \
         not kept: leaves of up to 8 and a traversal cost of 2 with the postponed leaves \
         (0.250 against 0.255, noise). What was left per node visit: 594 instructions, of \
         which about 170 fetched the child pair (4 texels x 8 lanes, one load each), about \
         115 pushed a stack entry (llvmpipe writes a private array for all 8 lanes, reading \
         back what the lanes that do not push keep) and about 50 popped one.\n\n\
         Third round. Kept: the traversal stacks in workgroup memory, one column per \
         invocation (llvmpipe writes workgroup memory lane by lane, for the lanes that \
         push only): nefertiti's bounce loop 9363 to 5152 instructions, the walk's inner \
         loop 594 to 453; spot 0.370 to 0.489, nefertiti 0.334 to 0.422, heightfield \
         0.356 to 0.372 Msamples/s (geometric mean 1.20x over the three meshes, worst \
         1.04x, the heightfield; the two Cornell boxes do not walk the BVH), the same \
         images bit for bit. Tried and not kept: a \
         4-wide BVH (the binary SAH tree collapsed, each node's up to four children side \
         by side in 8 texels, a sorting network for the nearest first, with the stack in \
         workgroup memory): its step is 843 instructions against 453 for a binary step, \
         so two binary levels cost 906 against 843, and on the two meshes it was tried \
         on nefertiti rendered 0.398 against 0.415 and spot 0.480 against 0.481 (0.96x \
         and 1.00x). Fetches stay 2 texels per child and \
         take about 45 instructions each; child boxes quantized to 8 bits in the node's \
         frame (Ylitie et al. 2017: 4 children in 4 texels) would save 4 of the 8 fetches \
         and add about 70 instructions of decoding, about 735 per step: 1.23x on the \
         interior loops, which a perf profile of the heightfield puts at 62% of its time \
         (closest hit 33%, shadow rays 29%; leaf loops 11%, the rest of the bounce 9%), \
         so about 1.13x on a mesh scene. Mitsuba 3's wheel traces the rays of its CPU \
         variants with Embree (it ships `libembree3.so`): wide BVHs walked with the \
         children's boxes tested in SIMD, where lavapipe runs 8 rays in SIMD and every node \
         fetch is a gather of 8 loads. The cost of a visit, not the tree, is the gap.\n\n\
         Fourth round (issue 32). Kept: the compressed 8-wide BVH of Ylitie, Karras and \
         Laine 2017 (`scene::bvh::collapse`: 80-byte nodes, 5 texels, whose 8 child boxes \
         are bytes in the node's power-of-two grid; hit masks ordered by the ray's octant; \
         a stack of node groups) in place of the binary tree: 16 spp, median of 3 renders \
         alternating with the binary before, spot 0.711 to 0.815 (1.15x), nefertiti 0.625 \
         to 0.782 (1.25x), heightfield 0.572 to 0.691 (1.21x) Msamples/s, the images the \
         same up to the order of equal hits (nefertiti's bit for bit on the GPU). The trees: \
         nefertiti 111,417 binary nodes of depth 21 against 12,205 wide nodes of depth 7, \
         the heightfield 1,016,557 (depth 22) against 204,577 (depth 7), 32 against 16.4 \
         bytes of nodes per triangle. In lavapipe's JIT code a node step is 986 \
         instructions (the binary step 453) and a leaf's primitive test 389; the bounce \
         loop went from 5158 to 6093. Tried and not kept: a single loop taking a node or a \
         primitive per turn (nefertiti 0.82 to 0.70 Msamples/s: llvmpipe runs both halves \
         whenever its lanes need both); `fma` for the slab distances (the same JIT code: \
         llvmpipe already fuses them). llvmpipe at 512 bits (16 lanes) is the default on \
         CPUs with AVX-512 (0.546 and 0.582 to 0.621 and 0.627 Msamples/s on nefertiti, \
         measured on such a CPU); on this machine's AVX2 it changed nothing (nefertiti \
         0.72 to 0.76 at 256 bits, 0.68 to 0.79 at 512, 0.72 to 0.78 at 128), and the live \
         lanes of a node step fall with the width (44% at 4 lanes, 31% at 8).\n\n\
         Fifth round (issue 44), on an Intel Xeon with AVX-512 (llvmpipe 512 bits, 16 \
         lanes; 16 spp, medians of 3 renders alternating, Msamples/s with / without unless \
         said otherwise). Kept: (1) `main`'s workgroups declared 64 x 1 x 1 instead of 8 x \
         8 x 1 (the same tiles): Mesa 22.3.6 there walked the BVH wrong in 8 x 8 x 1 \
         workgroups outside storage buffers, so the spot check fell back to storage \
         buffers on every mesh scene (nefertiti 0.197 to 0.235 in the fallback against \
         0.47 to 0.58 in textures; `wgtrace check`: 6 of 12 rows fail with 8 x 8 x 1, none \
         with 64 x 1 x 1); (2) the walk's stack in registers for trees of depth 8 at most \
         (`--tune no-register-stack`): on Mesa 22.3 spot 1.30x, textured 1.05x, nefertiti \
         1.29x, heightfield 1.22x (geometric mean 1.21x), on Mesa 25.0 1.05x, 1.05x, \
         0.99x, 1.14x (1.05x); the node loop is 1225 JIT instructions with no loop over \
         the lanes inside, against 1033 around two 16-lane loops (the stack's store and \
         load, about 20 instructions a lane), the same images bit for bit. Tried and not kept, each giving the same \
         images: the subgroup walking the rays of its last 2 walking lanes one at a time, \
         a child box and a leaf primitive per lane (ballot, shuffle, or and min; the \
         Embree way): 0.46x to 0.54x on the four meshes on Mesa 22.3 and 0.60x to 0.71x on \
         Mesa 25 (geometric means 0.50x and 0.64x), because on llvmpipe a subgroup \
         operation is a scalar loop over the lanes and a node fetch at an address every \
         lane shares is still a load per lane: its node step was 633 JIT instructions plus \
         those loops against 808 for a lane's own (at 256 bits). Nor does a form of the \
         fetch share it: with the node index through `subgroupBroadcastFirst` the node \
         loop went from 1225 to 1152 instructions in textures (the address arithmetic \
         once, the 16 loads each) and from 1112 to 1127 in storage buffers (Mesa's \
         single-load path takes only addresses uniform over the whole dispatch, \
         `nir_src_is_always_uniform`). The refill of a walk (a vertex's shadow ray walked \
         with the path's next ray in one walk, a lane taking the second as its first \
         ends; the same rays and sums): the bounce loop 7178 to 5918 instructions, the \
         node steps' live share 21.8% to 22.6%, speed 0.95x to 1.11x over 11 scene and \
         driver pairs, geometric mean 1.02x (noise); a lane's walk is as long as its \
         slowest stretch between leaves, not its end. Ending the node loop once at most a \
         quarter of the walking lanes still look for a leaf (`subgroupAdd`): node steps \
         22.6% to 27.1% live, primitive tests 23.5% to 19.1%, 0.90x to 1.09x, geometric \
         mean 0.97x. Not built: a wavefront split, whose ray states would go through \
         storage between kernels, a store and a load per lane and component on llvmpipe, \
         the cost the register stack removed from the walk.\n"
    );
}

fn scaling(md: &mut String, dir: &Path, scene: &Path) {
    let _ = writeln!(
        md,
        "## How time scales\n\nwgtrace on lavapipe, `bench/cornell.toml` with one setting \
         changed at a time from 256 x 256, 4 spp, max depth 8; render seconds as wgtrace \
         reports them (median of {ROUNDS}). For triangles, the first sphere is replaced by \
         an icosphere mesh (20 x 4^k triangles; past 64 primitives the BVH is walked).\n"
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
        let band = pixels.min(MAX_BAND_PIXELS as f64);
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
