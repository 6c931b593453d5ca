//! Accumulation buffer -> image files: PNG (8-bit sRGB), EXR (linear float), PPM (binary P6).

use std::path::{Path, PathBuf};

use image::codecs::pnm::{PnmEncoder, PnmSubtype, SampleEncoding};
use image::{ImageEncoder, ImageFormat};

/// Output formats, chosen by file extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputFormat {
    /// 8-bit, sRGB transfer, clamped to [0, 1].
    Png,
    /// Linear float RGB: the radiance itself.
    Exr,
    /// Binary P6, 8-bit sRGB like PNG.
    Ppm,
}

#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error(
        "{}: unknown image extension (use .png, .exr or .ppm)",
        path.display()
    )]
    UnknownExtension { path: PathBuf },
    #[error("{}: cannot read image: {cause}", path.display())]
    Read {
        path: PathBuf,
        cause: Box<dyn std::error::Error + Send + Sync>,
    },
    #[error("{}: cannot write image: {cause}", path.display())]
    Write {
        path: PathBuf,
        // not `source`: the message already holds it, and a chain would repeat it
        cause: Box<dyn std::error::Error + Send + Sync>,
    },
}

impl OutputFormat {
    /// The format named by `path`'s extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<Self, ImageError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => Ok(Self::Png),
            Some("exr") => Ok(Self::Exr),
            Some("ppm") => Ok(Self::Ppm),
            _ => Err(ImageError::UnknownExtension {
                path: path.to_path_buf(),
            }),
        }
    }
}

/// The sRGB transfer function (IEC 61966-2-1) of a linear value, clamped to [0, 1].
pub fn linear_to_srgb(x: f32) -> f32 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    if x <= 0.0031308 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Linear RGB -> 8-bit sRGB, rounding to nearest.
pub fn to_srgb8(rgb: &[f32]) -> Vec<u8> {
    rgb.iter()
        .map(|&x| (linear_to_srgb(x) * 255.0 + 0.5) as u8)
        .collect()
}

/// Writes linear RGB (`width * height * 3` floats, row-major from the top-left) to `path` in
/// the format its extension names. The file is written beside the target and renamed over
/// it, so a reader never sees a half-written image.
pub fn write_image(path: &Path, width: u32, height: u32, rgb: &[f32]) -> Result<(), ImageError> {
    write_pixels(path, width, height, rgb, || to_srgb8(rgb))
}

/// Writes layers of linear values (the colour as `R`, `G`, `B`, then AOVs as `albedo.R`,
/// ...) to `path`, atomically. EXR holds them all as named channels of one part (the
/// OpenEXR convention for layers, which Nuke, Blender and OIDN's tools read); PNG and PPM
/// hold the colour only, so a second layer there is refused.
pub fn write_layers(
    path: &Path,
    width: u32,
    height: u32,
    layers: &[Layer],
) -> Result<(), ImageError> {
    let format = OutputFormat::from_path(path)?;
    let [first, rest @ ..] = layers else {
        return Err(ImageError::Write {
            path: path.to_path_buf(),
            cause: "no layers to write".into(),
        });
    };
    if rest.is_empty() {
        return write_image(path, width, height, &first.values);
    }
    if format != OutputFormat::Exr {
        return Err(ImageError::Write {
            path: path.to_path_buf(),
            cause: "only an EXR file holds AOVs (`albedo.R`, ...) beside the colour; name an .exr output"
                .into(),
        });
    }
    let tmp = temp_path(path);
    let result = (|| -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
        use exr::prelude::*;
        let n = width as usize * height as usize;
        let mut channels = SmallVec::new();
        for layer in layers {
            let k = layer.channels.len();
            if layer.values.len() != n * k {
                return Err(format!("layer {:?} does not match the image size", layer.name).into());
            }
            for (c, name) in layer.channel_names().into_iter().enumerate() {
                let samples: Vec<f32> = layer.values.iter().skip(c).step_by(k).copied().collect();
                channels.push(AnyChannel::new(name.as_str(), FlatSamples::F32(samples)));
            }
        }
        let image = Image::from_channels(
            (width as usize, height as usize),
            AnyChannels::sort(channels),
        );
        image.write().to_file(&tmp)?;
        std::fs::rename(&tmp, path)?;
        Ok(())
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(|cause| ImageError::Write {
        path: path.to_path_buf(),
        cause,
    })
}

/// An EXR file's channels, each as f32 by its full name (`R`, `albedo.R`; a part's name
/// prefixed where a file has several parts), row-major from the top-left.
#[derive(Debug, Clone, PartialEq)]
pub struct ExrChannels {
    pub width: u32,
    pub height: u32,
    pub channels: Vec<(String, Vec<f32>)>,
}

/// Every channel of an EXR file.
pub fn read_exr(path: &Path) -> Result<ExrChannels, ImageError> {
    let image =
        exr::prelude::read_all_flat_layers_from_file(path).map_err(|e| ImageError::Read {
            path: path.to_path_buf(),
            cause: e.into(),
        })?;
    let mut size = (0, 0);
    let mut channels = Vec::new();
    let parts = image.layer_data.len();
    for (i, layer) in image.layer_data.iter().enumerate() {
        let this = (layer.size.0 as u32, layer.size.1 as u32);
        if i > 0 && this != size {
            return Err(ImageError::Read {
                path: path.to_path_buf(),
                cause: format!(
                    "its parts differ in size ({}x{} and {}x{})",
                    size.0, size.1, this.0, this.1
                )
                .into(),
            });
        }
        size = this;
        let prefix = match (&layer.attributes.layer_name, parts) {
            (Some(name), 2..) => format!("{name}."),
            _ => String::new(),
        };
        for ch in &layer.channel_data.list {
            channels.push((
                format!("{prefix}{}", ch.name),
                ch.sample_data.values_as_f32().collect(),
            ));
        }
    }
    Ok(ExrChannels {
        width: size.0,
        height: size.1,
        channels,
    })
}

/// Writes a per-pixel relative error estimate (`width * height` values): EXR keeps the
/// values themselves (in all three channels); PNG and PPM show log10 of the error from -3
/// (0.1%, dark blue) to 0 (100%, yellow) in the viridis colour map.
pub fn write_error_map(
    path: &Path,
    width: u32,
    height: u32,
    errors: &[f32],
) -> Result<(), ImageError> {
    use plotters::style::colors::colormaps::ViridisRGB;
    let gray: Vec<f32> = errors.iter().flat_map(|&e| [e; 3]).collect();
    write_pixels(path, width, height, &gray, || {
        errors
            .iter()
            .flat_map(|&e| {
                let t = (f64::from(e).max(1e-12).log10() + 3.0) / 3.0;
                let c = ViridisRGB::get_color(if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) });
                [c.0, c.1, c.2]
            })
            .collect()
    })
}

