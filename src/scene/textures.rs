//! Textures: image files decoded to linear RGB, the Perlin noise tables, and the texture
//! records both backends read.

use std::path::Path;

use super::format::{CheckerMapping, NoiseKind, TextureDesc, WrapMode};
use super::materials::common::ColorDesc;
use super::records::{self, Texture, NOISE_TABLE_ENTRIES, NO_TEXTURE, TEX_FLAG_SOLID};

/// An image in linear RGB, row 0 at the top.
#[derive(Debug, Clone)]
pub struct ImageData {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[f32; 4]>,
}

/// The sRGB transfer function undone (IEC 61966-2-1).
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Largest side of an image texture.
pub const MAX_TEXTURE_SIDE: u32 = 16384;

/// Most texels of all a scene's images together (2^26: 1 GiB as linear RGBA floats).
pub const MAX_TEXELS: u64 = 1 << 26;

/// Reads an image file with the `image` crate: float formats (HDR, EXR) are linear
/// already, 8- and 16-bit ones are sRGB-decoded when `srgb` is set. Its size is read
/// from the header first: a side over [`MAX_TEXTURE_SIDE`] or more than [`MAX_TEXELS`]
/// texels is refused before decoding. Texels hold (r, g, b, alpha).
pub fn load_image(path: &Path, srgb: bool) -> Result<ImageData, String> {
    let reader = || {
        image::ImageReader::open(path)
            .and_then(|r| r.with_guessed_format())
            .map_err(|e| e.to_string())
    };
    decode(reader, srgb)
}

/// [`load_image`] of an image held in memory (a glTF buffer view or data URI).
pub fn decode_image(bytes: &[u8], srgb: bool) -> Result<ImageData, String> {
    let reader = || {
        image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| e.to_string())
    };
    decode(reader, srgb)
}

fn decode<R: std::io::BufRead + std::io::Seek>(
    reader: impl Fn() -> Result<image::ImageReader<R>, String>,
    srgb: bool,
) -> Result<ImageData, String> {
    let (w, h) = reader()?.into_dimensions().map_err(|e| e.to_string())?;
    if w > MAX_TEXTURE_SIDE || h > MAX_TEXTURE_SIDE || w as u64 * h as u64 > MAX_TEXELS {
        return Err(format!(
            "is {w}x{h}, more than the {MAX_TEXTURE_SIDE} per side and {MAX_TEXELS} texels \
             accepted"
        ));
    }
    let img = reader()?.decode().map_err(|e| e.to_string())?;
    let linear = !srgb
        || matches!(
            img.color(),
            image::ColorType::Rgb32F | image::ColorType::Rgba32F
        );
    let rgba = img.to_rgba32f();
    let (width, height) = rgba.dimensions();
    if width == 0 || height == 0 {
        return Err("is empty".into());
    }
    let texels = rgba
        .pixels()
        .map(|p| {
            let c = |v: f32| if linear { v } else { srgb_to_linear(v) };
            [c(p[0]), c(p[1]), c(p[2]), p[3]]
        })
        .collect::<Vec<_>>();
    if !texels.iter().flatten().all(|x| x.is_finite() && *x >= 0.0) {
        return Err("has a negative or non-finite texel".into());
    }
    Ok(ImageData {
        width,
        height,
        texels,
    })
}

/// The Perlin tables of "Ray Tracing: The Next Week" from a fixed seed: 256 random unit
/// vectors, then 256 rows holding the x, y and z permutations of 0..255.
pub fn noise_tables() -> Vec<[f32; 4]> {
    let mut state = 0x2545_f491u32;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        (state >> 8) as f32 / (1u32 << 24) as f32
    };
    let mut table = Vec::with_capacity(NOISE_TABLE_ENTRIES as usize);
    while table.len() < 256 {
        let v = glam::Vec3::new(next(), next(), next()) * 2.0 - 1.0;
        // rejection sampling in the unit ball, then normalized: uniform directions
        if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
            table.push(v.normalize().extend(0.0).to_array());
        }
    }
    let mut perms = [[0u32; 256]; 3];
    for perm in &mut perms {
        for (i, p) in perm.iter_mut().enumerate() {
            *p = i as u32;
        }
        for i in (1..256).rev() {
            let j = ((next() * (i + 1) as f32) as usize).min(i);
            perm.swap(i, j);
        }
    }
    let [px, py, pz] = perms;
    table.extend(
        px.iter()
            .zip(py.iter().zip(&pz))
            .map(|(x, (y, z))| [*x as f32, *y as f32, *z as f32, 0.0]),
    );
    table
}

