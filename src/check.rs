//! `wgtrace check`: what a user runs on a new GPU or driver. For each scene class (a list
//! of primitives with no BVH, a BVH over mixed primitives, a BVH over a smooth, textured
//! triangle mesh) and each record placement a render can use (written into the shader,
//! uniform buffers, textures, storage buffers), it runs the kernel suite's ray queries
//! (closest hit, surface, shadow rays) against the CPU reference ray by ray, and the
//! render's spot check (`crate::spot_check`), and reports a row per pair. The ray
//! comparison ([`cpu_hit`], [`agree`]) is the one `tests/kernel.rs` uses. Like
//! `spot_check`, it holds both backends.

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use crate::cpu::bindings::Bindings;
use crate::cpu::intersect::{intersect_scene, occluded, surface_at};
use crate::cpu::path::{camera_ray, extend_path, start_path, Path};
use crate::cpu::samplers::{pixel_position, sample_2d, DIM_LENS};
use crate::cpu::types::{Ray, FAR, NO_HIT};
use crate::gpu::context::GpuContext;
use crate::gpu::kernel::intersect_rays;
use crate::gpu::render::GpuRenderer;
use crate::scene::error::SceneError;
use crate::scene::flat::FlatScene;
use crate::scene::records::{KernelHit, KernelRay, PathQuery, PathStep, PATH_STEPS};
use crate::scene::Overrides;
use crate::spot_check::{self, Verdict};
use crate::tuning::Tuning;

