//! `type = "pbr"`: glTF 2.0's metallic-roughness material (its Appendix B, with
//! KHR_materials_ior and KHR_materials_specular): a GGX lobe (alpha = `roughness`^2,
//! Smith's height-correlated visibility, Fresnel-Schlick) over a Lambertian base of
//! `base_color` for the dielectric (F0 from `ior`, scaled by `specular` and
//! `specular_color`), mixed by `metallic` with a metal whose F0 is `base_color`; the base
//! gets what the Fresnel of both directions lets through. Over it may lie a sheen
//! (KHR_materials_sheen: the Charlie distribution of Estevez and Kulla 2017, the layer
//! under it scaled by what the sheen reflects) and over both a clearcoat
//! (KHR_materials_clearcoat: a GGX dielectric of ior 1.5, with its own roughness and
//! normal map, over a layer that receives what the coat transmits). Its defaults are
//! glTF's. glTF materials and .mtl's non-refracting ones map onto it. Shading:
//! `shaders/materials/pbr.wgsl`, CPU twin `cpu/materials/pbr.rs`.

use std::sync::OnceLock;

use glam::Vec3;
use serde::Deserialize;

use super::common::{
    at_most_one, glass_ior, material_view, one, white_color, Check, ColorDesc, Lobes, Model,
    Surface, TextureNames,
};
use crate::scene::gltf::error::Result;
use crate::scene::gltf::reader::{self, MaterialReader};
use crate::scene::records::{
    Material, ALPHA_SMOOTH, MAT_FLAG_ALPHA_BLEND, MAT_FLAG_ALPHA_MASK, NO_TEXTURE, SHEEN_ALPHA_MIN,
    SHEEN_TABLE_SIZE,
};

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
    /// The strength of a clear coat over the material (KHR_materials_clearcoat's factor).
    #[serde(default)]
    pub clearcoat: f32,
    /// A texture whose red channel multiplies `clearcoat` (linear).
    #[serde(default)]
    pub clearcoat_texture: Option<String>,
    /// The coat's roughness (GGX alpha = its square).
    #[serde(default)]
    pub clearcoat_roughness: f32,
    /// A texture whose green channel multiplies `clearcoat_roughness` (linear).
    #[serde(default)]
    pub clearcoat_roughness_texture: Option<String>,
    /// The coat's own tangent-space normal map (linear); without one the coat follows
    /// the surface's normal, not `normal_map`.
    #[serde(default)]
    pub clearcoat_normal_map: Option<String>,
    #[serde(default = "one")]
    pub clearcoat_normal_scale: f32,
    /// The sheen's colour (KHR_materials_sheen's sheenColor; black: no sheen).
    #[serde(default)]
    pub sheen_color: ColorDesc,
    /// The sheen's roughness (Charlie alpha = its square).
    #[serde(default)]
    pub sheen_roughness: f32,
    /// A texture whose alpha channel multiplies `sheen_roughness`.
    #[serde(default)]
    pub sheen_roughness_texture: Option<String>,
    /// Give the GGX lobe back the energy it loses to multiple scattering, and the base
    /// what the compensated lobe leaves (Kulla and Conty); default: `[render]
    /// energy_compensation` (off, as glTF has none).
    #[serde(default)]
    pub energy_compensation: Option<bool>,
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
            clearcoat: 0.0,
            clearcoat_texture: None,
            clearcoat_roughness: 0.0,
            clearcoat_roughness_texture: None,
            clearcoat_normal_map: None,
            clearcoat_normal_scale: 1.0,
            sheen_color: ColorDesc::default(),
            sheen_roughness: 0.0,
            sheen_roughness_texture: None,
            energy_compensation: None,
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
        /// The clearcoat's strength (0: none).
        clearcoat: f32 = scalars2.x,
        /// The coat's GGX alpha, at least ALPHA_SMOOTH.
        coat_alpha: f32 = scalars2.y,
        coat_normal_scale: f32 = scalars2.z,
        /// 1 where the base has a normal map: the coat then follows the surface's own
        /// normal (or its own map), not the base's.
        base_normal_mapped: f32 = scalars2.w,
        /// At a hit: the coat's normal (its map's, or the surface's unmapped one) where
        /// the texture hook sets it, else 0 (the shading normal).
        coat_normal: rgb = normal2,
        /// Its red scales `clearcoat`.
        clearcoat_texture: u32 = tex_data2,
        /// Its green scales the coat's roughness.
        clearcoat_roughness_texture: u32 = tex_data3,
        coat_normal_texture: u32 = tex_normal2,
        /// The sheen's colour (black: none).
        sheen_color: rgb = color3,
        sheen_color_texture: u32 = tex_data4,
        /// The sheen's Charlie alpha, at least SHEEN_ALPHA_MIN.
        sheen_alpha: f32 = color3.w,
        /// Its alpha scales the sheen's roughness.
        sheen_roughness_texture: u32 = tex_data5,
        /// The first `tables` entry of the sheen's albedo table (`place_sheen_table`).
        sheen_table: u32 = table,
        /// The record's flags (`MAT_FLAG_ENERGY`: compensated).
        flags: u32 = flags,
    }
}

