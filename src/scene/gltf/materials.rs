//! glTF materials onto wgtrace's: a transmissive one (KHR_materials_transmission) onto
//! `dielectric`, any other onto `pbr` (each module maps its own), glTF's default material
//! onto pbr's defaults; then the same checks as a scene file's materials, their problems
//! named by the JSON path.

use super::error::{GltfError, Result};
use super::loader::Loader;
use crate::scene::materials::{dielectric, imported_key, pbr, MaterialDesc};

impl Loader<'_> {
    /// The scene-format material of glTF material `index` (None: glTF's default
    /// material), made once.
    pub(super) fn material(&mut self, index: Option<usize>) -> Result<usize> {
        if let Some(&id) = self.material_ids.get(&index) {
            return Ok(id);
        }
        let (name, desc) = match index {
            None => (
                format!("{}default material", self.prefix),
                MaterialDesc::Pbr(pbr::Desc::default()),
            ),
            Some(i) => {
                let m = self.doc.materials().nth(i).expect("validated index");
                let name = match m.name() {
                    Some(n) => format!("{}materials[{i}] ({n})", self.prefix),
                    None => format!("{}materials[{i}]", self.prefix),
                };
                (name, self.material_desc(&m)?)
            }
        };
        self.out.materials.push((name, desc));
        let id = self.out.materials.len() - 1;
        self.material_ids.insert(index, id);
        Ok(id)
    }

    fn material_desc(&mut self, m: &gltf::Material) -> Result<MaterialDesc> {
        let key = format!("materials[{}]", m.index().expect("not the default"));
        let (sets, dropped) = uv_sets(m);
        if let Some(d) = dropped {
            self.out.warnings.push(format!(
                "{key}: its textures read TEXCOORD_{d} besides TEXCOORD_{} and TEXCOORD_{}; \
                 wgtrace gives a primitive two uv sets, and reads those textures from \
                 TEXCOORD_{}",
                sets[0], sets[1], sets[0]
            ));
        }
        self.uv_sets = sets;
        let transmission = match m.transmission() {
            Some(t) => {
                let factor = t.transmission_factor();
                if !(0.0..=1.0).contains(&factor) {
                    return Err(GltfError::new(
                        format!("{key}.extensions.KHR_materials_transmission.transmissionFactor"),
                        format!("must be in [0, 1], got {factor}"),
                    ));
                }
                factor
            }
            None => 0.0,
        };
        let (desc, keys) = if transmission > 0.0 {
            for ext in ["KHR_materials_clearcoat", "KHR_materials_sheen"] {
                if m.extension_value(ext).is_some() {
                    self.out.warnings.push(format!(
                        "{key}: {ext} on a transmissive material is left out (it is \
                         rendered as glass)"
                    ));
                }
            }
            let d = dielectric::from_gltf(m, &key, transmission, self)?;
            (MaterialDesc::Dielectric(d), dielectric::GLTF_KEYS)
        } else {
            (
                MaterialDesc::Pbr(pbr::from_gltf(m, &key, self)?),
                pbr::GLTF_KEYS,
            )
        };
        let textures: Vec<String> = self.out.textures.iter().map(|t| t.name.clone()).collect();
        let named = |field: &str| imported_key(&key, keys, field);
        match desc.check(&named, &textures).into_iter().next() {
            Some((k, message)) => Err(GltfError::new(k, message)),
            None => Ok(desc),
        }
    }
}

/// The glTF uv sets a material's textures read (occlusion's apart: it is not used), in
/// slot order: the lowest first, then the next; and a third one, which is left out (its
/// textures read slot 0).
pub(super) fn uv_sets(m: &gltf::Material) -> (Vec<u32>, Option<u32>) {
    let set = |info: gltf::texture::Info| {
        info.texture_transform()
            .and_then(|t| t.tex_coord())
            .unwrap_or(info.tex_coord())
    };
    let pbr = m.pbr_metallic_roughness();
    let sg = m.pbr_specular_glossiness();
    let mut sets: Vec<u32> = [
        pbr.base_color_texture(),
        pbr.metallic_roughness_texture(),
        sg.as_ref().and_then(|s| s.diffuse_texture()),
        sg.as_ref().and_then(|s| s.specular_glossiness_texture()),
        m.emissive_texture(),
        m.specular().and_then(|s| s.specular_color_texture()),
        m.specular().and_then(|s| s.specular_texture()),
    ]
    .into_iter()
    .flatten()
    .map(set)
    .collect();
    if let Some(n) = m.normal_texture() {
        sets.push(normal_tex_coord(&n));
    }
    sets.extend(pbr::layer_textures(m).into_iter().map(json_tex_coord));
    sets.sort_unstable();
    sets.dedup();
    let dropped = sets.get(2).copied();
    sets.truncate(2);
    (sets, dropped)
}

/// The uv set a texture reference given as JSON reads: its KHR_texture_transform's
/// texCoord, else its own, else 0.
pub(super) fn json_tex_coord(info: &gltf::json::Value) -> u32 {
    let set = |v: Option<&gltf::json::Value>| v.and_then(|c| c.as_u64());
    set(info
        .get("extensions")
        .and_then(|e| e.get("KHR_texture_transform"))
        .and_then(|t| t.get("texCoord")))
    .or(set(info.get("texCoord")))
    .unwrap_or(0) as u32
}

/// The uv set a normal texture reads (the crate gives its KHR_texture_transform only as
/// JSON).
pub(super) fn normal_tex_coord(n: &gltf::material::NormalTexture) -> u32 {
    n.extension_value("KHR_texture_transform")
        .and_then(|e| e.get("texCoord"))
        .and_then(|c| c.as_u64())
        .map_or(n.tex_coord(), |c| c as u32)
}
