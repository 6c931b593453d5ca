//! `type = "dielectric"`: glass, smooth or rough. Smooth, reflection or refraction is
//! chosen by the exact Fresnel reflectance; rough (`roughness` > 0, alpha =
//! roughness^2, or `roughness_u` along the tangent and `roughness_v` along the
//! bitangent), GGX or Beckmann microfacets (`distribution`) reflect and refract as Walter
//! et al. 2007 define them, with Smith's height-correlated masking-shadowing, sampled by
//! their visible normals. `tint` multiplies what goes through, `specular` (default:
//! `tint`) what reflects, and `absorption`
//! (per unit length, Beer-Lambert) acts inside. glTF's KHR_materials_transmission (with
//! KHR_materials_volume) and .mtl's refracting illumination models map onto it. Shading:
//! `shaders/materials/dielectric.wgsl`, CPU twin `cpu/materials/dielectric.rs`.

use serde::Deserialize;

use super::common::{
    at_most_one, material_view, one, white_color, Check, ColorDesc, Distribution, Lobes, Model,
    OpacityDesc, Roughness, TextureNames,
};
use crate::scene::gltf::error::{GltfError, Result};
use crate::scene::gltf::reader::{self, MaterialReader};
use crate::scene::records::{
    Material, ALPHA_SMOOTH, MAT_FLAG_ANISOTROPIC, MAT_FLAG_COLOR2_CLAMPED, MAT_FLAG_ENERGY,
    MS_DIELECTRIC_BECKMANN_CORRELATED, MS_DIELECTRIC_GGX_CORRELATED,
};

/// Its entry in the scene format.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Desc {
    pub ior: f32,
    /// Multiplies what goes through (and what reflects, unless `specular` says).
    #[serde(default = "white_color")]
    pub tint: ColorDesc,
    /// Multiplies what reflects (Mitsuba's `specular_reflectance`); default: `tint`.
    #[serde(default)]
    pub specular: Option<ColorDesc>,
    #[serde(default)]
    pub absorption: [f32; 3],
    /// Perceptual roughness in [0, 1] (alpha = its square); 0 is smooth glass. Or
    /// `roughness_u` along the tangent and `roughness_v` along the bitangent.
    pub roughness: Option<f32>,
    pub roughness_u: Option<f32>,
    pub roughness_v: Option<f32>,
    /// GGX (default) or Beckmann microfacets.
    #[serde(default)]
    pub distribution: Distribution,
    #[serde(default)]
    pub emission: ColorDesc,
    /// Emit from the back side too.
    #[serde(default)]
    pub two_sided: bool,
    /// An opacity mask: a number in [0, 1] or a texture's name.
    #[serde(default)]
    pub opacity: Option<OpacityDesc>,
    /// A bump map: a height texture (its luminance) that tilts the shading normal, times
    /// `bump_scale`.
    pub bump: Option<String>,
    #[serde(default = "one")]
    pub bump_scale: f32,
    /// A normal map (Mitsuba's `normalmap`): a texture's raw colour c as the normal
    /// 2c - 1 in the frame of the surface's dp/du, n x dp/du and shading normal n.
    pub normal_map: Option<String>,
    /// Give rough glass back the energy its microfacets lose to multiple scattering,
    /// reflected and transmitted (Kulla and Conty); default: `[render]
    /// energy_compensation`.
    pub energy_compensation: Option<bool>,
}

material_view! {
    /// What the shaders read of it.
    pub struct Params("DielectricParams") {
        /// Multiplies the transmission.
        tint: rgb = color,
        tint_texture: u32 = tex_color,
        /// Multiplies the reflection (a reflectance: its texture is clamped to 1).
        specular: rgb = color2,
        specular_texture: u32 = tex_color2,
        /// Index of refraction inside (outside is 1).
        ior: f32 = scalars.x,
        /// Absorption per unit length inside: the flattener moves it into a medium of
        /// albedo 0 inside the glass (`flatten::absorbing_glass`) and leaves 0 here.
        absorption: rgb = color3,
        /// Alpha = roughness^2 (along the tangent where it is anisotropic); below
        /// ALPHA_SMOOTH on both axes smooth glass.
        alpha: f32 = scalars.y,
        /// Alpha along the bitangent (`alpha` where it is isotropic).
        alpha_v: f32 = scalars.z,
        /// 1: Beckmann, 0: GGX.
        beckmann: f32 = scalars.w,
        /// The hit's tangent, which `material_at` writes for an anisotropic one
        /// (`MAT_FLAG_ANISOTROPIC`); zero elsewhere (the normal's own frame).
        tangent: rgb = normal2,
        /// At a hit: 1 on the back face (inside), else 0 (`material_at`).
        back_face: f32 = normal2.w,
        /// The record's flags (`MAT_FLAG_ENERGY`: compensated).
        flags: u32 = flags,
    }
}