/// Whether a pbr material's record has a clearcoat (`HAS_CLEARCOAT`).
pub fn has_clearcoat(m: &Material) -> bool {
    Params::read(m).clearcoat > 0.0
}

/// Whether a pbr material's record has a sheen (`HAS_SHEEN`).
pub fn has_sheen(m: &Material) -> bool {
    Params::read(m).sheen_color != Vec3::ZERO
}

/// Whether a pbr material's clearcoat has a normal map (`HAS_NORMAL_MAP`).
pub fn has_coat_normal_map(m: &Material) -> bool {
    Params::read(m).coat_normal_texture != NO_TEXTURE
}

/// The Charlie sheen distribution at cos(theta_h) = c (pbr.wgsl's `charlie_d`), in f64.
fn charlie_d(c: f64, alpha: f64) -> f64 {
    let inv = 1.0 / alpha;
    (2.0 + inv) * (1.0 - c * c).max(0.0).powf(0.5 * inv) / (2.0 * std::f64::consts::PI)
}

/// Estevez and Kulla's Lambda of the Charlie distribution (pbr.wgsl's `charlie_lambda`),
/// in f64.
fn charlie_lambda(c: f64, alpha: f64) -> f64 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let mix = |a: f64, b: f64| a + (b - a) * t;
    let l = |x: f64| {
        mix(21.5473, 25.3245) / (1.0 + mix(3.82987, 3.32435) * x.powf(mix(0.19823, 0.16801)))
            + mix(-1.97760, -1.27393) * x
            + mix(-4.32054, -4.85967)
    };
    if c < 0.5 {
        l(c).exp()
    } else {
        (2.0 * l(0.5) - l(1.0 - c)).exp()
    }
}

/// The directional albedo of a white sheen lobe, E(cos_o, alpha) = the integral over the
/// hemisphere of D(h) / (4 cos_o (1 + Lambda(cos_o) + Lambda(cos_i))) d omega_i, at
/// SHEEN_TABLE_SIZE cosines (their square roots i / (SIZE - 1), the first at 1e-4) by as
/// many alphas (i / (SIZE - 1), at least SHEEN_ALPHA_MIN), alphas in rows: what pbr's
/// sheen takes from the layer under it. The midpoint rule on 96 x 48 points of the half
/// hemisphere (the lobe is symmetric about the plane of wo and the normal): within 2e-3
/// of 400 x 400 points, and above it (the safe side: the layer under the sheen keeps
/// less); computed once, rows in parallel.
pub fn sheen_albedo_table() -> &'static [f32] {
    static TABLE: OnceLock<Vec<f32>> = OnceLock::new();
    TABLE.get_or_init(|| {
        use rayon::prelude::*;
        let size = SHEEN_TABLE_SIZE as usize;
        let (nt, np) = (96, 48);
        let (dt, dp) = (
            std::f64::consts::FRAC_PI_2 / nt as f64,
            std::f64::consts::PI / np as f64,
        );
        let rows: Vec<Vec<f32>> = (0..size)
            .into_par_iter()
            .map(|ia| {
                let alpha = (ia as f64 / (size - 1) as f64).max(SHEEN_ALPHA_MIN as f64);
                let mut row = Vec::with_capacity(size);
                for ic in 0..size {
                    let cos_o = (ic as f64 / (size - 1) as f64).powi(2).max(1e-4);
                    let wo = glam::DVec3::new((1.0 - cos_o * cos_o).sqrt(), 0.0, cos_o);
                    let lambda_o = charlie_lambda(cos_o, alpha);
                    let mut e = 0.0;
                    for i in 0..nt {
                        let theta = (i as f64 + 0.5) * dt;
                        let (s, cos_i) = theta.sin_cos();
                        let lambda_i = charlie_lambda(cos_i, alpha);
                        for j in 0..np {
                            let phi = (j as f64 + 0.5) * dp;
                            let wi = glam::DVec3::new(s * phi.cos(), s * phi.sin(), cos_i);
                            let h = (wo + wi).normalize();
                            e += charlie_d(h.z, alpha)
                                / (4.0 * cos_o * (1.0 + lambda_o + lambda_i))
                                * s;
                        }
                    }
                    row.push((2.0 * e * dt * dp) as f32);
                }
                row
            })
            .collect();
        rows.concat()
    })
}

