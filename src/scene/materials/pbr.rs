//! `type = "pbr"`: glTF 2.0's metallic-roughness material (its Appendix B, with
//! KHR_materials_ior and KHR_materials_specular): a GGX lobe (alpha = `roughness`^2,
//! Smith's height-correlated visibility, Fresnel-Schlick) over a Lambertian base of
//! `base_color` for the dielectric (F0 from `ior`, scaled by `specular` and
//! `specular_color`), mixed by `metallic` with a metal whose F0 is `base_color`; the base
//! gets what the Fresnel of both directions lets through. Its defaults are glTF's. glTF
//! materials and .mtl's non-refracting ones map onto it. Shading:
//! `shaders/materials/pbr.wgsl`, CPU twin `cpu/materials/pbr.rs`.

use serde::Deserialize;

use super::common::{
    at_most_one, glass_ior, material_view, one, white_color, Check, ColorDesc, Lobes, Model,
    Surface, TextureNames,
};
use crate::scene::gltf::error::Result;
use crate::scene::gltf::reader::{self, MaterialReader};
use crate::scene::records::{Material, ALPHA_SMOOTH, MAT_FLAG_ALPHA_BLEND, MAT_FLAG_ALPHA_MASK};

/// Its entry in the scene format.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Desc {
    #[serde(default = "white_color")]
    pub base_color: ColorDesc,
    #[serde(default = "one")]
    pub metallic: f32,
    #[serde(default = "one")]
    pub roughness: f32,
    #[serde(default = "glass_ior")]
    pub ior: f32,
    #[serde(default = "one")]
    pub specular: f32,
    #[serde(default = "white_color")]
    pub specular_color: ColorDesc,
    /// A texture whose green channel multiplies `roughness` and blue `metallic` (glTF's
    /// metallicRoughnessTexture; give it `color_space = "linear"`).
    #[serde(default)]
    pub metallic_roughness: Option<String>,
    /// A texture whose alpha channel multiplies `specular` (KHR_materials_specular's
    /// specularTexture).
    #[serde(default)]
    pub specular_texture: Option<String>,
    /// A tangent-space normal map (`color_space = "linear"`, +y toward growing v), its x
    /// and y scaled by `normal_scale`; it needs a mesh with normals and uvs.
    #[serde(default)]
    pub normal_map: Option<String>,
    #[serde(default = "one")]
    pub normal_scale: f32,
    /// Opacity, times the base colour texture's alpha.
    #[serde(default = "one")]
    pub alpha: f32,
    /// `opaque` (alpha ignored), `mask` (cut out where alpha < `alpha_cutoff`) or `blend`
    /// (opaque with probability alpha), for camera and shadow rays alike.
    #[serde(default)]
    pub alpha_mode: AlphaMode,
    #[serde(default = "half")]
    pub alpha_cutoff: f32,
    #[serde(default)]
    pub emission: ColorDesc,
    /// Emit from the back side too.
    #[serde(default)]
    pub two_sided: bool,
}

fn half() -> f32 {
    0.5
}

/// `alpha_mode`, as glTF's alphaMode.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AlphaMode {
    #[default]
    Opaque,
    Mask,
    Blend,
}

/// The format's defaults, which are glTF's (and its default material).
impl Default for Desc {
    fn default() -> Self {
        Desc {
            base_color: white_color(),
            metallic: 1.0,
            roughness: 1.0,
            ior: glass_ior(),
            specular: 1.0,
            specular_color: white_color(),
            metallic_roughness: None,
            specular_texture: None,
            normal_map: None,
            normal_scale: 1.0,
            alpha: 1.0,
            alpha_mode: AlphaMode::Opaque,
            alpha_cutoff: half(),
            emission: ColorDesc::default(),
            two_sided: false,
        }
    }
}

material_view! {
    /// What the shaders read of it (its alpha and normal map are the surface's:
    /// `common::Surface`).
    pub struct Params("PbrParams") {
        /// The diffuse base's colour and the metal's F0.
        base_color: rgb = color,
        base_color_texture: u32 = tex_color,
        /// GGX alpha = roughness^2, at least ALPHA_SMOOTH: a mirror for every purpose but
        /// a delta.
        alpha: f32 = scalars.x,
        ior: f32 = scalars.y,
        metallic: f32 = scalars.z,
        /// KHR_materials_specular's factor: F0 and F90 of the dielectric scale by it.
        specular: f32 = scalars.w,
        /// Scales the dielectric's F0 (may exceed 1: F0 is clamped to 1 instead).
        specular_color: rgb = color2,
        specular_color_texture: u32 = tex_color2,
        /// Green scales the roughness, blue the metallic factor.
        metallic_roughness_texture: u32 = tex_data0,
        /// Its alpha scales `specular`.
        specular_texture: u32 = tex_data1,
    }
}