/// Writes `linear` (EXR) or the 8-bit pixels `encoded` makes (PNG, PPM), atomically.
fn write_pixels(
    path: &Path,
    width: u32,
    height: u32,
    linear: &[f32],
    encoded: impl Fn() -> Vec<u8>,
) -> Result<(), ImageError> {
    let format = OutputFormat::from_path(path)?;
    let wrap = |e: Box<dyn std::error::Error + Send + Sync>| ImageError::Write {
        path: path.to_path_buf(),
        cause: e,
    };
    let tmp = temp_path(path);
    let result = (|| -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
        match format {
            OutputFormat::Png => {
                image::RgbImage::from_raw(width, height, encoded())
                    .ok_or("image size does not match the pixel data")?
                    .save_with_format(&tmp, ImageFormat::Png)?;
            }
            OutputFormat::Exr => {
                image::Rgb32FImage::from_raw(width, height, linear.to_vec())
                    .ok_or("image size does not match the pixel data")?
                    .save_with_format(&tmp, ImageFormat::OpenExr)?;
            }
            OutputFormat::Ppm => {
                let file = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
                PnmEncoder::new(file)
                    .with_subtype(PnmSubtype::Pixmap(SampleEncoding::Binary))
                    .write_image(&encoded(), width, height, image::ExtendedColorType::Rgb8)?;
            }
        }
        std::fs::rename(&tmp, path)?;
        Ok(())
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(wrap)
}

/// Fails now, rather than after a long render, when an image cannot be written at `path`:
/// an unknown extension, a missing or read-only folder, or a folder in the way.
pub fn check_writable(path: &Path) -> Result<(), ImageError> {
    OutputFormat::from_path(path)?;
    probe_writable(path).map_err(|e| ImageError::Write {
        path: path.to_path_buf(),
        cause: e.into(),
    })
}

/// Creates and removes a temporary file beside `path` (where an atomic write puts its
/// temporary file), and refuses a folder at `path` itself.
pub fn probe_writable(path: &Path) -> std::io::Result<()> {
    if path.is_dir() {
        return Err(std::io::Error::other("is a folder"));
    }
    let tmp = temp_path(path);
    std::fs::File::create(&tmp)?;
    std::fs::remove_file(&tmp)
}

fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// A named set of channels of one image: the colour (prefix "") or an AOV.
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    /// The channels' prefix: `albedo` makes `albedo.R`; "" for the colour.
    pub name: String,
    pub channels: Vec<String>,
    /// `channels.len()` values per pixel, row-major from the top-left.
    pub values: Vec<f32>,
}

impl Layer {
    /// The colour's layer: `R`, `G`, `B` of linear rgb (`name` "" in a file's main layer).
    pub fn rgb(name: &str, rgb: Vec<f32>) -> Layer {
        Layer {
            name: name.into(),
            channels: ["R", "G", "B"].map(String::from).to_vec(),
            values: rgb,
        }
    }

    /// Its channels' full names in a file: `albedo.R`, or `R` for the main layer.
    pub fn channel_names(&self) -> Vec<String> {
        self.channels
            .iter()
            .map(|c| match self.name.as_str() {
                "" => c.clone(),
                prefix => format!("{prefix}.{c}"),
            })
            .collect()
    }
}
