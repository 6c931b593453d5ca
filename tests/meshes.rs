//! Mesh files: PLY in ASCII and both binary byte orders loads into the same records as
//! the same mesh in OBJ (positions, normals, uvs, polygons as fans); broken PLY files are
//! refused with an error naming the scene's line and key and the mesh file, never a panic,
//! and counts beyond what a scene may hold are refused from the header.
//! Every file is written here. No GPU needed.

mod common;

use std::path::{Path, PathBuf};

use proptest::prelude::*;
use wgtrace::scene::materials::common::Surface;
use wgtrace::scene::materials::{dielectric, pbr, MaterialKind};
use wgtrace::{FlatScene, Overrides};

const HEAD: &str = "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[materials]\n\
                    m = { type = \"lambertian\", albedo = [0.5, 0.5, 0.5] }\n";

/// A quad and a triangle: (position, normal, uv) per vertex.
const VERTICES: [[f32; 8]; 5] = [
    [0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
    [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0],
    [1.0, 1.0, 0.0, 0.0, 0.6, 0.8, 1.0, 1.0],
    [0.0, 1.0, 0.0, 0.0, 0.6, 0.8, 0.0, 1.0],
    [0.5, 2.0, 0.5, 0.0, 0.8, 0.6, 0.5, 0.25],
];

fn faces() -> Vec<Vec<u32>> {
    vec![vec![0, 1, 2, 3], vec![3, 2, 4]]
}

/// The mesh as PLY: `format` is `ascii`, `binary_little_endian` or `binary_big_endian`;
/// `uv` names the texture coordinates (`s`/`t`, `u`/`v`, ...). The file also has a
/// comment, an `edge` element after the faces and double-precision normals.
fn ply(format: &str, uv: [&str; 2], vertices: &[[f32; 8]], faces: &[Vec<u32>]) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat {format} 1.0\ncomment written by tests/meshes.rs\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n\
         property double nx\nproperty double ny\nproperty double nz\n\
         property float {}\nproperty float {}\nelement face {}\n\
         property list uchar int vertex_indices\nelement edge 1\n\
         property int vertex1\nproperty int vertex2\nend_header\n",
        vertices.len(),
        uv[0],
        uv[1],
        faces.len()
    )
    .into_bytes();
    let big = format == "binary_big_endian";
    let f32b = |x: f32| {
        if big {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        }
    };
    let f64b = |x: f64| {
        if big {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        }
    };
    let i32b = |x: i32| {
        if big {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        }
    };
    for v in vertices {
        if format == "ascii" {
            let words: Vec<String> = v.iter().map(|x| x.to_string()).collect();
            out.extend(format!("{}\n", words.join(" ")).bytes());
        } else {
            for (k, &x) in v.iter().enumerate() {
                if (3..6).contains(&k) {
                    out.extend(f64b(x as f64));
                } else {
                    out.extend(f32b(x));
                }
            }
        }
    }
    for f in faces {
        if format == "ascii" {
            let words: Vec<String> = f.iter().map(|i| i.to_string()).collect();
            out.extend(format!("{} {}\n", f.len(), words.join(" ")).bytes());
        } else {
            out.push(f.len() as u8);
            for &i in f {
                out.extend(i32b(i as i32));
            }
        }
    }
    if format == "ascii" {
        out.extend(b"0 1\n");
    } else {
        out.extend(i32b(0));
        out.extend(i32b(1));
    }
    out
}

/// The same mesh as OBJ.
fn obj() -> String {
    let mut s = String::new();
    for v in VERTICES {
        s += &format!(
            "v {} {} {}\nvn {} {} {}\nvt {} {}\n",
            v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]
        );
    }
    for f in faces() {
        let corners: Vec<String> = f.iter().map(|i| format!("{0}/{0}/{0}", i + 1)).collect();
        s += &format!("f {}\n", corners.join(" "));
    }
    s
}

