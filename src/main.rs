//! The `wgtrace` command line: parse, call the library, report.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context;
use clap::{Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

use wgtrace::checkpoint::Checkpoint;
use wgtrace::gpu::GpuError;
use wgtrace::image_io::{check_writable, probe_writable, write_error_map, write_image};
use wgtrace::render::{render_from, render_progressive, Accumulation, StopRule, Stopped};
use wgtrace::scene::format::{LightSampling, SamplerKind};
use wgtrace::{BackendChoice, Engine, Overrides};

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
    Render(RenderArgs),
    /// Measure how error falls with samples and seconds, per sampler and light-sampling
    /// strategy, against a reference; writes results.csv, report.md and plots.
    Converge(ConvergeArgs),
    /// Print the features a scene uses, the shader defines they select, and the size of the
    /// specialized shader against the full one.
    Features {
        /// Scene file (TOML).
        scene: PathBuf,
    },
    /// Check scene files without rendering them: parse, validate every value, load their
    /// textures and meshes, build the BVH, and assemble and validate the shader each would
    /// use. Prints a summary per scene; exits non-zero if any scene has a problem.
    Validate {
        /// Scene files (TOML).
        #[arg(required = true)]
        scenes: Vec<PathBuf>,
    },
    /// Render the README's gallery (every scene of scenes/, and the Cornell box with each
    /// pixel sampler) to OUT/NAME.png, then rewrite the README's gallery table with each
    /// render time. Run it from the repository root.
    Gallery(GalleryArgs),
    /// List the Vulkan adapters wgtrace can see, in the order `--adapter` counts them.
    Info,
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
    },
}

#[derive(clap::Args)]
struct GalleryArgs {
    /// Folder for the images.
    #[arg(long, default_value = "docs/gallery")]
    out: PathBuf,
    /// README whose gallery block (between its two gallery comment lines) is rewritten.
    #[arg(long, default_value = "README.md")]
    readme: PathBuf,
    /// Render only these images (names as in the table, e.g. `--only box --only sky`); the
    /// README is then left alone.
    #[arg(long, value_name = "NAME")]
    only: Vec<String>,
    /// Samples per pixel for every image instead of each entry's own (quick looks); the
    /// README is then left alone.
    #[arg(long)]
    spp: Option<u32>,
    /// Which Vulkan adapter (index from `wgtrace info`).
    #[arg(long, default_value_t = 0)]
    adapter: usize,
}

#[derive(clap::Args)]
struct ConvergeArgs {
    /// Scene file (TOML).
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
    /// Which Vulkan adapter (index from `wgtrace info`).
    #[arg(long, default_value_t = 0)]
    adapter: usize,
    /// Image width (overrides [render] width, for every render and the reference).
    #[arg(long)]
    width: Option<u32>,
    /// Image height (overrides [render] height).
    #[arg(long)]
    height: Option<u32>,
    /// Rays per path of configurations that give none (overrides [render] max_depth).
    #[arg(long)]
    max_depth: Option<u32>,
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
    /// Scene file (TOML).
    scene: PathBuf,
    /// Output image; the extension picks the format: .png (8-bit sRGB), .exr (linear float),
    /// .ppm (binary P6). Default: the scene's name with .png, in the current directory.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Which backend renders.
    #[arg(long, value_enum, default_value_t = BackendArg::Gpu)]
    backend: BackendArg,
    /// Which Vulkan adapter (index from `wgtrace info`).
    #[arg(long, default_value_t = 0)]
    adapter: usize,
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
    /// Rewrite the output file every N passes, to watch the render converge.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    preview_every: Option<u32>,
    /// Pixel sampler (overrides [render] sampler).
    #[arg(long, value_enum)]
    sampler: Option<SamplerKind>,
    /// How paths find lights (overrides [render] light_sampling).
    #[arg(long, value_enum)]
    light_sampling: Option<LightSampling>,
    /// Stop after as many passes as fit in this many seconds, then write the image. Without
    /// --spp the scene's spp no longer caps the passes (except for hammersley, whose point
    /// set depends on it).
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
    /// Test every primitive on every ray instead of traversing the BVH (for comparisons).
    #[arg(long)]
    no_bvh: bool,
    /// Run the full shader instead of one specialized to the scene's features (for
    /// comparisons and debugging).
    #[arg(long)]
    no_specialize: bool,
    /// Walk the BVH even in a scene of at most 16 untransformed primitives, where a plain
    /// loop over them is the default (for comparisons).
    #[arg(long, conflicts_with = "no_bvh")]
    bvh: bool,
    /// Keep every scene record in a storage buffer, none in a uniform buffer (for
    /// comparisons).
    #[arg(long)]
    no_uniform_records: bool,
    /// Read a small scene's primitives, materials and lights from their buffers instead
    /// of writing them into its shader as constants (for comparisons).
    #[arg(long)]
    no_baked_records: bool,
    /// Trace one sample per GPU invocation instead of a group of 16 (for comparisons).
    #[arg(long)]
    no_sample_groups: bool,
    /// Trace every path to max_depth without Russian roulette (for comparisons; Russian
    /// roulette from the fourth ray on is unbiased).
    #[arg(long)]
    no_russian_roulette: bool,
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
    /// No progress bar.
    #[arg(short, long)]
    quiet: bool,
}