/// The lobes of its type: deltas (smooth glass's reflection and refraction, and rough
/// glass that absorbs), and rough glass's reflection and transmission with a density.
pub const LOBES: Lobes = Lobes {
    density: true,
    delta: true,
    transmission: true,
};

/// Whether glass has a density that light sampling may weigh: rough. (Absorbing rough
/// glass too: its absorption is a medium inside it, which shadow rays cross.)
pub fn has_density(alpha: (f32, f32)) -> bool {
    alpha.0.max(alpha.1) >= ALPHA_SMOOTH
}

/// Whether a dielectric's record is rough glass (`HAS_ROUGH_DIELECTRIC`).
pub fn is_rough(m: &Material) -> bool {
    let p = Params::read(m);
    p.alpha.max(p.alpha_v) >= ALPHA_SMOOTH
}

/// Whether a dielectric's record is rough glass other than isotropic GGX: Beckmann or
/// anisotropic (`HAS_GLASS_MICROFACETS`; dielectric.wgsl's `dielectric_general`).
pub fn is_general(m: &Material) -> bool {
    let p = Params::read(m);
    is_rough(m) && (p.beckmann > 0.5 || p.alpha != p.alpha_v)
}

/// The dielectric albedo tables a compensated dielectric's record reads
/// (`microfacet_albedo::DielectricVariant`): rough glass's, by its distribution.
pub fn ms_variant(m: &Material) -> Option<u32> {
    if !is_rough(m) || m.flags & MAT_FLAG_ENERGY == 0 {
        return None;
    }
    Some(if Params::read(m).beckmann > 0.5 {
        MS_DIELECTRIC_BECKMANN_CORRELATED
    } else {
        MS_DIELECTRIC_GGX_CORRELATED
    })
}

/// Whether a dielectric's record has Beckmann microfacets (`HAS_BECKMANN`).
pub fn is_beckmann(m: &Material) -> bool {
    is_rough(m) && Params::read(m).beckmann > 0.5
}

impl Desc {
    fn roughness(&self) -> Roughness {
        Roughness {
            roughness: self.roughness,
            roughness_u: self.roughness_u,
            roughness_v: self.roughness_v,
        }
    }

    /// Alpha along the tangent and the bitangent (the squares of the roughnesses, kept
    /// off 0 when rough: `Roughness::packed`), and 0 (smooth) where ior = 1: an
    /// index-matched boundary neither reflects nor bends light, whatever its microfacets
    /// (pbrt-v4's rule). Rough glass's generalized half vector eta wo + wi is the zero
    /// vector there for the straight-through direction, and its density infinite: glTF's
    /// transmission test grids, whose ior runs from 1, rendered non-finite samples.
    pub fn alpha(&self) -> (f32, f32) {
        if self.ior == 1.0 {
            (0.0, 0.0)
        } else {
            self.roughness().packed()
        }
    }
}

impl Model for Desc {
    fn check(&self, c: &mut Check) {
        c.positive("ior", self.ior);
        c.color("tint", &self.tint, true);
        if let Some(specular) = &self.specular {
            c.color("specular", specular, true);
        }
        c.nonnegative3("absorption", self.absorption);
        self.roughness().check(c);
        c.color("emission", &self.emission, false);
    }

    fn emission(&self) -> (&ColorDesc, bool) {
        (&self.emission, self.two_sided)
    }

    fn opacity(&self) -> Option<&OpacityDesc> {
        self.opacity.as_ref()
    }

    fn bump(&self) -> Option<(&str, f32)> {
        Some((self.bump.as_deref()?, self.bump_scale))
    }

    fn uv_normal_map(&self) -> Option<&str> {
        self.normal_map.as_deref()
    }

    fn anisotropic(&self) -> bool {
        let (u, v) = self.alpha();
        u != v
    }

    fn energy_compensation(&self) -> Option<Option<bool>> {
        Some(self.energy_compensation)
    }

    fn lobes(&self) -> Lobes {
        let density = has_density(self.alpha());
        Lobes {
            density,
            delta: !density,
            transmission: density,
        }
    }

    fn pack(&self, t: &TextureNames, record: &mut Material) {
        let (tint, tint_texture) = t.color(&self.tint);
        let (specular, specular_texture) = t.color(self.specular.as_ref().unwrap_or(&self.tint));
        let (alpha, alpha_v) = self.alpha();
        Params {
            tint,
            tint_texture,
            specular,
            specular_texture,
            ior: self.ior,
            absorption: self.absorption.into(),
            alpha,
            alpha_v,
            beckmann: self.distribution.code(),
            tangent: glam::Vec3::ZERO,
            back_face: 0.0,
            flags: record.flags,
        }
        .write(record);
        record.flags |= MAT_FLAG_COLOR2_CLAMPED;
        if self.anisotropic() {
            record.flags |= MAT_FLAG_ANISOTROPIC;
        }
    }
}

