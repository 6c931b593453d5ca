//! `gen_gltf`: writes procedurally generated glTF 2.0 assets into `scenes/gltf/` for the glTF
//! loader's tests and the gallery. No third-party asset is used: every mesh, texture and
//! material is computed here.
//!
//! # Usage
//!
//! ```text
//! cargo run --release --example gen_gltf [-- OUT_DIR]      (default scenes/gltf)
//! ```
//!
//! * `spheres.gltf` + `spheres.bin`: a 5 x 5 grid of UV spheres (radius 0.4, spacing 1, in the
//!   x-y plane, centred on the origin), one material each: gold-ish base colour, `metallic`
//!   = column / 4 (left to right), `roughness` = row / 4 (top to bottom). The 25 meshes share one
//!   set of accessors. A grey floor quad at y = -2.6, a camera "front" at (0, 0, 7.5) looking down
//!   -Z, a directional light along (1, -1, -1) and a point light at (-3, 3, 4)
//!   (KHR_lights_punctual).
//! * `brick.glb`: a unit sphere with a 256 x 256 brick base-colour texture, a matching
//!   tangent-space normal map (OpenGL / glTF convention: green = towards decreasing v) and a
//!   metallic-roughness texture, with analytic TANGENTs; on a floor quad, with a camera "front"
//!   and the same two kinds of light. Images live in buffer views.
//!
//! Each run checks the winding of every triangle and the files' framing, then prints one line
//! per file written.

#[path = "../tests/common/gltf_writer.rs"]
mod gltf_writer;

use std::path::{Path, PathBuf};

use glam::{Quat, Vec3};
use gltf_writer::{light_ref, quad, sampler, uv_sphere, GltfWriter, MeshArrays};
use serde_json::{json, Value};

type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

fn main() -> Result<()> {
    let dir = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "scenes/gltf".into()),
    );
    std::fs::create_dir_all(&dir)?;
    let spheres = spheres()?.to_gltf_external(&dir, "spheres")?;
    check_external(&spheres)?;
    report(&spheres)?;
    report(&dir.join("spheres.bin"))?;
    let glb = dir.join("brick.glb");
    brick()?.to_glb(&glb)?;
    check_glb(&std::fs::read(&glb)?)?;
    report(&glb)?;
    Ok(())
}

/// The rotation that turns -Z (a light's or camera's forward) into `dir`.
fn facing(dir: Vec3) -> [f32; 4] {
    Quat::from_rotation_arc(Vec3::NEG_Z, dir.normalize()).to_array()
}

fn pbr(name: &str, color: [f64; 4], metallic: f64, roughness: f64) -> Value {
    json!({ "name": name, "pbrMetallicRoughness": {
        "baseColorFactor": color, "metallicFactor": metallic, "roughnessFactor": roughness } })
}

/// The floor quad, camera "front" and the two lights every asset has; returns their nodes.
fn stage(w: &mut GltfWriter, floor: MeshArrays, eye: Vec3, target: Vec3, yfov: f64) -> Vec<usize> {
    let floor_mat = w.material(pbr("floor", [0.5, 0.5, 0.5, 1.0], 0.0, 0.8));
    let floor_mesh = w.add_mesh_arrays(&floor, Some(floor_mat), true);
    w.json["meshes"][floor_mesh]["name"] = json!("floor");
    let cam = w.camera(json!({ "name": "front", "type": "perspective",
        "perspective": { "yfov": yfov, "znear": 0.05 } }));
    let sun = w.light(
        json!({ "name": "sun", "type": "directional", "color": [1.0, 1.0, 1.0],
        "intensity": 2.5 }),
    );
    let lamp = w.light(
        json!({ "name": "lamp", "type": "point", "color": [1.0, 1.0, 1.0],
        "intensity": 20.0 }),
    );
    let mut sun_node = light_ref(sun);
    sun_node["name"] = json!("sun");
    sun_node["rotation"] = json!(facing(Vec3::new(1.0, -1.0, -1.0)));
    let mut lamp_node = light_ref(lamp);
    lamp_node["name"] = json!("lamp");
    lamp_node["translation"] = json!([-3.0, 3.0, 4.0]);
    vec![
        w.node(json!({ "name": "floor", "mesh": floor_mesh })),
        w.node(
            json!({ "name": "front", "camera": cam, "translation": eye.to_array(),
            "rotation": facing(target - eye) }),
        ),
        w.node(sun_node),
        w.node(lamp_node),
    ]
}