/// The lobes of its type: the diffuse base and the GGX lobe, with a density (alpha is
/// never below ALPHA_SMOOTH).
pub const LOBES: Lobes = Lobes {
    density: true,
    delta: false,
};

impl Model for Desc {
    fn check(&self, c: &mut Check) {
        c.color("base_color", &self.base_color, true);
        c.color("specular_color", &self.specular_color, false);
        for (name, t) in [
            ("metallic_roughness", &self.metallic_roughness),
            ("specular_texture", &self.specular_texture),
            ("normal_map", &self.normal_map),
        ] {
            if let Some(t) = t {
                c.texture(name, t);
            }
        }
        c.finite("normal_scale", self.normal_scale);
        for (name, v) in [
            ("metallic", self.metallic),
            ("roughness", self.roughness),
            ("specular", self.specular),
            ("alpha", self.alpha),
            ("alpha_cutoff", self.alpha_cutoff),
        ] {
            c.unit(name, v);
        }
        c.at_least("ior", self.ior, 1.0);
        c.color("emission", &self.emission, false);
    }

    fn emission(&self) -> (&ColorDesc, bool) {
        (&self.emission, self.two_sided)
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn pack(&self, t: &TextureNames, record: &mut Material) {
        let (base_color, base_color_texture) = t.color(&self.base_color);
        let (specular_color, specular_color_texture) = t.color(&self.specular_color);
        Params {
            base_color,
            base_color_texture,
            alpha: (self.roughness * self.roughness).max(ALPHA_SMOOTH),
            ior: self.ior,
            metallic: self.metallic,
            specular: self.specular,
            specular_color,
            specular_color_texture,
            metallic_roughness_texture: t.optional(self.metallic_roughness.as_deref()),
            specular_texture: t.optional(self.specular_texture.as_deref()),
        }
        .write(record);
        let mut surface = Surface::read(record);
        surface.opacity = self.alpha;
        surface.alpha_cutoff = self.alpha_cutoff;
        surface.normal_texture = t.optional(self.normal_map.as_deref());
        surface.normal_scale = self.normal_scale;
        surface.write(record);
        record.flags |= match self.alpha_mode {
            AlphaMode::Opaque => 0,
            AlphaMode::Mask => MAT_FLAG_ALPHA_MASK,
            AlphaMode::Blend => MAT_FLAG_ALPHA_BLEND,
        };
    }

    fn normal_map(&self) -> Option<&str> {
        self.normal_map.as_deref()
    }
}

/// Where a glTF material's values come from, by field: its problems name the JSON path.
pub const GLTF_KEYS: &[(&str, &str)] = &[
    ("base_color", "pbrMetallicRoughness.baseColorFactor"),
    ("metallic", "pbrMetallicRoughness.metallicFactor"),
    ("roughness", "pbrMetallicRoughness.roughnessFactor"),
    ("ior", "extensions.KHR_materials_ior.ior"),
    (
        "specular",
        "extensions.KHR_materials_specular.specularFactor",
    ),
    (
        "specular_color",
        "extensions.KHR_materials_specular.specularColorFactor",
    ),
    ("normal_scale", "normalTexture.scale"),
    ("alpha", "pbrMetallicRoughness.baseColorFactor[3]"),
    ("alpha_cutoff", "alphaCutoff"),
    ("emission", "emissiveFactor"),
];

/// A glTF material (not transmissive): its metallic-roughness values and textures, with
/// KHR_materials_ior, KHR_materials_specular and KHR_materials_emissive_strength.
pub fn from_gltf(m: &gltf::Material, key: &str, r: &mut dyn MaterialReader) -> Result<Desc> {
    if let Some(sg) = m.pbr_specular_glossiness() {
        return from_specular_glossiness(m, &sg, key, r);
    }
    let pbr = m.pbr_metallic_roughness();
    let factor = pbr.base_color_factor();
    reader::factor(
        &format!("{key}.pbrMetallicRoughness.baseColorFactor"),
        &factor,
        true,
    )?;
    let [red, green, blue, alpha] = factor;
    let base_color = r.color(
        pbr.base_color_texture(),
        [red, green, blue],
        &format!("{key}.pbrMetallicRoughness.baseColorTexture"),
    )?;
    let emission = reader::emission(m, key, r)?;
    let metallic_roughness = match pbr.metallic_roughness_texture() {
        Some(info) => Some(r.texture(
            &info,
            false,
            &format!("{key}.pbrMetallicRoughness.metallicRoughnessTexture"),
        )?),
        None => None,
    };
    let (normal_map, normal_scale) = match m.normal_texture() {
        Some(n) => (
            Some(r.normal_texture(&n, &format!("{key}.normalTexture"))?),
            n.scale(),
        ),
        None => (None, 1.0),
    };
    let mut desc = Desc {
        base_color,
        metallic: pbr.metallic_factor(),
        roughness: pbr.roughness_factor(),
        ior: m.ior().unwrap_or(1.5),
        metallic_roughness,
        normal_map,
        normal_scale,
        alpha,
        alpha_mode: alpha_mode(m),
        alpha_cutoff: m.alpha_cutoff().unwrap_or(0.5),
        emission,
        two_sided: m.double_sided(),
        ..Desc::default()
    };
    if let Some(s) = m.specular() {
        let sk = format!("{key}.extensions.KHR_materials_specular");
        desc.specular = s.specular_factor();
        reader::factor(
            &format!("{sk}.specularColorFactor"),
            &s.specular_color_factor(),
            false,
        )?;
        desc.specular_color = r.color(
            s.specular_color_texture(),
            s.specular_color_factor(),
            &format!("{sk}.specularColorTexture"),
        )?;
        if let Some(info) = s.specular_texture() {
            // its alpha channel (linear) scales specularFactor
            desc.specular_texture =
                Some(r.texture(&info, false, &format!("{sk}.specularTexture"))?);
        }
    }
    Ok(desc)
}

/// The JSON path of KHR_materials_pbrSpecularGlossiness's fields.
const SG: &str = "extensions.KHR_materials_pbrSpecularGlossiness";

/// KHR_materials_pbrSpecularGlossiness (older exports) onto pbr, exactly for its shading
/// model: the diffuse colour (and texture, sRGB, its alpha the opacity) is the base colour
/// of a dielectric (metallic 0) whose reflectance at normal incidence is the specular
/// colour: KHR_materials_specular's F0 = min(0.04 specular_color, 1) x specular with
/// specular 1 and specular_color = specular / 0.04 (times the specularGlossiness texture,
/// sRGB), F90 = 1; roughness = 1 - glossiness (times the texture's alpha: a roughness map
/// made from it). A metal (black diffuse, coloured specular) and its metal-rough twin
/// then have the same BSDF.
fn from_specular_glossiness(
    m: &gltf::Material,
    sg: &gltf::material::PbrSpecularGlossiness,
    key: &str,
    r: &mut dyn MaterialReader,
) -> Result<Desc> {
    let diffuse = sg.diffuse_factor();
    reader::factor(&format!("{key}.{SG}.diffuseFactor"), &diffuse, true)?;
    let specular = sg.specular_factor();
    reader::factor(&format!("{key}.{SG}.specularFactor"), &specular, true)?;
    let glossiness = sg.glossiness_factor();
    if !(0.0..=1.0).contains(&glossiness) {
        return Err(crate::scene::gltf::error::GltfError::new(
            format!("{key}.{SG}.glossinessFactor"),
            format!("must be in [0, 1], got {glossiness}"),
        ));
    }
    let [red, green, blue, alpha] = diffuse;
    let base_color = r.color(
        sg.diffuse_texture(),
        [red, green, blue],
        &format!("{key}.{SG}.diffuseTexture"),
    )?;
    let texture = sg.specular_glossiness_texture();
    let tkey = format!("{key}.{SG}.specularGlossinessTexture");
    let specular_color = r.color(texture.clone(), specular.map(|s| s / 0.04), &tkey)?;
    let (roughness, metallic_roughness) = match &texture {
        // the map holds 1 - glossiness x alpha; the factor then is 1
        Some(info) => (1.0, Some(r.roughness_texture(info, glossiness, &tkey)?)),
        None => (1.0 - glossiness, None),
    };
    let emission = reader::emission(m, key, r)?;
    let (normal_map, normal_scale) = match m.normal_texture() {
        Some(n) => (
            Some(r.normal_texture(&n, &format!("{key}.normalTexture"))?),
            n.scale(),
        ),
        None => (None, 1.0),
    };
    Ok(Desc {
        base_color,
        metallic: 0.0,
        roughness,
        ior: 1.5,
        specular: 1.0,
        specular_color,
        metallic_roughness,
        normal_map,
        normal_scale,
        alpha,
        alpha_mode: alpha_mode(m),
        alpha_cutoff: m.alpha_cutoff().unwrap_or(0.5),
        emission,
        two_sided: m.double_sided(),
        ..Desc::default()
    })
}

/// glTF's alphaMode as the format's.
fn alpha_mode(m: &gltf::Material) -> AlphaMode {
    match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
        gltf::material::AlphaMode::Mask => AlphaMode::Mask,
        gltf::material::AlphaMode::Blend => AlphaMode::Blend,
    }
}

