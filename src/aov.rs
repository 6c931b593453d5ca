//! Arbitrary output variables: what a render gives beside its colour, per pixel, for
//! denoisers, compositing and learning pipelines. Albedo, normal, depth and position are
//! summed per sample in the accumulation (`HAS_AOVS`, both backends); variance comes from
//! the colour's own sums. In an EXR file each is a layer of named channels beside the
//! colour's `R`, `G`, `B`: `albedo.R`, `normal.X`, `depth.Z`, ...

use std::fmt;
use std::path::{Path, PathBuf};

use crate::accumulation::Accumulation;
use crate::denoise::{DenoiseError, Denoiser};
use crate::image_io::{write_layers, ImageError, Layer, OutputFormat};

/// One output variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Aov {
    /// The directional albedo of the first surface whose bounce is not a delta lobe's
    /// (through glass and mirrors): the mean of f cos / pdf of its sampled bounce, which
    /// is the reflectance itself for a Lambertian surface. A light's albedo is its
    /// emission and the background's its radiance, each clamped to [0, 1].
    Albedo,
    /// The shading normal (normal maps and vertex normals applied) of that same surface,
    /// in world space, facing the ray; the mean of unit vectors, shorter where a pixel
    /// sees several surfaces; 0 where the ray escapes.
    Normal,
    /// The distance along the camera ray to the first surface it hits (through
    /// transparent alpha, not through glass); 0 where it escapes.
    Depth,
    /// The world-space point of that first hit; 0 where the ray escapes.
    Position,
    /// The variance of the pixel's mean colour (a sample's variance over the sample
    /// count), per channel: the noise left in it.
    Variance,
}

impl Aov {
    pub const ALL: [Aov; 5] = [
        Aov::Albedo,
        Aov::Normal,
        Aov::Depth,
        Aov::Position,
        Aov::Variance,
    ];

    /// Its name on the command line, in Python and as the EXR layer's prefix.
    pub fn name(self) -> &'static str {
        match self {
            Aov::Albedo => "albedo",
            Aov::Normal => "normal",
            Aov::Depth => "depth",
            Aov::Position => "position",
            Aov::Variance => "variance",
        }
    }

    /// Its channels' names in an EXR file, after the layer's prefix.
    pub fn channels(self) -> &'static [&'static str] {
        match self {
            Aov::Albedo | Aov::Variance => &["R", "G", "B"],
            Aov::Normal | Aov::Position => &["X", "Y", "Z"],
            Aov::Depth => &["Z"],
        }
    }

    /// Whether the render must sum it per sample (`FlatScene::aovs`); variance comes from
    /// the colour's sums.
    pub fn summed(self) -> bool {
        self != Aov::Variance
    }

    /// The AOV named `name`.
    pub fn from_name(name: &str) -> Result<Aov, String> {
        Aov::ALL
            .into_iter()
            .find(|a| a.name() == name)
            .ok_or_else(|| {
                format!(
                    "unknown AOV {name:?}; the AOVs are {}",
                    Aov::ALL.map(Aov::name).join(", ")
                )
            })
    }

    /// A comma-separated list (`albedo,normal,depth`), each once, in the order given.
    pub fn parse_list(list: &str) -> Result<Vec<Aov>, String> {
        let mut out = Vec::new();
        for name in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let aov = Aov::from_name(name)?;
            if out.contains(&aov) {
                return Err(format!("AOV {name:?} is named twice"));
            }
            out.push(aov);
        }
        Ok(out)
    }

    /// Its values for every pixel, `channels().len()` per pixel, row-major from the
    /// top-left; zeros where the sums hold no AOVs.
    pub fn values(self, acc: &Accumulation) -> Vec<f32> {
        let n = acc.pixel_count();
        let mut out = Vec::with_capacity(n * self.channels().len());
        for i in 0..n {
            match self {
                Aov::Albedo => out.extend_from_slice(&acc.aov_mean(i, 2)[..3]),
                Aov::Depth => out.push(acc.aov_mean(i, 2)[3]),
                Aov::Normal => out.extend_from_slice(&acc.aov_mean(i, 3)[..3]),
                Aov::Position => out.extend_from_slice(&acc.aov_mean(i, 4)[..3]),
                Aov::Variance => {
                    let n = acc.samples(i).max(1.0);
                    out.extend(acc.variance(i).map(|v| v / n));
                }
            }
        }
        out
    }

    /// Its layer of an image from `acc`.
    pub fn layer(self, acc: &Accumulation) -> Layer {
        Layer {
            name: self.name().into(),
            channels: self.channels().iter().map(|c| c.to_string()).collect(),
            values: self.values(acc),
        }
    }
}