/// A fresh folder for one test.
fn dir(test: &str) -> PathBuf {
    common::tmp_dir(&format!("meshes-{test}"))
}

fn load(dir: &Path, file: &str) -> Result<FlatScene, String> {
    let src = format!("{HEAD}[[objects]]\ntype = \"mesh\"\npath = \"{file}\"\nmaterial = \"m\"\n");
    wgtrace::load_scene_str(&src, &dir.join("scene.toml"), &Overrides::default())
        .map_err(|e| e.to_string())
}

#[test]
fn ply_in_ascii_and_binary_loads_the_records_of_the_same_obj() {
    let dir = dir("same");
    std::fs::write(dir.join("m.obj"), obj()).unwrap();
    let reference = load(&dir, "m.obj").unwrap();
    // a quad and a triangle: three triangles, with vertex normals and uvs
    assert_eq!(reference.primitives.len(), 3);
    assert!(!reference.shape_data.is_empty());
    let variants = [
        ("ascii", ["s", "t"]),
        ("binary_little_endian", ["u", "v"]),
        ("binary_big_endian", ["texture_u", "texture_v"]),
    ];
    for (format, uv) in variants {
        let name = format!("m-{format}.PLY");
        std::fs::write(dir.join(&name), ply(format, uv, &VERTICES, &faces())).unwrap();
        let s = load(&dir, &name).unwrap_or_else(|e| panic!("{format}: {e}"));
        assert_eq!(s.primitives, reference.primitives, "{format}");
        assert_eq!(s.shape_data, reference.shape_data, "{format}");
    }
    // without normals and uvs: flat triangles, no attributes
    let bare = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                property float z\nelement face 1\nproperty list uchar uint vertex_index\n\
                end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    std::fs::write(dir.join("bare.ply"), bare).unwrap();
    let s = load(&dir, "bare.ply").unwrap();
    assert_eq!(s.primitives.len(), 1);
    assert!(s.shape_data.is_empty(), "no attributes to keep");
}

#[test]
fn broken_ply_files_are_refused_with_the_file_and_the_reason() {
    let dir = dir("broken");
    let good = ply("binary_little_endian", ["s", "t"], &VERTICES, &faces());
    let header_end = good.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let mut nan = VERTICES;
    nan[2][1] = f32::NAN;
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "truncated.ply",
            good[..good.len() - 9].to_vec(),
            "is not a PLY file",
        ),
        (
            "header-only.ply",
            good[..header_end].to_vec(),
            "is not a PLY file",
        ),
        (
            "index.ply",
            ply("ascii", ["s", "t"], &VERTICES, &[vec![0, 1, 7]]),
            "face 0 has vertex index 7, outside its 5 vertices",
        ),
        (
            "nan.ply",
            ply("binary_big_endian", ["s", "t"], &nan, &faces()),
            "has a non-finite coordinate",
        ),
        (
            "huge.ply",
            String::from_utf8_lossy(&good[..header_end])
                .replace("element vertex 5", "element vertex 4000000000")
                .into_bytes(),
            "declares 4000000000 vertices and 2 faces, more than the 16777216 triangles",
        ),
        (
            "list-x.ply",
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty list uchar float x\n\
              property float y\nproperty float z\nelement face 0\n\
              property list uchar int vertex_indices\nend_header\n1 0 0 0\n"
                .to_vec(),
            "has a vertex property x that is a list",
        ),
        (
            "no-faces.ply",
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
              property float z\nend_header\n0 0 0\n"
                .to_vec(),
            "has no face element",
        ),
        (
            "no-z.ply",
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
              element face 0\nproperty list uchar int vertex_indices\nend_header\n0 0\n"
                .to_vec(),
            "has no vertex element with properties x, y, z",
        ),
        (
            "text.ply",
            b"solid cube\nfacet normal 0 0 1\n".to_vec(),
            "is not a PLY file",
        ),
    ];
    for (name, bytes, reason) in cases {
        std::fs::write(dir.join(name), bytes).unwrap();
        let e = match load(&dir, name) {
            Ok(s) => panic!("{name} loaded: {} primitives", s.primitives.len()),
            Err(e) => e,
        };
        assert!(
            e.contains("scene.toml:")
                && e.contains("objects[0].path")
                && e.contains(name)
                && e.contains(reason),
            "{name}: {e}"
        );
    }
    let e = load(&dir, "missing.ply").unwrap_err();
    assert!(
        e.contains("objects[0].path") && e.contains("missing.ply"),
        "{e}"
    );
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    /// A PLY file with bytes cut, overwritten or inserted anywhere loads or is refused,
    /// never a panic.
    #[test]
    fn mutated_ply_files_are_loaded_or_refused(
        format in 0usize..3,
        edits in proptest::collection::vec((any::<proptest::sample::Index>(), any::<u8>(), 0u8..3), 1..6),
    ) {
        let format = ["ascii", "binary_little_endian", "binary_big_endian"][format];
        let mut bytes = ply(format, ["s", "t"], &VERTICES, &faces());
        for (at, byte, kind) in edits {
            let i = at.index(bytes.len());
            match kind {
                0 => bytes[i] = byte,
                1 => bytes.insert(i, byte),
                _ => bytes.truncate(i),
            }
            if bytes.is_empty() {
                break;
            }
        }
        static DIR: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
        let dir = DIR.get_or_init(|| dir("fuzz"));
        let name = "fuzz.ply";
        std::fs::write(dir.join(name), &bytes).unwrap();
        if let Err(e) = load(dir, name) {
            prop_assert!(e.contains("objects[0].path") && e.contains(name), "{}", e);
        }
    }
}

