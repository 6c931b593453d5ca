//! The `wgtrace` command line: parse, call the library, report.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context;
use clap::{Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

use wgtrace::checkpoint::Checkpoint;
use wgtrace::gpu::limits::DeviceFit;
use wgtrace::gpu::plan::{Feature, GpuPlan};
use wgtrace::image_io::check_writable;
use wgtrace::scene::format::{FilterKind, LightSampling, SamplerKind};
use wgtrace::session::{
    Output, Passes, Saving, Session, SessionError, SessionOptions, StopRule, Stopped,
};
use wgtrace::tuning::{Tuning, KNOBS};
use wgtrace::{BackendChoice, Overrides};

#[derive(Parser)]
#[command(
    name = "wgtrace",
    version,
    about = "Headless path tracer: TOML scene in, PNG/EXR/PPM out, on any Vulkan GPU \
             (or lavapipe) with a CPU reference",
    after_help = "Examples:\n  \
        wgtrace render scenes/cornell.toml -o cornell.png\n  \
        wgtrace render scenes/sky.toml --spp 1024 --time-limit 60 -o sky.exr\n  \
        wgtrace render scenes/cornell.toml --backend cpu --sampler jittered -o cpu.png\n  \
        wgtrace validate scenes/*.toml\n  \
        wgtrace converge scenes/cornell.toml --spp-max 64 --out study\n\n\
        Every key of a scene file: docs/scene-format.md. `wgtrace COMMAND --help` \
        describes each command's options."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene file to an image.
    Render(Box<RenderArgs>),
    /// Measure how error falls with samples and seconds, per sampler and light-sampling
    /// strategy, against a reference; writes results.csv, report.md and plots.
    Converge(ConvergeArgs),
    /// Print the features a scene uses, the shader defines they select, and the size of the
    /// specialized shader against the full one.
    Features {
        /// Scene file: TOML, or a glTF 2.0 file (.gltf, .glb) on its own.
        scene: PathBuf,
    },
    /// Check scene files without rendering them: parse, validate every value, load their
    /// textures and meshes, build the BVH, and assemble and validate the shader each would
    /// use. Prints a summary per scene; exits non-zero if any scene has a problem.
    Validate {
        /// Scene files: TOML, or glTF 2.0 files (.gltf, .glb) on their own.
        #[arg(required = true)]
        scenes: Vec<PathBuf>,
    },
    /// Write a Mitsuba 3 scene file (.xml) as wgtrace's TOML scene format, to read and edit
    /// what the import makes of it; `wgtrace render` reads the .xml file the same way.
    Convert {
        /// The Mitsuba 3 scene file.
        scene: PathBuf,
        /// The TOML file to write (default: the scene's name with .toml, beside it, where
        /// no such file is yet).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// A `<default>` replaced, as Mitsuba's -D (repeatable).
        #[arg(short = 'D', value_name = "NAME=VALUE", value_parser = parse_define)]
        define: Vec<(String, String)>,
    },
    /// List the Vulkan adapters wgtrace can see, in the order `--adapter` counts them.
    Info,
    /// Check a GPU and its driver against the CPU reference: for each scene class (no
    /// BVH, BVH, triangle mesh) and record placement (shader, uniform, texture, storage),
    /// compare rays one by one and a spot check of a render. Prints a table; exits non-zero
    /// on any mismatch. Run it on a new GPU or driver.
    Check {
        /// Which Vulkan adapter: an index from `wgtrace info`, or part of its name.
        #[arg(long, value_name = "INDEX|NAME")]
        adapter: Option<String>,
        /// Tuning knobs under the placements (see `render --help`); `perturb=all` shows a
        /// failing check.
        #[arg(long, value_name = "KNOBS", value_parser = Tuning::parse)]
        tune: Option<Tuning>,
    },
    /// Combine checkpoints of one scene rendered over disjoint sample ranges
    /// (`render --sample-range`) into one image, and optionally one checkpoint.
    Merge {
        /// Checkpoints to add up (same scene, settings, size and version; no sample index
        /// in two of them).
        #[arg(required = true)]
        checkpoints: Vec<PathBuf>,
        /// Output image (.png, .exr or .ppm).
        #[arg(short, long)]
        output: PathBuf,
        /// Also write the merged checkpoint here.
        #[arg(long, value_name = "PATH")]
        checkpoint: Option<PathBuf>,
        /// AOVs to write beside the colour (EXR only), as `render --aov`; the checkpoints
        /// must hold their sums (rendered with --aov or --denoise).
        #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = wgtrace::aov::Aov::from_name)]
        aov: Vec<wgtrace::aov::Aov>,
        /// Denoise the merged image, as `render --denoise`.
        #[arg(long)]
        denoise: bool,
    },
}

