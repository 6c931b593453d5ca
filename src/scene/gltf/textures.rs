//! Textures: each look-up of a glTF texture (its image, colour space, factor, uv set and
//! KHR_texture_transform) becomes a texture of the scene format, made once; each image is
//! decoded once per colour space, within the texel cap. The material modules ask for them
//! through [`MaterialReader`].

use std::sync::Arc;

use super::error::{GltfError, Result};
use super::file::{check_uri, source_error};
use super::loader::{Loader, TextureKey};
use super::materials::{json_tex_coord, normal_tex_coord};
use super::reader::MaterialReader;
use crate::scene::format::{ColorSpace, Filter, TextureDesc, UvTransformDesc, Wrap, WrapMode};
use crate::scene::imported::ImportedTexture;
use crate::scene::materials::common::ColorDesc;
use crate::scene::texels::TexelKind;
use crate::scene::textures::{self, ImageData};

impl Loader<'_> {
    /// The name of the scene-format texture for one look-up of a glTF texture.
    fn texture_of(
        &mut self,
        info: &gltf::texture::Info,
        srgb: bool,
        factor: [f32; 3],
        key: &str,
    ) -> Result<String> {
        let t = info.texture_transform();
        let transform = t
            .as_ref()
            .map(|t| UvTransformDesc::from_v_down(t.offset(), t.rotation(), t.scale()));
        if let Some(tr) = &t {
            let [a, b] = tr.offset();
            let [c, d] = tr.scale();
            if ![a, b, c, d, tr.rotation()].iter().all(|x| x.is_finite()) {
                return Err(GltfError::new(
                    format!("{key}.extensions.KHR_texture_transform"),
                    "must hold finite numbers",
                ));
            }
        }
        let uv_set = t.and_then(|t| t.tex_coord()).unwrap_or(info.tex_coord());
        self.texture_lookup(
            info.texture(),
            self.uv_slot(uv_set),
            transform,
            srgb,
            factor,
        )
        .map_err(|e| GltfError::new(e.key, format!("{} (the image of {key})", e.message)))
    }

    /// A normal texture's look-up: the crate gives its KHR_texture_transform only as JSON.
    fn normal_texture_of(
        &mut self,
        n: &gltf::material::NormalTexture,
        key: &str,
    ) -> Result<String> {
        let transform = json_transform(n.extension_value("KHR_texture_transform"), key)?;
        let uv_set = normal_tex_coord(n);
        self.texture_lookup(
            n.texture(),
            self.uv_slot(uv_set),
            transform,
            false,
            [1.0; 3],
        )
    }

    /// A look-up of a texture reference given as JSON (`MaterialReader::json_texture`).
    fn json_texture_of(
        &mut self,
        info: &gltf::json::Value,
        srgb: bool,
        factor: [f32; 3],
        key: &str,
    ) -> Result<String> {
        let count = self.doc.textures().len();
        let tex = info
            .get("index")
            .and_then(|i| i.as_u64())
            .and_then(|i| self.doc.textures().nth(i as usize))
            .ok_or_else(|| {
                GltfError::new(
                    format!("{key}.index"),
                    format!("must name one of the file's {count} textures"),
                )
            })?;
        let ext = info
            .get("extensions")
            .and_then(|e| e.get("KHR_texture_transform"));
        let transform = json_transform(ext, key)?;
        self.texture_lookup(
            tex,
            self.uv_slot(json_tex_coord(info)),
            transform,
            srgb,
            factor,
        )
        .map_err(|e| GltfError::new(e.key, format!("{} (the image of {key})", e.message)))
    }
}

