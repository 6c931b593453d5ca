//! What a material module asks of the glTF file while it maps one of its materials
//! ([`MaterialReader`], which the loader implements), and the parts every glTF material
//! has in the same way (its emission).

use super::error::{GltfError, Result};
use crate::scene::materials::common::ColorDesc;

/// The glTF file's textures and notes, as a material module maps a material.
pub trait MaterialReader {
    /// A colour parameter: `factor`, times the sRGB texture of `info` when there is one;
    /// `key` names the texture reference in errors.
    fn color(
        &mut self,
        info: Option<gltf::texture::Info>,
        factor: [f32; 3],
        key: &str,
    ) -> Result<ColorDesc>;
    /// The name of the texture of `info`: sRGB-decoded (`srgb`) or linear data.
    fn texture(&mut self, info: &gltf::texture::Info, srgb: bool, key: &str) -> Result<String>;
    /// The name of a roughness map made from a texture's alpha (KHR_materials_
    /// pbrSpecularGlossiness: roughness = 1 - `glossiness` x alpha, in green).
    fn roughness_texture(
        &mut self,
        info: &gltf::texture::Info,
        glossiness: f32,
        key: &str,
    ) -> Result<String>;
    /// The name of a normal texture (linear).
    fn normal_texture(&mut self, n: &gltf::material::NormalTexture, key: &str) -> Result<String>;
    /// The name of the texture of a texture reference given as JSON (`index`, `texCoord`
    /// and KHR_texture_transform, as an extension the crate does not read holds it),
    /// sRGB-decoded (`srgb`) or linear, its texels times `factor`.
    fn json_texture(
        &mut self,
        info: &gltf::json::Value,
        srgb: bool,
        factor: [f32; 3],
        key: &str,
    ) -> Result<String>;
    /// A note of what was approximated or left out.
    fn warn(&mut self, message: String);
}

/// A colour factor's components checked: each in [0, 1] for a reflectance, else finite
/// and >= 0. A factor that multiplies a texture is baked into the texture, where the
/// material's own checks no longer see it; so every factor is checked here, by index.
pub fn factor(key: &str, factor: &[f32], reflectance: bool) -> Result<()> {
    for (c, &x) in factor.iter().enumerate() {
        let ok = if reflectance {
            (0.0..=1.0).contains(&x)
        } else {
            x >= 0.0 && x.is_finite()
        };
        if !ok {
            let range = if reflectance { "in [0, 1]" } else { ">= 0" };
            return Err(GltfError::new(
                format!("{key}[{c}]"),
                format!("must be {range}, got {x}"),
            ));
        }
    }
    Ok(())
}

/// The radiance a glTF material emits: emissiveFactor (each in [0, 1], as glTF says)
/// times KHR_materials_emissive_strength, times the emissive texture.
pub fn emission(m: &gltf::Material, key: &str, r: &mut dyn MaterialReader) -> Result<ColorDesc> {
    let strength = m.emissive_strength().unwrap_or(1.0);
    if !(strength >= 0.0 && strength.is_finite()) {
        return Err(GltfError::new(
            format!("{key}.extensions.KHR_materials_emissive_strength.emissiveStrength"),
            format!("must be >= 0, got {strength}"),
        ));
    }
    let emissive = m.emissive_factor();
    factor(&format!("{key}.emissiveFactor"), &emissive, true)?;
    // an emissive texture times 0 (glTF's default emissiveFactor) emits nothing: no
    // texture, so that the material is not taken for a light
    r.color(
        m.emissive_texture()
            .filter(|_| emissive != [0.0; 3] && strength > 0.0),
        emissive.map(|c| c * strength),
        &format!("{key}.emissiveTexture"),
    )
}