fn spheres() -> Result<GltfWriter> {
    let mut w = GltfWriter::new();
    let sphere = uv_sphere([0.0; 3], 0.4, 32, 64);
    check_winding(&sphere, [0.0; 3])?;
    // one set of accessors for all 25 meshes: they differ only in material
    let shared = w.primitive_from_arrays(&sphere, None, false);
    let mut roots = Vec::new();
    for row in 0..5 {
        for col in 0..5 {
            let (metal, rough) = (col as f64 / 4.0, row as f64 / 4.0);
            let name = format!("metal {metal:.2} rough {rough:.2}");
            let mat = w.material(pbr(&name, [0.9, 0.6, 0.2, 1.0], metal, rough));
            let mut p = shared.clone();
            p["material"] = json!(mat);
            let mesh = w.mesh(vec![p]);
            w.json["meshes"][mesh]["name"] = json!(name);
            let at = [col as f32 - 2.0, 2.0 - row as f32, 0.0];
            roots.push(w.node(json!({ "name": name, "mesh": mesh, "translation": at })));
        }
    }
    let floor = quad([0.0, -2.6, 0.0], [6.0, 0.0, 0.0], [0.0, 0.0, -6.0]);
    roots.extend(stage(
        &mut w,
        floor,
        Vec3::new(0.0, 0.0, 7.5),
        Vec3::ZERO,
        0.75,
    ));
    w.scene(&roots);
    Ok(w)
}

const TEX: u32 = 256;
/// Brick cells: 8 across, 8 down, every other row shifted by half a brick.
const CELL_W: f32 = 32.0;
const CELL_H: f32 = 32.0;
/// Half the mortar line's width and the width of the bevel from mortar up to brick, in pixels.
const MORTAR: f32 = 2.0;
const BEVEL: f32 = 3.0;

fn hash(a: u32, b: u32) -> f32 {
    let mut h = a.wrapping_mul(0x9E37_79B9) ^ b.wrapping_mul(0x85EB_CA6B);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2C1B_3C6D);
    h ^= h >> 12;
    (h & 0xFFFF) as f32 / 65535.0
}

/// At pixel centre (x, y): the brick's (column, row) and the distance to the nearest cell edge.
fn brick_at(x: f32, y: f32) -> (u32, u32, f32) {
    let row = (y / CELL_H).floor();
    let shift = if row as u32 % 2 == 1 {
        CELL_W / 2.0
    } else {
        0.0
    };
    let xs = (x + shift).rem_euclid(TEX as f32);
    let col = (xs / CELL_W).floor();
    let (fx, fy) = (xs - col * CELL_W, y - row * CELL_H);
    let d = fx.min(CELL_W - fx).min(fy).min(CELL_H - fy);
    (col as u32, row as u32, d)
}

