//! Textures: image files decoded at their source precision, the Perlin noise tables, and
//! the texture records both backends read (their texels placed by `scene::texels`).

use std::path::Path;

use super::format::{CheckerMapping, Filter, NoiseKind, TextureDesc, WrapMode};
use super::materials::common::ColorDesc;
use super::records::{self, Texture, NOISE_TABLE_ENTRIES, NO_TEXTURE, TEX_FLAG_SOLID};
pub use super::texels::srgb_to_linear;
use super::texels::{pack, srgb_texel, Block, TexelKind, Texels};

/// An image at its source precision, row 0 at the top: `width` x `height` texels of
/// `kind` (four channels: r, g, b, alpha); an 8-bit one's colour sRGB-encoded when `srgb`
/// is set (its texture decodes it at look-up).
#[derive(Debug, Clone, PartialEq)]
pub struct ImageData {
    pub width: u32,
    pub height: u32,
    pub kind: TexelKind,
    pub srgb: bool,
    pub data: Vec<u8>,
}

impl ImageData {
    /// Texel i (row-major) as linear (r, g, b, alpha).
    pub fn texel(&self, i: usize) -> [f32; 4] {
        if self.srgb {
            srgb_texel(&self.data, i)
        } else {
            self.kind.decode(&self.data, i)
        }
    }

    /// Texel (x, y), linear.
    pub fn at(&self, x: u32, y: u32) -> [f32; 4] {
        self.texel(y as usize * self.width as usize + x as usize)
    }

    /// Every texel, linear (r, g, b, alpha).
    pub fn linear(&self) -> Vec<[f32; 4]> {
        (0..self.width as usize * self.height as usize)
            .map(|i| self.texel(i))
            .collect()
    }

    /// Its number of texels.
    pub fn texel_count(&self) -> u64 {
        self.width as u64 * self.height as u64
    }

    /// Bytes its texels take on either backend.
    pub fn bytes(&self) -> u64 {
        self.data.len() as u64
    }

    /// The block the texel banks place.
    pub fn block(&self) -> Block<'_> {
        Block {
            kind: self.kind,
            width: self.width,
            height: self.height,
            data: &self.data,
        }
    }
}

/// Largest side of an image texture.
pub const MAX_TEXTURE_SIDE: u32 = 16384;

/// Most texels of one image (2^26: 1 GiB as floats, one texel bank).
pub const MAX_IMAGE_TEXELS: u64 = 1 << 26;

/// Most texels of all a scene's images together (2^31: 8 GiB of 8-bit images, every
/// texel bank wgtrace binds).
pub const MAX_TEXELS: u64 = 1 << 31;

/// Reads an image file with the `image` crate, keeping its precision: 8-bit images as
/// 8 bits per channel (sRGB-encoded when `srgb` is set, decoded at look-up), 16-bit ones
/// as half floats (sRGB-decoded first when `srgb` is set), float ones (HDR, EXR, linear
/// already) as floats. Its size is read from the header first: a side over
/// [`MAX_TEXTURE_SIDE`] or more than [`MAX_IMAGE_TEXELS`] texels is refused before
/// decoding.
pub fn load_image(path: &Path, srgb: bool) -> Result<ImageData, String> {
    if is_pfm(path) {
        let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
        return read_pfm(&bytes);
    }
    if let Some(bytes) = hdr_bytes(path)? {
        return decode_image(&bytes, srgb);
    }
    let reader = || {
        image::ImageReader::open(path)
            .and_then(|r| r.with_guessed_format())
            .map_err(|e| e.to_string())
    };
    decode(reader, srgb)
}

/// An image file's width and height, read from its header.
pub fn image_size(path: &Path) -> Result<(u32, u32), String> {
    if is_pfm(path) {
        let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
        return pfm_header(&bytes).map(|h| (h.width, h.height));
    }
    if let Some(bytes) = hdr_bytes(path)? {
        return image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| e.to_string())?
            .into_dimensions()
            .map_err(|e| e.to_string());
    }
    image::image_dimensions(path).map_err(|e| e.to_string())
}

