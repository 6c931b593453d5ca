//! The `wgtrace` command line: parse, call the library, report.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context;
use clap::{Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

use wgtrace::image_io::{write_image, OutputFormat};
use wgtrace::render::{render_progressive, Progress};
use wgtrace::scene::format::{LightSampling, SamplerKind};
use wgtrace::{BackendChoice, Engine, Overrides};

#[derive(Parser)]
#[command(
    name = "wgtrace",
    version,
    about = "Headless path tracer: TOML scene in, PNG/EXR/PPM out, on any Vulkan GPU \
             (or lavapipe) with a CPU reference"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene file to an image.
    Render(RenderArgs),
    /// List the Vulkan adapters wgtrace can see, in the order `--adapter` counts them.
    Info,
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
    /// Test every primitive on every ray instead of traversing the BVH (for comparisons).
    #[arg(long)]
    no_bvh: bool,
    /// No progress bar.
    #[arg(short, long)]
    quiet: bool,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render(args),
        Command::Info => info(),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
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

fn default_output(scene: &Path) -> PathBuf {
    let stem = scene.file_stem().unwrap_or_default().to_string_lossy();
    PathBuf::from(format!("{stem}.png"))
}

fn render(args: RenderArgs) -> anyhow::Result<()> {
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| default_output(&args.scene));
    // Refuse a bad output name before spending time on the render.
    OutputFormat::from_path(&output)?;
    let overrides = Overrides {
        width: args.width,
        height: args.height,
        spp: args.spp,
        max_depth: args.max_depth,
        seed: args.seed,
        no_bvh: args.no_bvh,
        sampler: args.sampler,
        light_sampling: args.light_sampling,
    };
    let loading = std::time::Instant::now();
    let scene = wgtrace::load_scene(&args.scene, &overrides)?;
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
    let choice = match args.backend {
        BackendArg::Gpu => BackendChoice::Gpu {
            adapter: args.adapter,
        },
        BackendArg::Cpu => BackendChoice::Cpu,
    };
    let (mut engine, note) = Engine::open(&scene, choice)?;
    if let Some(note) = note {
        eprintln!("{note}");
    }
    eprintln!("device: {}", engine.name());

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
    let write = |engine: &mut Engine| -> anyhow::Result<()> {
        let acc = engine.accumulation()?;
        write_image(&output, w, h, &acc.to_rgb())?;
        Ok(())
    };
    let done: Progress = render_progressive(&mut engine, &scene, |p, engine| {
        bar.set_position(p.passes_done as u64);
        bar.set_message(format!("{:.2} Msamples/s", p.samples_per_second() / 1e6));
        if let Some(n) = args.preview_every {
            if p.passes_done % n == 0 && p.passes_done < p.passes_total {
                write(engine).context("writing preview")?;
            }
        }
        Ok::<(), anyhow::Error>(())
    })?;
    bar.finish_and_clear();
    write(&mut engine)?;
    println!(
        "{}: {}x{}, {} spp, {:.3} s, {:.3} Msamples/s",
        output.display(),
        w,
        h,
        done.passes_done,
        done.elapsed.as_secs_f64(),
        done.samples_per_second() / 1e6
    );
    Ok(())
}