/// The record placements a render can use, each as the tuning that asks for it on top of
/// `base`: `shader` is the default (small arrays written into the shader, the rest in
/// uniform buffers and textures), `uniform` stops writing records in, `texture` also
/// keeps them out of uniform buffers (the primitives and the BVH go to textures), and
/// `storage` also keeps them out of textures. A scene gets the placement it is asked for
/// where its arrays fit it ([`spot_check::placements`] says where they went).
pub fn placement_tunings(base: &Tuning) -> [(&'static str, Tuning); 4] {
    let shader = *base;
    let uniform = Tuning {
        baked_records: false,
        ..shader
    };
    let texture = Tuning {
        uniform_records: false,
        ..uniform
    };
    let storage = Tuning {
        texture_records: false,
        ..texture
    };
    [
        ("shader", shader),
        ("uniform", uniform),
        ("texture", texture),
        ("storage", storage),
    ]
}

/// The CPU reference's answer for ray `r` in the kernel's record.
pub fn cpu_hit(scene: &FlatScene, r: &Ray) -> KernelHit {
    let b = Bindings::new(scene, scene.params(0, scene.full_band()));
    let c = intersect_scene(&b, r, FAR);
    let mut out = KernelHit {
        t: c.t,
        prim: c.prim,
        occluded: occluded(&b, r, FAR) as u32 | (occluded(&b, r, 0.999 * c.t) as u32) << 1,
        ..Default::default()
    };
    if c.prim != NO_HIT {
        let h = surface_at(&b, r, &c);
        out.front_face = h.front_face as u32;
        out.p = h.p.extend(h.err).to_array();
        out.ng = h.ng.extend(0.0).to_array();
        out.ns = h.ns.extend(0.0).to_array();
        out.uv = [h.uv.x, h.uv.y, c.u, c.v];
        // the instance hit through, plus 1 (0: none)
        out.uv1 = [h.uv.z, h.uv.w, c.inst.wrapping_add(1) as f32, 0.0];
        out.color = h.color.to_array();
    }
    out
}

/// Angles in uv wrap around: 0.999 and 0.001 are 0.002 apart.
fn uv_distance(a: f32, b: f32) -> f32 {
    let d = (a - b).abs();
    d.min((1.0 - d).abs())
}

/// Whether two answers for one ray agree: same primitive and side; t, point, normals and
/// uv within a few ulps of f32 on different math libraries (atan2, acos, sqrt); the
/// shadow rays blocked exactly when there is a hit (to infinity) and not before it (to
/// 0.999 t: at t itself, rounding decides).
pub fn agree(g: &KernelHit, c: &KernelHit) -> Result<(), String> {
    if g.prim != c.prim {
        return Err(format!("prim {} vs {}", g.prim, c.prim));
    }
    let expected = (c.prim != NO_HIT) as u32;
    if g.occluded != expected || c.occluded != expected {
        return Err(format!(
            "occluded {:#b} (gpu) and {:#b} (cpu), expected {expected:#b}",
            g.occluded, c.occluded
        ));
    }
    if c.prim == NO_HIT {
        return Ok(());
    }
    let rel = |a: f32, b: f32, tol: f32| (a - b).abs() <= tol * (1.0 + b.abs());
    let angle = |a: f32, b: f32| uv_distance(a, b) <= 1e-3 * (1.0 + b.abs());
    let (gp, cp) = (Vec4::from(g.p), Vec4::from(c.p));
    let checks = [
        ("t", rel(g.t, c.t, 1e-4)),
        ("front_face", g.front_face == c.front_face),
        (
            "p",
            (gp - cp).truncate().abs().max_element()
                <= 1e-4 * (1.0 + cp.truncate().abs().max_element()),
        ),
        ("err", rel(gp.w, cp.w, 1e-3)),
        (
            "ng",
            Vec3::from_slice(&g.ng).dot(Vec3::from_slice(&c.ng)) > 0.9999,
        ),
        (
            "ns",
            Vec3::from_slice(&g.ns).dot(Vec3::from_slice(&c.ns)) > 0.9999,
        ),
        ("uv", angle(g.uv[0], c.uv[0]) && rel(g.uv[1], c.uv[1], 1e-3)),
        (
            "candidate uv",
            rel(g.uv[2], c.uv[2], 1e-3) && rel(g.uv[3], c.uv[3], 1e-3),
        ),
        (
            "second uv set",
            angle(g.uv1[0], c.uv1[0]) && rel(g.uv1[1], c.uv1[1], 1e-3),
        ),
        (
            "vertex colour",
            (0..4).all(|k| rel(g.color[k], c.color[k], 1e-5)),
        ),
        ("instance", g.uv1[2] == c.uv1[2]),
    ];
    match checks.iter().find(|(_, ok)| !ok) {
        Some((what, _)) => Err(format!("{what} differs")),
        None => Ok(()),
    }
}

/// The CPU reference's answer for path query `q` in the kernel's records (`paths_main`):
/// the same camera ray and `extend_path` calls, `PATH_STEPS` states.
pub fn cpu_path_steps(scene: &FlatScene, q: &PathQuery) -> Vec<PathStep> {
    let b = Bindings::new(scene, scene.params(0, scene.full_band()));
    let pixel = q.y * b.params.width + q.x;
    let jitter = pixel_position(&b, pixel, q.sample);
    let lens = sample_2d(&b, pixel, q.sample, DIM_LENS);
    let mut path = start_path(&b, camera_ray(&b, q.x, q.y, jitter, lens));
    let step = |path: &Path, going: bool, calls: u32| PathStep {
        origin: path.ray.origin.extend(path.depth as f32).to_array(),
        dir: path.ray.dir.extend(going as u32 as f32).to_array(),
        throughput: path.throughput.extend(calls as f32).to_array(),
        radiance: path.radiance.extend(0.0).to_array(),
    };
    let mut out = vec![PathStep::default(); PATH_STEPS as usize];
    let mut going = b.params.max_depth != 0;
    out[0] = step(&path, going, 0);
    let mut calls = 0;
    while going {
        going = extend_path(&b, &mut path, pixel, q.sample);
        calls += 1;
        out[calls.min(PATH_STEPS - 1) as usize] = step(&path, going, calls);
    }
    out
}

/// Whether two paths' states agree step by step: the same depths, ends and number of
/// bounces; origins, directions, throughputs and radiance within what the two math
/// libraries' last bits grow to over a path's bounces (1e-3 of their size). The error
/// names the first step that differs and what.
pub fn path_agree(g: &[PathStep], c: &[PathStep]) -> Result<(), String> {
    let close = |a: [f32; 4], b: [f32; 4]| {
        let (a, b) = (Vec4::from(a).truncate(), Vec4::from(b).truncate());
        (a - b).abs().max_element() <= 1e-3 * (1.0 + b.abs().max_element())
    };
    for (k, (g, c)) in g.iter().zip(c).enumerate() {
        let checks = [
            ("depth", g.origin[3] == c.origin[3]),
            ("end", g.dir[3] == c.dir[3]),
            ("bounces", g.throughput[3] == c.throughput[3]),
            ("origin", close(g.origin, c.origin)),
            ("direction", close(g.dir, c.dir)),
            ("throughput", close(g.throughput, c.throughput)),
            ("radiance", close(g.radiance, c.radiance)),
        ];
        if let Some((what, _)) = checks.iter().find(|(_, ok)| !ok) {
            return Err(format!(
                "step {k}: {what} differs\n  gpu {g:?}\n  cpu {c:?}"
            ));
        }
    }
    Ok(())
}

/// A ray in the kernel's record.
pub fn to_kernel(r: &Ray) -> KernelRay {
    KernelRay {
        origin: r.origin.extend(0.0).to_array(),
        dir: r.dir.extend(0.0).to_array(),
    }
}

/// `n` rays about the sphere of `center` and `radius`: three in four from a sphere of
/// three times the radius toward points inside it, one in four started near the centre in
/// any direction (from inside what the scene holds there). The same `seed`, the same rays.
pub fn rays(center: Vec3, radius: f32, n: usize, seed: u32) -> Vec<Ray> {
    let mut state = seed.max(1);
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        (state >> 8) as f32 / (1u32 << 24) as f32
    };
    let mut unit = move || {
        let z = 2.0 * next() - 1.0;
        let phi = std::f32::consts::TAU * next();
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    };
    (0..n)
        .map(|i| {
            if i % 4 == 3 {
                let origin = center + 0.3 * radius * unit();
                Ray {
                    origin,
                    dir: unit(),
                }
            } else {
                let origin = center + 3.0 * radius * unit();
                let target = center + 0.9 * radius * unit();
                Ray {
                    origin,
                    dir: (target - origin).normalize(),
                }
            }
        })
        .collect()
}