/// Where a .mtl material's values come from, by field.
pub const MTL_KEYS: &[(&str, &str)] = &[
    ("base_color", "Kd"),
    ("specular_color", "Ks"),
    ("emission", "Ke"),
    ("ior", "Ni"),
    ("alpha", "d"),
    ("roughness", "Ns"),
    ("normal_scale", "-bm"),
];

/// A .mtl image: its texture's name and the statement's `-bm` value, read by `image`
/// (file statement, sRGB, factor).
pub type MtlImage<'a> =
    dyn FnMut(&str, bool, [f32; 3]) -> std::result::Result<(String, f32), String> + 'a;

/// A .mtl material that does not refract: metallic 0, base colour Kd (each component
/// at most 1; with map_Kd, Kd multiplies the texture as given), specular colour Ks (no specular lobe without Ks), roughness
/// (2 / (Ns + 2))^(1/4) (GGX alpha = sqrt(2 / (Ns + 2)), Blinn-Phong's exponent matched,
/// as in pbrt's conversion), ior Ni, opacity d (blend below 1), the normal map of map_Bump
/// / bump / norm (its -bm scales it), emission Ke.
pub fn from_mtl(
    m: &tobj::Material,
    image: &mut MtlImage,
    warnings: &mut Vec<String>,
) -> std::result::Result<Desc, String> {
    let kd = m.diffuse.unwrap_or([0.8; 3]);
    let ks = m.specular.unwrap_or([0.0; 3]);
    let base_color = match &m.diffuse_texture {
        // Kd is the texture's factor then, which no check of the material sees
        Some(_) if !kd.iter().all(|x| x.is_finite() && *x >= 0.0) => {
            return Err(format!("Kd: must be >= 0, got {kd:?}"));
        }
        Some(t) => ColorDesc::Texture(image(t, true, kd)?.0),
        // at most 1, a NaN kept for the check to find
        None => ColorDesc::Rgb(kd.map(at_most_one)),
    };
    let (normal_map, normal_scale) = match m
        .normal_texture
        .as_deref()
        .or(m.unknown_param.get("norm").map(String::as_str))
    {
        Some(t) => {
            let (name, bump) = image(t, false, [1.0; 3])?;
            (Some(name), bump)
        }
        None => (None, 1.0),
    };
    let ns = m.shininess.unwrap_or(0.0).max(0.0);
    let dissolve = m.dissolve.unwrap_or(1.0);
    if m.specular_texture.is_some() || m.shininess_texture.is_some() || m.dissolve_texture.is_some()
    {
        warnings.push(format!(
            "material \"{}\": map_Ks, map_Ns and map_d are left out (their factors apply)",
            m.name
        ));
    }
    // any Ks but black has a specular lobe (a negative or NaN one too, for the check)
    let has_specular = ks != [0.0; 3];
    Ok(Desc {
        base_color,
        metallic: 0.0,
        roughness: (2.0 / (ns + 2.0)).powf(0.25),
        ior: m.optical_density.unwrap_or(1.5),
        specular: if has_specular { 1.0 } else { 0.0 },
        specular_color: ColorDesc::Rgb(if has_specular { ks } else { [1.0; 3] }),
        normal_map,
        normal_scale,
        alpha: dissolve,
        alpha_mode: if dissolve < 1.0 {
            AlphaMode::Blend
        } else {
            AlphaMode::Opaque
        },
        emission: ColorDesc::Rgb(m.emissive.unwrap_or([0.0; 3])),
        ..Desc::default()
    })
}