/// A KHR_texture_transform given as JSON (`ext`), checked: its offset, rotation and
/// scale, finite.
fn json_transform(ext: Option<&gltf::json::Value>, key: &str) -> Result<Option<UvTransformDesc>> {
    let pair = |name: &str, default: [f32; 2]| -> Result<[f32; 2]> {
        match ext.and_then(|e| e.get(name)) {
            None => Ok(default),
            Some(v) => match v
                .as_array()
                .map(|a| a.iter().map(|x| x.as_f64()).collect::<Vec<_>>())
            {
                Some(a) if a.len() == 2 && a.iter().all(|x| x.is_some_and(f64::is_finite)) => {
                    Ok([a[0].unwrap_or(0.0) as f32, a[1].unwrap_or(0.0) as f32])
                }
                _ => Err(GltfError::new(
                    format!("{key}.extensions.KHR_texture_transform.{name}"),
                    "must be two finite numbers",
                )),
            },
        }
    };
    Ok(match ext {
        Some(e) => {
            let rotation = e
                .get("rotation")
                .map_or(Some(0.0), |r| r.as_f64())
                .filter(|r| r.is_finite())
                .ok_or_else(|| {
                    GltfError::new(
                        format!("{key}.extensions.KHR_texture_transform.rotation"),
                        "must be a finite number",
                    )
                })? as f32;
            Some(UvTransformDesc::from_v_down(
                pair("offset", [0.0; 2])?,
                rotation,
                pair("scale", [1.0; 2])?,
            ))
        }
        None => None,
    })
}

impl Loader<'_> {
    /// The slot of its primitive's uv sets that glTF uv set `set` of the material being
    /// read is in (slot 0 for a set left out: see `materials::uv_sets`).
    fn uv_slot(&self, set: u32) -> u32 {
        self.uv_sets.iter().position(|&s| s == set).unwrap_or(0) as u32
    }

    /// The texture of KHR_materials_pbrSpecularGlossiness's glossiness as a roughness map:
    /// a linear 8-bit image whose green is 1 - `glossiness` x the alpha of the texture
    /// of `info` (pbr's metallic-roughness texture reads roughness from green, metallic
    /// from blue: 0), made once per texture and glossiness factor.
    pub(super) fn roughness_from_glossiness(
        &mut self,
        info: &gltf::texture::Info,
        glossiness: f32,
        key: &str,
    ) -> Result<String> {
        let uv_set = info
            .texture_transform()
            .and_then(|t| t.tex_coord())
            .unwrap_or(info.tex_coord());
        let transform = info
            .texture_transform()
            .map(|t| UvTransformDesc::from_v_down(t.offset(), t.rotation(), t.scale()));
        let tex = info.texture();
        let k = TextureKey {
            texture: tex.index(),
            srgb: false,
            factor: [1.0; 3],
            uv_slot: self.uv_slot(uv_set),
            transform,
            derived: Some(glossiness.to_bits()),
        };
        if let Some(name) = self.known_texture(&k) {
            return Ok(name);
        }
        let source = self
            .image(&tex.source(), false)
            .map_err(|e| GltfError::new(e.key, format!("{} (the image of {key})", e.message)))?;
        let texels = (0..source.texel_count() as usize).flat_map(|i| {
            let a = source.texel(i)[3];
            let g = ((1.0 - glossiness * a).clamp(0.0, 1.0) * 255.0).round() as u8;
            [0, g, 0, 255]
        });
        let image = ImageData {
            width: source.width,
            height: source.height,
            kind: TexelKind::Unorm8,
            srgb: false,
            data: texels.collect(),
        };
        self.texture_entry(tex, k, Arc::new(image))
    }

    /// The name of the texture already made for `k`, if one was.
    fn known_texture(&self, k: &TextureKey) -> Option<String> {
        let i = self.texture_keys.iter().position(|t| t == k)?;
        Some(self.out.textures[i].name.clone())
    }

    fn texture_lookup(
        &mut self,
        tex: gltf::Texture,
        uv_slot: u32,
        transform: Option<UvTransformDesc>,
        srgb: bool,
        factor: [f32; 3],
    ) -> Result<String> {
        let k = TextureKey {
            texture: tex.index(),
            srgb,
            factor,
            uv_slot,
            transform,
            derived: None,
        };
        if let Some(name) = self.known_texture(&k) {
            return Ok(name);
        }
        let image = self.image(&tex.source(), srgb)?;
        self.texture_entry(tex, k, image)
    }

    /// A texture of the scene format over `image`, with its sampler's modes and what key
    /// `k` says (uv slot, factor, colour space, transform): its name.
    fn texture_entry(
        &mut self,
        tex: gltf::Texture,
        k: TextureKey,
        image: Arc<ImageData>,
    ) -> Result<String> {
        let sampler = tex.sampler();
        let mode = |w: gltf::texture::WrappingMode| match w {
            gltf::texture::WrappingMode::ClampToEdge => WrapMode::Clamp,
            gltf::texture::WrappingMode::MirroredRepeat => WrapMode::Mirror,
            gltf::texture::WrappingMode::Repeat => WrapMode::Repeat,
        };
        let wrap = Wrap([mode(sampler.wrap_s()), mode(sampler.wrap_t())]);
        // the magnification filter: wgtrace has no mipmaps, so minFilter does not apply
        let filter = match sampler.mag_filter() {
            Some(gltf::texture::MagFilter::Nearest) => Filter::Nearest,
            _ => Filter::Bilinear,
        };
        let name = format!(
            "{}textures[{}]#{}",
            self.prefix,
            tex.index(),
            self.texture_keys.len()
        );
        self.out.textures.push(ImportedTexture {
            name: name.clone(),
            desc: TextureDesc::Image {
                path: String::new(),
                wrap,
                filter,
                uv_set: k.uv_slot,
                factor: k.factor,
                color_space: if k.srgb {
                    ColorSpace::Srgb
                } else {
                    ColorSpace::Linear
                },
                transform: k.transform,
            },
            image,
        });
        self.texture_keys.push(k);
        Ok(name)
    }

    /// glTF image `source` decoded (sRGB or linear), once per colour space.
    fn image(&mut self, source: &gltf::Image, srgb: bool) -> Result<Arc<ImageData>> {
        if let Some(img) = self.images.get(&(source.index(), srgb)) {
            return Ok(img.clone());
        }
        let key = format!("images[{}]", source.index());
        let bytes: Vec<u8> = match source.source() {
            gltf::image::Source::View { view, .. } => {
                let b = &self.buffers[view.buffer().index()];
                b[view.offset()..view.offset() + view.length()].to_vec()
            }
            gltf::image::Source::Uri { uri, .. } => {
                check_uri(uri, &format!("{key}.uri"))?;
                let src = gltf::buffer::Source::Uri(uri);
                gltf::buffer::Data::from_source(src, Some(self.dir))
                    .map_err(|e| {
                        GltfError::new(
                            format!("{key}.uri"),
                            source_error(e, &gltf::buffer::Source::Uri(uri)),
                        )
                    })?
                    .0
            }
        };
        let img =
            textures::decode_image(&bytes, srgb).map_err(|e| GltfError::new(key.clone(), e))?;
        self.texels += img.texel_count();
        if self.texels > textures::MAX_TEXELS {
            return Err(GltfError::new(
                key,
                format!(
                    "brings the file's texels past the {} accepted",
                    textures::MAX_TEXELS
                ),
            ));
        }
        let img = Arc::new(img);
        self.images.insert((source.index(), srgb), img.clone());
        Ok(img)
    }
}

