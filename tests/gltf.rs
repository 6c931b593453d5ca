//! glTF 2.0 files: every asset is written here by `common/gltf_writer.rs` (no third-party
//! file). What the loader reads (node hierarchy, instancing, sparse accessors, data URIs,
//! GLB, cameras, lights, materials and their extensions), what it refuses (with the JSON
//! path), and renders against closed forms on both backends.

mod common;
#[path = "common/gltf_writer.rs"]
mod gltf_writer;

use std::path::{Path, PathBuf};

use glam::Vec3;
use gltf_writer::{light_ref, quad, GltfWriter};
use serde_json::json;
use wgtrace::scene::materials::common::Surface;
use wgtrace::scene::materials::{dielectric, pbr, MaterialKind};
use wgtrace::scene::records::{self, LIGHT_DIRECTIONAL, LIGHT_POINT, LIGHT_SPOT};
use wgtrace::{FlatScene, Overrides};

fn load(path: &Path) -> FlatScene {
    wgtrace::load_scene(path, &Overrides::default()).unwrap_or_else(|e| panic!("{e}"))
}

fn load_err(path: &Path) -> String {
    match wgtrace::load_scene(path, &Overrides::default()) {
        Ok(_) => panic!("{} loaded", path.display()),
        Err(e) => e.to_string(),
    }
}

