//! `type = "dielectric"`: glass, smooth or rough. Smooth, reflection or refraction is
//! chosen by the exact Fresnel reflectance; rough (`roughness` > 0, GGX alpha =
//! roughness^2), GGX microfacets reflect and refract as Walter et al. 2007 define them,
//! sampled by their visible normals. `tint` multiplies every scattering and `absorption`
//! (per unit length, Beer-Lambert) acts inside. glTF's KHR_materials_transmission (with
//! KHR_materials_volume) and .mtl's refracting illumination models map onto it. Shading:
//! `shaders/materials/dielectric.wgsl`, CPU twin `cpu/materials/dielectric.rs`.

use serde::Deserialize;

use super::common::{
    at_most_one, material_view, white_color, Check, ColorDesc, Lobes, Model, OpacityDesc,
    TextureNames,
};
use crate::scene::gltf::error::{GltfError, Result};
use crate::scene::gltf::reader::{self, MaterialReader};
use crate::scene::records::{Material, ALPHA_SMOOTH};

/// Its entry in the scene format.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Desc {
    pub ior: f32,
    #[serde(default = "white_color")]
    pub tint: ColorDesc,
    #[serde(default)]
    pub absorption: [f32; 3],
    /// Perceptual roughness in [0, 1] (GGX alpha = its square); 0 is smooth glass.
    #[serde(default)]
    pub roughness: f32,
    #[serde(default)]
    pub emission: ColorDesc,
    /// Emit from the back side too.
    #[serde(default)]
    pub two_sided: bool,
    /// An opacity mask: a number in [0, 1] or a texture's name.
    #[serde(default)]
    pub opacity: Option<OpacityDesc>,
}

material_view! {
    /// What the shaders read of it.
    pub struct Params("DielectricParams") {
        /// Multiplies every scattering.
        tint: rgb = color,
        tint_texture: u32 = tex_color,
        /// Index of refraction inside (outside is 1).
        ior: f32 = scalars.x,
        /// Beer-Lambert coefficient per unit length inside.
        absorption: rgb = color2,
        /// GGX alpha = roughness^2; below ALPHA_SMOOTH smooth glass.
        alpha: f32 = scalars.y,
        /// At a hit: 1 on the back face (inside), else 0 (`material_at`).
        back_face: f32 = normal2.w,
    }
}

/// The lobes of its type: deltas (smooth glass's reflection and refraction, and rough
/// glass that absorbs), and rough glass's reflection and transmission with a density.
pub const LOBES: Lobes = Lobes {
    density: true,
    delta: true,
    transmission: true,
};

/// Whether rough glass has a density that light sampling may weigh: without absorption.
/// Next-event estimation at a hit inside absorbing glass would need the transmittance of
/// the segment the ray ran, which the BSDF's questions do not carry: absorbing rough
/// glass is found by its own sampling, as a delta.
pub fn has_density(alpha: f32, absorption: [f32; 3]) -> bool {
    alpha >= ALPHA_SMOOTH && absorption == [0.0; 3]
}

/// Whether a dielectric's record is rough glass (`HAS_ROUGH_DIELECTRIC`).
pub fn is_rough(m: &Material) -> bool {
    Params::read(m).alpha >= ALPHA_SMOOTH
}

impl Desc {
    /// GGX alpha = roughness^2, and 0 (smooth) where ior = 1: an index-matched boundary
    /// neither reflects nor bends light, whatever its microfacets (pbrt-v4's rule). Rough
    /// glass's generalized half vector eta wo + wi is the zero vector there for the
    /// straight-through direction, and its density infinite: glTF's transmission test
    /// grids, whose ior runs from 1, rendered non-finite samples.
    pub fn alpha(&self) -> f32 {
        if self.ior == 1.0 {
            0.0
        } else {
            self.roughness * self.roughness
        }
    }
}

impl Model for Desc {
    fn check(&self, c: &mut Check) {
        c.positive("ior", self.ior);
        c.color("tint", &self.tint, true);
        c.nonnegative3("absorption", self.absorption);
        c.unit("roughness", self.roughness);
        c.color("emission", &self.emission, false);
    }

    fn emission(&self) -> (&ColorDesc, bool) {
        (&self.emission, self.two_sided)
    }

    fn opacity(&self) -> Option<&OpacityDesc> {
        self.opacity.as_ref()
    }

    fn lobes(&self) -> Lobes {
        let density = has_density(self.alpha(), self.absorption);
        Lobes {
            density,
            delta: !density,
            transmission: density,
        }
    }

    fn pack(&self, t: &TextureNames, record: &mut Material) {
        let (tint, tint_texture) = t.color(&self.tint);
        Params {
            tint,
            tint_texture,
            ior: self.ior,
            absorption: self.absorption.into(),
            alpha: self.alpha(),
            back_face: 0.0,
        }
        .write(record);
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
        ior,
        tint,
        absorption,
        roughness: pbr.roughness_factor(),
        emission,
        two_sided: m.double_sided(),
        opacity: None,
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
        ior,
        tint,
        absorption: [0.0; 3],
        roughness: 0.0,
        emission: ColorDesc::Rgb(m.emissive.unwrap_or([0.0; 3])),
        two_sided: false,
        opacity: None,
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