#[derive(clap::Args)]
struct ConvergeArgs {
    /// Scene file: TOML, or a glTF 2.0 file (.gltf, .glb) on its own.
    scene: PathBuf,
    /// Reference image (linear EXR of the same size). Default: render one at
    /// --reference-spp, cached in the output folder with its settings beside it.
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Samples per pixel of a rendered reference.
    #[arg(long, default_value_t = 4096)]
    reference_spp: u32,
    /// Backend of a rendered reference (the CPU reference is much faster than lavapipe).
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    reference_backend: BackendArg,
    /// Largest samples per pixel of the ladder 1, 2, 4, ...
    #[arg(long, default_value_t = 256)]
    spp_max: u32,
    /// Independent runs (seeds) per point.
    #[arg(long, default_value_t = 3)]
    runs: u32,
    /// Configurations, sampler:strategy[:max_depth], comma-separated (default: all four
    /// samplers with bsdf, mixture and mis).
    #[arg(long, value_delimiter = ',', value_parser = wgtrace::converge::Config::parse)]
    configs: Vec<wgtrace::converge::Config>,
    /// Output folder.
    #[arg(long, default_value = "converge")]
    out: PathBuf,
    /// Backend of the measured renders.
    #[arg(long, value_enum, default_value_t = BackendArg::Gpu)]
    backend: BackendArg,
    /// Which Vulkan adapter: an index from `wgtrace info`, or part of its name. Default:
    /// the GPU a cluster's scheduler assigned (CUDA_VISIBLE_DEVICES, ROCR_VISIBLE_DEVICES
    /// or HIP_VISIBLE_DEVICES, matched by PCI bus order or UUID), else the first.
    #[arg(long, value_name = "INDEX|NAME")]
    adapter: Option<String>,
    /// Image width (overrides [render] width, for every render and the reference).
    #[arg(long)]
    width: Option<u32>,
    /// Image height (overrides [render] height).
    #[arg(long)]
    height: Option<u32>,
    /// Rays per path of configurations that give none (overrides [render] max_depth).
    #[arg(long)]
    max_depth: Option<u32>,
    /// Also measure every point denoised with Open Image Denoise (a `LABEL +oidn` curve
    /// per configuration; its seconds include the denoiser's).
    #[arg(long)]
    denoise: bool,
    /// No progress bar.
    #[arg(short, long)]
    quiet: bool,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum BackendArg {
    /// The first Vulkan adapter (real GPUs before software ones).
    Gpu,
    /// The CPU reference renderer.
    Cpu,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Scene file: TOML, or a glTF 2.0 file (.gltf, .glb) on its own.
    scene: PathBuf,
    /// Output image; the extension picks the format: .png (8-bit sRGB), .exr (linear float),
    /// .ppm (binary P6). Default: the scene's name with .png, in the current directory.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Which backend renders.
    #[arg(long, value_enum, default_value_t = BackendArg::Gpu)]
    backend: BackendArg,
    /// Which Vulkan adapter: an index from `wgtrace info`, or part of its name. Default:
    /// the GPU a cluster's scheduler assigned (CUDA_VISIBLE_DEVICES, ROCR_VISIBLE_DEVICES
    /// or HIP_VISIBLE_DEVICES, matched by PCI bus order or UUID), else the first.
    #[arg(long, value_name = "INDEX|NAME")]
    adapter: Option<String>,
    /// Samples per pixel (overrides [render] spp).
    #[arg(long)]
    spp: Option<u32>,
    /// Image width in pixels (overrides [render] width).
    #[arg(long)]
    width: Option<u32>,
    /// Image height in pixels (overrides [render] height).
    #[arg(long)]
    height: Option<u32>,
    /// Rays per path: 1 shows emitters and background only (overrides [render] max_depth).
    #[arg(long)]
    max_depth: Option<u32>,
    /// Random seed (overrides [render] seed).
    #[arg(long)]
    seed: Option<u32>,
    /// A glTF file's camera, by its name or its node's (default: the file's first camera;
    /// without one, a view that frames the scene).
    #[arg(long, value_name = "NAME")]
    camera: Option<String>,
    /// A Mitsuba scene file's `<default>` replaced, as Mitsuba's -D (repeatable).
    #[arg(short = 'D', value_name = "NAME=VALUE", value_parser = parse_define)]
    define: Vec<(String, String)>,
    /// A uniform background of this radiance (replaces the scene's [background], and the
    /// studio environment of a glTF file without punctual lights; 0,0,0 for none).
    #[arg(long, value_name = "R,G,B", value_parser = parse_rgb)]
    background: Option<[f32; 3]>,
    /// Rewrite the output file every N passes, to watch the render converge.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    preview_every: Option<u32>,
    /// Pixel sampler (overrides [render] sampler).
    #[arg(long, value_enum)]
    sampler: Option<SamplerKind>,
    /// How paths find lights (overrides [render] light_sampling).
    #[arg(long, value_enum)]
    light_sampling: Option<LightSampling>,
    /// Pixel filter (overrides [render] filter; its radius and deviation come from the
    /// file, else Mitsuba 3's defaults).
    #[arg(long, value_enum)]
    filter: Option<FilterKind>,
    /// Compensate every microfacet lobe for the energy it loses to multiple scattering
    /// (Kulla and Conty 2017; sets [render] energy_compensation, which a material's own
    /// key overrides). Off by default, as in Mitsuba and glTF.
    #[arg(long)]
    energy_compensation: bool,
    /// Stop after as many passes as fit in this many seconds, then write the image. Without
    /// --spp the scene's spp no longer caps the passes (except for hammersley and jittered,
    /// whose points depend on it).
    #[arg(long, value_name = "SECONDS", value_parser = positive_f64)]
    time_limit: Option<f64>,
    /// Stop once the estimated relative error (sqrt of mean (variance / n) / (mean^2 +
    /// 0.01) over pixels and channels) is at most E; e.g. 0.02 for 2%. Uncapped by the
    /// scene's spp as with --time-limit.
    #[arg(long, value_name = "E", value_parser = positive_f64)]
    target_error: Option<f64>,
    /// Also write the per-pixel relative error estimate: .exr holds the values, .png/.ppm
    /// show them in colour (log scale, 0.1% dark blue to 100% yellow).
    #[arg(long, value_name = "PATH")]
    error_map: Option<PathBuf>,
    /// Knobs of how the render runs, for benchmarks and comparisons: a comma-separated
    /// list, each knob named and described by `wgtrace render --help`. The image is the
    /// same up to noise; the defaults are the fastest.
    #[arg(long, value_name = "KNOBS", value_parser = Tuning::parse, long_help = tune_help())]
    tune: Option<Tuning>,
    /// Keep the render's state in this checkpoint file (written whole: temporary file,
    /// then rename) every --checkpoint-every seconds and at the end; `--resume` continues
    /// from it. Ctrl-C or SIGTERM always writes one (here, or beside the image as .ckpt).
    #[arg(long, value_name = "PATH")]
    checkpoint: Option<PathBuf>,
    /// Seconds between checkpoints (0: after every pass).
    #[arg(long, value_name = "SECONDS", default_value_t = 60.0)]
    checkpoint_every: f64,
    /// Continue the render in this checkpoint (same scene and settings; --spp may ask for
    /// more samples). The result equals an uninterrupted render, bit for bit on the same
    /// backend.
    #[arg(long, value_name = "PATH")]
    resume: Option<PathBuf>,
    /// Render only the samples with these indices (END at most spp), and keep them in a
    /// checkpoint: ranges rendered apart (other processes or machines) are combined with
    /// `wgtrace merge`.
    #[arg(long, value_name = "START..END", value_parser = wgtrace::checkpoint::parse_range)]
    sample_range: Option<std::ops::Range<u32>>,
    /// Seconds one GPU submission should take: the work per submission adapts to the
    /// measured times to stay near this, far below the 2 s after which Windows resets a GPU
    /// (several samples per submission when quick, a few rows when slow).
    #[arg(long, value_name = "SECONDS", default_value_t = 0.5, value_parser = positive_f64)]
    submission_time: f64,
    /// Write these AOVs beside the colour, as layers of the EXR output (albedo.R,
    /// normal.X, depth.Z, ...): albedo, normal, depth, position, variance (comma-separated;
    /// see docs/cli.md for what each holds).
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = wgtrace::aov::Aov::from_name)]
    aov: Vec<wgtrace::aov::Aov>,
    /// Denoise the image with Intel Open Image Denoise (`pip install pyoidn`, or OIDN_DIR),
    /// guided by the albedo and normal AOVs; an EXR output keeps the noisy colour as its
    /// `noisy` layer.
    #[arg(long)]
    denoise: bool,
    /// No progress bar.
    #[arg(short, long)]
    quiet: bool,
}