/// An OBJ file's .mtl materials apply when the object names none: Kd (times map_Kd), Ks,
/// Ns, Ni, d and Ke onto `pbr`, illum 7 onto `dielectric`, map_Bump onto a normal map
/// with MikkTSpace tangents; a `material` of the scene replaces them; a PLY file or an OBJ
/// without a .mtl then needs one.
#[test]
fn obj_materials_come_from_the_mtl_unless_the_scene_names_one() {
    use wgtrace::scene::records;
    let dir = common::tmp_dir("mtl");
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
               vn 0 0 1\no a\nusemtl paint\nf 1/1/1 2/2/1 3/3/1\no b\nusemtl glass\nf 1/1/1 3/3/1 4/4/1\n";
    std::fs::write(dir.join("m.obj"), obj).unwrap();
    let mtl = "newmtl paint\nKd 0.5 0.25 1\nKs 0.5 0.5 0.5\nNs 98\nNi 1.6\nd 0.75\nKe 2 0 0\n\
               map_Kd tex.png\nmap_Bump -bm 0.5 normal.png\n\
               newmtl glass\nillum 7\nNi 1.33\nKd 0 0 0\n";
    std::fs::write(dir.join("m.mtl"), mtl).unwrap();
    image::RgbImage::from_pixel(2, 2, image::Rgb([255, 255, 255]))
        .save(dir.join("tex.png"))
        .unwrap();
    image::RgbImage::from_pixel(2, 2, image::Rgb([128, 128, 255]))
        .save(dir.join("normal.png"))
        .unwrap();
    let scene =
        |object: &str| format!("{HEAD}[[objects]]\ntype = \"mesh\"\npath = \"m.obj\"\n{object}");
    let s = wgtrace::load_scene_str(&scene(""), &dir.join("s.toml"), &Overrides::default())
        .unwrap_or_else(|e| panic!("{e}"));
    // the scene's material m, then the .mtl's paint and glass
    assert_eq!(s.materials.len(), 3, "{:?}", s.material_names);
    let (paint, glass) = (s.materials[1], s.materials[2]);
    assert_eq!(paint.tag, MaterialKind::Pbr.tag());
    let (p, surface) = (pbr::Params::read(&paint), Surface::read(&paint));
    let roughness = (2.0f32 / 100.0).powf(0.25);
    assert_eq!(
        (p.alpha, p.ior, p.metallic, p.specular),
        (roughness * roughness, 1.6, 0.0, 1.0)
    );
    assert_eq!(p.specular_color, glam::Vec3::splat(0.5));
    assert_eq!(surface.normal_scale, 0.5, "-bm scales the normal map");
    assert_eq!(surface.emission, glam::Vec3::new(2.0, 0.0, 0.0));
    assert_eq!(surface.opacity, 0.75);
    assert_ne!(paint.flags & records::MAT_FLAG_ALPHA_BLEND, 0);
    assert_ne!(surface.normal_texture, records::NO_TEXTURE);
    // map_Kd times Kd: the texture's factor
    let base = s.textures[p.base_color_texture as usize];
    assert_eq!(&base.color0[..3], &[0.5, 0.25, 1.0]);
    assert_eq!(glass.tag, MaterialKind::Dielectric.tag());
    assert_eq!(dielectric::Params::read(&glass).ior, 1.33);
    // the normal-mapped triangle has tangents, +x along u
    let mapped = s.primitives.iter().find(|p| p.material == 1).unwrap();
    assert_ne!(mapped.flags & records::PRIM_FLAG_TANGENTS, 0);
    assert_eq!(s.shape_data[mapped.data as usize + 4], [1.0, 0.0, 0.0, 1.0]);
    // the scene's material instead
    let s = wgtrace::load_scene_str(
        &scene("material = \"m\"\n"),
        &dir.join("s.toml"),
        &Overrides::default(),
    )
    .unwrap();
    assert_eq!(s.materials.len(), 1);
    assert!(s.primitives.iter().all(|p| p.material == 0));
    // without a .mtl, or a PLY file, a material is needed
    std::fs::write(dir.join("bare.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let e = wgtrace::load_scene_str(
        &scene("").replace("m.obj", "bare.obj"),
        &dir.join("s.toml"),
        &Overrides::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("objects[0].path: ") && e.contains("has no materials"),
        "{e}"
    );
    std::fs::write(
        dir.join("p.ply"),
        ply("ascii", ["u", "v"], &VERTICES, &faces()),
    )
    .unwrap();
    let e = wgtrace::load_scene_str(
        &scene("").replace("m.obj", "p.ply"),
        &dir.join("s.toml"),
        &Overrides::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("a PLY file has no materials"), "{e}");
    // flip_tex_coords names PLY files only
    let e = wgtrace::load_scene_str(
        &scene("material = \"m\"\nflip_tex_coords = true\n"),
        &dir.join("s.toml"),
        &Overrides::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("objects[0].path: ") && e.contains("flip_tex_coords applies to PLY files"),
        "{e}"
    );
    // values out of range, named by their statement
    for (statement, why) in [
        ("Kd 0.5 inf 0.5", "Kd: must be finite"),
        ("Kd 0.5 -1 0.5\nmap_Kd tex.png", "Kd: must be >= 0"),
        ("Ks -1 0 0", "Ks: must be >= 0"),
        ("Ni 0.5", "Ni: must be >= 1, got 0.5"),
        ("illum 7\nNi 0.5", "Ni: must be >= 1, got 0.5"),
        ("illum 7\nTf 1 inf 1", "Tf: must be finite"),
        ("d 2", "d: must be in [0, 1], got 2"),
    ] {
        std::fs::write(dir.join("v.mtl"), format!("newmtl v\n{statement}\n")).unwrap();
        std::fs::write(
            dir.join("v.obj"),
            "mtllib v.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl v\nf 1 2 3\n",
        )
        .unwrap();
        let e = wgtrace::load_scene_str(
            &scene("").replace("m.obj", "v.obj"),
            &dir.join("s.toml"),
            &Overrides::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("material \"v\"") && e.contains(why),
            "{statement}: {e}"
        );
    }
    // a .mtl naming an image that is not there
    std::fs::remove_file(dir.join("tex.png")).unwrap();
    let e = wgtrace::load_scene_str(&scene(""), &dir.join("s.toml"), &Overrides::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("material \"paint\"") && e.contains("tex.png"),
        "{e}"
    );
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    /// An OBJ file and its .mtl with characters changed, inserted or cut load or are
    /// refused, never a panic.
    #[test]
    fn mutated_obj_and_mtl_files_are_loaded_or_refused(
        edits in proptest::collection::vec(
            (any::<bool>(), any::<proptest::sample::Index>(),
             proptest::sample::select(vec![b'0', b'9', b'-', b'.', b' ', b'\n', b'e', b'/', b'#']), 0u8..3),
            1..6),
    ) {
        let mut obj = b"mtllib f.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n\
                        usemtl a\nf 1/1/1 2/2/1 3/3/1\n".to_vec();
        let mut mtl = b"newmtl a\nKd 0.5 0.5 0.5\nKs 1 1 1\nNs 50\nNi 1.5\nd 0.5\nKe 1 0 0\nillum 2\n".to_vec();
        for (in_mtl, at, byte, kind) in edits {
            let text = if in_mtl { &mut mtl } else { &mut obj };
            let i = at.index(text.len());
            match kind {
                0 => text[i] = byte,
                1 => text.insert(i, byte),
                _ => text.truncate(i),
            }
            if text.is_empty() {
                text.push(b'\n');
            }
        }
        static DIR: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
        let dir = DIR.get_or_init(|| dir("fuzz-mtl"));
        std::fs::write(dir.join("f.obj"), &obj).unwrap();
        std::fs::write(dir.join("f.mtl"), &mtl).unwrap();
        let src = format!("{HEAD}[[objects]]\ntype = \"mesh\"\npath = \"f.obj\"\n");
        let _ = wgtrace::load_scene_str(&src, &dir.join("s.toml"), &Overrides::default());
    }
}

/// Vertex colours of OBJ (`v x y z r g b`) and PLY (`red`, `green`, `blue`, 8-bit here)
/// files are display colours, decoded from sRGB, that multiply the material's colour: a
/// white-lit Lambertian quad of one vertex colour shows albedo x colour exactly (every
/// cosine-weighted sample of a uniform sky weighs the albedo), on both backends. A PLY
/// file's `r`, `g`, `b` (Mitsuba's names) read alike, and with `color_space = "linear"`
/// are taken as they are, as Mitsuba takes them.
#[test]
fn obj_and_ply_vertex_colours_multiply_the_material_colour() {
    use wgtrace::scene::texels::srgb_to_linear;
    let dir = dir("colours");
    let quad = [[-1.0f32, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
    let obj: String = quad
        .iter()
        .map(|[x, y]| format!("v {x} {y} 0 0.5 0.25 1\n"))
        .collect::<String>()
        + "f 1 2 3 4\n";
    std::fs::write(dir.join("c.obj"), obj).unwrap();
    // a quad of one colour: its type, its property names and each vertex's values
    let ply = |ty: &str, [r, g, b]: [&str; 3], values: &str| {
        let mut text = format!(
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
             property float z\nproperty {ty} {r}\nproperty {ty} {g}\nproperty {ty} {b}\n\
             element face 1\nproperty list uchar int vertex_indices\nend_header\n"
        );
        for [x, y] in quad {
            text += &format!("{x} {y} 0 {values}\n");
        }
        text + "4 0 1 2 3\n"
    };
    let names = ["red", "green", "blue"];
    std::fs::write(dir.join("c.ply"), ply("uchar", names, "200 100 50")).unwrap();
    std::fs::write(
        dir.join("rgb.ply"),
        ply("float", ["r", "g", "b"], "0.7 0.4 0.1"),
    )
    .unwrap();
    let albedo = 0.8f32;
    let want = |c: [f32; 3]| c.map(|x| albedo * srgb_to_linear(x));
    for (file, keys, colour) in [
        ("c.obj", "", want([0.5, 0.25, 1.0])),
        (
            "c.ply",
            "",
            want([200.0 / 255.0, 100.0 / 255.0, 50.0 / 255.0]),
        ),
        ("rgb.ply", "", want([0.7, 0.4, 0.1])),
        (
            "rgb.ply",
            "color_space = \"linear\"\n",
            [0.7, 0.4, 0.1].map(|x| albedo * x),
        ),
    ] {
        let src = format!(
            "[render]\nwidth = 16\nheight = 16\nspp = 4\nmax_depth = 2\n\
             [camera]\nprojection = \"orthographic\"\nheight = 1.5\n\
             look_from = [0, 0, 3]\nlook_at = [0, 0, 0]\n[background]\ncolor = [1, 1, 1]\n\
             [materials]\nm = {{ type = \"lambertian\", albedo = [{albedo}, {albedo}, {albedo}] }}\n\
             [[objects]]\ntype = \"mesh\"\npath = \"{file}\"\nmaterial = \"m\"\n{keys}"
        );
        let s = wgtrace::load_scene_str(&src, &dir.join("s.toml"), &Overrides::default())
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(s
            .primitives
            .iter()
            .all(|p| p.flags & wgtrace::scene::records::PRIM_FLAG_COLORS != 0));
        for (backend, img) in [
            ("gpu", common::render_gpu(&s)),
            ("cpu", common::render_cpu(&s)),
        ] {
            for i in 0..img.pixel_count() {
                let got = img.mean(i);
                for k in 0..3 {
                    assert!(
                        (got[k] - colour[k]).abs() < 1e-5,
                        "{file} on the {backend}, pixel {i}: {got:?}, not {colour:?}"
                    );
                }
            }
        }
    }
}

/// A PLY file's face colours give each triangle corners of its own, after the vertex
/// normals are made over the shared corners: a folded quad of two coloured faces, without
/// normals, with `smooth_normals` (as the Mitsuba importer writes), has the same normal
/// at each end of the fold in both triangles, and each triangle one colour.
#[test]
fn face_colours_keep_smooth_normals_over_shared_corners() {
    use glam::{Vec3, Vec4};
    use wgtrace::scene::mesh::{adjust, load_mesh, Adjust, ColorChoice};
    let dir = dir("face-colours");
    let ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
               property float z\nelement face 2\nproperty float r\nproperty float g\n\
               property float b\nproperty list uchar int vertex_indices\nend_header\n\
               -1 0 0\n0 -1 0.5\n1 0 0\n0 1 0.5\n1 0 0 3 0 1 3\n0 0 1 3 1 2 3\n";
    std::fs::write(dir.join("fold.ply"), ply).unwrap();
    let mut m = load_mesh(&dir.join("fold.ply"), ColorChoice::default()).unwrap();
    adjust(
        &mut m,
        Adjust {
            smooth_normals: true,
            ..Default::default()
        },
    );
    assert_eq!(m.triangles.len(), 2);
    assert_eq!(m.positions.len(), 6, "each triangle's corners its own");
    let corner = |t: usize, p: Vec3| {
        let k = m.triangles[t]
            .into_iter()
            .find(|&i| m.positions[i as usize] == p)
            .unwrap() as usize;
        (m.normals[k], m.colors[k])
    };
    for p in [Vec3::new(0.0, -1.0, 0.5), Vec3::new(0.0, 1.0, 0.5)] {
        let ((n0, c0), (n1, c1)) = (corner(0, p), corner(1, p));
        assert!((n0 - n1).length() < 1e-6, "{p}: {n0} and {n1}");
        assert_eq!(
            (c0, c1),
            (Vec4::new(1.0, 0.0, 0.0, 1.0), Vec4::new(0.0, 0.0, 1.0, 1.0))
        );
    }
}

/// `flip_tex_coords` flips a file's uvs; a file without uvs gets its triangles' default
/// uvs, v down under `default_uvs_v_down`, as corners that follow the file's winding
/// through `flip_normals`; `winding_front` turns the front of a mesh left without the
/// file's normals, and only of such a mesh.
#[test]
fn mesh_uvs_and_fronts_as_adjust_is_asked() {
    use glam::{Vec2, Vec3};
    use wgtrace::scene::mesh::{adjust, Adjust, MeshData};
    let quad = |uvs: Vec<Vec2>, normals: Vec<Vec3>| MeshData {
        positions: vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        uvs,
        normals,
        ..Default::default()
    };
    let stored = vec![
        Vec2::new(0.0, 0.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(0.0, 1.0),
    ];
    let mut m = quad(stored.clone(), vec![]);
    adjust(
        &mut m,
        Adjust {
            flip_tex_coords: true,
            corner_uvs: true,
            ..Default::default()
        },
    );
    let flipped: Vec<Vec2> = stored
        .iter()
        .map(|uv| Vec2::new(uv.x, 1.0 - uv.y))
        .collect();
    assert_eq!(
        (m.uvs, m.positions.len()),
        (flipped, 4),
        "stored uvs flipped in place"
    );

    // each triangle's corner k (in the file's winding) keeps the default uv k, v down
    let want = [
        Vec2::new(0.0, 1.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(0.0, 0.0),
    ];
    for flip_normals in [false, true] {
        let file = quad(vec![], vec![]);
        let mut m = file.clone();
        let a = Adjust {
            default_uvs_v_down: true,
            corner_uvs: true,
            flip_normals,
            ..Default::default()
        };
        adjust(&mut m, a);
        assert_eq!(m.positions.len(), 6, "corners of their own");
        for (t, tri) in file.triangles.iter().enumerate() {
            for (k, &i) in tri.iter().enumerate() {
                let p = file.positions[i as usize];
                let at = m.triangles[t]
                    .into_iter()
                    .find(|&j| m.positions[j as usize] == p)
                    .unwrap();
                assert_eq!(
                    m.uvs[at as usize], want[k],
                    "flip_normals {flip_normals}: triangle {t} corner {k}"
                );
            }
        }
        let n = |m: &MeshData| {
            let p = m.triangles[0].map(|i| m.positions[i as usize]);
            (p[1] - p[0]).cross(p[2] - p[0]).z.signum()
        };
        assert_eq!(n(&m), if flip_normals { -1.0 } else { 1.0 });
    }
    // face colours survive the corners the default uvs take
    let mut m = quad(vec![], vec![]);
    m.face_colors = vec![glam::Vec4::X, glam::Vec4::Y];
    adjust(
        &mut m,
        Adjust {
            default_uvs_v_down: true,
            corner_uvs: true,
            ..Default::default()
        },
    );
    assert_eq!((m.uvs.len(), m.colors.len()), (6, 6));
    assert_eq!(m.colors[3..], [glam::Vec4::Y; 3]);
    // without a material that reads uvs, nothing is unwelded
    let mut m = quad(vec![], vec![]);
    adjust(
        &mut m,
        Adjust {
            default_uvs_v_down: true,
            ..Default::default()
        },
    );
    assert!(m.uvs.is_empty() && m.positions.len() == 4);

    // winding_front turns a mesh without normals, or with face_normals, not one with normals
    for (normals, face_normals, turned) in [
        (false, false, true),
        (true, true, true),
        (true, false, false),
    ] {
        let mut m = quad(vec![], if normals { vec![Vec3::Z; 4] } else { vec![] });
        adjust(
            &mut m,
            Adjust {
                winding_front: true,
                face_normals,
                ..Default::default()
            },
        );
        assert_eq!(
            m.triangles[0] != [0, 1, 2],
            turned,
            "normals {normals}, face_normals {face_normals}"
        );
    }
}
