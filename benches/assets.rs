//! Asset benchmark: a helmet-class glTF asset (about 15,000 triangles; base colour,
//! metallic-roughness, normal, occlusion and emissive maps of 2048 x 2048) written here,
//! then loaded and rendered: the texels' bytes on the GPU, the load time, and samples per
//! second on the first Vulkan adapter and the CPU reference. Writes
//! `docs/bench/assets.md`.
//!
//! Run: `cargo bench --bench assets`. Timings come from one run on whatever machine runs
//! it; compare within the report, not across machines.

mod common;
#[path = "../tests/common/gltf_writer.rs"]
mod gltf_writer;

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use common::samples_per_second;
use gltf_writer::GltfWriter;
use serde_json::json;
use wgtrace::{Engine, Overrides};

/// Side of each map.
const MAP: u32 = 2048;
/// Image size of the timed renders.
const SIDE: u32 = 256;
/// Passes are timed until this much time has passed (after one untimed warm-up pass).
const MIN_TIME: Duration = Duration::from_millis(3000);

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A map of `MAP` x `MAP` texels with detail at every scale (so that its PNG is as large
/// and as slow to decode as a scanned asset's): `f` of the texel and a hash of it.
fn map(f: impl Fn(u32, u32, u32) -> [u8; 4]) -> image::RgbaImage {
    image::RgbaImage::from_fn(MAP, MAP, |x, y| {
        let mut h = x.wrapping_mul(0x9e37_79b9) ^ y.wrapping_mul(0x85eb_ca6b);
        h ^= h >> 15;
        h = h.wrapping_mul(0x2c1b_3c6d);
        h ^= h >> 12;
        image::Rgba(f(x, y, h))
    })
}

/// The asset as a GLB: a sphere of 15,312 triangles under five maps, and an emissive one.
fn asset() -> Vec<u8> {
    let mut w = GltfWriter::new();
    let maps = [
        map(|x, y, h| [(x >> 3) as u8, (y >> 3) as u8, (h & 63) as u8 + 120, 255]),
        map(|_, _, h| [255, (h & 127) as u8 + 64, (h >> 8 & 255) as u8, 255]),
        map(|_, _, h| {
            [
                128 + (h & 31) as u8 - 16,
                128 + (h >> 5 & 31) as u8 - 16,
                240,
                255,
            ]
        }),
        map(|_, _, h| [(h & 255) as u8; 4]),
        map(|x, y, _| {
            let on = (x / 128 + y / 128) % 7 == 0;
            [if on { 255 } else { 0 }, if on { 160 } else { 0 }, 0, 255]
        }),
    ];
    let t: Vec<usize> = maps
        .iter()
        .map(|m| w.png_texture(m, None).expect("encode a map"))
        .collect();
    let m = w.material(json!({
        "pbrMetallicRoughness": { "baseColorTexture": { "index": t[0] },
            "metallicRoughnessTexture": { "index": t[1] } },
        "normalTexture": { "index": t[2] },
        "occlusionTexture": { "index": t[3] },
        "emissiveTexture": { "index": t[4] },
        "emissiveFactor": [1.0, 1.0, 1.0] }));
    let sphere = gltf_writer::uv_sphere([0.0; 3], 1.0, 88, 88);
    let mesh = w.add_mesh_arrays(&sphere, Some(m), true);
    let n = w.node(json!({ "mesh": mesh }));
    let c =
        w.camera(json!({ "type": "perspective", "perspective": { "yfov": 0.8, "znear": 0.1 } }));
    let cam = w.node(json!({ "camera": c, "translation": [0.0, 0.0, 3.2] }));
    w.scene(&[n, cam]);
    w.glb_bytes()
}

fn main() {
    let dir = root().join("target/bench-assets");
    std::fs::create_dir_all(&dir).expect("target/bench-assets");
    let path = dir.join("helmet-class.glb");
    let start = Instant::now();
    std::fs::write(&path, asset()).expect("write the asset");
    eprintln!("asset written in {:.1} s", start.elapsed().as_secs_f64());
    let file_mib = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0) as f64 / 1048576.0;
    let o = Overrides {
        width: Some(SIDE),
        height: Some(SIDE),
        ..Default::default()
    };
    let mut loads = Vec::new();
    let mut scene = None;
    for _ in 0..3 {
        let start = Instant::now();
        let s = wgtrace::load_scene(&path, &o).expect("the asset loads");
        loads.push(start.elapsed().as_secs_f64());
        scene = Some(s);
    }
    loads.sort_by(f64::total_cmp);
    let scene = scene.expect("loaded");
    let bytes = scene.texels.bytes();
    let texels: u64 = scene
        .texels
        .banks
        .iter()
        .map(|b| b.width as u64 * b.height as u64 * b.layers as u64)
        .sum();
    // the maps' bank (8-bit) apart from the studio environment's (float)
    let maps: Vec<_> = scene
        .texels
        .banks
        .iter()
        .filter(|b| b.kind == wgtrace::scene::texels::TexelKind::Unorm8)
        .collect();
    let map_bytes: u64 = maps.iter().map(|b| b.data.len() as u64).sum();
    let map_texels: u64 = maps
        .iter()
        .map(|b| b.width as u64 * b.height as u64 * b.layers as u64)
        .sum();
    let gpu = Engine::gpu(&scene, 0)
        .unwrap_or_else(|e| panic!("the benchmark needs a Vulkan adapter: {e}"));
    let device = gpu.name();
    let gpu_rate = samples_per_second(gpu, &scene, MIN_TIME);
    let cpu_rate = samples_per_second(Engine::cpu(&scene), &scene, MIN_TIME);
    eprintln!(
        "{} triangles, {bytes} bytes of texels, load {:.2} s, GPU {gpu_rate:.0} / CPU {cpu_rate:.0} samples/s",
        scene.primitives.len(),
        loads[1]
    );
    let mut r = String::new();
    let _ = writeln!(r, "# A helmet-class asset: texels, load time and speed\n");
    let _ = writeln!(
        r,
        "Written on {} by `cargo bench --bench assets` on {device}. The asset is written by the \
         bench itself (benches/assets.rs): a GLB of {} triangles (a sphere) under base colour, \
         metallic-roughness, normal, occlusion and emissive maps of {MAP} x {MAP} texels, 8 \
         bits a channel, with detail at every scale ({file_mib:.1} MiB). Rendered on its own at \
         {SIDE} x {SIDE}, max depth 8, MIS, lit by its emission and the studio environment; \
         samples per second over at least {} s after one warm-up pass. One run on one machine.\n",
        wgtrace::report::today(),
        scene.primitives.len(),
        MIN_TIME.as_secs_f64()
    );
    let _ = writeln!(r, "| what | value |\n|---|---:|");
    let _ = writeln!(
        r,
        "| maps on the GPU (occlusion is not read), and the studio environment | {} + 1 |",
        maps.iter().map(|b| b.layers).sum::<u32>()
    );
    let _ = writeln!(
        r,
        "| texel banks | {} ({}) |",
        scene.texels.banks.len(),
        scene
            .texels
            .banks
            .iter()
            .map(|b| format!(
                "{} page{} of {} x {}, {}",
                b.layers,
                if b.layers == 1 { "" } else { "s" },
                b.width,
                b.height,
                b.kind.name()
            ))
            .collect::<Vec<_>>()
            .join("; ")
    );
    let _ = writeln!(
        r,
        "| GPU bytes of texels | {bytes} ({:.1} MiB) |",
        bytes as f64 / 1048576.0
    );
    let _ = writeln!(
        r,
        "| bytes per texel of the maps (of all texels) | {:.2} ({:.2}) |",
        map_bytes as f64 / map_texels as f64,
        bytes as f64 / texels as f64
    );
    let _ = writeln!(
        r,
        "| the same texels as four f32 each (before texel banks) | {:.1} MiB: more than lavapipe's 128 MiB binding, refused |",
        (texels * 16) as f64 / 1048576.0
    );
    let _ = writeln!(
        r,
        "| load: read, decode, flatten, BVH (median of 3) | {:.2} s ({:.2} to {:.2}) |",
        loads[1], loads[0], loads[2]
    );
    let _ = writeln!(r, "| GPU samples per second | {gpu_rate:.0} |");
    let _ = writeln!(r, "| CPU reference samples per second | {cpu_rate:.0} |");
    let out = root().join("docs/bench/assets.md");
    std::fs::write(&out, r).expect("write docs/bench/assets.md");
    eprintln!("wrote {}", out.display());
}