/// A render that Ctrl-C or SIGTERM stopped, its image and checkpoint written.
#[derive(Debug, thiserror::Error)]
#[error("interrupted")]
struct Interrupted;

/// `--tune`'s long help: the list, and what each knob does.
fn tune_help() -> String {
    let mut s = "Knobs of how the render runs, for benchmarks and comparisons: a \
                 comma-separated list; the image is the same up to noise, and the defaults \
                 are the fastest."
        .to_string();
    for (name, what) in KNOBS {
        s += &format!("\n  {name}: {what}");
    }
    s
}

fn parse_define(s: &str) -> Result<(String, String), String> {
    match s.split_once('=') {
        Some((name, value)) if !name.trim().is_empty() => {
            Ok((name.trim().to_string(), value.to_string()))
        }
        _ => Err(format!("must be NAME=VALUE, got {s}")),
    }
}

/// `wgtrace convert`: a Mitsuba scene file as TOML, checked by loading it as it was written.
fn convert(
    scene: &Path,
    output: Option<PathBuf>,
    defines: &[(String, String)],
) -> anyhow::Result<()> {
    if !wgtrace::scene::load::is_mitsuba(scene) {
        anyhow::bail!(
            "{}: convert reads Mitsuba 3 scene files (.xml)",
            scene.display()
        );
    }
    let output = match output {
        Some(o) => o,
        // the file beside the scene, which a user may have edited: never replaced unasked
        None => {
            let beside = scene.with_extension("toml");
            if beside.exists() {
                anyhow::bail!(
                    "{}: exists; convert writes beside the scene only where nothing is: \
                     name the output with -o (the same path replaces it)",
                    beside.display()
                );
            }
            beside
        }
    };
    if output == scene {
        anyhow::bail!(
            "{}: the output would overwrite the scene file",
            output.display()
        );
    }
    let base = output.parent().unwrap_or(Path::new(""));
    let converted = wgtrace::scene::load::convert_mitsuba(scene, defines, base)?;
    for n in &converted.notes {
        eprintln!("note: {n}");
    }
    std::fs::write(&output, &converted.toml)
        .map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", output.display()))?;
    // what was written must load: its values checked, its files read
    wgtrace::scene::load(
        &output,
        &Overrides::default(),
        wgtrace::Tuning::default().build(),
    )
    .map_err(|e| anyhow::anyhow!("the converted scene does not load:\n{e}"))?;
    println!("{} -> {}", scene.display(), output.display());
    Ok(())
}