/// A Radiance HDR file's bytes (`.hdr`, `.pic`), read once, with a first line of `#?RGBE`
/// (as Mitsuba and other writers sign it) made `#?RADIANCE`, the only signature the image
/// crate's decoder accepts; None for any other file.
fn hdr_bytes(path: &Path) -> Result<Option<Vec<u8>>, String> {
    if !path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("hdr") || e.eq_ignore_ascii_case("pic"))
    {
        return Ok(None);
    }
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    Ok(Some(match bytes.strip_prefix(b"#?RGBE") {
        Some(rest) if rest.first() == Some(&b'\n') => [b"#?RADIANCE".as_slice(), rest].concat(),
        _ => bytes,
    }))
}

/// Whether `path` names a Portable FloatMap (`.pfm`), which the image crate does not read.
fn is_pfm(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("pfm"))
}

/// A PFM file's header: `PF` (RGB) or `Pf` (grey), the width and height, and a scale whose
/// sign gives the byte order (negative: little-endian), each followed by white space;
/// then `at`, where the floats begin.
struct PfmHeader {
    channels: usize,
    width: u32,
    height: u32,
    little_endian: bool,
    at: usize,
}

fn pfm_header(bytes: &[u8]) -> Result<PfmHeader, String> {
    // four tokens, each ended by one white-space byte (the last one before the floats)
    let mut tokens = Vec::new();
    let mut at = 0;
    while tokens.len() < 4 {
        while at < bytes.len() && bytes[at].is_ascii_whitespace() {
            at += 1;
        }
        let start = at;
        while at < bytes.len() && !bytes[at].is_ascii_whitespace() {
            at += 1;
        }
        if start == at || at == bytes.len() {
            return Err("is not a PFM file (its header ends early)".into());
        }
        tokens.push(String::from_utf8_lossy(&bytes[start..at]).into_owned());
        at += 1;
    }
    let channels = match tokens[0].as_str() {
        "PF" => 3,
        "Pf" => 1,
        t => return Err(format!("is not a PFM file (it begins {t:?}, not PF or Pf)")),
    };
    let size = |t: &str| t.parse::<u32>().ok().filter(|&n| n > 0);
    let (Some(width), Some(height)) = (size(&tokens[1]), size(&tokens[2])) else {
        return Err(format!(
            "PFM size {} x {}: not two positive integers",
            tokens[1], tokens[2]
        ));
    };
    let scale: f32 = tokens[3]
        .parse()
        .ok()
        .filter(|s: &f32| s.is_finite() && *s != 0.0)
        .ok_or_else(|| format!("PFM scale {:?}: not a non-zero number", tokens[3]))?;
    Ok(PfmHeader {
        channels,
        width,
        height,
        little_endian: scale < 0.0,
        at,
    })
}