/// Points a pbr material's record at the sheen's albedo table, placed at `tables`
/// entry `offset` (every pbr material of a scene with a sheen: the shader reads it for
/// each).
pub fn point_at_sheen_table(m: &mut Material, offset: u32) {
    let mut p = Params::read(m);
    p.sheen_table = offset;
    p.write(m);
}

/// The lobes of its type: the diffuse base and the GGX lobe, with a density (alpha is
/// never below ALPHA_SMOOTH).
pub const LOBES: Lobes = Lobes {
    density: true,
    delta: false,
    transmission: false,
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
        c.color("sheen_color", &self.sheen_color, true);
        for (name, v) in [
            ("clearcoat", self.clearcoat),
            ("clearcoat_roughness", self.clearcoat_roughness),
            ("sheen_roughness", self.sheen_roughness),
        ] {
            c.unit(name, v);
        }
        c.finite("clearcoat_normal_scale", self.clearcoat_normal_scale);
        for (name, t) in [
            ("clearcoat_texture", &self.clearcoat_texture),
            (
                "clearcoat_roughness_texture",
                &self.clearcoat_roughness_texture,
            ),
            ("clearcoat_normal_map", &self.clearcoat_normal_map),
            ("sheen_roughness_texture", &self.sheen_roughness_texture),
        ] {
            if let Some(t) = t {
                c.texture(name, t);
            }
        }
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
        let (sheen_color, sheen_color_texture) = t.color(&self.sheen_color);
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
            clearcoat: self.clearcoat,
            coat_alpha: (self.clearcoat_roughness * self.clearcoat_roughness).max(ALPHA_SMOOTH),
            coat_normal_scale: self.clearcoat_normal_scale,
            base_normal_mapped: if self.normal_map.is_some() { 1.0 } else { 0.0 },
            coat_normal: Vec3::ZERO,
            clearcoat_texture: t.optional(self.clearcoat_texture.as_deref()),
            clearcoat_roughness_texture: t.optional(self.clearcoat_roughness_texture.as_deref()),
            coat_normal_texture: t.optional(self.clearcoat_normal_map.as_deref()),
            sheen_color,
            sheen_color_texture,
            sheen_alpha: (self.sheen_roughness * self.sheen_roughness).max(SHEEN_ALPHA_MIN),
            sheen_roughness_texture: t.optional(self.sheen_roughness_texture.as_deref()),
            // placed by place_sheen_table
            sheen_table: 0,
            flags: record.flags,
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
        self.normal_map
            .as_deref()
            .or(self.clearcoat_normal_map.as_deref())
    }

    fn energy_compensation(&self) -> Option<Option<bool>> {
        Some(self.energy_compensation)
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
    (
        "clearcoat",
        "extensions.KHR_materials_clearcoat.clearcoatFactor",
    ),
    (
        "clearcoat_roughness",
        "extensions.KHR_materials_clearcoat.clearcoatRoughnessFactor",
    ),
    (
        "clearcoat_normal_scale",
        "extensions.KHR_materials_clearcoat.clearcoatNormalTexture.scale",
    ),
    (
        "sheen_color",
        "extensions.KHR_materials_sheen.sheenColorFactor",
    ),
    (
        "sheen_roughness",
        "extensions.KHR_materials_sheen.sheenRoughnessFactor",
    ),
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
    layers_from_gltf(m, key, &mut desc, r)?;
    Ok(desc)
}

