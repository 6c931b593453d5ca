//! Checkpoints of a progressive render: the accumulation (linear sums, squares and counts
//! per pixel), how many passes it holds, the renderer's version and a hash of the scene as
//! flattened, so a render can stop (Ctrl-C, SIGTERM, a time limit) and continue later to
//! the same result, bit for bit on the same backend.
//!
//! File layout: a text header (`wgtrace checkpoint` on the first line, then `key = value`
//! lines, then an empty line) followed by the sums as little-endian f32, two `[f32; 4]`
//! per pixel. Written to a temporary name and renamed, so a checkpoint on disk is always
//! whole.

use std::ops::Range;
use std::path::{Path, PathBuf};

use crate::accumulation::Accumulation;
use crate::scene::flat::FlatScene;
use crate::scene::records::Params;

const MAGIC: &str = "wgtrace checkpoint";

/// The renderer version a checkpoint must come from.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The checkpoint format (the `format` line of the header). 6: the scene hash covers every
/// byte of every record ([`scene_hash`]), the parameters' `hide_emitters` and samples kept
/// on the image among them, and a light with a surface has its primitive's tag as its
/// kind; format 5 hashed the light records before their kinds were renumbered so, and
/// format 4 the parameters before they held `hide_emitters`, so the hashes of both differ
/// from format 6's for the same scene. Format 3 hashed the parameters before they held the filter, so its hashes differ from
/// format 4's for the same scene. Format 2 hashed a material record only up to its
/// first 96 bytes unless pbr had a layer, so a material keeping parameters past them would
/// not change its hash, and `--resume` or `merge` would take samples of another scene;
/// format 1 (no `format` line) hashed with Rust's `DefaultHasher`, which a new Rust
/// release may change. Files of any of them are refused with the reason.
pub const FORMAT: u32 = 6;

#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("{}: cannot read checkpoint: {cause}", path.display())]
    Io {
        path: PathBuf,
        // not `source`: the message already holds it, and a chain would repeat it
        cause: std::io::Error,
    },
    #[error("{}: not a usable wgtrace checkpoint: {reason}", path.display())]
    Corrupt { path: PathBuf, reason: String },
    #[error("{}: {reason}", path.display())]
    Mismatch { path: PathBuf, reason: String },
}

/// A render's state: the sums of the samples with the indices in `samples` (sorted,
/// disjoint, adjacent ranges joined).
#[derive(Debug, Clone, PartialEq)]
pub struct Checkpoint {
    pub version: String,
    pub scene_hash: u64,
    pub samples: Vec<Range<u32>>,
    pub accumulation: Accumulation,
}

/// Sorts ranges and joins those that touch; None when two overlap.
pub fn join_ranges(mut ranges: Vec<Range<u32>>) -> Option<Vec<Range<u32>>> {
    ranges.retain(|r| !r.is_empty());
    ranges.sort_by_key(|r| r.start);
    let mut out: Vec<Range<u32>> = Vec::new();
    for r in ranges {
        match out.last_mut() {
            Some(last) if r.start < last.end => return None,
            Some(last) if r.start == last.end => last.end = r.end,
            _ => out.push(r),
        }
    }
    Some(out)
}

fn format_ranges(ranges: &[Range<u32>]) -> String {
    let parts: Vec<String> = ranges
        .iter()
        .map(|r| format!("{}..{}", r.start, r.end))
        .collect();
    parts.join(",")
}

/// Parses `START..END` (END > START).
pub fn parse_range(s: &str) -> Result<Range<u32>, String> {
    let (a, b) = s
        .split_once("..")
        .ok_or_else(|| format!("expected START..END, got {s}"))?;
    let parse = |x: &str| {
        x.trim()
            .parse::<u32>()
            .map_err(|_| format!("expected START..END with whole numbers, got {s}"))
    };
    let (a, b) = (parse(a)?, parse(b)?);
    if b <= a {
        return Err(format!("END must exceed START, got {s}"));
    }
    Ok(a..b)
}

