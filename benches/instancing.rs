//! Instancing benchmark: a forest of one real mesh (`../shared/meshes/spot.obj`, 5,856
//! triangles) placed N times on a grid, each copy turned and scaled by a seeded random
//! draw, as a group with N instances and as the flattened scene (N mesh objects, every
//! triangle written out), from 1 to 100,000 copies. For each: the records a render uploads
//! (primitives, BVH nodes, shape data), the time to load and flatten the scene, and the
//! render's steady rate on the first Vulkan adapter (256 x 256, 16 spp, medians of 3
//! after the pipeline's compile), in one run. A scene whose records the renderer refuses
//! (over the device's storage bindings) is loaded only, and one of more than the scene
//! format's 2^24 triangles not at all. Writes `docs/bench/instancing.md`.
//!
//! Run: `cargo bench --bench instancing`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use wgtrace::gpu::{GpuContext, GpuRenderer};
use wgtrace::scene::mesh::MAX_TRIANGLES;
use wgtrace::scene::records::{BvhNode, Primitive};
use wgtrace::{FlatScene, Overrides, Tuning};

const SIZE: u32 = 256;
const SPP: u32 = 16;
const ROUNDS: usize = 3;
const COUNTS: [usize; 6] = [1, 16, 256, 1_000, 10_000, 100_000];
const MESH_TRIANGLES: usize = 5_856;

fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v[v.len() / 2]
}

/// A seeded draw in [0, 1).
fn draw(state: &mut u32) -> f32 {
    *state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
    (*state >> 8) as f32 / (1u32 << 24) as f32
}

/// The forest's TOML: N copies of the mesh on a square grid 2.5 apart, each turned about
/// y and scaled by 0.8 to 1.2, on a ground plane under a sun and a sky; as instances of a
/// group, or as N mesh objects.
fn forest(mesh: &Path, n: usize, instanced: bool) -> String {
    let side = (n as f32).sqrt().ceil() as usize;
    let extent = side as f32 * 2.5;
    let mut s = format!(
        "[render]\nwidth = {SIZE}\nheight = {SIZE}\nspp = {SPP}\nmax_depth = 4\n\
         [camera]\nlook_from = [0, {}, {}]\nlook_at = [0, 0, 0]\nvfov = 40\n\
         [background]\ncolor = [0.6, 0.7, 0.9]\n\
         [materials]\nhide = {{ type = \"lambertian\", albedo = [0.7, 0.6, 0.5] }}\n\
         ground = {{ type = \"lambertian\", albedo = [0.3, 0.4, 0.2] }}\n\
         [[lights]]\ntype = \"directional\"\ndirection = [-0.4, -1, -0.3]\nirradiance = [2, 2, 2]\n\
         [[objects]]\ntype = \"plane\"\npoint = [0, -0.7, 0]\nnormal = [0, 1, 0]\nmaterial = \"ground\"\n",
        0.9 * extent + 3.0,
        1.1 * extent + 3.0
    );
    let mut rng = 7u32;
    for k in 0..n {
        let (i, j) = (k % side, k / side);
        let x = (i as f32 + 0.5) * 2.5 - extent / 2.0;
        let z = (j as f32 + 0.5) * 2.5 - extent / 2.0;
        let turn = 360.0 * draw(&mut rng);
        let scale = 0.8 + 0.4 * draw(&mut rng);
        let transform =
            format!("{{ translate = [{x}, 0, {z}], rotate = [0, {turn}, 0], scale = {scale} }}");
        if instanced {
            writeln!(
                s,
                "[[objects]]\ntype = \"instance\"\ngroup = \"spot\"\ntransform = {transform}"
            )
            .unwrap();
        } else {
            writeln!(s, "[[objects]]\ntype = \"mesh\"\npath = \"{}\"\nmaterial = \"hide\"\ntransform = {transform}", mesh.display()).unwrap();
        }
    }
    if instanced {
        writeln!(
            s,
            "[[groups.spot.objects]]\ntype = \"mesh\"\npath = \"{}\"\nmaterial = \"hide\"",
            mesh.display()
        )
        .unwrap();
    }
    s
}

/// Bytes of the records a render uploads for the geometry.
fn record_bytes(scene: &FlatScene) -> usize {
    scene.primitives.len() * std::mem::size_of::<Primitive>()
        + scene.bvh.len() * std::mem::size_of::<BvhNode>()
        + scene.shape_data.len() * 16
}

struct Row {
    records: usize,
    primitives: usize,
    load: Duration,
    rate: Option<f64>,
}

