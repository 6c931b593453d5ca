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