/// 64-bit FNV-1a (Fowler, Noll, Vo; offset basis 0xcbf29ce484222325, prime 0x100000001b3)
/// over `bytes`, continuing from `hash`: a specified hash, so the value is the same on every
/// build and platform.
pub fn fnv1a64(hash: u64, bytes: &[u8]) -> u64 {
    bytes.iter().fold(hash, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// FNV-1a's offset basis: the hash of nothing.
pub const FNV1A64_BASIS: u64 = 0xcbf2_9ce4_8422_2325;

/// A hash of everything that decides a render's samples: every byte of the records both
/// backends read, the tables, the texel banks (their kinds and sizes, then their bytes)
/// and the parameters (camera, size, seed, sampler, pixel filter, light sampling, depth), as their
/// little-endian bytes, each array preceded by its length. The sample count is left out,
/// so a resumed render may ask for more samples, except for samplers whose points depend
/// on it (`SamplerKind::depends_on_spp`).
pub fn scene_hash(scene: &FlatScene) -> u64 {
    let mut params = scene.params(0, scene.full_band());
    if !scene.sampler.depends_on_spp() {
        params.spp = 0;
        params.strata_log2 = 0;
    }
    // the parameters but the media's four words, which follow and are hashed only for
    // a scene with media (so a checkpoint's hash does not depend on their placement)
    let bytes = bytemuck::bytes_of(&params);
    let media_at = std::mem::offset_of!(Params, media);
    let before_media = [&bytes[..media_at], &bytes[media_at + 16..]].concat();
    let parts: [&[u8]; 8] = [
        &before_media,
        bytemuck::cast_slice(&scene.primitives),
        bytemuck::cast_slice(&scene.materials),
        bytemuck::cast_slice(&scene.emitters),
        bytemuck::cast_slice(&scene.bvh),
        bytemuck::cast_slice(&scene.shape_data),
        bytemuck::cast_slice(&scene.textures),
        bytemuck::cast_slice(&scene.tables),
    ];
    // the texel banks, when there are images: each bank's kind and size, then its bytes
    // (a scene without images hashes as it did before images had banks)
    let banks: Vec<[u32; 4]> = scene
        .texels
        .banks
        .iter()
        .map(|b| [b.kind as u32, b.width, b.height, b.layers])
        .collect();
    let texels = (!banks.is_empty())
        .then(|| bytemuck::cast_slice(&banks))
        .into_iter()
        .chain(scene.texels.banks.iter().map(|b| &b.data[..]));
    let media = [params.media, params.camera_medium, params.material_media];
    let media = (scene.num_media > 0).then(|| bytemuck::cast_slice(&media));
    parts
        .into_iter()
        .chain(texels)
        .chain(media)
        .fold(FNV1A64_BASIS, |h, part| {
            let h = fnv1a64(h, &(part.len() as u64).to_le_bytes());
            fnv1a64(h, part)
        })
}

impl Checkpoint {
    /// The state of a render of `scene` holding the samples `samples`.
    pub fn new(scene: &FlatScene, samples: Range<u32>, accumulation: Accumulation) -> Self {
        Checkpoint {
            version: VERSION.to_string(),
            scene_hash: scene_hash(scene),
            samples: vec![samples],
            accumulation,
        }
    }

    /// Samples per pixel held.
    pub fn sample_count(&self) -> u32 {
        self.samples.iter().map(|r| r.end - r.start).sum()
    }

    /// The one contiguous range of samples held, if it is one (a render can continue it).
    pub fn contiguous(&self) -> Option<Range<u32>> {
        match self.samples.as_slice() {
            [r] => Some(r.clone()),
            _ => None,
        }
    }

    /// Adds the samples of checkpoints of the same scene, settings, size and version, whose
    /// sample ranges do not overlap (`paths` name them in errors).
    pub fn merge(parts: &[(PathBuf, Checkpoint)]) -> Result<Checkpoint, CheckpointError> {
        let (first_path, first) = parts.first().ok_or_else(|| CheckpointError::Mismatch {
            path: PathBuf::new(),
            reason: "no checkpoints to merge".into(),
        })?;
        let mut merged = first.clone();
        for (path, c) in &parts[1..] {
            let mismatch = |what: &str| CheckpointError::Mismatch {
                path: path.clone(),
                reason: format!("{what} differs from {}'s", first_path.display()),
            };
            if c.version != first.version {
                return Err(mismatch("the renderer version"));
            }
            if c.scene_hash != first.scene_hash {
                return Err(mismatch("the scene or its settings"));
            }
            let (a, b) = (&c.accumulation, &merged.accumulation);
            if (a.width, a.height) != (b.width, b.height) {
                return Err(mismatch("the image size"));
            }
            if a.aovs != b.aovs {
                return Err(mismatch("whether it holds AOVs (--aov)"));
            }
            let all = merged.samples.iter().chain(&c.samples).cloned().collect();
            merged.samples = join_ranges(all).ok_or_else(|| CheckpointError::Mismatch {
                path: path.clone(),
                reason: format!(
                    "its samples {} overlap samples already merged ({})",
                    format_ranges(&c.samples),
                    format_ranges(&merged.samples)
                ),
            })?;
            for (m, x) in merged
                .accumulation
                .data
                .iter_mut()
                .zip(&c.accumulation.data)
            {
                for k in 0..4 {
                    m[k] += x[k];
                }
            }
        }
        Ok(merged)
    }

    /// Writes the checkpoint to `path` whole: to a temporary file beside it, then renamed.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        let bytes = self.to_bytes();
        let mut tmp = path.as_os_str().to_owned();
        tmp.push(format!(".tmp{}", std::process::id()));
        let tmp = PathBuf::from(tmp);
        std::fs::write(&tmp, &bytes)
            .and_then(|_| std::fs::rename(&tmp, path))
            .inspect_err(|_| {
                let _ = std::fs::remove_file(&tmp);
            })
    }

    /// The file's bytes: the text header, then the sums.
    pub fn to_bytes(&self) -> Vec<u8> {
        let acc = &self.accumulation;
        let mut bytes = format!(
            "{MAGIC}\nformat = {FORMAT}\nversion = {}\nscene_hash = {:016x}\nwidth = {}\nheight = {}\nsamples = {}\naovs = {}\n\n",
            self.version,
            self.scene_hash,
            acc.width,
            acc.height,
            format_ranges(&self.samples),
            if acc.aovs { "yes" } else { "no" }
        )
        .into_bytes();
        for v in acc.data.iter().flatten() {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        bytes
    }

    /// Reads a checkpoint, refusing anything that is not a whole one.
    pub fn read(path: &Path) -> Result<Self, CheckpointError> {
        let bytes = std::fs::read(path).map_err(|cause| CheckpointError::Io {
            path: path.to_path_buf(),
            cause,
        })?;
        Self::from_bytes(&bytes, path)
    }

    /// A checkpoint from its bytes (as [`Checkpoint::to_bytes`] writes them); `path`
    /// names it in errors.
    pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<Self, CheckpointError> {
        let corrupt = |reason: String| CheckpointError::Corrupt {
            path: path.to_path_buf(),
            reason,
        };
        let end = bytes
            .windows(2)
            .position(|w| w == b"\n\n")
            .filter(|_| bytes.starts_with(MAGIC.as_bytes()))
            .ok_or_else(|| corrupt("no checkpoint header".into()))?;
        let header = std::str::from_utf8(&bytes[..end])
            .map_err(|_| corrupt("the header is not text".into()))?;
        let field = |key: &str| -> Result<&str, CheckpointError> {
            header
                .lines()
                .find_map(|l| l.strip_prefix(key)?.trim_start().strip_prefix('='))
                .map(str::trim)
                .ok_or_else(|| corrupt(format!("no {key} in the header")))
        };
        let number = |key: &str| -> Result<u32, CheckpointError> {
            field(key)?
                .parse()
                .map_err(|_| corrupt(format!("{key} is not a number")))
        };
        let format = match field("format") {
            Ok(f) => f
                .parse::<u32>()
                .map_err(|_| corrupt("format is not a number".into()))?,
            Err(_) => 1,
        };
        if format != FORMAT {
            return Err(CheckpointError::Mismatch {
                path: path.to_path_buf(),
                reason: format!(
                    "is checkpoint format {format}, this wgtrace reads format {FORMAT}{}; \
                     render again",
                    if format == 1 {
                        " (format 1 hashed the scene with Rust's DefaultHasher, which may \
                         change between builds, so its hash cannot be trusted)"
                    } else if format == 2 {
                        " (its scene hash left out part of each material record, so it \
                         cannot tell this scene from one that differs there)"
                    } else if format == 3 {
                        " (its scene hash came before the parameters held the pixel \
                         filter, so it cannot match this wgtrace's hash of the same scene)"
                    } else if format == 4 {
                        " (its scene hash came before the parameters held hide_emitters \
                         and the filter's border rule, so it cannot match this wgtrace's \
                         hash of the same scene)"
                    } else if format < FORMAT {
                        " (its scene hash came before the lights with a surface took their \
                         primitive's tag as their kind, so it cannot match this wgtrace's \
                         hash of the same scene)"
                    } else {
                        " (written by a newer wgtrace)"
                    }
                ),
            });
        }
        let scene_hash = u64::from_str_radix(field("scene_hash")?, 16)
            .map_err(|_| corrupt("scene_hash is not a hex number".into()))?;
        let (width, height) = (number("width")?, number("height")?);
        let samples = field("samples")?
            .split(',')
            .map(parse_range)
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| corrupt(format!("samples: {e}")))?;
        let samples = join_ranges(samples)
            .filter(|r| !r.is_empty())
            .ok_or_else(|| corrupt("samples: empty or overlapping ranges".into()))?;
        // written before AOVs existed: none
        let aovs = match field("aovs") {
            Ok("yes") => true,
            Ok("no") | Err(_) => false,
            Ok(other) => return Err(corrupt(format!("aovs is {other}, not yes or no"))),
        };
        let data = &bytes[end + 2..];
        let expected =
            width as u64 * height as u64 * 16 * crate::accumulation::entries_per_pixel(aovs) as u64;
        if data.len() as u64 != expected {
            return Err(corrupt(format!(
                "{} bytes of sums where a {width}x{height} image has {expected} (truncated?)",
                data.len()
            )));
        }
        let floats: Vec<f32> = data
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        Ok(Checkpoint {
            version: field("version")?.to_string(),
            scene_hash,
            samples,
            accumulation: Accumulation {
                width,
                height,
                aovs,
                data: floats
                    .chunks_exact(4)
                    .map(|c| [c[0], c[1], c[2], c[3]])
                    .collect(),
            },
        })
    }

    /// Whether this checkpoint can continue a render of `scene` (read from `path`) that
    /// ends before sample `end`: same renderer version, same scene and settings, same
    /// size, no samples past the end.
    pub fn check(&self, scene: &FlatScene, end: u32, path: &Path) -> Result<(), CheckpointError> {
        let mismatch = |reason: String| CheckpointError::Mismatch {
            path: path.to_path_buf(),
            reason,
        };
        if self.version != VERSION {
            return Err(mismatch(format!(
                "written by wgtrace {}, this is {VERSION}; render again",
                self.version
            )));
        }
        let acc = &self.accumulation;
        if (acc.width, acc.height) != (scene.width, scene.height) {
            return Err(mismatch(format!(
                "holds a {}x{} image, the render is {}x{}",
                acc.width, acc.height, scene.width, scene.height
            )));
        }
        if self.scene_hash != scene_hash(scene) {
            return Err(mismatch(
                "comes from a different scene or different settings (seed, sampler, light \
                 sampling, max_depth, camera)"
                    .into(),
            ));
        }
        let held = self.samples.last().map_or(0, |r| r.end);
        if held > end {
            return Err(mismatch(format!(
                "already holds samples up to index {held}, more than the {end} asked for"
            )));
        }
        Ok(())
    }
}