/// A 2 x 2 quad in the z = 0 plane facing +z (uv over it), with `material`.
fn quad_mesh(w: &mut GltfWriter, material: Option<usize>) -> usize {
    let q = quad([0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
    w.add_mesh_arrays(&q, material, true)
}

/// A one-quad file: the quad, a camera "front" at z = 3, a point light.
fn quad_file(material: serde_json::Value) -> GltfWriter {
    let mut w = GltfWriter::new();
    let m = w.material(material);
    let mesh = quad_mesh(&mut w, Some(m));
    let n = w.node(json!({ "mesh": mesh }));
    let c =
        w.camera(json!({ "type": "perspective", "perspective": { "yfov": 0.5, "znear": 0.1 } }));
    let cam = w.node(json!({ "camera": c, "name": "front", "translation": [0.0, 0.0, 3.0] }));
    let l = w.light(json!({ "type": "point", "intensity": 4.0, "color": [1.0, 0.5, 0.25] }));
    let mut ln = json!({ "translation": [0.0, 0.0, 2.0] });
    ln.as_object_mut()
        .unwrap()
        .extend(light_ref(l).as_object().unwrap().clone());
    let ln = w.node(ln);
    w.scene(&[n, cam, ln]);
    w
}

fn pbr(factor: [f32; 4], metallic: f32, roughness: f32) -> serde_json::Value {
    json!({ "pbrMetallicRoughness": {
        "baseColorFactor": factor, "metallicFactor": metallic, "roughnessFactor": roughness } })
}

fn dir(name: &str) -> PathBuf {
    common::tmp_dir(&format!("gltf-{name}"))
}

#[test]
fn gltf_embedded_external_and_glb_give_the_same_records() {
    let w = quad_file(pbr([0.8, 0.4, 0.2, 1.0], 0.25, 0.5));
    let d = dir("forms");
    let external = w.to_gltf_external(&d, "external").unwrap();
    let embedded = d.join("embedded.gltf");
    w.to_gltf_embedded(&embedded).unwrap();
    let glb = d.join("binary.glb");
    w.to_glb(&glb).unwrap();
    let a = load(&external);
    for other in [&embedded, &glb] {
        let b = load(other);
        assert_eq!(a.primitives, b.primitives, "{}", other.display());
        assert_eq!(a.materials, b.materials);
        assert_eq!(a.emitters, b.emitters);
        assert_eq!(a.shape_data, b.shape_data);
    }
    // the quad's two triangles, one pbr material: alpha = roughness^2, metallic, ior 1.5
    assert_eq!(a.primitives.len(), 2);
    let m = a.materials[0];
    assert_eq!(m.tag, MaterialKind::Pbr.tag());
    let p = pbr::Params::read(&m);
    assert_eq!(p.base_color, Vec3::new(0.8, 0.4, 0.2));
    assert_eq!(
        (p.alpha, p.ior, p.metallic, p.specular),
        (0.25, 1.5, 0.25, 1.0)
    );
    // the camera of node "front": at z = 3, looking down -z, yfov 0.5 rad
    assert_eq!(a.camera.origin, Vec3::new(0.0, 0.0, 3.0));
    assert!((a.camera.forward - Vec3::NEG_Z).length() < 1e-6);
    let half = (0.25f32).tan() * a.camera.focus_distance;
    assert!((a.camera.half_height - half).abs() < 1e-5);
    // KHR_lights_punctual's point light: intensity x colour as W/sr, at its node
    let p = a.punctual();
    assert_eq!(p.len(), 1);
    assert_eq!(p[0].kind, LIGHT_POINT);
    assert_eq!(&p[0].a[..3], &[0.0, 0.0, 2.0]);
    assert_eq!(&p[0].b[..3], &[4.0, 2.0, 1.0]);
    // it has a light: no background is added, and nothing to warn of
    assert_eq!(a.background, [0.0; 3]);
    assert!(a.warnings.is_empty(), "{:?}", a.warnings);
}

#[test]
fn the_node_hierarchy_places_meshes_by_matrix_and_trs_and_instances_each_use() {
    let mut w = GltfWriter::new();
    let mesh = quad_mesh(&mut w, None);
    // child: scale 2 about x, then the parent's translation and 90 degrees about z
    let child = w.node(json!({ "mesh": mesh, "scale": [2.0, 1.0, 1.0] }));
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let parent = w.node(
        json!({ "children": [child], "translation": [10.0, 0.0, 0.0],
        "rotation": [0.0, 0.0, s, s] }),
    );
    // the same mesh again by a matrix (column-major): translate (0, 0, -5)
    let other = w.node(json!({ "mesh": mesh,
        "matrix": [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -5.0, 1.0] }));
    w.scene(&[parent, other]);
    let d = dir("nodes");
    let scene = load(&w.to_gltf_external(&d, "nodes").unwrap());
    assert_eq!(
        scene.primitives.len(),
        4,
        "two instances of a two-triangle mesh"
    );
    let corners: Vec<Vec3> = scene
        .primitives
        .iter()
        .flat_map(|p| [p.a, p.b, p.c])
        .map(|v| Vec3::new(v[0], v[1], v[2]))
        .collect();
    // the quad's corner (1, 1, 0): scaled to (2, 1, 0), turned to (-1, 2, 0), moved
    let placed = Vec3::new(9.0, 2.0, 0.0);
    assert!(
        corners.iter().any(|c| (*c - placed).length() < 1e-5),
        "{corners:?}"
    );
    assert!(corners
        .iter()
        .any(|c| (*c - Vec3::new(1.0, 1.0, -5.0)).length() < 1e-6));
    // no camera: a view that frames the scene, said on stderr; no punctual light: the
    // studio environment, in the light list
    assert!(
        scene.warnings.iter().any(|w| w.contains("frames")),
        "{:?}",
        scene.warnings
    );
    assert!(scene
        .warnings
        .iter()
        .any(|w| w.contains("the studio environment lights it")));
    let env = scene.env.expect("the studio environment");
    assert_ne!(env.light, records::NO_LIGHT);
    let o = Overrides {
        background: Some([0.25, 0.5, 1.0]),
        ..Default::default()
    };
    let path = d.join("nodes.gltf");
    let s = wgtrace::load_scene(&path, &o).unwrap();
    assert_eq!(s.background, [0.25, 0.5, 1.0]);
    assert!(s.env.is_none(), "--background replaces it");
}

#[test]
fn a_sparse_accessor_overrides_the_positions_it_names() {
    let mut w = GltfWriter::new();
    let q = quad([0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
    let pos = w.positions(&q.positions);
    let idx = w.indices_u32(&q.indices);
    // vertex 3 ((1, 1, 0)) moved to (1, 3, 0) by a sparse part
    let iv = w.view(&3u32.to_le_bytes(), None);
    let values: Vec<u8> = [1.0f32, 3.0, 0.0]
        .iter()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    let vv = w.view(&values, None);
    w.json["accessors"][pos]["sparse"] = json!({ "count": 1,
        "indices": { "bufferView": iv, "componentType": 5125 },
        "values": { "bufferView": vv } });
    w.json["accessors"][pos]["max"] = json!([1.0, 3.0, 0.0]);
    let mesh = w.mesh(vec![GltfWriter::primitive(
        &[("POSITION", pos)],
        Some(idx),
        None,
    )]);
    let n = w.node(json!({ "mesh": mesh }));
    w.scene(&[n]);
    let scene = load(&w.to_gltf_external(&dir("sparse"), "sparse").unwrap());
    let corners: Vec<[f32; 2]> = scene
        .primitives
        .iter()
        .flat_map(|p| [p.a, p.b, p.c])
        .map(|v| [v[0], v[1]])
        .collect();
    assert!(
        corners.contains(&[1.0, 3.0]) && !corners.contains(&[1.0, 1.0]),
        "{corners:?}"
    );
}

#[test]
fn cameras_are_chosen_by_name_and_orthographic_ones_are_parallel() {
    let mut w = quad_file(pbr([0.5; 4], 0.0, 1.0));
    let c = w.camera(json!({ "type": "orthographic", "name": "top",
        "orthographic": { "xmag": 2.0, "ymag": 1.5, "znear": 0.1, "zfar": 10.0 } }));
    // looking down -y from above: rotated -90 degrees about x
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let n = w.node(
        json!({ "camera": c, "translation": [0.0, 4.0, 0.0], "rotation": [-s, 0.0, 0.0, s] }),
    );
    let mut nodes: Vec<usize> = w.json["scenes"][0]["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect();
    nodes.push(n);
    w.json["scenes"][0]["nodes"] = json!(nodes);
    let path = w.to_gltf_external(&dir("cameras"), "cameras").unwrap();
    // the first camera by default
    assert!(!load(&path).camera.orthographic);
    let top = Overrides {
        camera: Some("top".into()),
        ..Default::default()
    };
    let s = wgtrace::load_scene(&path, &top).unwrap();
    assert!(s.camera.orthographic);
    assert_eq!(s.camera.half_height, 1.5);
    assert!((s.camera.forward - Vec3::NEG_Y).length() < 1e-6);
    // orthographic rays all go along the view direction, from the view rectangle
    let b = wgtrace::cpu::bindings::Bindings::new(&s, s.params(0, s.full_band()));
    let r0 = wgtrace::cpu::path::camera_ray(&b, 0, 0, [0.5; 2], [0.5; 2]);
    let r1 = wgtrace::cpu::path::camera_ray(&b, s.width - 1, s.height - 1, [0.5; 2], [0.5; 2]);
    assert_eq!(r0.dir, r1.dir);
    assert!((r0.origin - r1.origin).length() > 2.0);
    let nope = Overrides {
        camera: Some("side".into()),
        ..Default::default()
    };
    let e = wgtrace::load_scene(&path, &nope).unwrap_err().to_string();
    assert!(
        e.contains("no camera named \"side\"") && e.contains("front, top"),
        "{e}"
    );
}

#[test]
fn lights_punctual_map_onto_point_spot_and_directional_lights() {
    let mut w = quad_file(pbr([0.5; 4], 0.0, 1.0));
    let spot = w.light(json!({ "type": "spot", "intensity": 2.0, "range": 5.0,
        "spot": { "innerConeAngle": 0.2, "outerConeAngle": 0.5 } }));
    let sun = w.light(json!({ "type": "directional", "intensity": 3.0 }));
    let mut nodes = vec![];
    for (l, t) in [(spot, [1.0, 2.0, 3.0]), (sun, [0.0; 3])] {
        let mut n = json!({ "translation": t });
        n.as_object_mut()
            .unwrap()
            .extend(light_ref(l).as_object().unwrap().clone());
        nodes.push(w.node(n));
    }
    let mut all: Vec<usize> = (0..w.json["nodes"].as_array().unwrap().len() - 2).collect();
    all.extend(nodes);
    w.json["scenes"][0]["nodes"] = json!(all);
    let s = load(&w.to_gltf_external(&dir("lights"), "lights").unwrap());
    let kinds: Vec<u32> = s.punctual().iter().map(|e| e.kind).collect();
    assert_eq!(kinds, [LIGHT_POINT, LIGHT_SPOT, LIGHT_DIRECTIONAL]);
    let spot = s.punctual()[1];
    assert_eq!(&spot.a[..3], &[1.0, 2.0, 3.0]);
    assert!((spot.a[3] - 0.5f32.cos()).abs() < 1e-6 && (spot.b[3] - 0.2f32.cos()).abs() < 1e-6);
    assert_eq!(&spot.c[..3], &[0.0, 0.0, -1.0]);
    // a directional light's record holds the direction toward it: +z for one along -z
    let sun = s.punctual()[2];
    assert_eq!(&sun.a[..3], &[0.0, 0.0, 1.0]);
    assert_eq!(&sun.b[..3], &[3.0; 3]);
    assert!(
        s.warnings.iter().any(|w| w.contains("range is ignored")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn material_extensions_map_onto_pbr_and_dielectric() {
    let mut w = GltfWriter::new();
    let a = w.material(json!({
        "pbrMetallicRoughness": { "baseColorFactor": [1.0, 1.0, 1.0, 0.5], "metallicFactor": 0.0 },
        "emissiveFactor": [1.0, 0.5, 0.0], "doubleSided": true,
        "alphaMode": "MASK", "alphaCutoff": 0.25,
        "extensions": {
            "KHR_materials_emissive_strength": { "emissiveStrength": 4.0 },
            "KHR_materials_ior": { "ior": 1.8 },
            "KHR_materials_specular": { "specularFactor": 0.5, "specularColorFactor": [1.0, 0.5, 0.25] } } }));
    let glass = w.material(json!({
        "pbrMetallicRoughness": { "baseColorFactor": [0.9, 1.0, 0.9, 1.0], "roughnessFactor": 0.0 },
        "alphaMode": "BLEND",
        "extensions": {
            "KHR_materials_transmission": { "transmissionFactor": 1.0 },
            "KHR_materials_ior": { "ior": 1.33 },
            "KHR_materials_volume": { "attenuationDistance": 2.0, "attenuationColor": [0.5, 1.0, 0.25] } } }));
    let frosted = w.material(json!({
        "pbrMetallicRoughness": { "roughnessFactor": 0.5 },
        "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1.0 } } }));
    for e in [
        "KHR_materials_emissive_strength",
        "KHR_materials_ior",
        "KHR_materials_specular",
        "KHR_materials_transmission",
        "KHR_materials_volume",
    ] {
        w.use_extension(e, true);
    }
    let m0 = quad_mesh(&mut w, Some(a));
    let m1 = quad_mesh(&mut w, Some(glass));
    let n0 = w.node(json!({ "mesh": m0 }));
    let n1 = w.node(json!({ "mesh": m1, "translation": [0.0, 0.0, -1.0] }));
    let m2 = quad_mesh(&mut w, Some(frosted));
    let n2 = w.node(json!({ "mesh": m2, "translation": [0.0, 0.0, -2.0] }));
    w.scene(&[n0, n1, n2]);
    let s = load(&w.to_gltf_external(&dir("ext"), "ext").unwrap());
    let (m, g) = (s.materials[0], s.materials[1]);
    assert_eq!(m.tag, MaterialKind::Pbr.tag());
    let (p, surface) = (pbr::Params::read(&m), Surface::read(&m));
    assert_eq!(surface.emission, Vec3::new(4.0, 2.0, 0.0));
    assert_eq!(
        (p.alpha, p.ior, p.metallic, p.specular),
        (1.0, 1.8, 0.0, 0.5)
    );
    assert_eq!(p.specular_color, Vec3::new(1.0, 0.5, 0.25));
    assert_eq!(
        m.flags,
        records::MAT_FLAG_TWO_SIDED | records::MAT_FLAG_ALPHA_MASK | records::MAT_FLAG_NEE
    );
    assert_eq!((surface.opacity, surface.alpha_cutoff), (0.5, 0.25));
    assert_eq!(g.tag, MaterialKind::Dielectric.tag());
    let glass = dielectric::Params::read(&g);
    assert_eq!((glass.ior, glass.alpha), (1.33, 0.0));
    assert_eq!(glass.tint, Vec3::new(0.9, 1.0, 0.9));
    // rough transmission: rough glass, GGX alpha = roughnessFactor^2
    let frosted = dielectric::Params::read(&s.materials[2]);
    assert_eq!((frosted.ior, frosted.alpha), (1.5, 0.25));
    // sigma_a = -ln(colour) / distance, a medium of albedo 0 inside the glass: the
    // record's absorption moved into it, the record's media word its interior
    let want = Vec3::new(0.5f32.ln() / -2.0, 0.0, 0.25f32.ln() / -2.0);
    assert_eq!(glass.absorption, Vec3::ZERO);
    assert_eq!(s.num_media, 1);
    let (t, a) = (s.tables[s.media as usize], s.tables[s.media as usize + 1]);
    assert!(
        (Vec3::new(t[0], t[1], t[2]) - want).abs().max_element() < 1e-6,
        "{t:?}"
    );
    assert_eq!(a, [0.0; 4]);
    let word = (s.material_media * 4 + 1) as usize;
    assert_eq!(s.tables[word >> 2][word & 3], 1.0);
    assert!(s.has_media());
    // it emits: no background is added
    assert_eq!(s.background, [0.0; 3]);
}

/// KHR_materials_clearcoat and KHR_materials_sheen map onto pbr's layers with their
/// factors and textures (the coat's normal map and the sheen's sRGB colour among them),
/// the sheen's albedo table placed in the scene's tables; their mistakes are named by
/// their JSON paths.
#[test]
fn clearcoat_and_sheen_map_onto_pbr_with_their_textures() {
    let img = image::RgbaImage::from_fn(2, 2, |x, y| {
        image::Rgba([200, 100, (x * 255) as u8, (y * 255) as u8])
    });
    let layered = |clearcoat: serde_json::Value, sheen: serde_json::Value| {
        let mut w = GltfWriter::new();
        let t = w.png_texture(&img, None).unwrap();
        let fill = |v: serde_json::Value| {
            serde_json::from_str::<serde_json::Value>(
                &v.to_string().replace("\"T\"", &t.to_string()),
            )
            .unwrap()
        };
        let m = w.material(json!({
            "pbrMetallicRoughness": { "baseColorFactor": [0.2, 0.3, 0.4, 1.0], "metallicFactor": 0.0 },
            "extensions": { "KHR_materials_clearcoat": fill(clearcoat), "KHR_materials_sheen": fill(sheen) } }));
        w.use_extension("KHR_materials_clearcoat", false);
        w.use_extension("KHR_materials_sheen", false);
        let mesh = quad_mesh(&mut w, Some(m));
        let n = w.node(json!({ "mesh": mesh }));
        w.scene(&[n]);
        w
    };
    let w = layered(
        json!({ "clearcoatFactor": 0.8, "clearcoatRoughnessFactor": 0.4,
                "clearcoatTexture": { "index": "T" }, "clearcoatRoughnessTexture": { "index": "T" },
                "clearcoatNormalTexture": { "index": "T", "scale": 0.5 } }),
        json!({ "sheenColorFactor": [0.5, 0.25, 1.0], "sheenColorTexture": { "index": "T" },
                "sheenRoughnessFactor": 0.6, "sheenRoughnessTexture": { "index": "T" } }),
    );
    let s = load(&w.to_gltf_external(&dir("layers"), "layers").unwrap());
    assert!(
        !s.warnings.iter().any(|w| w.contains("KHR_materials")),
        "{:?}",
        s.warnings
    );
    let p = pbr::Params::read(&s.materials[0]);
    assert_eq!((p.clearcoat, p.coat_normal_scale), (0.8, 0.5));
    assert!((p.coat_alpha - 0.16).abs() < 1e-6 && (p.sheen_alpha - 0.36).abs() < 1e-6);
    for t in [
        p.clearcoat_texture,
        p.clearcoat_roughness_texture,
        p.coat_normal_texture,
        p.sheen_color_texture,
        p.sheen_roughness_texture,
    ] {
        assert_ne!(t, records::NO_TEXTURE);
    }
    // the sheen colour is its texture, sRGB, times the factor
    assert_eq!(p.sheen_color, Vec3::ONE);
    let sheen_tex = &s.textures[p.sheen_color_texture as usize];
    assert_eq!(sheen_tex.color0, [0.5, 0.25, 1.0, 0.0]);
    assert_ne!(sheen_tex.flags & records::TEX_FLAG_SRGB, 0);
    assert_eq!(
        s.textures[p.clearcoat_texture as usize].flags & records::TEX_FLAG_SRGB,
        0
    );
    let table = pbr::sheen_albedo_table();
    let at = p.sheen_table as usize;
    assert_eq!(s.tables[at], [table[0], table[1], table[2], table[3]]);
    assert_eq!(s.tables.len(), at + table.len() / 4);

    // mistakes, by their JSON paths
    let no_sheen = json!({});
    for (clearcoat, sheen, want) in [
        (
            json!({ "clearcoatFactor": 1.5 }),
            no_sheen.clone(),
            "materials[0].extensions.KHR_materials_clearcoat.clearcoatFactor: must be in [0, 1]",
        ),
        (
            json!({ "clearcoatRoughnessFactor": "rough" }),
            no_sheen.clone(),
            "materials[0].extensions.KHR_materials_clearcoat.clearcoatRoughnessFactor: must be a finite number",
        ),
        (
            json!({ "clearcoatFactor": 1.0, "clearcoatTexture": { "index": 7 } }),
            no_sheen.clone(),
            "materials[0].extensions.KHR_materials_clearcoat.clearcoatTexture.index: must name one of the file's 1 textures",
        ),
        (
            json!({}),
            json!({ "sheenColorFactor": [2.0, 0.0, 0.0] }),
            "materials[0].extensions.KHR_materials_sheen.sheenColorFactor[0]: must be in [0, 1]",
        ),
        (
            json!({}),
            json!({ "sheenColorFactor": [1.0, 0.0] }),
            "materials[0].extensions.KHR_materials_sheen.sheenColorFactor: must be three numbers",
        ),
    ] {
        let w = layered(clearcoat, sheen);
        let err = load_err(&w.to_gltf_external(&dir("layer-errors"), "bad").unwrap());
        assert!(err.contains(want), "{err}\nwanted: {want}");
    }
}

#[test]
fn textures_keep_their_colour_space_factor_and_transform() {
    let mut w = GltfWriter::new();
    let img = image::RgbaImage::from_fn(4, 2, |x, y| {
        image::Rgba([(x * 60) as u8, 128, (y * 200) as u8, 255])
    });
    let t = w.png_texture(&img, None).unwrap();
    let m = w.material(json!({
        "pbrMetallicRoughness": {
            "baseColorTexture": { "index": t, "extensions": { "KHR_texture_transform":
                { "offset": [0.5, 0.0], "rotation": 0.0, "scale": [2.0, 1.0] } } },
            "baseColorFactor": [0.5, 1.0, 1.0, 1.0],
            "metallicRoughnessTexture": { "index": t } },
        "normalTexture": { "index": t, "scale": 0.5 } }));
    w.use_extension("KHR_texture_transform", false);
    let mesh = quad_mesh(&mut w, Some(m));
    let n = w.node(json!({ "mesh": mesh }));
    w.scene(&[n]);
    let s = load(&w.to_gltf_external(&dir("tex"), "tex").unwrap());
    let mat = s.materials[0];
    assert_eq!(
        s.textures.len(),
        3,
        "the studio environment; base colour (sRGB); metallic-roughness and normal \
         (linear, one look-up)"
    );
    let (p, surface) = (pbr::Params::read(&mat), Surface::read(&mat));
    let base = s.textures[p.base_color_texture as usize];
    assert_eq!(&base.color0[..3], &[0.5, 1.0, 1.0]);
    // glTF's u' = 2u + 0.5; v' = v (v down) -> wgtrace's v' = 1 - (1 - v) = v
    assert_eq!(&base.color1[..3], &[2.0, 0.0, 0.5]);
    assert_eq!(&base.params[..3], &[0.0, 1.0, 0.0]);
    let texel = |t: u32, i: u32| {
        let tex = s.textures[t as usize];
        let srgb = tex.flags & records::TEX_FLAG_SRGB != 0;
        s.texels.texel(tex.bank, tex.layer, tex.x + i, tex.y, srgb)
    };
    // 128 / 255: decoded from sRGB for the colour, taken as it is for the data
    assert!((texel(p.base_color_texture, 0)[1] - 0.2158605).abs() < 1e-5);
    assert!((texel(p.metallic_roughness_texture, 0)[1] - 128.0 / 255.0).abs() < 1e-6);
    assert_eq!(
        surface.normal_texture, p.metallic_roughness_texture,
        "the same linear look-up"
    );
    assert_eq!(surface.normal_scale, 0.5, "normal scale");
    // a normal-mapped mesh without tangents gets MikkTSpace's: +x along u on this quad
    let p = s.primitives[0];
    assert_ne!(p.flags & records::PRIM_FLAG_TANGENTS, 0);
    let t0 = s.shape_data[p.data as usize + 4];
    assert!(
        (Vec3::new(t0[0], t0[1], t0[2]) - Vec3::X).length() < 1e-5,
        "{t0:?}"
    );
    assert_eq!(t0[3], 1.0);
}

#[test]
fn extensions_it_cannot_honour_are_errors_when_required_and_notes_when_used() {
    let mut w = quad_file(pbr([0.5; 4], 0.0, 1.0));
    w.use_extension("KHR_materials_anisotropy", false);
    let d = dir("required");
    let s = load(&w.to_gltf_external(&d, "used").unwrap());
    assert!(
        s.warnings
            .iter()
            .any(|m| m.contains("KHR_materials_anisotropy")),
        "{:?}",
        s.warnings
    );
    w.use_extension("KHR_materials_anisotropy", true);
    let e = load_err(&w.to_gltf_external(&d, "required").unwrap());
    assert!(
        e.contains("required.gltf: extensionsRequired[0]: ")
            && e.contains("KHR_materials_anisotropy"),
        "{e}"
    );
    // Draco: refused with a way to decompress the file
    let mut w = quad_file(pbr([0.5; 4], 0.0, 1.0));
    w.use_extension("KHR_draco_mesh_compression", true);
    let e = load_err(&w.to_gltf_external(&d, "draco").unwrap());
    assert!(
        e.contains("draco.gltf: extensionsRequired[0]: ")
            && e.contains("Draco-compressed")
            && e.contains("@gltf-transform/cli copy"),
        "{e}"
    );
}

/// A broken file: `edit` changes the writer or the bytes; the error names the file and `key`.
fn assert_refused(name: &str, w: &GltfWriter, key: &str, why: &str) {
    let d = dir(name);
    let path = w.to_gltf_external(&d, name).unwrap();
    let e = load_err(&path);
    assert!(e.contains(&format!("{name}.gltf: {key}")), "{name}: {e}");
    assert!(e.contains(why), "{name}: {e}");
}

#[test]
fn broken_files_are_refused_with_the_json_path() {
    let base = quad_file(pbr([0.5; 4], 0.0, 1.0));
    // POSITION is accessor 0, NORMAL 1, TEXCOORD_0 2, indices 3 (add_mesh_arrays' order)
    let mut w = base.clone();
    w.json["accessors"][0]["count"] = json!(1u64 << 40);
    assert_refused(
        "huge",
        &w,
        "meshes[0].primitives[0].attributes.POSITION (accessors[0].count)",
        "wgtrace reads 1 to",
    );
    let mut w = base.clone();
    w.json["accessors"][0]["byteOffset"] = json!(1000);
    assert_refused(
        "outside",
        &w,
        "meshes[0].primitives[0].attributes.POSITION",
        "reads up to byte",
    );
    let mut w = base.clone();
    w.json["bufferViews"][0]["byteLength"] = json!(1 << 20);
    assert_refused("view", &w, "bufferViews[0]", "past the end of buffers[0]");
    let mut w = base.clone();
    // unsigned int positions: neither float nor KHR_mesh_quantization's
    w.json["accessors"][0]["componentType"] = json!(5125);
    assert_refused(
        "type",
        &w,
        "meshes[0].primitives[0].attributes.POSITION (accessors[0])",
        "expected Vec3 of [F32, I8, U8, I16, U16]",
    );
    let mut w = base.clone();
    w.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(99);
    assert_refused(
        "dangling",
        &w,
        "meshes[0].primitives[0].attributes.POSITION",
        "names accessors[99]",
    );
    let mut w = base.clone();
    w.json["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = json!(99);
    assert_refused(
        "dangling2",
        &w,
        "meshes[0].primitives[0].attributes[\"NORMAL\"]",
        "Index",
    );
    // NaN positions
    let mut w = base.clone();
    w.bin[0..4].copy_from_slice(&f32::NAN.to_le_bytes());
    assert_refused("nan", &w, "meshes[0].primitives[0]", "non-finite");
    // an index past the vertices
    let mut w = base.clone();
    let at = w.json["bufferViews"][3]["byteOffset"].as_u64().unwrap_or(0) as usize;
    w.bin[at..at + 4].copy_from_slice(&77u32.to_le_bytes());
    assert_refused(
        "index",
        &w,
        "meshes[0].primitives[0]",
        "beyond its vertex list",
    );
    // the buffer shorter than its byteLength, and a missing buffer file
    let d = dir("short");
    let path = base.to_gltf_external(&d, "short").unwrap();
    let bin = d.join("short.bin");
    let bytes = std::fs::read(&bin).unwrap();
    std::fs::write(&bin, &bytes[..bytes.len() / 2]).unwrap();
    let e = load_err(&path);
    assert!(e.contains("short.gltf: buffers[0].byteLength: is "), "{e}");
    std::fs::remove_file(&bin).unwrap();
    let e = load_err(&path);
    assert!(
        e.contains("short.gltf: buffers[0]: \"short.bin\" cannot be read"),
        "{e}"
    );
    // a missing and an undecodable image
    let mut w = base.clone();
    let t = w.png_texture_uri("missing.png", None);
    w.json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({ "index": t });
    assert_refused(
        "noimage",
        &w,
        "images[0].uri",
        "\"missing.png\" cannot be read",
    );
    let d = dir("badimage");
    std::fs::write(d.join("missing.png"), b"not a png").unwrap();
    let path = w.to_gltf_external(&d, "badimage").unwrap();
    let e = load_err(&path);
    assert!(e.contains("badimage.gltf: images[0]: "), "{e}");
    // not JSON, a truncated GLB
    let d = dir("truncated");
    std::fs::write(d.join("text.gltf"), "{ \"asset\": ").unwrap();
    assert!(load_err(&d.join("text.gltf")).contains("text.gltf: is not glTF 2.0"));
    let glb = base.glb_bytes();
    std::fs::write(d.join("cut.glb"), &glb[..glb.len() - 10]).unwrap();
    let e = load_err(&d.join("cut.glb"));
    assert!(
        e.contains("cut.glb: is a GLB file whose header declares"),
        "{e}"
    );
}

/// A material's values are checked whether or not a texture multiplies them (a factor
/// is then baked into the texture, out of the material check's sight), and glTF's ior
/// (inside against air) is at least 1 on glass too.
#[test]
fn material_factors_are_checked_with_or_without_a_texture() {
    let texel = image::RgbaImage::from_pixel(2, 2, image::Rgba([255, 255, 255, 255]));
    let cases = [
        (
            "factor",
            json!({ "baseColorFactor": [1.5, 0.5, 0.5, 1.0] }),
            None,
            "materials[0].pbrMetallicRoughness.baseColorFactor[0]",
            "must be in [0, 1], got 1.5",
        ),
        (
            "factortex",
            json!({ "baseColorFactor": [0.5, 1.5, 0.5, 1.0] }),
            None,
            "materials[0].pbrMetallicRoughness.baseColorFactor[1]",
            "must be in [0, 1], got 1.5",
        ),
        (
            "specular",
            json!({}),
            Some(json!({ "KHR_materials_specular": { "specularColorFactor": [1.0, -1.0, 1.0] } })),
            "materials[0].extensions.KHR_materials_specular.specularColorFactor[1]",
            "must be >= 0, got -1",
        ),
        (
            "glassior",
            json!({}),
            Some(
                json!({ "KHR_materials_transmission": { "transmissionFactor": 1.0 },
                         "KHR_materials_ior": { "ior": 0.8 } }),
            ),
            "materials[0].extensions.KHR_materials_ior.ior",
            "must be >= 1, got 0.8",
        ),
        (
            "glassfactor",
            json!({ "baseColorFactor": [0.5, 0.5, 2.0, 1.0] }),
            Some(json!({ "KHR_materials_transmission": { "transmissionFactor": 1.0 } })),
            "materials[0].pbrMetallicRoughness.baseColorFactor[2]",
            "must be in [0, 1], got 2",
        ),
    ];
    for (name, mut pbr, extensions, key, why) in cases {
        // the quad's file has no texture yet: the one added after it is texture 0
        if name != "factor" {
            pbr["baseColorTexture"] = json!({ "index": 0 });
        }
        let mut material = json!({ "pbrMetallicRoughness": pbr });
        let mut used = Vec::new();
        if let Some(mut e) = extensions {
            if let Some(s) = e.get_mut("KHR_materials_specular") {
                s["specularColorTexture"] = json!({ "index": 0 });
            }
            used = e.as_object().unwrap().keys().cloned().collect();
            material["extensions"] = e;
        }
        let mut w = quad_file(material);
        for k in &used {
            w.use_extension(k, false);
        }
        assert_eq!(w.png_texture(&texel, None).unwrap(), 0);
        assert_refused(name, &w, key, why);
    }
}

#[test]
fn a_cycle_in_the_node_hierarchy_is_refused_not_walked_forever() {
    let mut w = quad_file(pbr([0.5; 4], 0.0, 1.0));
    w.json["nodes"][0]["children"] = json!([0]);
    let d = dir("cycle");
    let e = load_err(&w.to_gltf_external(&d, "cycle").unwrap());
    assert!(e.contains("nodes[0]"), "{e}");
}

/// A GLB with bytes changed, cut or appended loads or is refused with an error, never
/// panics; so does its JSON with characters changed.
mod fuzz {
    use super::*;
    use proptest::prelude::*;

    fn try_load(bytes: &[u8], ext: &str, tag: u64) {
        let d = std::env::temp_dir().join(format!("wgtrace-gltf-fuzz-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let path = d.join(format!("f{tag}.{ext}"));
        std::fs::write(&path, bytes).unwrap();
        let _ = wgtrace::load_scene(&path, &Overrides::default());
        let _ = std::fs::remove_file(&path);
    }

    /// A file that reaches every reader: a textured quad, and a second primitive with
    /// quantized positions, a u8 colour, a second uv set and meshopt-compressed indices,
    /// under a spec-gloss material reading both uv sets.
    fn asset() -> GltfWriter {
        let mut w = quad_file(pbr([0.5; 4], 0.5, 0.5));
        let img = image::RgbaImage::from_pixel(2, 2, image::Rgba([200, 100, 50, 255]));
        let t = w.png_texture(&img, None).unwrap();
        w.json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({ "index": t });
        let sg = w.material(json!({ "extensions": { "KHR_materials_pbrSpecularGlossiness": {
            "diffuseTexture": { "index": t }, "specularGlossinessTexture": { "index": t, "texCoord": 1 } } } }));
        let quads: [[i16; 4]; 4] = [
            [0, 0, 0, 0],
            [100, 0, 0, 0],
            [100, 100, 0, 0],
            [0, 100, 0, 0],
        ];
        let pos: Vec<u8> = quads
            .iter()
            .flatten()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let pv = w.view(&pos, Some(8));
        let pa = w.accessor(
            pv,
            0,
            5122,
            4,
            "VEC3",
            Some((vec![0.0; 3], vec![100.0, 100.0, 0.0])),
        );
        let cv = w.view(
            &[
                255, 0, 0, 255, 0, 255, 0, 128, 0, 0, 255, 255, 255, 255, 255, 0,
            ],
            None,
        );
        let ca = w.accessor(cv, 0, 5121, 4, "VEC4", None);
        w.json["accessors"][ca]["normalized"] = json!(true);
        let t0 = w.vec2(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        let t1 = w.vec2(&[[0.0, 1.0], [2.0, 1.0], [2.0, 0.0], [0.0, 0.0]]);
        let encoded = meshopt::encoding::encode_index_buffer(&[0u32, 1, 2, 0, 2, 3], 4).unwrap();
        let raw = w.view(&encoded, None);
        let at = w.json["bufferViews"][raw]["byteOffset"].clone();
        let iv = w.push("bufferViews", json!({ "buffer": 1, "byteLength": 24,
            "extensions": { "EXT_meshopt_compression": { "buffer": 0, "byteOffset": at,
                "byteLength": encoded.len(), "byteStride": 4, "count": 6, "mode": "TRIANGLES" } } }));
        let ia = w.accessor(iv, 0, 5125, 6, "SCALAR", None);
        w.more_buffers.push(json!({ "byteLength": 24,
            "extensions": { "EXT_meshopt_compression": { "fallback": true } } }));
        let prim = GltfWriter::primitive(
            &[
                ("POSITION", pa),
                ("COLOR_0", ca),
                ("TEXCOORD_0", t0),
                ("TEXCOORD_1", t1),
            ],
            Some(ia),
            Some(sg),
        );
        let mesh = w.mesh(vec![prim]);
        let n = w.node(json!({ "mesh": mesh, "scale": [0.01, 0.01, 0.01] }));
        w.json["scenes"][0]["nodes"]
            .as_array_mut()
            .unwrap()
            .push(json!(n));
        for e in [
            "KHR_mesh_quantization",
            "EXT_meshopt_compression",
            "KHR_materials_pbrSpecularGlossiness",
        ] {
            w.use_extension(e, true);
        }
        w
    }

    /// The fuzz tests' asset loads as it is: the mutations start from a file that works.
    #[test]
    fn the_fuzzed_asset_loads() {
        let w = asset();
        let d = dir("fuzz-asset");
        let s = load(&w.to_gltf_external(&d, "asset").unwrap());
        assert!(s.primitives.len() >= 4, "{}", s.primitives.len());
        let both = records::PRIM_FLAG_UV1 | records::PRIM_FLAG_COLORS;
        assert!(s.primitives.iter().any(|p| p.flags & both == both));
        std::fs::write(d.join("asset.glb"), w.glb_bytes()).unwrap();
        load(&d.join("asset.glb"));
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

        #[test]
        fn mutated_glb_files_load_or_are_refused(
            edits in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8),
            cut in any::<prop::sample::Index>(),
            tag in any::<u64>(),
        ) {
            let mut bytes = asset().glb_bytes();
            for (at, b) in &edits {
                let i = at.index(bytes.len());
                bytes[i] = *b;
            }
            try_load(&bytes, "glb", tag);
            let n = cut.index(bytes.len());
            try_load(&bytes[..n], "glb", tag);
        }

        #[test]
        fn mutated_gltf_json_loads_or_is_refused(
            edits in proptest::collection::vec((any::<prop::sample::Index>(), prop::sample::select(vec![b'0', b'9', b'-', b'1', b'"', b'}', b'[', b'e'])), 1..6),
            tag in any::<u64>(),
        ) {
            let w = asset();
            let d = std::env::temp_dir().join(format!("wgtrace-gltf-fuzzj-{}-{tag}", std::process::id()));
            std::fs::create_dir_all(&d).unwrap();
            let path = w.to_gltf_external(&d, "f").unwrap();
            let mut text = std::fs::read(&path).unwrap();
            for (at, b) in &edits {
                let i = at.index(text.len());
                text[i] = *b;
            }
            std::fs::write(&path, &text).unwrap();
            let _ = wgtrace::load_scene(&path, &Overrides::default());
            let _ = std::fs::remove_dir_all(&d);
        }
    }
}

#[test]
fn a_scene_file_places_a_gltf_object_under_its_own_camera_and_lights() {
    let w = quad_file(pbr([0.5; 4], 0.0, 1.0));
    let d = dir("object");
    w.to_gltf_external(&d, "model").unwrap();
    let src = r#"
[camera]
look_from = [0, 0, 10]
look_at = [0, 0, 0]
[background]
color = [0.5, 0.5, 0.5]
[materials.white]
type = "lambertian"
albedo = [0.8, 0.8, 0.8]
[[objects]]
type = "gltf"
path = "model.gltf"
transform = { translate = [5, 0, 0], scale = 2 }
[[objects]]
type = "sphere"
center = [0, 0, -3]
radius = 1
material = "white"
"#;
    let s = wgtrace::load_scene_str(src, &d.join("scene.toml"), &Overrides::default())
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.camera.origin, Vec3::new(0.0, 0.0, 10.0));
    assert_eq!(s.background, [0.5; 3]);
    // the scene's material first, then the file's
    assert_eq!(s.material_names[0], "white");
    assert!(
        s.material_names[1].starts_with("objects[0]/"),
        "{:?}",
        s.material_names
    );
    let xs: Vec<f32> = s
        .primitives
        .iter()
        .filter(|p| p.tag == wgtrace::scene::primitives::PrimitiveKind::Triangle.tag())
        .flat_map(|p| [p.a[0], p.b[0], p.c[0]])
        .collect();
    assert!(
        xs.iter().all(|&x| (3.0..=7.0).contains(&x)) && xs.contains(&7.0),
        "{xs:?}"
    );
    // the file's light comes along, placed by the object's transform
    assert_eq!(&s.punctual()[0].a[..3], &[5.0, 0.0, 4.0]);
    // a file that is missing: the object's line and key
    let e = wgtrace::load_scene_str(
        &src.replace("model.gltf", "nope.gltf"),
        &d.join("scene.toml"),
        &Overrides::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("scene.toml:10:1: objects[0].path: ") && e.contains("nope.gltf"),
        "{e}"
    );
}

/// A directional light on a white Lambertian quad seen from above, tilted by phi toward
/// +y: the radiance is E cos(phi) / pi everywhere (E = 3); with a normal map tilting every
/// normal by theta toward the bitangent (+v, here +y) it is E cos(theta - phi) / pi (a
/// bitangent the wrong way round would give cos(theta + phi)). Both backends.
#[test]
fn a_normal_map_tilts_the_shading_normal_by_its_angle() {
    let theta = 0.5f32;
    let mut w = GltfWriter::new();
    // n = (0, sin, cos) in tangent space: tilted toward the bitangent (+v, +y)
    let c = |x: f32| ((x * 0.5 + 0.5) * 255.0).round() as u8;
    let img = image::RgbaImage::from_pixel(
        4,
        4,
        image::Rgba([c(0.0), c(theta.sin()), c(theta.cos()), 255]),
    );
    let t = w.png_texture(&img, None).unwrap();
    let flat = w.material(json!({ "pbrMetallicRoughness": { "metallicFactor": 0.0 },
        "extensions": { "KHR_materials_specular": { "specularFactor": 0.0 } } }));
    let mapped = w.material(json!({ "pbrMetallicRoughness": { "metallicFactor": 0.0 },
        "normalTexture": { "index": t },
        "extensions": { "KHR_materials_specular": { "specularFactor": 0.0 } } }));
    let q = |x: f32| quad([x, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
    let (a, b) = (q(-1.0), q(1.0));
    let ma = w.add_mesh_arrays(&a, Some(flat), true);
    let mb = w.add_mesh_arrays(&b, Some(mapped), true);
    let na = w.node(json!({ "mesh": ma }));
    let nb = w.node(json!({ "mesh": mb }));
    let phi = 0.3f32;
    let l = w.light(json!({ "type": "directional", "intensity": 3.0 }));
    // -z turned about x by -phi: travelling along (0, -sin phi, -cos phi)
    let mut ln = json!({ "rotation": [(-phi / 2.0).sin(), 0.0, 0.0, (phi / 2.0).cos()] });
    ln.as_object_mut()
        .unwrap()
        .extend(light_ref(l).as_object().unwrap().clone());
    let ln = w.node(ln);
    let cam = w.camera(json!({ "type": "orthographic", "orthographic": { "xmag": 2.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0 } }));
    let cn = w.node(json!({ "camera": cam, "translation": [0.0, 0.0, 5.0] }));
    w.scene(&[na, nb, ln, cn]);
    let path = w.to_gltf_external(&dir("normal"), "normal").unwrap();
    let o = Overrides {
        width: Some(32),
        height: Some(16),
        spp: Some(4),
        max_depth: Some(2),
        ..Default::default()
    };
    let s = wgtrace::load_scene(&path, &o).unwrap();
    let cos = c(theta.cos()) as f32 / 255.0 * 2.0 - 1.0;
    let sin = c(theta.sin()) as f32 / 255.0 * 2.0 - 1.0;
    let to_light = Vec3::new(0.0, phi.sin(), phi.cos());
    let expect_flat = 3.0 / std::f32::consts::PI * phi.cos();
    let expect_mapped =
        3.0 / std::f32::consts::PI * Vec3::new(0.0, sin, cos).normalize().dot(to_light);
    for (name, img) in [
        ("cpu", common::render_cpu(&s)),
        ("gpu", common::render_gpu(&s)),
    ] {
        let rgb = img.to_rgb();
        let px = |x: u32, y: u32| rgb[3 * (y * img.width + x) as usize];
        for y in 2..14 {
            for x in 2..14 {
                let (l, r) = (px(x, y), px(x + 16, y));
                assert!(
                    (l - expect_flat).abs() < 1e-3,
                    "{name} flat {l} vs {expect_flat}"
                );
                assert!(
                    (r - expect_mapped).abs() < 1e-3,
                    "{name} mapped {r} vs {expect_mapped}"
                );
            }
        }
    }
}

/// alphaMode MASK cuts a quad out where its texture's alpha is below the cutoff, and
/// BLEND lets 1 - alpha through on average: a white quad in front of an emitter of
/// radiance 1 (the background), seen head on, shows 1 through the holes; on both backends,
/// for camera rays and shadow rays (a second test below).
#[test]
fn alpha_mask_and_blend_let_the_background_through() {
    // left half of the texture alpha 0, right half alpha 1 (MASK); BLEND at alpha 0.25
    let mut w = GltfWriter::new();
    let img = image::RgbaImage::from_fn(8, 8, |x, _| {
        image::Rgba([255, 255, 255, if x < 4 { 0 } else { 255 }])
    });
    let t = w
        .png_texture(
            &img,
            Some(json!({ "magFilter": 9728, "minFilter": 9728, "wrapS": 33071, "wrapT": 33071 })),
        )
        .unwrap();
    let mask = w.material(
        json!({ "pbrMetallicRoughness": { "baseColorTexture": { "index": t },
        "baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0 },
        "alphaMode": "MASK", "alphaCutoff": 0.5 }),
    );
    let blend = w.material(json!({ "pbrMetallicRoughness": {
        "baseColorFactor": [0.0, 0.0, 0.0, 0.25], "metallicFactor": 0.0 },
        "alphaMode": "BLEND" }));
    let q = |x: f32| quad([x, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
    let ma = w.add_mesh_arrays(&q(-1.0), Some(mask), true);
    let mb = w.add_mesh_arrays(&q(1.0), Some(blend), true);
    let na = w.node(json!({ "mesh": ma }));
    let nb = w.node(json!({ "mesh": mb }));
    let cam = w.camera(json!({ "type": "orthographic", "orthographic": { "xmag": 2.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0 } }));
    let cn = w.node(json!({ "camera": cam, "translation": [0.0, 0.0, 5.0] }));
    w.scene(&[na, nb, cn]);
    let path = w.to_gltf_external(&dir("alpha"), "alpha").unwrap();
    let spp = 256;
    let o = Overrides {
        width: Some(32),
        height: Some(16),
        spp: Some(spp),
        max_depth: Some(1),
        background: Some([1.0; 3]),
        ..Default::default()
    };
    let s = wgtrace::load_scene(&path, &o).unwrap();
    assert_eq!(s.background, [1.0; 3]);
    for (name, img) in [
        ("cpu", common::render_cpu(&s)),
        ("gpu", common::render_gpu(&s)),
    ] {
        let rgb = img.to_rgb();
        let px = |x: u32, y: u32| rgb[3 * (y * img.width + x) as usize] as f64;
        for y in 2..14 {
            // the mask: the background through its left half (pixels 0..8), black right
            assert_eq!(px(2, y), 1.0, "{name}");
            assert_eq!(px(13, y), 0.0, "{name}");
        }
        // blend: each camera ray passes with probability 0.75; over 12 x 12 pixels of
        // `spp` samples the mean is within 4 standard errors of 0.75
        let mut sum = 0.0;
        for y in 2..14 {
            for x in 18..30 {
                sum += px(x, y);
            }
        }
        let n = 144.0 * spp as f64;
        let mean: f64 = sum / 144.0;
        let se = (0.75f64 * 0.25 / n).sqrt();
        assert!(
            (mean - 0.75).abs() < 4.0 * se,
            "{name}: {mean} vs 0.75 +- {se}"
        );
    }
}

/// A shadow ray passes a blended surface with probability 1 - alpha: a white Lambertian
/// floor under a directional light, with a BLEND quad of alpha 0.25 between them, has
/// 0.75 of the unshadowed radiance on average.
#[test]
fn shadow_rays_pass_blended_surfaces_in_proportion() {
    let mut w = GltfWriter::new();
    let white = w.material(json!({ "pbrMetallicRoughness": { "metallicFactor": 0.0 },
        "extensions": { "KHR_materials_specular": { "specularFactor": 0.0 } } }));
    let veil = w.material(json!({ "pbrMetallicRoughness": { "baseColorFactor": [0.0, 0.0, 0.0, 0.25], "metallicFactor": 0.0 },
        "alphaMode": "BLEND" }));
    let floor = w.add_mesh_arrays(
        &quad([0.0; 3], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]),
        Some(white),
        true,
    );
    let above = w.add_mesh_arrays(
        &quad([0.0, 0.0, 1.0], [4.0, 0.0, 0.0], [0.0, 4.0, 0.0]),
        Some(veil),
        true,
    );
    let nf = w.node(json!({ "mesh": floor }));
    let nv = w.node(json!({ "mesh": above }));
    let l = w.light(json!({ "type": "directional", "intensity": 3.0 }));
    let ln = w.node(light_ref(l));
    let cam = w.camera(json!({ "type": "orthographic", "orthographic": { "xmag": 1.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0 } }));
    // the camera under the veil, looking down at the floor
    let cn = w.node(json!({ "camera": cam, "translation": [0.0, 0.0, 0.5] }));
    w.scene(&[nf, nv, ln, cn]);
    let path = w.to_gltf_external(&dir("veil"), "veil").unwrap();
    let spp = 64;
    let o = Overrides {
        width: Some(16),
        height: Some(16),
        spp: Some(spp),
        max_depth: Some(2),
        ..Default::default()
    };
    let s = wgtrace::load_scene(&path, &o).unwrap();
    let lit = 3.0 / std::f64::consts::PI;
    for (name, img) in [
        ("cpu", common::render_cpu(&s)),
        ("gpu", common::render_gpu(&s)),
    ] {
        let mean: f64 = img
            .to_rgb()
            .iter()
            .step_by(3)
            .map(|&p| p as f64)
            .sum::<f64>()
            / 256.0;
        let n = 256.0 * spp as f64;
        let se = lit * (0.75f64 * 0.25 / n).sqrt();
        assert!(
            (mean - 0.75 * lit).abs() < 4.0 * se,
            "{name}: {mean} vs {} +- {se}",
            0.75 * lit
        );
    }
}

/// The gallery's glTF files (written by `cargo run --example gen_gltf`) load, and the GPU
/// agrees with the CPU reference on them.
#[test]
fn the_shipped_gltf_files_render_alike_on_both_backends() {
    for rel in ["scenes/gltf/spheres.gltf", "scenes/gltf/brick.glb"] {
        let o = Overrides {
            width: Some(48),
            height: Some(32),
            spp: Some(16),
            ..Default::default()
        };
        let s = wgtrace::load_scene(&common::repo_path(rel), &o).unwrap_or_else(|e| panic!("{e}"));
        let c = common::compare(&common::render_gpu(&s), &common::render_cpu(&s), 8);
        assert!(
            c.failed_tiles.is_empty(),
            "{rel}: {}",
            c.failed_tiles.join("\n")
        );
        assert!(c.agree_fraction >= 0.98, "{rel}: {}", c.agree_fraction);
    }
}

/// Instances are flattened: a mesh used by n nodes is read once, and its triangles are
/// written n times into the records. This measures what that costs (printed;
/// ARCHITECTURE.md's limits quote it) and holds the records to n times one instance's.
#[test]
fn instances_cost_their_triangles_each_in_the_records() {
    let sphere = gltf_writer::uv_sphere([0.0; 3], 0.4, 32, 64);
    let bytes =
        |s: &FlatScene| s.primitives.len() * 64 + s.shape_data.len() * 16 + s.bvh.len() * 32;
    let mut sizes = Vec::new();
    for n in [1usize, 10, 100] {
        let mut w = GltfWriter::new();
        let mesh = w.add_mesh_arrays(&sphere, None, true);
        let nodes: Vec<usize> = (0..n)
            .map(|i| w.node(json!({ "mesh": mesh, "translation": [i as f32, 0.0, 0.0] })))
            .collect();
        w.scene(&nodes);
        let d = dir(&format!("instances{n}"));
        let file = w.to_gltf_external(&d, "i").unwrap();
        let file_bytes = std::fs::metadata(d.join("i.bin")).unwrap().len();
        let s = load(&file);
        assert_eq!(s.primitives.len(), n * sphere.indices.len() / 3);
        eprintln!(
            "{n} instances of {} triangles: file {file_bytes} B, records {} B ({:.1} B per placed triangle)",
            sphere.indices.len() / 3,
            bytes(&s),
            bytes(&s) as f64 / s.primitives.len() as f64
        );
        sizes.push(bytes(&s));
    }
    // linear in the instances, within the BVH's shape
    let per = sizes[0] as f64;
    assert!((sizes[2] as f64 / per - 100.0).abs() < 5.0, "{sizes:?}");
}

/// A primitive gets the uv set its material's textures read: TEXCOORD_1 here; and
/// KHR_materials_specular's specularTexture scales the specular factor by its alpha.
#[test]
fn textures_on_a_second_uv_set_and_the_specular_texture_are_read() {
    let mut w = GltfWriter::new();
    let img = image::RgbaImage::from_pixel(2, 2, image::Rgba([255, 255, 255, 64]));
    let t = w.png_texture(&img, None).unwrap();
    let m = w.material(json!({ "pbrMetallicRoughness": {
            "baseColorTexture": { "index": t, "texCoord": 1 }, "metallicFactor": 0.0 },
        "extensions": { "KHR_materials_specular": {
            "specularTexture": { "index": t, "texCoord": 1 }, "specularFactor": 0.5 } } }));
    w.use_extension("KHR_materials_specular", false);
    let q = quad([0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
    let pos = w.positions(&q.positions);
    let uv0 = w.vec2(&q.uvs);
    // the second set: every corner at (0.25, 0.75) (glTF's v down: wgtrace's v = 0.25)
    let uv1 = w.vec2(&[[0.25, 0.75]; 4]);
    let idx = w.indices_u32(&q.indices);
    let prim = GltfWriter::primitive(
        &[("POSITION", pos), ("TEXCOORD_0", uv0), ("TEXCOORD_1", uv1)],
        Some(idx),
        Some(m),
    );
    let mesh = w.mesh(vec![prim]);
    let n = w.node(json!({ "mesh": mesh }));
    w.scene(&[n]);
    let s = load(&w.to_gltf_external(&dir("uv1"), "uv1").unwrap());
    let p = s.primitives[0];
    let a = &s.shape_data[p.data as usize..p.data as usize + 4];
    // (n_k, u_k) then (v0, v1, v2, 0)
    assert_eq!([a[0][3], a[1][3], a[2][3]], [0.25; 3]);
    assert_eq!(&a[3][..3], &[0.25; 3]);
    assert!(
        !s.warnings.iter().any(|w| w.contains("TEXCOORD")),
        "{:?}",
        s.warnings
    );
    let mat = s.materials[0];
    assert_ne!(
        pbr::Params::read(&mat).specular_texture,
        records::NO_TEXTURE
    );
    // on the CPU: specular 0.5 x alpha 64/255 at the hit
    let b = wgtrace::cpu::bindings::Bindings::new(&s, s.params(0, s.full_band()));
    let hit = wgtrace::cpu::types::Hit {
        p: Vec3::ZERO,
        ng: Vec3::Z,
        ns: Vec3::Z,
        unmapped: Vec3::Z,
        uv: glam::Vec4::splat(0.5),
        front_face: true,
        material: 0,
        err: 0.0,
        tangent: glam::Vec4::ZERO,
        color: glam::Vec4::ONE,
        dpdu: glam::Vec3::ZERO,
        dpdv: glam::Vec3::ZERO,
    };
    let at = pbr::Params::read(&wgtrace::cpu::materials::material_at(&b, &mat, &hit));
    assert!((at.specular - 0.5 * 64.0 / 255.0).abs() < 1e-6, "{:?}", at);
}

/// COLOR_0 (float VEC3, normalized u8 VEC4, normalized u16 VEC3 with a stride) multiplies
/// the base colour and opacity; a material's texture reads the uv set it names (here
/// TEXCOORD_1, beside TEXCOORD_0); its sampler's wrapS, wrapT and NEAREST apply. The
/// records say so, the CPU's hits interpolate them, and the GPU's hits agree ray by ray.
#[test]
fn vertex_colours_second_uv_sets_and_sampler_modes_are_read() {
    use gltf_writer::{FLOAT, UNSIGNED_SHORT};
    use wgtrace::cpu::bindings::Bindings;
    use wgtrace::cpu::intersect::{intersect_scene, surface_at};
    use wgtrace::cpu::types::{Ray, FAR};
    let mut w = GltfWriter::new();
    let img = image::RgbaImage::from_fn(2, 2, |x, y| {
        image::Rgba([100 * x as u8, 100 * y as u8, 50, 255])
    });
    // CLAMP_TO_EDGE in u, MIRRORED_REPEAT in v, NEAREST magnification
    let sampler = json!({ "magFilter": 9728, "minFilter": 9728, "wrapS": 33071, "wrapT": 33648 });
    let t = w.png_texture(&img, Some(sampler)).unwrap();
    // base colour from TEXCOORD_1, metallic-roughness from TEXCOORD_0: two sets
    let m = w.material(json!({ "pbrMetallicRoughness": {
        "baseColorTexture": { "index": t, "texCoord": 1 },
        "metallicRoughnessTexture": { "index": t }, "metallicFactor": 0.0 } }));
    let corners = [
        [-1.0f32, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ];
    let uv0 = [[0.0f32, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    // the second set: u twice over, v upside down
    let uv1 = uv0.map(|[u, v]| [2.0 * u, 1.0 - v]);
    let colours = [
        [1.0f32, 0.0, 0.0, 1.0],
        [0.0, 1.0, 0.0, 0.5],
        [0.0, 0.0, 1.0, 1.0],
        [1.0, 1.0, 1.0, 0.25],
    ];
    let mut primitives = Vec::new();
    for (k, dz) in [0.0f32, -2.0, -4.0].into_iter().enumerate() {
        let p: Vec<[f32; 3]> = corners.iter().map(|c| [c[0], c[1], c[2] + dz]).collect();
        let pos = w.positions(&p);
        let (t0, t1) = (w.vec2(&uv0), w.vec2(&uv1));
        let colour = match k {
            0 => w.vec3(&colours.map(|c| [c[0], c[1], c[2]])),
            1 => {
                let bytes: Vec<u8> = colours
                    .iter()
                    .flatten()
                    .map(|x| (x * 255.0) as u8)
                    .collect();
                let v = w.view(&bytes, None);
                let a = w.accessor(v, 0, 5121, 4, "VEC4", None);
                w.json["accessors"][a]["normalized"] = json!(true);
                a
            }
            _ => {
                // VEC3 of u16 in 8-byte strides, as glTF's 4-byte alignment asks
                let bytes: Vec<u8> = colours
                    .iter()
                    .flat_map(|c| {
                        let q = |x: f32| ((x * 65535.0) as u16).to_le_bytes();
                        [q(c[0]), q(c[1]), q(c[2]), [0, 0]].concat()
                    })
                    .collect();
                let v = w.view(&bytes, Some(8));
                let a = w.accessor(v, 0, UNSIGNED_SHORT, 4, "VEC3", None);
                w.json["accessors"][a]["normalized"] = json!(true);
                a
            }
        };
        let idx = w.indices_u32(&[0, 1, 2, 0, 2, 3]);
        primitives.push(GltfWriter::primitive(
            &[
                ("POSITION", pos),
                ("TEXCOORD_0", t0),
                ("TEXCOORD_1", t1),
                ("COLOR_0", colour),
            ],
            Some(idx),
            Some(m),
        ));
    }
    assert_eq!(FLOAT, 5126);
    let mesh = w.mesh(primitives);
    let n = w.node(json!({ "mesh": mesh }));
    w.scene(&[n]);
    let s = load(
        &w.to_gltf_external(&dir("attributes"), "attributes")
            .unwrap(),
    );
    let tex = s.textures[pbr::Params::read(&s.materials[0]).base_color_texture as usize];
    assert_eq!(tex.uv_set, 1, "the second uv set");
    assert_eq!(
        tex.flags & (records::TEX_MODE_MASK | records::TEX_MODE_MASK << records::TEX_WRAP_T_SHIFT),
        records::WRAP_CLAMP | records::WRAP_MIRROR << records::TEX_WRAP_T_SHIFT
    );
    assert_ne!(tex.flags & records::TEX_FLAG_NEAREST, 0);
    let both = records::PRIM_FLAG_UV1 | records::PRIM_FLAG_COLORS;
    assert!(s.primitives.iter().all(|p| p.flags & both == both));
    // the CPU's hits: interpolated second uvs and colours, the same for the three encodings
    let b = Bindings::new(&s, s.params(0, s.full_band()));
    for (k, z) in [0.0f32, -2.0, -4.0].into_iter().enumerate() {
        // (0.5, 0.25) on the quad: its uv0 is (0.75, 0.625) in wgtrace's v-up
        let ray = Ray {
            origin: Vec3::new(0.5, 0.25, z + 0.5),
            dir: Vec3::NEG_Z,
        };
        let c = intersect_scene(&b, &ray, FAR);
        let h = surface_at(&b, &ray, &c);
        let (u, v) = (0.75f32, 0.625f32);
        // the file's set 1 is (2 u, 1 - v_file) where set 0 is (u, v_file); wgtrace reads
        // v as 1 - v_file, so its set 1 is (2 u, 1 - v) of its set 0's (u, v)
        let want_uv1 = [2.0 * u, 1.0 - v];
        assert!(
            (h.uv.z - want_uv1[0]).abs() < 1e-5 && (h.uv.w - want_uv1[1]).abs() < 1e-5,
            "{k}: {}",
            h.uv
        );
        // (0.5, 0.25) lies in the triangle of corners 0, 1, 2: barycentric weights
        let wgt = [0.25, 0.125, 0.625, 0.0];
        let want: [f32; 4] =
            std::array::from_fn(|ch| (0..4).map(|i| wgt[i] * colours[i][ch]).sum());
        let tol = if k == 1 { 3e-3 } else { 1e-4 };
        // a VEC3 colour has alpha 1
        let alpha = if k == 1 { want[3] } else { 1.0 };
        for (ch, want) in [want[0], want[1], want[2], alpha].into_iter().enumerate() {
            assert!(
                (h.color[ch] - want).abs() < tol,
                "{k}: {} vs {want}",
                h.color
            );
        }
    }
    // the GPU's hits, ray by ray
    let ctx = common::gpu_context();
    let mut rng = 5u32;
    let rays: Vec<Ray> = (0..512)
        .map(|_| {
            let o = Vec3::new(
                common::random_f32(&mut rng) * 2.4 - 1.2,
                common::random_f32(&mut rng) * 2.4 - 1.2,
                1.0,
            );
            Ray {
                origin: o,
                dir: Vec3::new(0.05, -0.03, -1.0).normalize(),
            }
        })
        .collect();
    let kernel: Vec<_> = rays.iter().map(common::to_kernel).collect();
    let gpu = wgtrace::gpu::kernel::intersect_rays(&ctx, &s, &Default::default(), &kernel).unwrap();
    let mut hits = 0;
    for (r, g) in rays.iter().zip(&gpu) {
        let c = intersect_scene(&b, r, FAR);
        assert_eq!(g.prim, c.prim);
        if c.prim == records::NO_HIT {
            continue;
        }
        hits += 1;
        let h = surface_at(&b, r, &c);
        for k in 0..2 {
            assert!(
                (g.uv1[k] - h.uv[2 + k]).abs() < 1e-5,
                "{r:?}: {:?} vs {}",
                g.uv1,
                h.uv
            );
        }
        for k in 0..4 {
            assert!(
                (g.color[k] - h.color[k]).abs() < 1e-5,
                "{r:?}: {:?} vs {}",
                g.color,
                h.color
            );
        }
    }
    assert!(hits > 200, "{hits} hits");
}

/// A file without punctual lights is lit by the studio environment, in the light list,
/// whether or not it has emissive parts (they add to it); one with a punctual light is not.
/// The environment's own claims hold: a white diffuse surface facing up sees radiance 1.0,
/// facing sideways 0.58, facing down 0.3 (its image integrated here).
#[test]
fn a_file_without_punctual_lights_gets_the_studio_environment() {
    let lamp = w_emissive();
    let s = load(&lamp.to_gltf_external(&dir("lamp"), "lamp").unwrap());
    let env = s.env.expect("the studio environment");
    assert_ne!(env.light, records::NO_LIGHT);
    assert!(
        s.emitters.len() >= 3,
        "the lamp's two triangles and the environment"
    );
    let lit = quad_file(pbr([0.5; 4], 0.0, 1.0));
    let s = load(&lit.to_gltf_external(&dir("lit"), "lit").unwrap());
    assert!(s.env.is_none() && s.num_punctual == 1);
    assert!(!s.warnings.iter().any(|w| w.contains("studio")));
    // the image's irradiance / pi toward up, sideways and down
    let img = wgtrace::scene::textures::studio_environment();
    let (w, h) = (img.width as usize, img.height as usize);
    for (n, want) in [(Vec3::Y, 1.0), (Vec3::X, 0.5775), (Vec3::NEG_Y, 0.3)] {
        let mut e = 0.0f64;
        for y in 0..h {
            let theta = std::f64::consts::PI * (y as f64 + 0.5) / h as f64;
            for x in 0..w {
                let phi = std::f64::consts::TAU * (x as f64 + 0.5) / w as f64;
                let d = Vec3::new(
                    (theta.sin() * phi.cos()) as f32,
                    theta.cos() as f32,
                    (theta.sin() * phi.sin()) as f32,
                );
                let cos = d.dot(n).max(0.0) as f64;
                let dw = theta.sin()
                    * (std::f64::consts::PI / h as f64)
                    * (std::f64::consts::TAU / w as f64);
                e += img.at(x as u32, y as u32)[0] as f64 * cos * dw;
            }
        }
        let radiance = e / std::f64::consts::PI;
        assert!(
            (radiance - want).abs() < 5e-3,
            "{n}: {radiance}, not {want}"
        );
    }
}

/// A quad of emissiveFactor 1 and nothing else: no punctual light.
fn w_emissive() -> GltfWriter {
    let mut w = GltfWriter::new();
    let m = w.material(json!({ "emissiveFactor": [1.0, 1.0, 1.0] }));
    let mesh = quad_mesh(&mut w, Some(m));
    let n = w.node(json!({ "mesh": mesh }));
    w.scene(&[n]);
    w
}

/// A mesh written with KHR_mesh_quantization (positions as non-normalized i16 on a grid,
/// scaled back by its node; normals as normalized i8; uvs as normalized u16) loads to the
/// same records, bit for bit, as its float twin holding the dequantized values.
#[test]
fn a_quantized_mesh_loads_as_its_float_twin() {
    let sphere = gltf_writer::uv_sphere([0.0; 3], 0.5, 12, 24);
    // the quantized values, and the floats they stand for
    let qp: Vec<[i16; 3]> = sphere
        .positions
        .iter()
        .map(|p| p.map(|x| (x * 1024.0).round() as i16))
        .collect();
    let qn: Vec<[i8; 3]> = sphere
        .normals
        .iter()
        .map(|n| n.map(|x| (x * 127.0).round() as i8))
        .collect();
    let qt: Vec<[u16; 2]> = sphere
        .uvs
        .iter()
        .map(|t| t.map(|x| (x * 65535.0).round() as u16))
        .collect();
    let fp: Vec<[f32; 3]> = qp.iter().map(|p| p.map(|x| x as f32 / 1024.0)).collect();
    let fnrm: Vec<[f32; 3]> = qn
        .iter()
        .map(|n| n.map(|x| (x as f32 / 127.0).max(-1.0)))
        .collect();
    let ft: Vec<[f32; 2]> = qt.iter().map(|t| t.map(|x| x as f32 / 65535.0)).collect();
    let material = |w: &mut GltfWriter| w.material(pbr([0.5; 4], 0.0, 0.5));
    // the float twin
    let mut plain = GltfWriter::new();
    let m = material(&mut plain);
    let attrs = [
        ("POSITION", plain.positions(&fp)),
        ("NORMAL", plain.vec3(&fnrm)),
        ("TEXCOORD_0", plain.vec2(&ft)),
    ];
    let idx = plain.indices_u32(&sphere.indices);
    let mesh = plain.mesh(vec![GltfWriter::primitive(&attrs, Some(idx), Some(m))]);
    let n = plain.node(json!({ "mesh": mesh }));
    plain.scene(&[n]);
    // the quantized file: attributes 4-byte aligned (i16 VEC3 in 8 bytes, i8 VEC3 in 4)
    let mut q = GltfWriter::new();
    let m = material(&mut q);
    let packed = |elems: Vec<Vec<u8>>, stride: usize| -> Vec<u8> {
        elems
            .into_iter()
            .flat_map(|mut e| {
                e.resize(stride, 0);
                e
            })
            .collect()
    };
    let pos_bytes = packed(
        qp.iter()
            .map(|p| p.iter().flat_map(|x| x.to_le_bytes()).collect())
            .collect(),
        8,
    );
    let nrm_bytes = packed(
        qn.iter()
            .map(|n| n.iter().map(|&x| x as u8).collect())
            .collect(),
        4,
    );
    let uv_bytes = packed(
        qt.iter()
            .map(|t| t.iter().flat_map(|x| x.to_le_bytes()).collect())
            .collect(),
        4,
    );
    let (pv, nv, tv) = (
        q.view(&pos_bytes, Some(8)),
        q.view(&nrm_bytes, Some(4)),
        q.view(&uv_bytes, Some(4)),
    );
    let count = qp.len();
    let lo: Vec<f32> = (0..3)
        .map(|k| qp.iter().map(|p| p[k]).min().unwrap() as f32)
        .collect();
    let hi: Vec<f32> = (0..3)
        .map(|k| qp.iter().map(|p| p[k]).max().unwrap() as f32)
        .collect();
    let pa = q.accessor(pv, 0, 5122, count, "VEC3", Some((lo, hi)));
    let na = q.accessor(nv, 0, 5120, count, "VEC3", None);
    q.json["accessors"][na]["normalized"] = json!(true);
    let ta = q.accessor(tv, 0, 5123, count, "VEC2", None);
    q.json["accessors"][ta]["normalized"] = json!(true);
    let idx = q.indices_u32(&sphere.indices);
    let attrs = [("POSITION", pa), ("NORMAL", na), ("TEXCOORD_0", ta)];
    let mesh = q.mesh(vec![GltfWriter::primitive(&attrs, Some(idx), Some(m))]);
    let s = 1.0 / 1024.0;
    let n = q.node(json!({ "mesh": mesh, "scale": [s, s, s] }));
    q.scene(&[n]);
    q.use_extension("KHR_mesh_quantization", true);
    let a = load(&plain.to_gltf_external(&dir("float-twin"), "twin").unwrap());
    let b = load(&q.to_gltf_external(&dir("quantized"), "quantized").unwrap());
    assert_eq!(a.primitives, b.primitives);
    assert_eq!(a.shape_data, b.shape_data);
    assert_eq!(a.bvh, b.bvh);
    // a normal that is not normalized is refused by its JSON path
    q.json["accessors"][na]["normalized"] = json!(false);
    let e = load_err(&q.to_gltf_external(&dir("quantized-bad"), "bad").unwrap());
    assert!(
        e.contains("attributes.NORMAL") && e.contains("not normalized"),
        "{e}"
    );
}

/// A mesh whose buffer views are EXT_meshopt_compression's encoding (vertex streams and a
/// triangle index buffer, in a fallback buffer without data) loads to the same records as
/// its plain twin; a view that does not decode is refused by its JSON path.
#[test]
fn a_meshopt_compressed_mesh_loads_as_its_plain_twin() {
    let sphere = gltf_writer::uv_sphere([0.0; 3], 0.5, 12, 24);
    let mut plain = GltfWriter::new();
    let m = plain.material(pbr([0.5; 4], 0.0, 0.5));
    let mesh = plain.add_mesh_arrays(&sphere, Some(m), true);
    let n = plain.node(json!({ "mesh": mesh }));
    plain.scene(&[n]);
    let a = load(
        &plain
            .to_gltf_external(&dir("meshopt-twin"), "twin")
            .unwrap(),
    );
    // the compressed file: buffer 0 holds the encoded streams, buffer 1 is the fallback
    // the views decode into
    let mut c = GltfWriter::new();
    let m = c.material(pbr([0.5; 4], 0.0, 0.5));
    let mut fallback_len = 0usize;
    let mut compressed_view = |c: &mut GltfWriter,
                               encoded: Vec<u8>,
                               stride: usize,
                               count: usize,
                               mode: &str| {
        // the encoded bytes in buffer 0 (through a view of their own, which nothing reads)
        let raw = c.view(&encoded, None);
        let at = c.json["bufferViews"][raw]["byteOffset"].clone();
        let mut view = json!({ "buffer": 1, "byteOffset": fallback_len, "byteLength": stride * count,
            "extensions": { "EXT_meshopt_compression": { "buffer": 0, "byteOffset": at,
                "byteLength": encoded.len(), "byteStride": stride, "count": count, "mode": mode } } });
        if mode == "ATTRIBUTES" {
            view["byteStride"] = json!(stride);
        }
        fallback_len += (stride * count).next_multiple_of(4);
        c.push("bufferViews", view)
    };
    let pos = meshopt::encoding::encode_vertex_buffer(&sphere.positions).unwrap();
    let nrm = meshopt::encoding::encode_vertex_buffer(&sphere.normals).unwrap();
    let uvs = meshopt::encoding::encode_vertex_buffer(&sphere.uvs).unwrap();
    let idx =
        meshopt::encoding::encode_index_buffer(&sphere.indices, sphere.positions.len()).unwrap();
    let count = sphere.positions.len();
    let pv = compressed_view(&mut c, pos, 12, count, "ATTRIBUTES");
    let nv = compressed_view(&mut c, nrm, 12, count, "ATTRIBUTES");
    let tv = compressed_view(&mut c, uvs, 8, count, "ATTRIBUTES");
    let iv = compressed_view(&mut c, idx, 4, sphere.indices.len(), "TRIANGLES");
    let lo: Vec<f32> = (0..3)
        .map(|k| {
            sphere
                .positions
                .iter()
                .map(|p| p[k])
                .fold(f32::MAX, f32::min)
        })
        .collect();
    let hi: Vec<f32> = (0..3)
        .map(|k| {
            sphere
                .positions
                .iter()
                .map(|p| p[k])
                .fold(f32::MIN, f32::max)
        })
        .collect();
    let pa = c.accessor(pv, 0, 5126, count, "VEC3", Some((lo, hi)));
    let na = c.accessor(nv, 0, 5126, count, "VEC3", None);
    let ta = c.accessor(tv, 0, 5126, count, "VEC2", None);
    let ia = c.accessor(iv, 0, 5125, sphere.indices.len(), "SCALAR", None);
    let attrs = [("POSITION", pa), ("NORMAL", na), ("TEXCOORD_0", ta)];
    let mesh = c.mesh(vec![GltfWriter::primitive(&attrs, Some(ia), Some(m))]);
    let n = c.node(json!({ "mesh": mesh }));
    c.scene(&[n]);
    c.use_extension("EXT_meshopt_compression", true);
    let d = dir("meshopt");
    let path = c.to_gltf_external(&d, "compressed").unwrap();
    // the second buffer: the fallback, without data
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    json["buffers"]
        .as_array_mut()
        .unwrap()
        .push(json!({ "byteLength": fallback_len,
        "extensions": { "EXT_meshopt_compression": { "fallback": true } } }));
    std::fs::write(&path, serde_json::to_string(&json).unwrap()).unwrap();
    let b = load(&path);
    assert_eq!(a.primitives, b.primitives);
    assert_eq!(a.shape_data, b.shape_data);
    // bytes that do not decode: the view's JSON path
    let at = json["bufferViews"][pv]["extensions"]["EXT_meshopt_compression"]["byteLength"]
        .as_u64()
        .unwrap();
    json["bufferViews"][pv]["extensions"]["EXT_meshopt_compression"]["byteLength"] = json!(at / 2);
    std::fs::write(&path, serde_json::to_string(&json).unwrap()).unwrap();
    let e = load_err(&path);
    assert!(
        e.contains(&format!(
            "bufferViews[{pv}].extensions.EXT_meshopt_compression"
        )) && e.contains("does not decode"),
        "{e}"
    );
}

/// KHR_materials_pbrSpecularGlossiness maps onto pbr so that a spec-gloss file and its
/// metal-rough twin look alike, tile by tile within the statistical bound, on the GPU: a
/// textured dielectric (diffuse texture; specular 0.04 with glossiness in the texture's
/// alpha, its twin's roughness map holding 1 - alpha) and an untextured metal (black
/// diffuse, coloured specular; the twin metallic 1 with that base colour).
#[test]
fn specular_glossiness_files_look_like_their_metal_rough_twins() {
    let diffuse = image::RgbaImage::from_fn(8, 8, |x, y| {
        image::Rgba([40 + 25 * x as u8, 200 - 20 * y as u8, 90, 255])
    });
    let gloss = |x: u32, y: u32| (20 + 28 * ((x + y) % 8)) as u8;
    let spec_gloss =
        image::RgbaImage::from_fn(8, 8, |x, y| image::Rgba([255, 255, 255, gloss(x, y)]));
    let rough = image::RgbaImage::from_fn(8, 8, |x, y| image::Rgba([0, 255 - gloss(x, y), 0, 255]));
    let build = |materials: [serde_json::Value; 2], textures: &[&image::RgbaImage], ext: bool| {
        let mut w = GltfWriter::new();
        for t in textures {
            w.png_texture(t, None).unwrap();
        }
        let ms: Vec<usize> = materials.into_iter().map(|m| w.material(m)).collect();
        let mut nodes = Vec::new();
        for (k, m) in ms.into_iter().enumerate() {
            let sphere = gltf_writer::uv_sphere([1.1 * k as f32 - 0.55, 0.0, 0.0], 0.5, 24, 48);
            let mesh = w.add_mesh_arrays(&sphere, Some(m), true);
            nodes.push(w.node(json!({ "mesh": mesh })));
        }
        let c = w
            .camera(json!({ "type": "perspective", "perspective": { "yfov": 0.6, "znear": 0.1 } }));
        nodes.push(w.node(json!({ "camera": c, "translation": [0.0, 0.3, 3.0] })));
        let l = w.light(json!({ "type": "point", "intensity": 8.0 }));
        let mut ln = json!({ "translation": [1.0, 2.0, 2.0] });
        ln.as_object_mut()
            .unwrap()
            .extend(light_ref(l).as_object().unwrap().clone());
        nodes.push(w.node(ln));
        w.scene(&nodes);
        if ext {
            w.use_extension("KHR_materials_pbrSpecularGlossiness", true);
        }
        w
    };
    let sg = "KHR_materials_pbrSpecularGlossiness";
    let spec = build(
        [
            json!({ "extensions": { sg: { "diffuseTexture": { "index": 0 },
                "specularFactor": [0.04, 0.04, 0.04], "glossinessFactor": 1.0,
                "specularGlossinessTexture": { "index": 1 } } } }),
            json!({ "extensions": { sg: { "diffuseFactor": [0.0, 0.0, 0.0, 1.0],
                "specularFactor": [0.9, 0.6, 0.3], "glossinessFactor": 0.7 } } }),
        ],
        &[&diffuse, &spec_gloss],
        true,
    );
    let twin = build(
        [
            json!({ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 },
                "metallicRoughnessTexture": { "index": 1 } } }),
            json!({ "pbrMetallicRoughness": { "baseColorFactor": [0.9, 0.6, 0.3, 1.0],
                "metallicFactor": 1.0, "roughnessFactor": 0.3 } }),
        ],
        &[&diffuse, &rough],
        false,
    );
    let o = Overrides {
        width: Some(48),
        height: Some(24),
        spp: Some(256),
        ..Default::default()
    };
    let a = wgtrace::load_scene(
        &spec.to_gltf_external(&dir("spec-gloss"), "sg").unwrap(),
        &o,
    )
    .unwrap();
    let b = wgtrace::load_scene(
        &twin.to_gltf_external(&dir("metal-rough"), "mr").unwrap(),
        &o,
    )
    .unwrap();
    let (ia, ib) = (common::render_gpu(&a), common::render_gpu(&b));
    let c = common::compare(&ia, &ib, 8);
    assert!(c.failed_tiles.is_empty(), "{}", c.failed_tiles.join("\n"));
    // the metal's Fresnel at normal incidence is its specular colour in both
    let metal = pbr::Params::read(&a.materials[1]);
    let f0 = metal.specular_color * 0.04;
    assert!(
        (f0 - Vec3::new(0.9, 0.6, 0.3)).abs().max_element() < 1e-6,
        "{f0}"
    );
}

/// glTF's triangle strips and fans become the triangles the specification numbers, all
/// wound alike; a strip's restart (a repeated vertex) adds none; a list comes in threes.
#[test]
fn strips_and_fans_become_triangles_wound_alike() {
    use gltf::mesh::Mode;
    use wgtrace::scene::gltf::meshes::triangles;
    assert_eq!(
        triangles(Mode::TriangleStrip, &[0, 1, 2, 3]).unwrap(),
        vec![[0, 1, 2], [1, 3, 2]]
    );
    assert_eq!(
        triangles(Mode::TriangleFan, &[0, 1, 2, 3]).unwrap(),
        vec![[1, 2, 0], [2, 3, 0]]
    );
    // two strips joined by a restart: 0 1 2, then 3 4 5 after 2 2 3 3
    assert_eq!(
        triangles(Mode::TriangleStrip, &[0, 1, 2, 2, 3, 3, 4, 5]).unwrap(),
        vec![[0, 1, 2], [3, 5, 4]]
    );
    assert!(triangles(Mode::Triangles, &[0, 1, 2, 3])
        .unwrap_err()
        .contains("not a multiple of 3"));
    assert!(triangles(Mode::TriangleFan, &[0, 1]).unwrap().is_empty());
}

/// A grid of rough transmissive spheres over roughness and ior, ior 1 among them, under
/// the studio environment (as glTF's public transmission-roughness test model has them)
/// renders no non-finite sample on either backend: an index-matched boundary is smooth
/// whatever its roughness (its record says so), where rough glass's generalized half
/// vector was the zero vector and its weight NaN.
#[test]
fn rough_transmission_at_every_ior_renders_finite_samples() {
    let mut w = GltfWriter::new();
    w.use_extension("KHR_materials_transmission", true);
    w.use_extension("KHR_materials_ior", true);
    let sphere = gltf_writer::uv_sphere([0.0; 3], 0.45, 16, 32);
    let mut nodes = Vec::new();
    for (row, ior) in [1.0f32, 1.05, 1.5].into_iter().enumerate() {
        for (col, roughness) in [0.3f32, 0.6, 1.0].into_iter().enumerate() {
            let m = w.material(json!({
                "pbrMetallicRoughness": { "roughnessFactor": roughness },
                "extensions": {
                    "KHR_materials_transmission": { "transmissionFactor": 1.0 },
                    "KHR_materials_ior": { "ior": ior } } }));
            let mesh = w.add_mesh_arrays(&sphere, Some(m), true);
            let t = [col as f32 - 1.0, row as f32 - 1.0, 0.0];
            nodes.push(w.node(json!({ "mesh": mesh, "translation": t })));
        }
    }
    let c =
        w.camera(json!({ "type": "perspective", "perspective": { "yfov": 0.9, "znear": 0.1 } }));
    nodes.push(w.node(json!({ "camera": c, "translation": [0.0, 0.0, 3.5] })));
    w.scene(&nodes);
    let path = dir("rough-transmission").join("grid.glb");
    w.to_glb(&path).unwrap();
    let o = Overrides {
        width: Some(64),
        height: Some(64),
        spp: Some(16),
        ..Default::default()
    };
    let scene = wgtrace::load_scene(&path, &o).unwrap_or_else(|e| panic!("{e}"));
    for m in &scene.materials[..3] {
        assert_eq!(dielectric::Params::read(m).alpha, 0.0, "ior 1 is smooth");
    }
    for (name, sums) in [
        ("gpu", common::render_gpu(&scene)),
        ("cpu", common::render_cpu(&scene)),
    ] {
        assert_eq!(sums.non_finite(), 0, "{name}: non-finite samples");
    }
}