/// A number of a glTF extension's JSON (`default` where it is left out), finite.
fn json_number(ext: &gltf::json::Value, name: &str, default: f32, key: &str) -> Result<f32> {
    match ext.get(name) {
        None => Ok(default),
        Some(v) => v
            .as_f64()
            .filter(|x| x.is_finite())
            .map(|x| x as f32)
            .ok_or_else(|| {
                crate::scene::gltf::error::GltfError::new(
                    format!("{key}.{name}"),
                    format!("must be a finite number, got {v}"),
                )
            }),
    }
}

/// KHR_materials_clearcoat and KHR_materials_sheen onto the coat and the sheen, with
/// their textures (the crate reads neither extension: their JSON). Factors are checked
/// as the format's keys are (the clearcoat and the roughnesses in [0, 1], the sheen
/// colour a reflectance), under their JSON paths.
fn layers_from_gltf(
    m: &gltf::Material,
    key: &str,
    desc: &mut Desc,
    r: &mut dyn MaterialReader,
) -> Result<()> {
    if let Some(cc) = m.extension_value("KHR_materials_clearcoat") {
        let ck = format!("{key}.extensions.KHR_materials_clearcoat");
        desc.clearcoat = json_number(cc, "clearcoatFactor", 0.0, &ck)?;
        desc.clearcoat_roughness = json_number(cc, "clearcoatRoughnessFactor", 0.0, &ck)?;
        if let Some(t) = cc.get("clearcoatTexture") {
            let tk = format!("{ck}.clearcoatTexture");
            desc.clearcoat_texture = Some(r.json_texture(t, false, [1.0; 3], &tk)?);
        }
        if let Some(t) = cc.get("clearcoatRoughnessTexture") {
            let tk = format!("{ck}.clearcoatRoughnessTexture");
            desc.clearcoat_roughness_texture = Some(r.json_texture(t, false, [1.0; 3], &tk)?);
        }
        if let Some(t) = cc.get("clearcoatNormalTexture") {
            let tk = format!("{ck}.clearcoatNormalTexture");
            desc.clearcoat_normal_map = Some(r.json_texture(t, false, [1.0; 3], &tk)?);
            desc.clearcoat_normal_scale = json_number(t, "scale", 1.0, &tk)?;
        }
    }
    if let Some(sh) = m.extension_value("KHR_materials_sheen") {
        let sk = format!("{key}.extensions.KHR_materials_sheen");
        let factor = match sh.get("sheenColorFactor") {
            None => [0.0; 3],
            Some(v) => {
                let a: Vec<Option<f64>> = v
                    .as_array()
                    .map(|a| a.iter().map(|x| x.as_f64()).collect())
                    .unwrap_or_default();
                match a[..] {
                    [Some(x), Some(y), Some(z)] => [x as f32, y as f32, z as f32],
                    _ => {
                        return Err(crate::scene::gltf::error::GltfError::new(
                            format!("{sk}.sheenColorFactor"),
                            format!("must be three numbers, got {v}"),
                        ))
                    }
                }
            }
        };
        reader::factor(&format!("{sk}.sheenColorFactor"), &factor, true)?;
        desc.sheen_color = match sh.get("sheenColorTexture") {
            Some(t) => ColorDesc::Texture(r.json_texture(
                t,
                true,
                factor,
                &format!("{sk}.sheenColorTexture"),
            )?),
            None => ColorDesc::Rgb(factor),
        };
        desc.sheen_roughness = json_number(sh, "sheenRoughnessFactor", 0.0, &sk)?;
        if let Some(t) = sh.get("sheenRoughnessTexture") {
            let tk = format!("{sk}.sheenRoughnessTexture");
            desc.sheen_roughness_texture = Some(r.json_texture(t, false, [1.0; 3], &tk)?);
        }
    }
    Ok(())
}

/// The JSON texture references of a material's KHR_materials_clearcoat and
/// KHR_materials_sheen, for the uv sets it reads.
pub fn layer_textures<'a>(m: &'a gltf::Material) -> Vec<&'a gltf::json::Value> {
    let mut out = Vec::new();
    for (ext, names) in [
        (
            "KHR_materials_clearcoat",
            &[
                "clearcoatTexture",
                "clearcoatRoughnessTexture",
                "clearcoatNormalTexture",
            ][..],
        ),
        (
            "KHR_materials_sheen",
            &["sheenColorTexture", "sheenRoughnessTexture"][..],
        ),
    ] {
        if let Some(e) = m.extension_value(ext) {
            out.extend(names.iter().filter_map(|n| e.get(*n)));
        }
    }
    out
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