/// Rays of the ray comparison per scene class and placement.
pub const RAYS: usize = 4096;

/// A scene class of the check: a scene, and the sphere its rays aim at.
pub struct Class {
    pub name: &'static str,
    pub scene: FlatScene,
    pub center: Vec3,
    pub radius: f32,
}

/// The size of the check scenes' images: the spot check's grid covers it as it covers a
/// user's.
const SIZE: u32 = 64;

/// The check's scene classes, built from text in the binary (the mesh class writes its
/// OBJ file to a temporary folder, removed once loaded).
pub fn classes() -> Result<Vec<Class>, SceneError> {
    let overrides = Overrides {
        width: Some(SIZE),
        height: Some(SIZE),
        ..Default::default()
    };
    let load = |src: &str, path: &std::path::Path| {
        crate::scene::load_str(src, path, &overrides, Tuning::default().build())
    };
    let cornell = load(
        include_str!("../scenes/cornell.toml"),
        std::path::Path::new("cornell.toml"),
    )?;
    let bvh = load(&mixed_scene(), std::path::Path::new("check-bvh.toml"))?;
    let dir = std::env::temp_dir().join(format!("wgtrace-check-{}", std::process::id()));
    let io = |cause| SceneError::Io {
        path: dir.join("sphere.obj"),
        cause,
    };
    std::fs::create_dir_all(&dir).map_err(io)?;
    std::fs::write(dir.join("sphere.obj"), sphere_obj(48, 24)).map_err(io)?;
    let mesh = load(MESH_SCENE, &dir.join("check-mesh.toml"));
    let _ = std::fs::remove_dir_all(&dir);
    Ok(vec![
        Class {
            name: "list",
            scene: cornell,
            center: Vec3::ZERO,
            radius: 1.0,
        },
        Class {
            name: "bvh",
            scene: bvh,
            center: Vec3::ZERO,
            radius: 3.0,
        },
        Class {
            name: "mesh",
            scene: mesh?,
            center: Vec3::ZERO,
            radius: 1.2,
        },
    ])
}