fn parse_rgb(s: &str) -> Result<[f32; 3], String> {
    let parts: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("must be three numbers R,G,B, got {s}"))?;
    match parts[..] {
        [r, g, b] if parts.iter().all(|x| *x >= 0.0 && x.is_finite()) => Ok([r, g, b]),
        _ => Err(format!("must be three numbers >= 0, R,G,B, got {s}")),
    }
}

fn positive_f64(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v > 0.0 && v.is_finite() => Ok(v),
        _ => Err(format!("must be a number > 0, got {s}")),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // llvmpipe compiles a scene's shader at its first use: seconds for a specialized one,
    // minutes for the full one on a wide CPU
    static NOTICE: std::sync::Once = std::sync::Once::new();
    wgtrace::gpu::context::set_compile_notice(|| {
        NOTICE.call_once(|| {
            eprintln!(
                "waiting for the driver to compile this scene's shader (its first use on this \
             machine; later renders reuse it); Ctrl-C ends at once"
            )
        })
    });
    let result = match cli.command {
        Command::Render(args) => render(*args),
        Command::Converge(args) => converge(args),
        Command::Features { scene } => features(&scene),
        Command::Validate { scenes } => validate(&scenes),
        Command::Convert {
            scene,
            output,
            define,
        } => convert(&scene, output, &define),
        Command::Info => info(),
        Command::Check { adapter, tune } => check(adapter.as_deref(), tune.unwrap_or_default()),
        Command::Merge {
            checkpoints,
            output,
            checkpoint,
            aov,
            denoise,
        } => merge(&checkpoints, &output, checkpoint.as_deref(), &aov, denoise),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // 128 + SIGINT, as a shell reports a command that Ctrl-C stopped
        Err(e) if e.is::<Interrupted>() => ExitCode::from(130),
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn merge(
    inputs: &[PathBuf],
    output: &Path,
    checkpoint: Option<&Path>,
    aovs: &[wgtrace::aov::Aov],
    denoise: bool,
) -> anyhow::Result<()> {
    check_writable(output)?;
    wgtrace::aov::check_output(output, aovs)?;
    let denoiser = denoise
        .then(wgtrace::denoise::Denoiser::shared)
        .transpose()?;
    let parts = inputs
        .iter()
        .map(|p| Ok((p.clone(), Checkpoint::read(p)?)))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let merged = Checkpoint::merge(&parts)?;
    let acc = &merged.accumulation;
    if (denoise || aovs.iter().any(|a| a.summed())) && !acc.aovs {
        anyhow::bail!(
            "{}: holds no AOV sums (render the ranges with --aov or --denoise)",
            parts[0].0.display()
        );
    }
    wgtrace::aov::write_output(output, acc, aovs, denoiser)?;
    if let Some(path) = checkpoint {
        merged
            .write(path)
            .with_context(|| format!("writing checkpoint {}", path.display()))?;
    }
    let ranges: Vec<String> = merged
        .samples
        .iter()
        .map(|r| format!("{}..{}", r.start, r.end))
        .collect();
    println!(
        "{}: {}x{}, {} spp (samples {}) from {} checkpoints",
        output.display(),
        acc.width,
        acc.height,
        merged.sample_count(),
        ranges.join(","),
        parts.len()
    );
    Ok(())
}

fn validate(paths: &[PathBuf]) -> anyhow::Result<()> {
    let mut failed = 0;
    for path in paths {
        let checked = wgtrace::load_scene(path, &Overrides::default())
            .map_err(anyhow::Error::from)
            .and_then(|scene| {
                let plan = GpuPlan::new(&scene, &DeviceFit::portable(), &Tuning::default());
                wgtrace::gpu::shader::validate("trace", &plan.shader.wgsl("trace")?)?;
                Ok(scene)
            });
        match checked {
            Ok(scene) => {
                for w in &scene.warnings {
                    println!("note: {}: {w}", path.display());
                }
                println!(
                    "{}: ok: {} x {}, {} spp, max depth {}; primitives {}, materials {}, \
                 textures {}, lights {}{}",
                    path.display(),
                    scene.width,
                    scene.height,
                    scene.spp,
                    scene.max_depth,
                    scene.primitives.len(),
                    scene.materials.len(),
                    scene.textures.len(),
                    scene.emitters.len(),
                    if scene.use_bvh { ", BVH" } else { "" }
                )
            }
            Err(e) => {
                failed += 1;
                eprintln!("error: {e:#}");
            }
        }
    }
    if failed > 0 {
        anyhow::bail!("{failed} of {} scenes have problems", paths.len());
    }
    Ok(())
}

fn info() -> anyhow::Result<()> {
    let adapters = wgtrace::gpu::list_adapters();
    if adapters.is_empty() {
        println!("{}", wgtrace::gpu::GpuError::NoAdapter);
    }
    for (i, a) in adapters.iter().enumerate() {
        println!("[{i}] {}", wgtrace::gpu::context::describe(a));
    }
    Ok(())
}

fn check(adapter: Option<&str>, tuning: Tuning) -> anyhow::Result<()> {
    let selected = wgtrace::gpu::context::select_adapter(adapter)?;
    let ctx = wgtrace::gpu::GpuContext::shared(selected.index)?;
    println!("adapter: {}", wgtrace::gpu::context::describe(&ctx.info));
    println!(
        "{} rays per row against the CPU reference (at most 1 in 1000 may differ: edges), and a \
         spot check of {} x {} pixel tiles of a render's first sample (at least {}% agree)",
        wgtrace::check::RAYS,
        wgtrace::spot_check::GRID * wgtrace::spot_check::GRID,
        wgtrace::spot_check::TILE * wgtrace::spot_check::TILE,
        wgtrace::spot_check::MIN_AGREEMENT * 100.0
    );
    println!(
        "{:<6} {:<9} {:<12} {:>8} {:<22} {:>8}  records",
        "class", "placement", "rays differ", "kernel", "spot check", "render"
    );
    let started = std::time::Instant::now();
    let rows = wgtrace::check::run(ctx, &tuning, |r| {
        println!(
            "{:<6} {:<9} {:<12} {:>7.2}s {:<22} {:>7.2}s  {}",
            r.class,
            r.placement,
            format!(
                "{} {}",
                r.rays_differ,
                if r.rays_differ * 1000 <= r.rays {
                    "ok"
                } else {
                    "FAIL"
                }
            ),
            r.kernel_time.as_secs_f64(),
            format!(
                "{}/{} {}",
                r.spot.agreeing,
                r.spot.pixels,
                if r.spot.passed() { "ok" } else { "FAIL" }
            ),
            r.spot.gpu_time.as_secs_f64(),
            r.records
        );
    })?;
    let failed: Vec<_> = rows.iter().filter(|r| !r.passed()).collect();
    for r in &failed {
        if let Some(d) = &r.first_ray_difference {
            println!("{} / {}: first ray that differs: {d}", r.class, r.placement);
        }
        if !r.spot.passed() {
            println!(
                "{} / {}: spot check: {}",
                r.class,
                r.placement,
                r.spot.describe()
            );
        }
    }
    let secs = started.elapsed().as_secs_f64();
    if failed.is_empty() {
        println!(
            "all {} rows agree with the CPU reference ({secs:.1} s)",
            rows.len()
        );
        Ok(())
    } else {
        anyhow::bail!(
            "{} of {} rows differ from the CPU reference ({secs:.1} s): renders on this \
             adapter are refused where their placement differs; render with --backend cpu, \
             or use another driver (for lavapipe, Mesa 25 from Debian's bookworm-backports)",
            failed.len(),
            rows.len()
        )
    }
}

fn features(path: &Path) -> anyhow::Result<()> {
    use wgtrace::gpu::bindings::{Placement, Slot};
    use wgtrace::gpu::plan::ShaderSpec;
    let scene = wgtrace::load_scene(path, &Overrides::default())?;
    let plan = GpuPlan::new(&scene, &DeviceFit::portable(), &Tuning::default());
    let spec = &plan.shader;
    println!("{}: features", path.display());
    for f in Feature::all() {
        let on = if spec.features.contains(f) {
            "yes"
        } else {
            "-"
        };
        println!("  {:<16} {on}", f.name());
    }
    // a list, or "none"
    let listed = |names: Vec<&str>| {
        if names.is_empty() {
            "none".to_string()
        } else {
            names.join(", ")
        }
    };
    let bound = spec.trace_slots();
    let placed = |p: Placement| {
        let names = Slot::RECORDS
            .into_iter()
            .filter(|&s| {
                spec.placements.get(s) == p && (p == Placement::Shader || bound.contains(&s))
            })
            .map(Slot::name)
            .collect();
        listed(names)
    };
    // the record arrays the shader binds as uniform buffers (not those written into it)
    println!("uniform records: {}", placed(Placement::Uniform));
    println!("texture records: {}", placed(Placement::Texture));
    println!(
        "records written into the shader: {}",
        placed(Placement::Shader)
    );
    let size = |spec: &ShaderSpec| -> anyhow::Result<(usize, usize, usize)> {
        let wgsl = spec.wgsl("trace")?;
        Ok((wgsl.len(), wgsl.lines().count(), spec.trace_slots().len()))
    };
    let (sb, sl, sn) = size(spec)?;
    let (fb, fl, fn_) = size(&ShaderSpec::full())?;
    println!(
        "trace shader: specialized {sb} bytes, {sl} lines, {sn} bindings; \
         full {fb} bytes, {fl} lines, {fn_} bindings"
    );
    println!("samples per invocation: {}", plan.sample_group);
    Ok(())
}

/// The backend asked for, with the adapter `--adapter` or a scheduler's variables choose
/// (`wgtrace::gpu::select`), and a line saying why when it is not the default.
fn backend_choice(
    arg: BackendArg,
    adapter: Option<&str>,
) -> anyhow::Result<(BackendChoice, Option<String>)> {
    match arg {
        BackendArg::Gpu => {
            let s = wgtrace::gpu::context::select_adapter(adapter)?;
            Ok((BackendChoice::Gpu { adapter: s.index }, s.reason))
        }
        BackendArg::Cpu => Ok((BackendChoice::Cpu, None)),
    }
}

fn converge(args: ConvergeArgs) -> anyhow::Result<()> {
    use wgtrace::converge::{self, Config, Event};
    let configs = if args.configs.is_empty() {
        Config::defaults()
    } else {
        args.configs.clone()
    };
    let opts = converge::Options {
        scene: args.scene.clone(),
        overrides: Overrides {
            width: args.width,
            height: args.height,
            max_depth: args.max_depth,
            ..Default::default()
        },
        reference: args.reference.clone(),
        reference_spp: args.reference_spp,
        reference_backend: backend_choice(args.reference_backend, args.adapter.as_deref())?.0,
        spp_max: args.spp_max,
        runs: args.runs,
        configs,
        backend: backend_choice(args.backend, args.adapter.as_deref())?.0,
        out: args.out.clone(),
        denoise: args.denoise,
    };
    let bar = progress_bar(
        args.quiet,
        1,
        "{elapsed_precise} [{bar:30}] {pos}/{len} {msg}",
    );
    let mut notes = std::collections::HashSet::new();
    let study = converge::run(&opts, |e| match e {
        Event::Note(note) => {
            // every render of the study opens a backend: each note once
            if notes.insert(note.to_string()) {
                bar.suspend(|| eprintln!("{note}"));
            }
        }
        Event::Reference { spp, done } => {
            bar.set_length(spp as u64);
            bar.set_position(done as u64);
            bar.set_message("reference passes");
        }
        Event::ReferenceReady { path, cached } => bar.suspend(|| {
            eprintln!(
                "reference: {}{}",
                path.display(),
                if cached { " (cached)" } else { "" }
            )
        }),
        Event::Passes { done, total } => {
            bar.set_length(total);
            bar.set_position(done);
        }
        Event::Measured(m) => {
            bar.set_message(format!(
                "{} run {} spp {}: relMSE {:.2e}",
                m.config, m.run, m.spp, m.rel_mse
            ));
        }
    })?;
    bar.finish_and_clear();
    println!(
        "{}: {} configurations, {} measurements on {}; {}",
        args.scene.display(),
        study.configs.len(),
        study.measurements.len(),
        study.device,
        args.out.join("report.md").display()
    );
    Ok(())
}

fn default_output(scene: &Path) -> PathBuf {
    let stem = scene.file_stem().unwrap_or_default().to_string_lossy();
    PathBuf::from(format!("{stem}.png"))
}

fn render(args: RenderArgs) -> anyhow::Result<()> {
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| default_output(&args.scene));
    // refuse a bad output name or place before spending time on loading
    check_writable(&output)?;
    let overrides = Overrides {
        width: args.width,
        height: args.height,
        spp: args.spp,
        max_depth: args.max_depth,
        seed: args.seed,
        sampler: args.sampler,
        light_sampling: args.light_sampling,
        filter: args.filter,
        background: args.background,
        camera: args.camera.clone(),
        energy_compensation: args.energy_compensation,
        defines: args.define.clone(),
    };
    let tuning = args.tune.unwrap_or_default();
    if tuning.lane_stats && matches!(args.backend, BackendArg::Cpu) {
        anyhow::bail!("--tune lane-stats counts the GPU's lanes: it needs --backend gpu");
    }
    let loading = std::time::Instant::now();
    let scene = wgtrace::scene::load(&args.scene, &overrides, tuning.build())?;
    // the first signal stops after the current pass and keeps the work; a second one, for
    // a pass that takes too long, exits at once, and so does the first while the driver
    // compiles the shader (no sample is in flight then, and nothing is half-written)
    let interrupt = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let flag = interrupt.clone();
    ctrlc::set_handler(move || {
        if wgtrace::gpu::context::compiling()
            || flag.swap(true, std::sync::atomic::Ordering::SeqCst)
        {
            std::process::exit(130);
        }
    })
    .context("installing the Ctrl-C handler")?;
    let limited = args.time_limit.is_some() || args.target_error.is_some();
    let rule = StopRule {
        time_limit: args.time_limit.map(std::time::Duration::from_secs_f64),
        target_error: args.target_error,
        interrupt: Some(interrupt),
        until: None,
    };
    for w in &scene.warnings {
        eprintln!("note: {}: {w}", args.scene.display());
    }
    if !args.quiet {
        eprintln!(
            "scene: {} primitives ({} unbounded), {} BVH nodes of depth {}, {:.2} s to load",
            scene.primitives.len(),
            scene.num_unbounded,
            scene.bvh_node_count(),
            scene.bvh_depth,
            loading.elapsed().as_secs_f64()
        );
    }
    let (backend, why) = backend_choice(args.backend, args.adapter.as_deref())?;
    if let (Some(why), false) = (why, args.quiet) {
        eprintln!("adapter: {why}");
    }
    let opts = session_options(&args, backend, tuning, output.clone(), limited);
    let mut session = Session::open(scene, opts)?;
    if let Some(note) = session.note() {
        eprintln!("{note}");
    }
    eprintln!("device: {}", session.device());
    if let (Some(at), Some(path)) = (session.resumed_at(), &args.resume) {
        eprintln!("resuming {} at sample {at}", path.display());
    }
    let bar = progress_bar(
        args.quiet,
        session.range().end as u64,
        "{elapsed_precise} [{bar:30}] {pos}/{len} passes  {msg}  ETA {eta}",
    );
    let first = session.range().start;
    let result = session.run(&rule, |p| {
        bar.set_position(p.passes_done as u64);
        bar.set_message(format!("{:.2} Msamples/s", p.samples_per_second() / 1e6));
    });
    bar.finish_and_clear();
    let done = match result {
        Ok(done) => done,
        Err(e) => {
            let message = failure(&args.scene, &e);
            if let SessionError::Interrupted { .. } = e {
                eprintln!("{message}");
                return Err(Interrupted.into());
            }
            anyhow::bail!("{message}");
        }
    };
    let mut line = summary(&output, &done, first, limited && args.spp.is_some());
    if limited && args.spp.is_none() && done.stopped == Stopped::AllPasses {
        let sampler = session.scene().sampler;
        if sampler.depends_on_spp() {
            line += &format!(
                " (all passes: the {} sampler places its points for the scene's {} spp; \
                 --spp asks for more)",
                sampler.name(),
                session.scene().spp
            );
        }
    }
    println!("{line}");
    if tuning.lane_stats {
        let (share, per_sample) = done.accumulation.lane_shares();
        println!(
            "live lanes (share of the subgroup's lanes in each step, and lane steps per \
             sample): bounce loop {:.1}% ({:.2}), BVH node steps {:.1}% ({:.2}), BVH \
             primitive tests {:.1}% ({:.2})",
            100.0 * share[0],
            per_sample[0],
            100.0 * share[1],
            per_sample[1],
            100.0 * share[2],
            per_sample[2]
        );
    }
    Ok(())
}

/// The session a render's flags ask for: the checkpoint file (`--checkpoint`, else the
/// one resumed, else beside the image) is written on an interrupt or a lost device, every
/// `--checkpoint-every` seconds with `--checkpoint`, and at the end when a later run will
/// continue or merge it.
fn session_options(
    args: &RenderArgs,
    backend: BackendChoice,
    tuning: Tuning,
    output: PathBuf,
    limited: bool,
) -> SessionOptions {
    let checkpoint = args
        .checkpoint
        .clone()
        .or_else(|| args.resume.clone())
        .unwrap_or_else(|| output.with_extension("ckpt"));
    SessionOptions {
        backend,
        cpu_fallback: true,
        tuning,
        passes: match (&args.sample_range, limited, args.spp) {
            (Some(r), _, _) => Passes::Range(r.clone()),
            // limited by time or error, the scene's spp no longer caps the passes
            (None, true, None) => Passes::Uncapped,
            _ => Passes::Scene,
        },
        resume: args.resume.clone(),
        saving: Some(Saving {
            path: checkpoint,
            periodic: args.checkpoint.is_some(),
            every: std::time::Duration::from_secs_f64(args.checkpoint_every),
            at_end: args.checkpoint.is_some()
                || args.resume.is_some()
                || args.sample_range.is_some(),
        }),
        output: Some(Output {
            image: output,
            error_map: args.error_map.clone(),
            preview_every: args.preview_every,
            aovs: args.aov.clone(),
            denoise: args.denoise,
        }),
        submission_target: std::time::Duration::from_secs_f64(args.submission_time),
    }
}

/// What a render that stopped short says: the session's error, and the command that
/// continues it when its work is in a checkpoint (an interrupt, a lost device).
fn failure(scene: &Path, e: &SessionError) -> String {
    let resume = e.resumable().map(|ckpt| {
        format!(
            "; continue with\n  wgtrace render {} --resume {} (and the same options)",
            scene.display(),
            ckpt.display()
        )
    });
    format!("{e}{}", resume.unwrap_or_default())
}

/// The line a finished render prints: the image, its size, samples, time and rate, the
/// samples dropped as not finite (there should be none), the error estimate, why it
/// stopped.
fn summary(
    output: &Path,
    done: &wgtrace::session::Finished,
    first: u32,
    limited_spp: bool,
) -> String {
    let p = &done.progress;
    let acc = &done.accumulation;
    let mut summary = format!(
        "{}: {}x{}, {} spp, {:.3} s, {:.3} Msamples/s, {} non-finite",
        output.display(),
        acc.width,
        acc.height,
        p.passes_done - first,
        p.elapsed.as_secs_f64(),
        p.samples_per_second() / 1e6,
        acc.non_finite()
    );
    if let Some(e) = done.estimate {
        summary += &format!(", estimated relative error {e:.4}");
    }
    match done.stopped {
        Stopped::TimeLimit => summary += " (time limit)",
        Stopped::TargetError => summary += " (target error reached)",
        Stopped::AllPasses if limited_spp => summary += " (all passes)",
        Stopped::AllPasses => {}
    }
    summary
}

/// A progress bar of `len` steps with `template`, or a hidden one.
fn progress_bar(quiet: bool, len: u64, template: &str) -> ProgressBar {
    let bar = if quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(len)
    };
    bar.set_style(
        ProgressStyle::with_template(template)
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    /// A lost device's message says what was saved and how to continue (the session
    /// side is tests/gpu.rs's `a_device_lost_mid_render_keeps_the_samples_read_back`).
    #[test]
    fn a_lost_device_says_how_to_continue() {
        use wgtrace::session::LostDevice;
        let e = SessionError::DeviceLost(Box::new(LostDevice {
            error: wgtrace::gpu::GpuError::Lost("the device was lost (test)".into()),
            at: 9,
            saved: Some(0..8),
            image: Some(PathBuf::from("out.png")),
            checkpoint: PathBuf::from("out.ckpt"),
            every: std::time::Duration::ZERO,
        }));
        let m = failure(Path::new("scene.toml"), &e);
        assert!(
            m.contains("at sample 9; wrote samples 0..8")
                && m.contains("out.png and checkpoint out.ckpt")
                && m.ends_with(
                    "wgtrace render scene.toml --resume out.ckpt (and the same options)"
                ),
            "{m}"
        );
    }

    /// `wgtrace --help` and each command's help describe every command, option and value.
    #[test]
    fn every_command_option_and_value_has_help() {
        let cli = Cli::command();
        cli.clone().debug_assert();
        assert!(cli.get_after_help().is_some());
        for sub in cli.get_subcommands() {
            let name = sub.get_name();
            assert!(sub.get_about().is_some(), "`wgtrace {name}` has no help");
            for arg in sub.get_arguments() {
                let id = arg.get_id().as_str();
                if id == "help" {
                    continue;
                }
                assert!(
                    arg.get_help().is_some(),
                    "`wgtrace {name}`: {id} has no help"
                );
                let values = if arg.get_action().takes_values() {
                    arg.get_possible_values()
                } else {
                    Vec::new()
                };
                for value in values {
                    assert!(
                        value.get_help().is_some() || value.is_hide_set(),
                        "`wgtrace {name}`: {id} value {} has no help",
                        value.get_name()
                    );
                }
            }
        }
    }
}