impl MaterialReader for Loader<'_> {
    /// The factor alone, or an sRGB texture named and made once per texture, factor and
    /// look-up.
    fn color(
        &mut self,
        info: Option<gltf::texture::Info>,
        factor: [f32; 3],
        key: &str,
    ) -> Result<ColorDesc> {
        Ok(match info {
            Some(info) => ColorDesc::Texture(self.texture_of(&info, true, factor, key)?),
            None => ColorDesc::Rgb(factor),
        })
    }

    fn texture(&mut self, info: &gltf::texture::Info, srgb: bool, key: &str) -> Result<String> {
        self.texture_of(info, srgb, [1.0; 3], key)
    }

    fn roughness_texture(
        &mut self,
        info: &gltf::texture::Info,
        glossiness: f32,
        key: &str,
    ) -> Result<String> {
        self.roughness_from_glossiness(info, glossiness, key)
    }

    fn normal_texture(&mut self, n: &gltf::material::NormalTexture, key: &str) -> Result<String> {
        self.normal_texture_of(n, key)
    }

    fn json_texture(
        &mut self,
        info: &gltf::json::Value,
        srgb: bool,
        factor: [f32; 3],
        key: &str,
    ) -> Result<String> {
        self.json_texture_of(info, srgb, factor, key)
    }

    fn warn(&mut self, message: String) {
        self.out.warnings.push(message);
    }
}