/// Height 0 in the mortar, rising smoothly to 1 over the bevel.
fn height(x: f32, y: f32) -> f32 {
    let t = ((brick_at(x, y).2 - MORTAR) / BEVEL).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Base colour (sRGB), normal map and metallic-roughness map of the bricks; all tile.
fn brick_textures() -> [image::RgbaImage; 3] {
    let n = TEX as usize;
    let h: Vec<f32> = (0..n * n)
        .map(|k| height((k % n) as f32 + 0.5, (k / n) as f32 + 0.5))
        .collect();
    let at =
        |x: i64, y: i64| h[y.rem_euclid(n as i64) as usize * n + x.rem_euclid(n as i64) as usize];
    let mut base = image::RgbaImage::new(TEX, TEX);
    let mut normal = image::RgbaImage::new(TEX, TEX);
    let mut mr = image::RgbaImage::new(TEX, TEX);
    for y in 0..TEX {
        for x in 0..TEX {
            let (col, row, d) = brick_at(x as f32 + 0.5, y as f32 + 0.5);
            let mortar = d < MORTAR;
            let grain = hash(x, y) - 0.5;
            let c = if mortar {
                [200.0, 194.0, 182.0].map(|c: f32| c + 20.0 * grain)
            } else {
                let tone = 0.8 + 0.4 * hash(col, row);
                [150.0 * tone, 58.0 * tone, 42.0 * tone].map(|c| c * (1.0 + 0.15 * grain))
            };
            let [r, g, b] = c.map(|c| c.clamp(0.0, 255.0).round() as u8);
            base.put_pixel(x, y, image::Rgba([r, g, b, 255]));
            // tangent space: +x = +u (right), +y = up in the image (decreasing v, row)
            let (xi, yi) = (x as i64, y as i64);
            let dhdx = (at(xi + 1, yi) - at(xi - 1, yi)) / 2.0;
            let dhdrow = (at(xi, yi + 1) - at(xi, yi - 1)) / 2.0;
            let strength = 2.0;
            let v = Vec3::new(-strength * dhdx, strength * dhdrow, 1.0).normalize();
            let e = v
                .to_array()
                .map(|c| ((c * 0.5 + 0.5) * 255.0).round() as u8);
            normal.put_pixel(x, y, image::Rgba([e[0], e[1], e[2], 255]));
            let rough = if mortar { 0.8 } else { 0.45 };
            mr.put_pixel(
                x,
                y,
                image::Rgba([0, (rough * 255.0f32).round() as u8, 0, 255]),
            );
        }
    }
    [base, normal, mr]
}

fn brick() -> Result<GltfWriter> {
    let mut w = GltfWriter::new();
    let sphere = uv_sphere([0.0; 3], 1.0, 48, 96);
    check_winding(&sphere, [0.0; 3])?;
    let [base, normal, mr] = brick_textures();
    let names = [
        "brick base colour",
        "brick normal",
        "brick metallic-roughness",
    ];
    let mut tex = [0; 3];
    for (k, img) in [base, normal, mr].iter().enumerate() {
        tex[k] = w.png_texture(img, Some(sampler()))?;
        let source = w.json["textures"][tex[k]]["source"]
            .as_u64()
            .ok_or("no source")?;
        w.json["images"][source as usize]["name"] = json!(names[k]);
    }
    let mat = w.material(json!({ "name": "brick", "pbrMetallicRoughness": {
        "baseColorTexture": { "index": tex[0] }, "metallicRoughnessTexture": { "index": tex[2] },
        "metallicFactor": 1.0, "roughnessFactor": 1.0 },
        "normalTexture": { "index": tex[1], "scale": 1.0 } }));
    // dP/du of the sphere (see uv_sphere); w = +1: cross(N, T) points up the image (-dP/dv)
    let tangents: Vec<[f32; 4]> = sphere
        .uvs
        .iter()
        .map(|uv| {
            let (s, c) = (std::f32::consts::TAU * uv[0]).sin_cos();
            [s, 0.0, c, 1.0]
        })
        .collect();
    let mut p = w.primitive_from_arrays(&sphere, Some(mat), true);
    p["attributes"]["TANGENT"] = json!(w.vec4(&tangents));
    let mesh = w.mesh(vec![p]);
    w.json["meshes"][mesh]["name"] = json!("brick sphere");
    let mut roots = vec![w.node(json!({ "name": "brick sphere", "mesh": mesh }))];
    let floor = quad([0.0, -1.0, 0.0], [5.0, 0.0, 0.0], [0.0, 0.0, -5.0]);
    let eye = Vec3::new(0.0, 0.6, 4.0);
    roots.extend(stage(&mut w, floor, eye, Vec3::ZERO, 0.7));
    w.scene(&roots);
    Ok(w)
}

/// Every triangle of a closed mesh around `center` is counter-clockwise seen from outside.
fn check_winding(m: &MeshArrays, center: [f32; 3]) -> Result<()> {
    let c = Vec3::from(center);
    for t in m.indices.chunks(3) {
        let [a, b, d] = [t[0], t[1], t[2]].map(|i| Vec3::from(m.positions[i as usize]));
        let n = (b - a).cross(d - a);
        if n.length() < 1e-12 || n.dot(a + b + d - 3.0 * c) <= 0.0 {
            return Err(format!("triangle {t:?} is degenerate or faces inwards").into());
        }
    }
    Ok(())
}

/// The `.gltf` parses and its buffer's byteLength is the `.bin`'s size.
fn check_external(gltf: &Path) -> Result<()> {
    let v: Value = serde_json::from_slice(&std::fs::read(gltf)?)?;
    let bin = std::fs::metadata(gltf.with_extension("bin"))?.len();
    if v["buffers"][0]["byteLength"].as_u64() != Some(bin) {
        return Err(format!("{}: buffer byteLength is not {bin}", gltf.display()).into());
    }
    Ok(())
}

/// The GLB's header and chunk lengths add up and its JSON parses.
fn check_glb(b: &[u8]) -> Result<()> {
    let u = |o: usize| {
        b.get(o..o + 4)
            .map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]) as usize)
    };
    let (Some(total), Some(jlen), Some(jty)) = (u(8), u(12), u(16)) else {
        return Err("GLB shorter than its header".into());
    };
    let v: Value = serde_json::from_slice(b.get(20..20 + jlen).ok_or("JSON chunk cut short")?)?;
    let (blen, bty) = (u(20 + jlen).unwrap_or(0), u(24 + jlen).unwrap_or(0));
    let ok = &b[..4] == b"glTF"
        && u(4) == Some(2)
        && total == b.len()
        && jty == 0x4E4F_534A
        && bty == 0x004E_4942
        && 28 + jlen + blen == total
        && v["buffers"][0]["byteLength"]
            .as_u64()
            .is_some_and(|l| l as usize <= blen);
    if !ok {
        return Err("GLB framing does not add up".into());
    }
    Ok(())
}

fn report(path: &Path) -> Result<()> {
    let size = std::fs::metadata(path)?.len();
    let what = match path.extension().and_then(|e| e.to_str()) {
        Some("bin") => String::from("buffer"),
        _ => {
            let v: Value = if path.extension().is_some_and(|e| e == "glb") {
                let b = std::fs::read(path)?;
                let jlen = u32::from_le_bytes([b[12], b[13], b[14], b[15]]) as usize;
                serde_json::from_slice(&b[20..20 + jlen])?
            } else {
                serde_json::from_slice(&std::fs::read(path)?)?
            };
            let count = |k: &str| v[k].as_array().map_or(0, |a| a.len());
            format!(
                "{} nodes, {} meshes, {} materials, {} textures, {} lights, {} cameras",
                count("nodes"),
                count("meshes"),
                count("materials"),
                count("textures"),
                v["extensions"]["KHR_lights_punctual"]["lights"]
                    .as_array()
                    .map_or(0, |a| a.len()),
                count("cameras")
            )
        }
    };
    println!("wrote {} ({size} bytes): {what}", path.display());
    Ok(())
}