fn measure(ctx: &std::sync::Arc<GpuContext>, src: &str, dir: &Path) -> Row {
    let start = Instant::now();
    let scene = wgtrace::load_scene_str(src, &dir.join("forest.toml"), &Overrides::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let load = start.elapsed();
    // a scene whose records do not fit the device's bindings is refused here
    let renderer = GpuRenderer::new(ctx.clone(), &scene, &Tuning::default())
        .map_err(|e| eprintln!("not rendered: {e}"))
        .ok();
    let rate = renderer.map(|mut r| {
        let zero = vec![[0.0; 4]; r.accumulation().unwrap().len()];
        // the first pass waits on the driver's compile
        r.render_samples(0..1).unwrap();
        r.accumulation().unwrap();
        let times: Vec<Duration> = (0..ROUNDS)
            .map(|_| {
                r.set_accumulation(&zero).unwrap();
                let start = Instant::now();
                r.render_samples(0..SPP).unwrap();
                r.accumulation().unwrap();
                start.elapsed()
            })
            .collect();
        (SIZE * SIZE * SPP) as f64 / median(times).as_secs_f64() / 1e6
    });
    Row {
        records: record_bytes(&scene),
        primitives: scene.primitives.len(),
        load,
        rate,
    }
}

fn mib(b: usize) -> String {
    format!("{:.2}", b as f64 / (1 << 20) as f64)
}

fn main() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mesh = root.join("../shared/meshes/spot.obj");
    assert!(mesh.exists(), "{} is missing", mesh.display());
    let mesh = mesh.canonicalize().unwrap();
    let dir = std::env::temp_dir();
    let ctx = GpuContext::shared(0).unwrap_or_else(|e| panic!("{e}"));
    let device = wgtrace::gpu::context::describe(&ctx.info);
    let binding = ctx.device.limits().max_storage_buffer_binding_size;
    let mut table = String::new();
    for n in COUNTS {
        let inst = measure(&ctx, &forest(&mesh, n, true), &dir);
        let flat = (n * MESH_TRIANGLES <= MAX_TRIANGLES)
            .then(|| measure(&ctx, &forest(&mesh, n, false), &dir));
        let rate = |r: &Row| {
            r.rate
                .map_or("records over the device's bindings".into(), |x| {
                    format!("{x:.3}")
                })
        };
        let (f_records, f_load, f_rate, ratio) = match &flat {
            Some(f) => (
                format!("{} ({} primitives)", mib(f.records), f.primitives),
                format!("{:.2}", f.load.as_secs_f64()),
                rate(f),
                match (inst.rate, f.rate) {
                    (Some(a), Some(b)) => format!("{:.2}", a / b),
                    _ => "-".into(),
                },
            ),
            None => (
                "over 2^24 triangles: refused".into(),
                "-".into(),
                "-".into(),
                "-".into(),
            ),
        };
        let line = format!(
            "| {n} | {} | {} ({} primitives) | {:.2} | {} | {f_records} | {f_load} | {f_rate} | {ratio} |",
            n * MESH_TRIANGLES,
            mib(inst.records),
            inst.primitives,
            inst.load.as_secs_f64(),
            rate(&inst),
        );
        eprintln!("{line}");
        writeln!(table, "{line}").unwrap();
    }
    let report = format!(
        "# Instancing: a forest of one mesh, instanced and flattened\n\n\
         Written on {} by `cargo bench --bench instancing` on {device}.\n\n\
         `../shared/meshes/spot.obj` ({MESH_TRIANGLES} triangles) placed N times on a grid, each \
         copy turned about y and scaled by 0.8 to 1.2 (a seeded draw), on a ground plane under \
         a directional light and a sky colour; {SIZE} x {SIZE}, {SPP} spp, max_depth 4, the \
         camera framing the whole grid. *Instanced*: a `[groups.spot]` of the mesh and N \
         `instance` objects (the group's triangles and BVH once, one instance record and box \
         per copy in the scene's BVH). *Flattened*: N `mesh` objects, every triangle written \
         out in world space. Records: the primitives, BVH nodes and shape data a render \
         uploads (textures and materials aside). Load: reading, validating and flattening \
         the scene (the flattened scene reads the OBJ once per object). Msamples/s: the \
         steady rate, medians of {ROUNDS} renders after the pipeline's compile, in one run. \
         A scene whose records exceed the device's storage bindings ({} MiB each here) is \
         refused by the renderer; one of more than 2^24 triangles by the loader.\n\n\
         | copies | triangles placed | instanced records MiB | instanced load s | instanced Msamples/s | flattened records MiB | flattened load s | flattened Msamples/s | instanced / flattened speed |\n\
         |---:|---:|---|---:|---:|---|---:|---:|---:|\n{table}",
        wgtrace::report::today(),
        binding >> 20,
    );
    let out = root.join("docs/bench/instancing.md");
    std::fs::write(&out, &report).unwrap();
    eprintln!("{report}wrote {}", out.display());
}