/// Set by Ctrl-C (SIGINT) or SIGTERM: the render stops after the current pass.
static INTERRUPTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// A render that Ctrl-C or SIGTERM stopped, its image and checkpoint written.
#[derive(Debug, thiserror::Error)]
#[error("interrupted")]
struct Interrupted;

fn positive_f64(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v > 0.0 && v.is_finite() => Ok(v),
        _ => Err(format!("must be a number > 0, got {s}")),
    }
}

/// The pass cap of a render limited by time or error when --spp is not given.
const UNCAPPED_PASSES: u32 = 1 << 20;

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render(args),
        Command::Converge(args) => converge(args),
        Command::Features { scene } => features(&scene),
        Command::Validate { scenes } => validate(&scenes),
        Command::Gallery(args) => gallery(args),
        Command::Info => info(),
        Command::Merge {
            checkpoints,
            output,
            checkpoint,
        } => merge(&checkpoints, &output, checkpoint.as_deref()),
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

fn merge(inputs: &[PathBuf], output: &Path, checkpoint: Option<&Path>) -> anyhow::Result<()> {
    check_writable(output)?;
    let parts = inputs
        .iter()
        .map(|p| Ok((p.clone(), Checkpoint::read(p)?)))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let merged = Checkpoint::merge(&parts)?;
    let acc = &merged.accumulation;
    write_image(output, acc.width, acc.height, &acc.to_rgb())?;
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
    use wgtrace::gpu::shader::{scene_shader, trace_shader, validate};
    let mut failed = 0;
    for path in paths {
        let checked = wgtrace::load_scene(path, &Overrides::default())
            .map_err(anyhow::Error::from)
            .and_then(|scene| {
                let wgsl = trace_shader(&scene_shader(&scene))?;
                validate("trace", &wgsl)?;
                Ok(scene)
            });
        match checked {
            Ok(scene) => println!(
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
            ),
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

fn gallery(args: GalleryArgs) -> anyhow::Result<()> {
    use wgtrace::gallery::{readme_block, replace_block, Rendered, ENTRIES, GALLERY_SPP};
    let unknown: Vec<&String> = args
        .only
        .iter()
        .filter(|n| !ENTRIES.iter().any(|e| e.name == n.as_str()))
        .collect();
    if !unknown.is_empty() {
        let names: Vec<&str> = ENTRIES.iter().map(|e| e.name).collect();
        anyhow::bail!(
            "no gallery image {unknown:?}; the images are: {}",
            names.join(", ")
        );
    }
    // a full run rewrites the README's table: check it has one before rendering for minutes
    let full = args.only.is_empty() && args.spp.is_none();
    let readme = if full {
        let text = std::fs::read_to_string(&args.readme)
            .with_context(|| format!("reading {}", args.readme.display()))?;
        replace_block(&text, "").map_err(|e| anyhow::anyhow!("{}: {e}", args.readme.display()))?;
        text
    } else {
        String::new()
    };
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let mut rendered = Vec::new();
    let mut device = String::new();
    for e in ENTRIES
        .iter()
        .filter(|e| args.only.is_empty() || args.only.iter().any(|n| n == e.name))
    {
        if let Some((file, cargo_args)) = e.generated {
            if !Path::new(file).exists() {
                println!(
                    "{file} is missing; writing it: cargo {}",
                    cargo_args.join(" ")
                );
                let status = std::process::Command::new("cargo")
                    .args(cargo_args)
                    .status()
                    .with_context(|| format!("running cargo to write {file}"))?;
                anyhow::ensure!(status.success(), "cargo {} failed", cargo_args.join(" "));
            }
        }
        let overrides = Overrides {
            spp: Some(args.spp.or(e.spp).unwrap_or(GALLERY_SPP)),
            sampler: e.sampler,
            ..Default::default()
        };
        let scene = wgtrace::load_scene(Path::new(e.scene), &overrides)?;
        // a first, one-sample render compiles the shader (lavapipe compiles at the first
        // dispatch), so the time is the render's alone
        let mut warm = scene.clone();
        warm.spp = 1;
        let no_report = |_: &_, _: &mut Engine| Ok::<(), GpuError>(());
        render_progressive(&mut Engine::gpu(&warm, args.adapter)?, &warm, no_report)?;
        let mut engine = Engine::gpu(&scene, args.adapter)?;
        device = engine.name();
        let progress = render_progressive(&mut engine, &scene, no_report)?;
        let acc = engine.accumulation()?;
        let output = args.out.join(format!("{}.png", e.name));
        write_image(&output, scene.width, scene.height, &acc.to_rgb())?;
        let seconds = progress.elapsed.as_secs_f64();
        println!(
            "{}: {} x {}, {} spp, {seconds:.2} s, {} non-finite",
            output.display(),
            scene.width,
            scene.height,
            scene.spp,
            acc.non_finite()
        );
        rendered.push(Rendered {
            entry: *e,
            width: scene.width,
            height: scene.height,
            spp: scene.spp,
            seconds,
        });
    }
    if !full {
        println!("{} left alone (a partial gallery)", args.readme.display());
        return Ok(());
    }
    let base = args.readme.parent().unwrap_or(Path::new(""));
    let dir = args.out.strip_prefix(base).unwrap_or(&args.out);
    let block = readme_block(&rendered, &device, &dir.to_string_lossy());
    let updated = replace_block(&readme, &block)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.readme.display()))?;
    std::fs::write(&args.readme, updated)
        .with_context(|| format!("writing {}", args.readme.display()))?;
    println!("{}: gallery table written", args.readme.display());
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

fn features(path: &Path) -> anyhow::Result<()> {
    use wgtrace::gpu::shader::{all_defines, scene_shader, trace_shader, used_bindings};
    let scene = wgtrace::load_scene(path, &Overrides::default())?;
    let spec = scene_shader(&scene);
    let defines = &spec.defines;
    let all = all_defines();
    println!("{}: features", path.display());
    for d in &all {
        let name = d.trim_start_matches("HAS_").to_ascii_lowercase();
        println!(
            "  {:<16} {}",
            name,
            if defines.contains(d) { "yes" } else { "-" }
        );
    }
    let wgsl = trace_shader(&spec)?;
    let bound = used_bindings("trace", &wgsl, "main", 0)?;
    // a list, or "none"
    let listed = |names: Vec<String>| {
        if names.is_empty() {
            "none".to_string()
        } else {
            names.join(", ")
        }
    };
    // the record arrays the shader binds as uniform buffers (not those written into it)
    let uniform = wgtrace::gpu::shader::UNIFORM_DEFINES
        .iter()
        .filter(|(d, binding)| defines.contains(*d) && bound.contains(binding))
        .map(|(d, _)| d.trim_start_matches("UNIFORM_").to_ascii_lowercase())
        .collect();
    println!("uniform records: {}", listed(uniform));
    let baked = [
        ("BAKED_PRIMITIVES", "primitives"),
        ("BAKED_MATERIALS", "materials"),
        ("BAKED_EMITTERS", "emitters"),
    ]
    .iter()
    .filter(|(d, _)| defines.contains(*d))
    .map(|&(_, name)| name.to_string())
    .collect();
    println!("records written into the shader: {}", listed(baked));
    let size = |wgsl: &str| -> anyhow::Result<(usize, usize, usize)> {
        let bindings = used_bindings("trace", wgsl, "main", 0)?.len();
        Ok((wgsl.len(), wgsl.lines().count(), bindings))
    };
    let (sb, sl, sn) = size(&wgsl)?;
    let (fb, fl, fn_) = size(&trace_shader(&all.into())?)?;
    println!(
        "trace shader: specialized {sb} bytes, {sl} lines, {sn} bindings; \
         full {fb} bytes, {fl} lines, {fn_} bindings"
    );
    Ok(())
}

fn backend_choice(arg: BackendArg, adapter: usize) -> BackendChoice {
    match arg {
        BackendArg::Gpu => BackendChoice::Gpu { adapter },
        BackendArg::Cpu => BackendChoice::Cpu,
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
        reference_backend: backend_choice(args.reference_backend, args.adapter),
        spp_max: args.spp_max,
        runs: args.runs,
        configs,
        backend: backend_choice(args.backend, args.adapter),
        out: args.out.clone(),
    };
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(1)
    };
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:30}] {pos}/{len} {msg}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    let study = converge::run(&opts, |e| match e {
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
    // Refuse a bad output name or place before spending time on the render.
    check_writable(&output)?;
    if let Some(map) = &args.error_map {
        check_writable(map)?;
    }
    let checkpoint_path = args
        .checkpoint
        .clone()
        .or_else(|| args.resume.clone())
        .unwrap_or_else(|| output.with_extension("ckpt"));
    probe_writable(&checkpoint_path)
        .with_context(|| format!("{}: cannot write checkpoint", checkpoint_path.display()))?;
    let overrides = Overrides {
        width: args.width,
        height: args.height,
        spp: args.spp,
        max_depth: args.max_depth,
        seed: args.seed,
        no_bvh: args.no_bvh,
        sampler: args.sampler,
        light_sampling: args.light_sampling,
        no_specialize: args.no_specialize,
        force_bvh: args.bvh,
        no_uniform_records: args.no_uniform_records,
        no_baked_records: args.no_baked_records,
        no_sample_groups: args.no_sample_groups,
        no_russian_roulette: args.no_russian_roulette,
    };
    let loading = std::time::Instant::now();
    let mut scene = wgtrace::load_scene(&args.scene, &overrides)?;
    let limited = args.time_limit.is_some() || args.target_error.is_some();
    if limited && args.spp.is_none() && scene.sampler != wgtrace::scene::records::SAMPLER_HAMMERSLEY
    {
        scene.spp = UNCAPPED_PASSES;
    }
    if !args.quiet {
        eprintln!(
            "scene: {} primitives ({} unbounded), {} BVH nodes of depth {}, {:.2} s to load",
            scene.primitives.len(),
            scene.num_unbounded,
            scene.bvh.len(),
            scene.bvh_depth,
            loading.elapsed().as_secs_f64()
        );
    }
    let choice = backend_choice(args.backend, args.adapter);
    let (mut engine, note) = Engine::open(&scene, choice)?;
    if let Some(note) = note {
        eprintln!("{note}");
    }
    eprintln!("device: {}", engine.name());
    let range = args.sample_range.clone().unwrap_or(0..scene.spp);
    if range.end > scene.spp {
        anyhow::bail!(
            "--sample-range {}..{} ends past the render's {} samples per pixel",
            range.start,
            range.end,
            scene.spp
        );
    }
    let mut first = range.start;
    if let Some(path) = &args.resume {
        let ckpt = Checkpoint::read(path)?;
        ckpt.check(&scene, path)?;
        let held = ckpt.contiguous().filter(|r| r.start == range.start);
        let Some(held) = held else {
            anyhow::bail!(
                "{}: holds samples {:?}, which do not start this render's samples {}..{}",
                path.display(),
                ckpt.samples,
                range.start,
                range.end
            );
        };
        engine.set_accumulation(&ckpt.accumulation)?;
        first = held.end;
        eprintln!("resuming {} at sample {first}", path.display());
    }
    let save_acc = |acc: Accumulation, passes: u32| -> anyhow::Result<()> {
        let ckpt = Checkpoint::new(&scene, range.start..passes, acc);
        ckpt.write(&checkpoint_path)
            .with_context(|| format!("writing checkpoint {}", checkpoint_path.display()))
    };
    // the first signal stops after the current pass and keeps the work; a second one, for
    // a pass that takes too long, exits at once
    ctrlc::set_handler(|| {
        if INTERRUPTED.swap(true, std::sync::atomic::Ordering::SeqCst) {
            std::process::exit(130);
        }
    })
    .context("installing the Ctrl-C handler")?;

    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(scene.spp as u64)
    };
    bar.set_style(
        ProgressStyle::with_template(
            "{elapsed_precise} [{bar:30}] {pos}/{len} passes  {msg}  ETA {eta}",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    let (w, h) = (scene.width, scene.height);
    let write_acc = |acc: &Accumulation| -> anyhow::Result<()> {
        write_image(&output, w, h, &acc.to_rgb())?;
        Ok(())
    };
    let write = |engine: &mut Engine| -> anyhow::Result<()> { write_acc(&engine.accumulation()?) };
    let rule = StopRule {
        time_limit: args.time_limit.map(std::time::Duration::from_secs_f64),
        target_error: args.target_error,
    };
    engine.set_submission_target(std::time::Duration::from_secs_f64(args.submission_time));
    // for tests of a device lost mid-render: the device is destroyed once this many
    // samples are done
    let lose_device_at: Option<u32> = std::env::var("WGTRACE_LOSE_DEVICE_AT_SAMPLE")
        .ok()
        .and_then(|v| v.parse().ok());
    let mut passes_done = first;
    let mut last_save = std::time::Instant::now();
    // Without --checkpoint, the accumulation read back every --checkpoint-every seconds
    // is kept here instead, to be written out if the device is lost.
    let mut kept: Option<(u32, Accumulation)> = None;
    // whether the checkpoint file holds this render's state (as --resume left it, or as
    // written since)
    let mut on_disk = args.resume.as_ref() == Some(&checkpoint_path);
    let result = render_from(&mut engine, &scene, rule, first..range.end, |p, engine| {
        let before = passes_done;
        passes_done = p.passes_done;
        bar.set_position(p.passes_done as u64);
        bar.set_message(format!("{:.2} Msamples/s", p.samples_per_second() / 1e6));
        if let Some(n) = args.preview_every {
            if p.passes_done / n > before / n && p.passes_done < p.passes_total {
                write(engine).context("writing preview")?;
            }
        }
        if INTERRUPTED.load(std::sync::atomic::Ordering::SeqCst) {
            return Err(Interrupted.into());
        }
        if last_save.elapsed().as_secs_f64() >= args.checkpoint_every {
            let acc = engine.accumulation()?;
            if args.checkpoint.is_some() {
                save_acc(acc, p.passes_done)?;
                on_disk = true;
            } else {
                kept = Some((p.passes_done, acc));
            }
            last_save = std::time::Instant::now();
        }
        if lose_device_at.is_some_and(|n| p.passes_done >= n) {
            engine.lose_device();
        }
        Ok::<(), anyhow::Error>(())
    });
    bar.finish_and_clear();
    // the sums are read back once; a device lost at any point up to here ends below
    let result = result.and_then(|done| Ok((done, engine.accumulation()?)));
    if let Err(e) = &result {
        if let Some(lost @ (GpuError::Lost(_) | GpuError::Failed(_))) = e.downcast_ref::<GpuError>()
        {
            // the device's sums are gone: write the last ones read back
            let held = match kept.take() {
                Some((held, acc)) => {
                    write_acc(&acc)?;
                    save_acc(acc, held)?;
                    held
                }
                None if on_disk => {
                    let ckpt = Checkpoint::read(&checkpoint_path)?;
                    write_acc(&ckpt.accumulation)?;
                    ckpt.samples.last().map_or(range.start, |r| r.end)
                }
                None => anyhow::bail!(
                    "{lost} at sample {passes_done}; no samples had been read back yet \
                     (that happens every --checkpoint-every {} s), so nothing was written",
                    args.checkpoint_every
                ),
            };
            anyhow::bail!(
                "{lost} at sample {passes_done}; wrote samples {}..{held} (the last read \
                 back) to {} and checkpoint {}; continue with\n  wgtrace render {} --resume {} \
                 (and the same options)",
                range.start,
                output.display(),
                checkpoint_path.display(),
                args.scene.display(),
                checkpoint_path.display()
            );
        }
    }
    let ((done, stopped, estimate), acc) = match result {
        Err(e) if e.is::<Interrupted>() => {
            let acc = engine.accumulation()?;
            write_acc(&acc)?;
            save_acc(acc, passes_done)?;
            eprintln!(
                "interrupted at sample {passes_done}: wrote {} and checkpoint {}; continue with\n  \
                 wgtrace render {} --resume {} (and the same options)",
                output.display(),
                checkpoint_path.display(),
                args.scene.display(),
                checkpoint_path.display()
            );
            return Err(e);
        }
        r => r?,
    };
    write_acc(&acc)?;
    if let Some(map) = &args.error_map {
        let errors: Vec<f32> = (0..acc.pixel_count())
            .map(|i| acc.pixel_rel_mse(i).sqrt() as f32)
            .collect();
        write_error_map(map, w, h, &errors)?;
    }
    // every sample that was not finite was dropped and counted; there should be none
    let dropped = acc.non_finite();
    if args.checkpoint.is_some() || args.resume.is_some() || args.sample_range.is_some() {
        save_acc(acc, done.passes_done)?;
    }
    let mut summary = format!(
        "{}: {}x{}, {} spp, {:.3} s, {:.3} Msamples/s",
        output.display(),
        w,
        h,
        done.passes_done - range.start,
        done.elapsed.as_secs_f64(),
        done.samples_per_second() / 1e6
    );
    summary += &format!(", {dropped} non-finite");
    if let Some(e) = estimate {
        summary += &format!(", estimated relative error {e:.4}");
    }
    match stopped {
        Stopped::TimeLimit => summary += " (time limit)",
        Stopped::TargetError => summary += " (target error reached)",
        Stopped::AllPasses if limited && args.spp.is_some() => summary += " (all passes)",
        Stopped::AllPasses => {}
    }
    println!("{summary}");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

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
