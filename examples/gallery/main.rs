//! The gallery, a development tool: renders every image of the README's gallery to
//! `docs/gallery/NAME.png` and rewrites the README's gallery table with each render time
//! and the day. Run it from the repository root:
//!
//! ```text
//! cargo run --release --example gallery                     # every image, then the table
//! cargo run --release --example gallery -- --only box --spp 16   # a quick look at one
//! ```
//!
//! A scene that needs a file too large for the repository (the 100k-triangle terrain)
//! gets it written first, by the `gen_mesh` example.

mod entries;
mod readme;

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Parser;
use entries::{Entry, ENTRIES, GALLERY_SPP};
use readme::{readme_block, replace_block, Rendered};
use wgtrace::engine::BackendChoice;
use wgtrace::report::today;
use wgtrace::scene::load::Overrides;
use wgtrace::session::{load_scene, Output, Session, SessionError, SessionOptions, StopRule};

/// Render the README's gallery (every scene of scenes/, and the Cornell box with each
/// pixel sampler) to OUT/NAME.png, then rewrite the README's gallery table.
#[derive(Parser)]
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

fn main() -> anyhow::Result<()> {
    gallery(GalleryArgs::parse())
}

fn gallery(args: GalleryArgs) -> anyhow::Result<()> {
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
        let r = render(e, args.spp, args.adapter, &args.out)?;
        println!(
            "{}: {} x {}, {} spp, {:.2} s, {} non-finite",
            args.out.join(format!("{}.png", e.name)).display(),
            r.width,
            r.height,
            r.spp,
            r.seconds,
            r.non_finite
        );
        rendered.push(r);
    }
    let device = rendered.last().map_or(String::new(), |r| r.device.clone());
    if !full {
        println!("{} left alone (a partial gallery)", args.readme.display());
        return Ok(());
    }
    let base = args.readme.parent().unwrap_or(Path::new(""));
    let dir = args.out.strip_prefix(base).unwrap_or(&args.out);
    let block = readme_block(&rendered, &device, &today(), &dir.to_string_lossy());
    let updated = replace_block(&readme, &block)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.readme.display()))?;
    std::fs::write(&args.readme, updated)
        .with_context(|| format!("writing {}", args.readme.display()))?;
    println!("{}: gallery table written", args.readme.display());
    Ok(())
}

/// Renders `entry` on Vulkan adapter `adapter` to `out/NAME.png`, with `spp` samples per
/// pixel instead of its own when given. A first, one-sample render compiles the shader
/// (lavapipe compiles at the first dispatch), so the seconds are the render's alone.
fn render(
    entry: &Entry,
    spp: Option<u32>,
    adapter: usize,
    out: &Path,
) -> Result<Rendered, SessionError> {
    let overrides = Overrides {
        spp: Some(spp.or(entry.spp).unwrap_or(GALLERY_SPP)),
        sampler: entry.sampler,
        ..Default::default()
    };
    let scene = load_scene(Path::new(entry.scene), &overrides)?;
    let opts = SessionOptions {
        backend: BackendChoice::Gpu { adapter },
        ..Default::default()
    };
    let mut warm = scene.clone();
    warm.spp = 1;
    Session::open(warm, opts.clone())?.run(&StopRule::default(), |_| {})?;
    let output = Output {
        image: out.join(format!("{}.png", entry.name)),
        error_map: None,
        preview_every: None,
        aovs: Vec::new(),
        denoise: false,
    };
    let opts = SessionOptions {
        output: Some(output),
        ..opts
    };
    let mut session = Session::open(scene.clone(), opts)?;
    let done = session.run(&StopRule::default(), |_| {})?;
    let acc = &done.accumulation;
    Ok(Rendered {
        entry: *entry,
        width: scene.width,
        height: scene.height,
        spp: scene.spp,
        seconds: done.progress.elapsed.as_secs_f64(),
        device: session.device(),
        non_finite: acc.non_finite(),
    })
}