impl fmt::Display for Aov {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Why an image with AOVs or denoised cannot be made or written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error(transparent)]
    Image(#[from] ImageError),
    #[error(transparent)]
    Denoise(#[from] DenoiseError),
    #[error(
        "{}: only an EXR file holds AOVs beside the colour (albedo.R, normal.X, depth.Z, \
         ...); name an .exr output",
        .0.display()
    )]
    NotExr(PathBuf),
    /// AOVs or denoising asked of sums rendered without the AOVs' sums.
    #[error("the render holds no AOV sums, which AOVs and denoising read (render with --aov or --denoise, aovs= in Python)")]
    NoAovSums,
}

/// Refuses, before a render, AOVs asked of an output format that cannot hold them.
pub fn check_output(path: &Path, aovs: &[Aov]) -> Result<(), OutputError> {
    if !aovs.is_empty() && OutputFormat::from_path(path)? != OutputFormat::Exr {
        return Err(OutputError::NotExr(path.to_path_buf()));
    }
    Ok(())
}

/// Writes the image of `acc` to `path`: an EXR file holds every layer of
/// [`image_layers`], a PNG or PPM file the colour only (denoised when asked).
pub fn write_output(
    path: &Path,
    acc: &Accumulation,
    aovs: &[Aov],
    denoiser: Option<&Denoiser>,
) -> Result<(), OutputError> {
    check_output(path, aovs)?;
    let mut layers = image_layers(acc, aovs, denoiser)?;
    if OutputFormat::from_path(path)? != OutputFormat::Exr {
        layers.truncate(1);
    }
    Ok(write_layers(path, acc.width, acc.height, &layers)?)
}

/// The layers of a finished image: the colour (denoised when `denoiser` is given, the
/// noisy colour then beside it as `noisy`), then each of `aovs`. Denoising and every AOV
/// but variance read the AOVs' sums, which `acc` must hold.
pub fn image_layers(
    acc: &Accumulation,
    aovs: &[Aov],
    denoiser: Option<&Denoiser>,
) -> Result<Vec<Layer>, OutputError> {
    if (denoiser.is_some() || aovs.iter().any(|a| a.summed())) && !acc.aovs {
        return Err(OutputError::NoAovSums);
    }
    let color = acc.to_rgb();
    let mut layers = Vec::with_capacity(aovs.len() + 2);
    match denoiser {
        Some(d) => {
            let clean = denoise(d, acc, &color)?;
            layers.push(Layer::rgb("", clean));
            layers.push(Layer::rgb("noisy", color));
        }
        None => layers.push(Layer::rgb("", color)),
    }
    layers.extend(aovs.iter().map(|&a| a.layer(acc)));
    Ok(layers)
}

/// `color` (the mean of `acc`) denoised with the albedo and normal AOVs as guides.
pub fn denoise(d: &Denoiser, acc: &Accumulation, color: &[f32]) -> Result<Vec<f32>, DenoiseError> {
    if !acc.aovs {
        return Err(DenoiseError::Failed(
            "the render holds no albedo and normal to guide it (render with AOVs)".into(),
        ));
    }
    let albedo = Aov::Albedo.values(acc);
    let normal = Aov::Normal.values(acc);
    d.denoise(acc.width, acc.height, color, Some(&albedo), Some(&normal))
}