/// A BVH scene of spheres, boxes (transformed), cylinders and triangles over a plane, with
/// a checker texture, metal and glass, under an area light and a sky: past the list's
/// size, so the flattener builds a BVH.
fn mixed_scene() -> String {
    let mut s = String::from(
        "[camera]\nlook_from = [0, 1, 9]\nlook_at = [0, 0, 0]\nvfov = 45\n\
         [background]\ntop = [0.5, 0.6, 0.9]\nbottom = [0.9, 0.9, 0.8]\n\
         [textures]\nchecks = { type = \"checker\", even = [0.8, 0.8, 0.8], odd = [0.2, 0.3, 0.5], scale = 4 }\n\
         [materials]\n\
         floor = { type = \"lambertian\", albedo = \"checks\" }\n\
         matte = { type = \"lambertian\", albedo = [0.7, 0.4, 0.3] }\n\
         steel = { type = \"metal\", albedo = [0.9, 0.9, 0.9], fuzz = 0.2 }\n\
         glass = { type = \"dielectric\", ior = 1.5 }\n\
         lamp = { type = \"emissive\", radiance = [8, 8, 8] }\n\
         [[objects]]\ntype = \"plane\"\npoint = [0, -3, 0]\nnormal = [0, 1, 0]\nmaterial = \"floor\"\n\
         [[objects]]\ntype = \"disk\"\ncenter = [0, 4, 0]\nnormal = [0, -1, 0]\nradius = 1.5\nmaterial = \"lamp\"\n",
    );
    let materials = ["matte", "steel", "glass", "floor"];
    for i in 0..96u32 {
        // a 4 x 4 x 6 lattice over [-3, 3]^3, jittered by the index
        let (x, y, z) = (i % 4, (i / 4) % 4, i / 16);
        let p = Vec3::new(x as f32, y as f32, z as f32 * 0.6) * 1.6 - Vec3::new(2.4, 2.4, 1.5)
            + 0.2 * Vec3::new((i as f32 * 1.3).sin(), (i as f32 * 2.1).cos(), 0.0);
        let m = materials[(i % 4) as usize];
        let object = match i % 4 {
            0 => format!("type = \"sphere\"\ncenter = [{}, {}, {}]\nradius = 0.45", p.x, p.y, p.z),
            1 => format!(
                "type = \"box\"\nmin = [{}, {}, {}]\nmax = [{}, {}, {}]\ntransform = {{ rotate = [{}, 30, 0] }}",
                p.x - 0.4,
                p.y - 0.3,
                p.z - 0.35,
                p.x + 0.4,
                p.y + 0.3,
                p.z + 0.35,
                i * 7
            ),
            2 => format!(
                "type = \"cylinder\"\nbase = [{}, {}, {}]\ntop = [{}, {}, {}]\nradius = 0.3",
                p.x,
                p.y - 0.4,
                p.z,
                p.x + 0.2,
                p.y + 0.4,
                p.z
            ),
            _ => format!(
                "type = \"triangle\"\nvertices = [[{}, {}, {}], [{}, {}, {}], [{}, {}, {}]]",
                p.x - 0.5,
                p.y - 0.4,
                p.z,
                p.x + 0.5,
                p.y - 0.4,
                p.z + 0.2,
                p.x,
                p.y + 0.5,
                p.z - 0.1
            ),
        };
        s += &format!("[[objects]]\n{object}\nmaterial = \"{m}\"\n");
    }
    s
}

/// The mesh class: a smooth UV sphere of the OBJ file beside it, textured, on a floor.
const MESH_SCENE: &str = "[camera]\nlook_from = [0, 0.6, 4]\nlook_at = [0, 0, 0]\nvfov = 40\n\
    [background]\ntop = [0.5, 0.6, 0.9]\nbottom = [0.9, 0.9, 0.8]\n\
    [textures]\nstripes = { type = \"checker\", even = [0.9, 0.5, 0.2], odd = [0.2, 0.5, 0.9], scale = 12 }\n\
    [materials]\nskin = { type = \"lambertian\", albedo = \"stripes\" }\n\
    floor = { type = \"lambertian\", albedo = [0.6, 0.6, 0.6] }\n\
    [[objects]]\ntype = \"mesh\"\npath = \"sphere.obj\"\nmaterial = \"skin\"\n\
    transform = { scale = [1, 0.9, 1.1], rotate = [10, 20, 0] }\n\
    [[objects]]\ntype = \"plane\"\npoint = [0, -1.2, 0]\nnormal = [0, 1, 0]\nmaterial = \"floor\"\n";