/// A material colour as a record value and a texture index: a colour is itself with no
/// texture; a texture name gives white, multiplied out by the texture at the hit.
pub fn color_slot(c: &ColorDesc, names: &[String]) -> ([f32; 4], u32) {
    match c {
        ColorDesc::Rgb(rgb) => ([rgb[0], rgb[1], rgb[2], 0.0], NO_TEXTURE),
        ColorDesc::Texture(name) => (
            [1.0, 1.0, 1.0, 0.0],
            names.iter().position(|n| n == name).expect("validated") as u32,
        ),
    }
}

/// Texture records and texels, in the order of `textures`: (name, texture, its image when
/// it is one).
pub fn texture_records(
    textures: &[(String, &TextureDesc, Option<&ImageData>)],
) -> (Vec<Texture>, Vec<[f32; 4]>) {
    let names: Vec<String> = textures.iter().map(|t| t.0.clone()).collect();
    let mut texels: Vec<[f32; 4]> = Vec::new();
    // an image several textures look up (a glTF file's, with other factors or
    // transforms) is written once
    let mut written: std::collections::HashMap<*const ImageData, u32> = Default::default();
    let mut noise_offset = None;
    let rgb = |c: [f32; 3]| [c[0], c[1], c[2], 0.0];
    let records = textures
        .iter()
        .map(|&(_, t, image)| match t {
            TextureDesc::Constant { color } => Texture {
                tag: records::TEX_CONSTANT,
                color0: rgb(*color),
                ..Default::default()
            },
            TextureDesc::Checker {
                even,
                odd,
                scale,
                mapping,
            } => {
                let (color0, even) = color_slot(even, &names);
                let (color1, odd) = color_slot(odd, &names);
                Texture {
                    tag: records::TEX_CHECKER,
                    flags: if *mapping == CheckerMapping::Solid {
                        TEX_FLAG_SOLID
                    } else {
                        0
                    },
                    even,
                    odd,
                    color0,
                    color1,
                    params: [*scale, 0.0, 0.0, 0.0],
                    ..Default::default()
                }
            }
            TextureDesc::Image {
                wrap,
                factor,
                transform,
                ..
            } => {
                let image = image.expect("images are loaded before flattening");
                let offset = *written.entry(image as *const ImageData).or_insert_with(|| {
                    let offset = texels.len() as u32;
                    texels.extend_from_slice(&image.texels);
                    offset
                });
                let [row0, row1] =
                    transform.map_or([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], |t| t.rows());
                Texture {
                    color0: rgb(*factor),
                    color1: [row0[0], row0[1], row0[2], 0.0],
                    params: [row1[0], row1[1], row1[2], 0.0],
                    tag: records::TEX_IMAGE,
                    flags: match wrap {
                        WrapMode::Repeat => 0,
                        WrapMode::Clamp => 1,
                        WrapMode::Mirror => 2,
                    },
                    width: image.width,
                    height: image.height,
                    offset,
                    ..Default::default()
                }
            }
            TextureDesc::Noise { scale, kind, color } => {
                let offset = *noise_offset.get_or_insert_with(|| {
                    let offset = texels.len() as u32;
                    texels.extend(noise_tables());
                    offset
                });
                Texture {
                    tag: records::TEX_NOISE,
                    flags: match kind {
                        NoiseKind::Perlin => 0,
                        NoiseKind::Turbulence => 1,
                        NoiseKind::Marble => 2,
                    },
                    offset,
                    color0: rgb(*color),
                    params: [*scale, 0.0, 0.0, 0.0],
                    ..Default::default()
                }
            }
        })
        .collect();
    (records, texels)
}