/// A PFM image (linear floats, rows stored bottom first) as float texels, top row first.
fn read_pfm(bytes: &[u8]) -> Result<ImageData, String> {
    let h = pfm_header(bytes)?;
    let (w, rows, c) = (h.width as usize, h.height as usize, h.channels);
    if h.width > MAX_TEXTURE_SIDE
        || h.height > MAX_TEXTURE_SIDE
        || (w as u64) * (rows as u64) > MAX_IMAGE_TEXELS
    {
        return Err(format!(
            "is {w}x{rows}, more than the {MAX_TEXTURE_SIDE} per side and {MAX_IMAGE_TEXELS} \
             texels accepted"
        ));
    }
    let body = &bytes[h.at..];
    let want = w * rows * c * 4;
    if body.len() < want {
        return Err(format!(
            "PFM data is {} bytes, {want} expected for {w}x{rows}x{c} floats",
            body.len()
        ));
    }
    let float = |k: usize| {
        let b: [u8; 4] = body[4 * k..4 * k + 4].try_into().unwrap();
        if h.little_endian {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        }
    };
    let mut data = Vec::with_capacity(w * rows * 16);
    for y in (0..rows).rev() {
        for x in 0..w {
            let k = (y * w + x) * c;
            let rgb = if c == 3 {
                [float(k), float(k + 1), float(k + 2)]
            } else {
                [float(k); 3]
            };
            if !rgb.iter().all(|v| v.is_finite() && *v >= 0.0) {
                return Err("has a negative or non-finite texel".into());
            }
            for v in [rgb[0], rgb[1], rgb[2], 1.0] {
                data.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    Ok(ImageData {
        width: h.width,
        height: h.height,
        kind: TexelKind::Float,
        srgb: false,
        data,
    })
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
    use image::ColorType as C;
    let (w, h) = reader()?.into_dimensions().map_err(|e| e.to_string())?;
    if w > MAX_TEXTURE_SIDE || h > MAX_TEXTURE_SIDE || w as u64 * h as u64 > MAX_IMAGE_TEXELS {
        return Err(format!(
            "is {w}x{h}, more than the {MAX_TEXTURE_SIDE} per side and {MAX_IMAGE_TEXELS} \
             texels accepted"
        ));
    }
    let img = reader()?.decode().map_err(|e| e.to_string())?;
    let (width, height) = (img.width(), img.height());
    if width == 0 || height == 0 {
        return Err("is empty".into());
    }
    let (kind, data) = match img.color() {
        C::L8 | C::La8 | C::Rgb8 | C::Rgba8 => (TexelKind::Unorm8, img.into_rgba8().into_raw()),
        C::L16 | C::La16 | C::Rgb16 | C::Rgba16 => {
            let c = |v: u16, colour: bool| {
                let x = v as f32 / 65535.0;
                let x = if srgb && colour { srgb_to_linear(x) } else { x };
                half::f16::from_f32(x).to_le_bytes()
            };
            let data = img
                .into_rgba16()
                .pixels()
                .flat_map(|p| {
                    [c(p[0], true), c(p[1], true), c(p[2], true), c(p[3], false)]
                        .into_iter()
                        .flatten()
                })
                .collect();
            (TexelKind::Half, data)
        }
        _ => {
            let rgba = img.into_rgba32f();
            if !rgba.iter().all(|x| x.is_finite() && *x >= 0.0) {
                return Err("has a negative or non-finite texel".into());
            }
            let data = rgba.iter().flat_map(|x| x.to_le_bytes()).collect();
            (TexelKind::Float, data)
        }
    };
    Ok(ImageData {
        width,
        height,
        kind,
        // a 16-bit image is decoded from sRGB above, a float one is linear
        srgb: srgb && kind == TexelKind::Unorm8,
        data,
    })
}

/// The environment a glTF file without punctual lights is lit by when rendered on its own
/// (a studio's neutral sky): an equirectangular float image, row 0 at +y, of radiance
/// `STUDIO_ZENITH` straight up falling as the sine of the elevation to `STUDIO_HORIZON` at
/// the horizon, over a ground of `STUDIO_GROUND`. A white diffuse surface facing up shows
/// 1.0, one facing sideways 0.58, one facing down 0.3: shapes, reflections and normal maps
/// read, and nothing is tinted.
pub fn studio_environment() -> ImageData {
    let (w, h) = (STUDIO_WIDTH, STUDIO_WIDTH / 2);
    let mut data = Vec::with_capacity(w as usize * h as usize * 16);
    for y in 0..h {
        // the elevation of the row's centre: +90 degrees at row 0
        let elevation =
            std::f32::consts::FRAC_PI_2 - std::f32::consts::PI * (y as f32 + 0.5) / h as f32;
        let l = if elevation > 0.0 {
            STUDIO_HORIZON + (STUDIO_ZENITH - STUDIO_HORIZON) * elevation.sin()
        } else {
            STUDIO_GROUND
        };
        for _ in 0..w {
            for c in [l, l, l, 1.0] {
                data.extend(c.to_le_bytes());
            }
        }
    }
    ImageData {
        width: w,
        height: h,
        kind: TexelKind::Float,
        srgb: false,
        data,
    }
}

/// [`studio_environment`]'s radiance straight up, at the horizon (from above) and below it.
pub const STUDIO_ZENITH: f32 = 1.2;
pub const STUDIO_HORIZON: f32 = 0.6;
pub const STUDIO_GROUND: f32 = 0.3;
/// Its width in texels (its height is half): 0.7 degrees a texel.
pub const STUDIO_WIDTH: u32 = 512;

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

/// What texture records read: their images' texels and their tables.
pub struct TextureData {
    pub records: Vec<Texture>,
    pub texels: Texels,
    pub tables: Vec<[f32; 4]>,
}

/// Texture records, the texels of their images and the tables they read, in the order of
/// `textures`: (name, texture, its image when it is one). An image several textures look
/// up (a glTF file's, with other factors or transforms) is placed once; the Perlin tables,
/// which every noise texture reads, are the first tables. Errors when the texels do not
/// fit the banks ([`pack`]).
pub fn texture_records(
    textures: &[(String, &TextureDesc, Option<&ImageData>)],
) -> Result<TextureData, String> {
    let names: Vec<String> = textures.iter().map(|t| t.0.clone()).collect();
    let mut images: Vec<&ImageData> = Vec::new();
    let image_of: Vec<Option<usize>> = textures
        .iter()
        .map(|&(_, t, image)| match (t, image) {
            (TextureDesc::Image { .. }, Some(img)) => {
                Some(match images.iter().position(|i| std::ptr::eq(*i, img)) {
                    Some(k) => k,
                    None => {
                        images.push(img);
                        images.len() - 1
                    }
                })
            }
            (TextureDesc::Image { .. }, None) => {
                panic!("images are loaded before flattening")
            }
            _ => None,
        })
        .collect();
    let blocks: Vec<Block> = images.iter().map(|i| i.block()).collect();
    let (regions, texels) = pack(&blocks)?;
    let tables = if textures
        .iter()
        .any(|t| matches!(t.1, TextureDesc::Noise { .. }))
    {
        noise_tables()
    } else {
        Vec::new()
    };
    let rgb = |c: [f32; 3]| [c[0], c[1], c[2], 0.0];
    let records = textures
        .iter()
        .zip(&image_of)
        .map(|(&(_, t, _), image)| match t {
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
                transform,
            } => {
                let (mut color0, even) = color_slot(even, &names);
                let (mut color1, odd) = color_slot(odd, &names);
                let solid = *mapping == CheckerMapping::Solid;
                let params = if solid {
                    [*scale, 0.0, 0.0, 0.0]
                } else {
                    // the cells' map, scale x transform: its first row and the second's
                    // first entry in params, the second's others in the colours' .w
                    let [r0, r1] =
                        transform.map_or([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], |t| t.rows());
                    color0[3] = scale * r1[1];
                    color1[3] = scale * r1[2];
                    [scale * r0[0], scale * r0[1], scale * r0[2], scale * r1[0]]
                };
                Texture {
                    tag: records::TEX_CHECKER,
                    flags: if solid { TEX_FLAG_SOLID } else { 0 },
                    even,
                    odd,
                    color0,
                    color1,
                    params,
                    ..Default::default()
                }
            }
            TextureDesc::Image {
                wrap,
                filter,
                uv_set,
                factor,
                transform,
                ..
            } => {
                let k = image.expect("an image texture has its image");
                let (img, region) = (images[k], regions[k]);
                let [row0, row1] =
                    transform.map_or([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], |t| t.rows());
                let [s, t] = wrap.0.map(|w| match w {
                    WrapMode::Repeat => records::WRAP_REPEAT,
                    WrapMode::Clamp => records::WRAP_CLAMP,
                    WrapMode::Mirror => records::WRAP_MIRROR,
                });
                let srgb = if img.srgb { records::TEX_FLAG_SRGB } else { 0 };
                let nearest = match filter {
                    Filter::Bilinear => 0,
                    Filter::Nearest => records::TEX_FLAG_NEAREST,
                };
                Texture {
                    color0: rgb(*factor),
                    color1: [row0[0], row0[1], row0[2], 0.0],
                    params: [row1[0], row1[1], row1[2], 0.0],
                    tag: records::TEX_IMAGE,
                    flags: s | t << records::TEX_WRAP_T_SHIFT | srgb | nearest,
                    uv_set: *uv_set,
                    width: img.width,
                    height: img.height,
                    bank: region.bank,
                    layer: region.layer,
                    x: region.x,
                    y: region.y,
                    ..Default::default()
                }
            }
            TextureDesc::MeshAttribute { .. } => Texture {
                tag: records::TEX_MESH_ATTRIBUTE,
                color0: [1.0; 4],
                ..Default::default()
            },
            TextureDesc::Noise { scale, kind, color } => Texture {
                tag: records::TEX_NOISE,
                flags: match kind {
                    NoiseKind::Perlin => 0,
                    NoiseKind::Turbulence => 1,
                    NoiseKind::Marble => 2,
                },
                offset: 0,
                color0: rgb(*color),
                params: [*scale, 0.0, 0.0, 0.0],
                ..Default::default()
            },
        })
        .collect();
    Ok(TextureData {
        records,
        texels,
        tables,
    })
}