/// A unit UV sphere as OBJ text: `slices` x `stacks` quads as triangles, with positions,
/// normals and texture coordinates per vertex.
fn sphere_obj(slices: u32, stacks: u32) -> String {
    let mut s = String::from("# wgtrace check: a UV sphere\n");
    for j in 0..=stacks {
        let theta = std::f32::consts::PI * j as f32 / stacks as f32;
        for i in 0..=slices {
            let phi = std::f32::consts::TAU * i as f32 / slices as f32;
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            s += &format!("v {} {} {}\nvn {} {} {}\n", n.x, n.y, n.z, n.x, n.y, n.z);
            s += &format!(
                "vt {} {}\n",
                i as f32 / slices as f32,
                1.0 - j as f32 / stacks as f32
            );
        }
    }
    let at = |i: u32, j: u32| j * (slices + 1) + i + 1;
    for j in 0..stacks {
        for i in 0..slices {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            // at the poles one triangle of each quad has two corners at the pole: left out
            if j > 0 {
                s += &format!("f {a}/{a}/{a} {c}/{c}/{c} {b}/{b}/{b}\n");
            }
            if j + 1 < stacks {
                s += &format!("f {a}/{a}/{a} {d}/{d}/{d} {c}/{c}/{c}\n");
            }
        }
    }
    s
}

/// One row of the check: a scene class under one placement.
#[derive(Debug, Clone)]
pub struct Row {
    pub class: &'static str,
    /// The placement asked for, and where the arrays the shader reads went.
    pub placement: &'static str,
    pub records: String,
    /// Rays compared, and those whose answers differ (the first described).
    pub rays: usize,
    pub rays_differ: usize,
    pub first_ray_difference: Option<String>,
    /// The kernel dispatch's time (with its shader's compile).
    pub kernel_time: Duration,
    /// The spot check's verdict and its time on the GPU (with the trace shader's
    /// compile).
    pub spot: Verdict,
}

impl Row {
    /// Whether the GPU agrees with the CPU reference on this row: at most 1 in 1000 rays
    /// differ (rays that graze an edge may land on either side of it), and the spot check
    /// passes.
    pub fn passed(&self) -> bool {
        self.rays_differ * 1000 <= self.rays && self.spot.passed()
    }
}

/// Runs the check of every class under every placement on `ctx` (under `base` tuning:
/// `--tune perturb=...` proves it can fail), calling `row` as each row is done. (One row
/// at a time: wgpu and llvmpipe compile one pipeline at a time whatever the threads.)
pub fn run(
    ctx: Arc<GpuContext>,
    base: &Tuning,
    mut row: impl FnMut(&Row),
) -> Result<Vec<Row>, anyhow::Error> {
    let classes = classes()?;
    let mut rows = Vec::new();
    for (k, class) in classes.iter().enumerate() {
        let rs = rays(class.center, class.radius, RAYS, 0x9e37 + k as u32);
        let batch: Vec<KernelRay> = rs.iter().map(to_kernel).collect();
        let cpu: Vec<KernelHit> = rs.par_iter().map(|r| cpu_hit(&class.scene, r)).collect();
        for (placement, tuning) in placement_tunings(base) {
            let start = Instant::now();
            let gpu = intersect_rays(&ctx, &class.scene, &tuning, &batch)?;
            let kernel_time = start.elapsed();
            let differ: Vec<String> = gpu
                .iter()
                .zip(&cpu)
                .zip(&rs)
                .filter_map(|((g, c), r)| {
                    agree(g, c)
                        .err()
                        .map(|e| format!("ray from {:?} along {:?}: {e}", r.origin, r.dir))
                })
                .collect();
            let mut renderer = GpuRenderer::new(ctx.clone(), &class.scene, &tuning)?;
            let spot = spot_check::check(&mut renderer, &class.scene)?;
            let r = Row {
                class: class.name,
                placement,
                records: spot_check::placements(renderer.plan()),
                rays: rs.len(),
                rays_differ: differ.len(),
                first_ray_difference: differ.into_iter().next(),
                kernel_time,
                spot,
            };
            row(&r);
            rows.push(r);
        }
    }
    Ok(rows)
}