/// Where a glTF material's values come from, by field: its problems name the JSON path.
pub const GLTF_KEYS: &[(&str, &str)] = &[
    ("ior", "extensions.KHR_materials_ior.ior"),
    ("tint", "pbrMetallicRoughness.baseColorFactor"),
    ("absorption", "extensions.KHR_materials_volume"),
    ("roughness", "pbrMetallicRoughness.roughnessFactor"),
    ("emission", "emissiveFactor"),
];

/// glTF's KHR_materials_transmission (`factor` > 0) onto glass of the material's
/// ior, tinted by the base colour, absorbing inside as KHR_materials_volume says
/// (sigma_a = -ln(attenuationColor) / attenuationDistance).
pub fn from_gltf(
    m: &gltf::Material,
    key: &str,
    factor: f32,
    r: &mut dyn MaterialReader,
) -> Result<Desc> {
    let pbr = m.pbr_metallic_roughness();
    let factor4 = pbr.base_color_factor();
    reader::factor(
        &format!("{key}.pbrMetallicRoughness.baseColorFactor"),
        &factor4,
        true,
    )?;
    let [red, green, blue, _] = factor4;
    // glTF's ior is the inside's against air: at least 1 (a scene file's may be less)
    let ior = m.ior().unwrap_or(1.5);
    if !(ior >= 1.0 && ior.is_finite()) {
        return Err(GltfError::new(
            format!("{key}.extensions.KHR_materials_ior.ior"),
            format!("must be >= 1, got {ior}"),
        ));
    }
    let tint = r.color(
        pbr.base_color_texture(),
        [red, green, blue],
        &format!("{key}.pbrMetallicRoughness.baseColorTexture"),
    )?;
    let emission = reader::emission(m, key, r)?;
    if factor < 1.0 {
        r.warn(format!(
            "{key}: transmissionFactor {factor} is rendered as 1 (wgtrace's glass transmits all it does not reflect)"
        ));
    }
    if pbr.metallic_roughness_texture().is_some() {
        r.warn(format!(
            "{key}: its metallicRoughnessTexture is left out: glass takes roughnessFactor as it is"
        ));
    }
    let mut absorption = [0.0; 3];
    if let Some(v) = m.volume() {
        let d = v.attenuation_distance();
        let c = v.attenuation_color();
        if d.is_nan() || d <= 0.0 {
            return Err(GltfError::new(
                format!("{key}.extensions.KHR_materials_volume.attenuationDistance"),
                format!("must be > 0, got {d}"),
            ));
        }
        if !c.iter().all(|x| (0.0..=1.0).contains(x)) {
            return Err(GltfError::new(
                format!("{key}.extensions.KHR_materials_volume.attenuationColor"),
                format!("must be in [0, 1], got {c:?}"),
            ));
        }
        if d.is_finite() {
            // a colour of 0 absorbs everything: a large finite coefficient
            absorption = c.map(|x| (-(x.max(1e-6)).ln() / d).min(1e6));
        }
    }
    Ok(Desc {
        specular: None,
        ior,
        tint,
        absorption,
        roughness: Some(pbr.roughness_factor()),
        roughness_u: None,
        roughness_v: None,
        distribution: Distribution::Ggx,
        emission,
        two_sided: m.double_sided(),
        opacity: None,
        bump: None,
        bump_scale: 1.0,
        normal_map: None,
        energy_compensation: None,
    })
}

/// Where a .mtl material's values come from, by field.
pub const MTL_KEYS: &[(&str, &str)] = &[("ior", "Ni"), ("tint", "Tf"), ("emission", "Ke")];

/// A .mtl material of a refracting illumination model (4, 6, 7, 9): glass of ior Ni
/// (1.5, at least 1), tinted by Tf (white; each component at most 1), emitting Ke.
pub fn from_mtl(m: &tobj::Material) -> std::result::Result<Desc, String> {
    let tint = match m.unknown_param.get("Tf").map(|s| parse3(s)) {
        Some(Some(c)) => ColorDesc::Rgb(c.map(at_most_one)),
        _ => white_color(),
    };
    let ior = m.optical_density.unwrap_or(1.5);
    if !(ior >= 1.0 && ior.is_finite()) {
        return Err(format!("Ni: must be >= 1, got {ior}"));
    }
    Ok(Desc {
        specular: None,
        ior,
        tint,
        absorption: [0.0; 3],
        roughness: None,
        roughness_u: None,
        roughness_v: None,
        distribution: Distribution::Ggx,
        emission: ColorDesc::Rgb(m.emissive.unwrap_or([0.0; 3])),
        two_sided: false,
        opacity: None,
        bump: None,
        bump_scale: 1.0,
        normal_map: None,
        energy_compensation: None,
    })
}

/// One number, or three, of a .mtl statement.
fn parse3(s: &str) -> Option<[f32; 3]> {
    let v: Vec<f32> = s
        .split_whitespace()
        .map(|w| w.parse().ok())
        .collect::<Option<_>>()?;
    match v[..] {
        [x] => Some([x; 3]),
        [r, g, b] => Some([r, g, b]),
        _ => None,
    }
}
