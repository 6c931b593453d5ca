//! The GPU intersection kernel against the CPU reference, ray by ray: for each primitive
//! type (and transformed and mesh variants), a batch of rays aimed at the object and rays
//! started inside it go through the GPU's closest-hit search and surface_at in one small
//! dispatch, and every field is compared with the CPU functions of the same names, the
//! shadow-ray search (`occluded`) included. The BVH and brute force give the same hits on
//! the GPU too. Each test runs under every record placement a render can use.

mod common;

use glam::Vec3;
use wgtrace::check::{agree, cpu_hit, placement_tunings};
use wgtrace::cpu::bindings::Bindings;
use wgtrace::cpu::types::{Ray, FAR, NO_HIT};
use wgtrace::gpu::kernel::intersect_rays;
use wgtrace::scene::bvh::WIDE_LEAF_SIZE;
use wgtrace::scene::records::{KernelHit, KernelRay};
use wgtrace::{FlatScene, Tuning};

const HEADER: &str = "[camera]\nlook_from = [0, 0, 10]\nlook_at = [0, 0, 0]\n\
    [materials]\nm = { type = \"lambertian\", albedo = [0.5, 0.5, 0.5] }\n[[objects]]\n";

/// (name, object TOML, center and radius of the region the rays aim at)
const OBJECTS: &[(&str, &str, [f32; 3], f32)] = &[
    ("plane", "type = \"plane\"\npoint = [0, -1, 0]\nnormal = [0.1, 1, 0.2]\nuv_scale = 0.7", [0.0, -1.0, 0.0], 3.0),
    ("box", "type = \"box\"\nmin = [-1, -0.5, -0.7]\nmax = [1, 0.5, 0.7]", [0.0; 3], 1.3),
    ("sphere", "type = \"sphere\"\ncenter = [0.5, 0, 0]\nradius = 1", [0.5, 0.0, 0.0], 1.0),
    ("triangle", "type = \"triangle\"\nvertices = [[-1, -1, 0], [1, -1, 0.3], [0, 1, -0.2]]\nuvs = [[0, 0], [2, 0], [1, 3]]", [0.0; 3], 1.2),
    ("polygon", "type = \"polygon\"\nvertices = [[-1, -1, 0], [1, -1, 0], [1.3, 0.5, 0], [0, 1, 0], [-1, 0.5, 0]]", [0.0; 3], 1.2),
    ("tetrahedron", "type = \"tetrahedron\"\nvertices = [[-1, -1, -1], [1, -1, -1], [0, -1, 1], [0, 1, 0]]", [0.0, -0.5, -0.3], 1.0),
    ("cylinder", "type = \"cylinder\"\nbase = [0, -1, 0]\ntop = [0.3, 1, 0.2]\nradius = 0.6", [0.15, 0.0, 0.1], 1.2),
    ("open cylinder", "type = \"cylinder\"\nbase = [0, -1, 0]\ntop = [0, 1, 0]\nradius = 0.6\ncaps = false", [0.0; 3], 1.1),
    ("disk", "type = \"disk\"\ncenter = [0, 0, 0]\nnormal = [0.3, 1, -0.4]\nradius = 1", [0.0; 3], 1.0),
    ("ellipsoid", "type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\ntransform = { scale = [1.5, 0.6, 1], rotate = [20, 30, 40], translate = [0.2, 0, 0] }", [0.2, 0.0, 0.0], 1.3),
    ("rotated box", "type = \"box\"\nmin = [-1, -0.5, -0.5]\nmax = [1, 0.5, 0.5]\ntransform = { rotate = [30, 45, 10] }", [0.0; 3], 1.2),
    ("squashed cylinder", "type = \"cylinder\"\nbase = [0, -1, 0]\ntop = [0, 1, 0]\nradius = 0.5\ntransform = { scale = [2, 1, 0.5], rotate = [0, 0, 60] }", [0.0; 3], 1.2),
    ("stretched disk", "type = \"disk\"\ncenter = [0, 0, 0]\nnormal = [0, 0, 1]\nradius = 1\ntransform = { scale = [2, 1, 1], rotate = [50, 0, 0] }", [0.0; 3], 1.5),
    ("mesh", "type = \"mesh\"\npath = \"meshes/icosphere.obj\"\ntransform = { scale = [1, 0.8, 1.2] }", [0.0; 3], 1.1),
];

fn scene(object: &str) -> FlatScene {
    common::scene_from_file_str(
        &format!("{HEADER}{object}\nmaterial = \"m\"\n"),
        "scenes/kernel-test.toml",
    )
}

/// Rays from a sphere of radius 3r around the target toward points inside it, and (one in
/// four) rays started near the center in any direction.
fn rays(center: Vec3, r: f32, n: usize, seed: u32) -> Vec<Ray> {
    let mut rng = seed;
    (0..n)
        .map(|i| {
            if i % 4 == 3 {
                let o = center + 0.3 * r * common::random_unit(&mut rng);
                Ray {
                    origin: o,
                    dir: common::random_unit(&mut rng),
                }
            } else {
                let o = center + 3.0 * r * common::random_unit(&mut rng);
                let target = center + 0.9 * r * common::random_unit(&mut rng);
                Ray {
                    origin: o,
                    dir: (target - o).normalize(),
                }
            }
        })
        .collect()
}

/// Where a render may keep its records, each as the tuning that asks for it
/// (`wgtrace check`'s list): every kernel test runs under each, since a driver may read
/// one placement wrong and not another (Mesa 22.3.6's lavapipe on an AVX-512 CPU reads
/// record textures wrong).
fn placements() -> [(&'static str, Tuning); 4] {
    placement_tunings(&Tuning::default())
}

#[test]
fn gpu_kernel_matches_cpu_ray_by_ray_for_every_primitive() {
    let ctx = common::gpu_context();
    const N: usize = 4096;
    for (i, &(name, object, center, radius)) in OBJECTS.iter().enumerate() {
        let s = scene(object);
        let batch = rays(center.into(), radius, N, 0x9e37 + i as u32);
        let kernel: Vec<KernelRay> = batch.iter().map(common::to_kernel).collect();
        let cpu: Vec<KernelHit> = batch.iter().map(|r| cpu_hit(&s, r)).collect();
        let hits = cpu.iter().filter(|c| c.prim != NO_HIT).count();
        assert!(
            hits >= N / 8,
            "{name}: only {hits} of {N} rays hit; the batch misses the object"
        );
        for (place, tuning) in placements() {
            let gpu = intersect_rays(&ctx, &s, &tuning, &kernel).expect("kernel dispatch");
            let mut disagree = Vec::new();
            for ((r, g), c) in batch.iter().zip(&gpu).zip(&cpu) {
                if let Err(e) = agree(g, c) {
                    disagree.push(format!("{r:?}: {e}\n  gpu {g:?}\n  cpu {c:?}"));
                }
            }
            // Rays that graze an edge may land on either side of it on the two backends;
            // any other difference is a bug. At most 1 in 1000 rays may differ.
            assert!(
                disagree.len() * 1000 <= N,
                "{name}, records in {place}: {} of {N} rays differ, first: {}",
                disagree.len(),
                disagree[0]
            );
            eprintln!(
                "{name}, {place}: {hits} hits, {} rays differ",
                disagree.len()
            );
        }
    }
}

#[test]
fn gpu_bvh_and_brute_force_find_the_same_hits() {
    let ctx = common::gpu_context();
    let mut rng = 21u32;
    let mut src = HEADER.trim_end_matches("[[objects]]\n").to_string();
    for i in 0..200 {
        let p = Vec3::new(
            common::random_f32(&mut rng),
            common::random_f32(&mut rng),
            common::random_f32(&mut rng),
        ) * 8.0
            - 4.0;
        let obj = if i % 2 == 0 {
            format!(
                "type = \"sphere\"\ncenter = [{}, {}, {}]\nradius = 0.4",
                p.x, p.y, p.z
            )
        } else {
            format!(
                "type = \"box\"\nmin = [{}, {}, {}]\nmax = [{}, {}, {}]",
                p.x,
                p.y,
                p.z,
                p.x + 0.5,
                p.y + 0.3,
                p.z + 0.6
            )
        };
        src += &format!("[[objects]]\n{obj}\nmaterial = \"m\"\n");
    }
    bvh_matches_brute_force(&ctx, &src, 2000);
}

/// Spheres about the origin have equal centroids (lo + hi = 0 exactly), so the binary
/// builder keeps them in one leaf, more than a leaf of the wide BVH holds: the collapse
/// cuts it into runs under nodes of their own, whose boxes nest, and the walk must find
/// the same hits as brute force, on both backends.
#[test]
fn gpu_bvh_walks_a_leaf_of_many_primitives() {
    let ctx = common::gpu_context();
    let mut src = HEADER.trim_end_matches("[[objects]]\n").to_string();
    let count = 8 * WIDE_LEAF_SIZE + 5;
    for k in 0..count {
        let radius = 0.3 + 0.25 * k as f32;
        src += &format!(
            "[[objects]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = {radius}\nmaterial = \"m\"\n"
        );
    }
    // past LIST_MAX_PRIMITIVES, so that the scene gets a BVH
    for i in 0..80 {
        let x = -4.0 + 0.1 * i as f32;
        src += &format!(
            "[[objects]]\ntype = \"box\"\nmin = [{x}, -4, -1]\nmax = [{}, -3.8, 1]\nmaterial = \"m\"\n",
            x + 0.08
        );
    }
    let with = common::scene_from_str(&src);
    // the spheres' runs take nodes below the one that holds the boxes' leaves
    assert!(with.bvh_depth >= 2, "depth {}", with.bvh_depth);
    bvh_matches_brute_force(&ctx, &src, 2000);
}

/// The GPU's closest-hit search and shadow rays with the BVH of `src` against brute force
/// (and the CPU's), ray by ray, over rays aimed at the scene's middle.
fn bvh_matches_brute_force(ctx: &wgtrace::gpu::GpuContext, src: &str, min_hits: usize) {
    let with = common::scene_from_str(src);
    let without = common::scene_without_bvh(src);
    let rs = rays(Vec3::ZERO, 4.0, 8192, 77);
    let batch: Vec<KernelRay> = rs.iter().map(common::to_kernel).collect();
    let b = intersect_rays(ctx, &without, &Tuning::default(), &batch).unwrap();
    let cpu: Vec<KernelHit> = rs.iter().map(|r| cpu_hit(&with, r)).collect();
    for (place, tuning) in placements() {
        let a = intersect_rays(ctx, &with, &tuning, &batch).unwrap();
        bvh_agrees(&with, &without, &rs, &a, &b, &cpu, min_hits)
            .unwrap_or_else(|e| panic!("records in {place}: {e}"));
    }
}

/// Whether the GPU's hits `a` with the BVH of `with` agree with the CPU's, `cpu`, and
/// with the GPU's `b` by brute force over `without`, ray by ray over `rs`.
fn bvh_agrees(
    with: &FlatScene,
    without: &FlatScene,
    rs: &[Ray],
    a: &[KernelHit],
    b: &[KernelHit],
    cpu: &[KernelHit],
    min_hits: usize,
) -> Result<(), String> {
    let hits = a.iter().filter(|h| h.prim != NO_HIT).count();
    if hits <= min_hits {
        return Err(format!("only {hits} hits"));
    }
    // the same rule as gpu_kernel_matches_cpu_ray_by_ray_for_every_primitive: rays that
    // graze an edge may land on either side of it, at most 1 in 1000
    let disagree: Vec<String> = a
        .iter()
        .zip(rs)
        .zip(cpu)
        .filter_map(|((g, r), c)| agree(g, c).err().map(|e| format!("{r:?}: {e}")))
        .collect();
    if disagree.len() * 1000 > rs.len() {
        return Err(format!(
            "GPU vs CPU with the BVH: {} of {} rays differ, first: {}",
            disagree.len(),
            rs.len(),
            disagree[0]
        ));
    }
    // without the BVH the primitives are sorted by type, so the same primitive has another
    // index: compare everything else, and the primitive's record
    let record =
        |s: &wgtrace::FlatScene, prim: u32| (prim != NO_HIT).then(|| s.primitives[prim as usize]);
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        let (mut x, mut y) = (*x, *y);
        let same_record = record(with, x.prim) == record(without, y.prim);
        x.prim = 0;
        y.prim = 0;
        if !same_record || x != y {
            return Err(format!("ray {k}: BVH vs brute force: {x:?} against {y:?}"));
        }
    }
    Ok(())
}

/// Instances of a group (analytic shapes, transformed ones and a mesh under a
/// translation, a rotation, a non-uniform scale and a mirror), ray by ray: the GPU's walk
/// into the group's BVH finds what the CPU's does (the same primitive through the same
/// instance, the same point, normals and uv), under every record placement; and both find
/// what the expanded scene (each object placed by the product of the matrices) finds:
/// the same distance, point, geometric normal, side and uv.
#[test]
fn gpu_instances_match_cpu_and_the_expanded_scene() {
    let ctx = common::gpu_context();
    let (instanced, expanded) =
        common::instances::instanced_and_expanded(HEADER.trim_end_matches("[[objects]]\n"));
    let load = |src: &str| common::scene_from_file_str(src, "scenes/kernel-test.toml");
    let (instanced, expanded) = (load(&instanced), load(&expanded));
    let copies = common::instances::placements().len();
    let group_prims = expanded.primitives.len() / copies;
    assert_eq!(
        instanced.primitives.len(),
        group_prims + copies,
        "the group's primitives are stored once"
    );
    const N: usize = 8192;
    let batch = rays(Vec3::ZERO, 2.5, N, 0x1257);
    let kernel: Vec<KernelRay> = batch.iter().map(common::to_kernel).collect();
    let cpu: Vec<KernelHit> = batch.iter().map(|r| cpu_hit(&instanced, r)).collect();
    let through = cpu.iter().filter(|c| c.uv1[2] > 0.0).count();
    assert!(
        through >= N / 4,
        "only {through} of {N} rays hit an instance"
    );
    for (place, tuning) in placements() {
        let gpu = intersect_rays(&ctx, &instanced, &tuning, &kernel).expect("kernel dispatch");
        let disagree: Vec<String> = batch
            .iter()
            .zip(&gpu)
            .zip(&cpu)
            .filter_map(|((r, g), c)| {
                agree(g, c)
                    .err()
                    .map(|e| format!("{r:?}: {e}\n  gpu {g:?}\n  cpu {c:?}"))
            })
            .collect();
        assert!(
            disagree.len() * 1000 <= N,
            "records in {place}: {} of {N} rays differ, first: {}",
            disagree.len(),
            disagree[0]
        );
    }
    // against the expanded scene: rays that graze an edge may land on either side
    let flat: Vec<KernelHit> = batch.iter().map(|r| cpu_hit(&expanded, r)).collect();
    let differ: Vec<String> = batch
        .iter()
        .zip(&cpu)
        .zip(&flat)
        .filter(|((_, a), b)| {
            if (a.prim == NO_HIT) != (b.prim == NO_HIT) {
                return true;
            }
            if a.prim == NO_HIT {
                return false;
            }
            let near = |x: f32, y: f32| (x - y).abs() <= 1e-4 * (1.0 + y.abs());
            let p = (0..3).all(|k| near(a.p[k], b.p[k]));
            let ng = Vec3::from_slice(&a.ng[..3]).dot(Vec3::from_slice(&b.ng[..3])) > 0.9999;
            let uv = (0..2).all(|k| near(a.uv[k], b.uv[k]));
            !(near(a.t, b.t) && p && ng && a.front_face == b.front_face && uv)
        })
        .map(|((r, a), b)| format!("{r:?}\n  instanced {a:?}\n  expanded {b:?}"))
        .collect();
    assert!(
        differ.len() * 1000 <= N,
        "{} of {N} rays differ from the expanded scene, first: {}",
        differ.len(),
        differ[0]
    );
}

// ------------------------------------------------------- materials and lights, GPU vs CPU

use wgtrace::cpu::lights::{
    background_radiance, light_pdf, light_pdf_total, sample_light, sample_punctual,
};
use wgtrace::cpu::materials::{
    bsdf_eval, bsdf_pdf, bsdf_scatter, emitted, material_at, mixture_applies, nee_applies,
};
use wgtrace::cpu::types::Hit;
use wgtrace::gpu::kernel::{sample_lights, shade_materials};
use wgtrace::scene::records::{LightQuery, LightReply, MaterialQuery, MaterialReply, NO_LIGHT};

/// Whether two values agree as the intersection kernel's do: to 1e-4 of their size (the
/// two math libraries' sqrt, sin, cos, exp, pow differ in the last bits), or both
/// negligible.
fn close(a: f32, b: f32) -> bool {
    (a - b).abs() <= 1e-4 * a.abs().max(b.abs()).max(1e-3)
}

/// Whether two pdfs of one sampled direction agree. The pdf a GGX lobe gives its own
/// sample is ill-conditioned in f32: the last bits of the direction move its half
/// vector's cosine by some 5e-7, which moves D by about 14 x 5e-7 sqrt(pdf) / alpha of
/// itself; for the sharpest lobe wgtrace has (alpha = ALPHA_SMOOTH, 1e-3) that is
/// 7e-3 sqrt(pdf): pdfs of 4,000 come out 20% apart on the two backends while the
/// weights, where D cancels, agree to 1e-6. Broad lobes are held to 1e-4 by `eval` and
/// `pdf` toward a fixed direction, which are well conditioned.
fn close_pdf(a: f32, b: f32) -> bool {
    let p = a.abs().max(b.abs());
    (a - b).abs() <= (1e-4 + 8e-3 * p.sqrt()) * p.max(1e-3)
}

fn close3(a: [f32; 4], b: [f32; 4], n: usize) -> bool {
    (0..n).all(|i| close(a[i], b[i]))
}

/// Unit direction `d` as agreeing when they are 1e-4 apart (the intersection kernel's
/// normals: cosine above 0.9999 is 1.4e-2 apart; this is tighter).
fn same_dir(a: [f32; 4], b: [f32; 4]) -> bool {
    Vec3::from_slice(&a[..3]).distance(Vec3::from_slice(&b[..3])) <= 1e-4
}

/// The table's materials (tests/common MATERIALS) and textured ones, each at random hits
/// with random rays, samples and directions: the GPU's material_at, scatter, bsdf_eval,
/// bsdf_pdf, emitted, nee_applies and mixture_applies agree with the CPU's query by query.
/// A sample within rounding of a choice (a lobe, a Fresnel coin) may go either way on the
/// two backends: at most 1 in 1000 queries may differ, as for rays that graze an edge.
#[test]
fn gpu_materials_match_cpu_query_by_query() {
    let ctx = common::gpu_context();
    let mut src = String::from(
        "[camera]\nlook_from = [0, 0, 10]\nlook_at = [0, 0, 0]\n[textures]\n\
         cells = { type = \"checker\", even = [0.9, 0.2, 0.1], odd = \"noise\", scale = 3 }\n\
         noise = { type = \"noise\", scale = 2, color = [1, 0.8, 0.6] }\n\
         bright = { type = \"constant\", color = [2.5, 0.5, 1.5] }\n\
         mr = { type = \"constant\", color = [1, 0.5, 0.8] }\n\
         turned = { type = \"checker\", even = [0.2, 0.3, 0.9], odd = [0.8, 0.7, 0.1], scale = 2, \
         transform = { matrix = [[1.5, -0.7, 0.2], [0.4, 2.5, -0.3]] } }\n",
    );
    let textured = [
        "type = \"lambertian\"\nalbedo = \"cells\"",
        "type = \"microfacet\"\nalbedo = [0.5, 0.5, 0.5]\nspecular = \"bright\"\nroughness = 0.3",
        "type = \"pbr\"\nbase_color = \"noise\"\nspecular_color = \"bright\"\nmetallic = 0.4\n\
         roughness = 0.6\nmetallic_roughness = \"mr\"\nspecular_texture = \"mr\"",
        "type = \"emissive\"\nradiance = \"cells\"\ntwo_sided = true",
        "type = \"dielectric\"\nior = 1.7\ntint = \"noise\"\nabsorption = [0.3, 0.1, 0.05]",
        "type = \"lambertian\"\nalbedo = \"turned\"",
        "type = \"dielectric\"\nior = 1.4\ntint = [0.9, 0.9, 0.9]\nspecular = \"turned\"\nroughness = 0.4",
    ];
    let keys: Vec<&str> = common::MATERIALS
        .iter()
        .map(|t| t.keys)
        .chain(textured)
        .collect();
    for (i, k) in keys.iter().enumerate() {
        src += &format!("[materials.m{i:02}]\n{k}\n");
    }
    src += "[[objects]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m00\"\n";
    for shading in ["bend", "strict"] {
        let s =
            common::scene_from_str(&format!("[render]\nshading_normals = \"{shading}\"\n{src}"));
        let b = Bindings::new(&s, s.params(0, s.full_band()));
        let mut rng = 0x5eed_u32;
        let mut queries = Vec::new();
        for m in 0..keys.len() as u32 {
            for _ in 0..256 {
                let ng = common::random_unit(&mut rng);
                // a shading normal on ng's side, tilted up to about 35 degrees
                let ns = (ng + 0.7 * common::random_unit(&mut rng)).normalize();
                let ns = if ns.dot(ng) > 0.05 { ns } else { ng };
                // half the hits normal-mapped: ns turned from another shading normal
                let unmapped = (ng + 0.4 * common::random_unit(&mut rng)).normalize();
                let unmapped = if common::random_f32(&mut rng) < 0.5 && unmapped.dot(ng) > 0.05 {
                    unmapped
                } else {
                    ns
                };
                let front = common::random_f32(&mut rng) < 0.5;
                let mut dir = common::random_unit(&mut rng);
                if (dir.dot(ng) < 0.0) != front {
                    dir = -dir;
                }
                let p = 2.0 * common::random_unit(&mut rng);
                queries.push(MaterialQuery {
                    material: m,
                    front_face: front as u32,
                    origin: (p - 1.5 * dir).extend(0.0).to_array(),
                    dir: dir.extend(0.0).to_array(),
                    p: p.extend(0.0).to_array(),
                    ng: ng.extend(0.0).to_array(),
                    ns: ns.extend(0.0).to_array(),
                    unmapped: unmapped.extend(0.0).to_array(),
                    uv: [
                        common::random_f32(&mut rng),
                        common::random_f32(&mut rng),
                        common::random_f32(&mut rng),
                        common::random_f32(&mut rng),
                    ],
                    wi: common::random_unit(&mut rng).extend(0.0).to_array(),
                    // the table's scenes have one uv set and no vertex colours
                    color: [1.0; 4],
                    ..Default::default()
                });
                let q = queries.last_mut().unwrap();
                q.uv1 = [q.uv[0], q.uv[1], 0.0, 0.0];
            }
        }
        let cpu = |q: &MaterialQuery| -> MaterialReply {
            let ray = Ray {
                origin: Vec3::from_slice(&q.origin[..3]),
                dir: Vec3::from_slice(&q.dir[..3]),
            };
            let hit = Hit {
                p: Vec3::from_slice(&q.p[..3]),
                ng: Vec3::from_slice(&q.ng[..3]),
                ns: Vec3::from_slice(&q.ns[..3]),
                unmapped: Vec3::from_slice(&q.unmapped[..3]),
                uv: glam::Vec4::new(q.uv[0], q.uv[1], q.uv1[0], q.uv1[1]),
                front_face: q.front_face != 0,
                material: q.material,
                err: 0.0,
                tangent: glam::Vec4::ZERO,
                color: glam::Vec4::from(q.color),
                dpdu: glam::Vec3::ZERO,
                dpdv: glam::Vec3::ZERO,
            };
            let mat = material_at(&b, &s.materials[q.material as usize], &hit);
            let sc = bsdf_scatter(&mat, &ray, &hit, [q.uv[2], q.uv[3]]);
            let wi = Vec3::from_slice(&q.wi[..3]);
            MaterialReply {
                flags: sc.ok as u32
                    | (sc.delta as u32) << 1
                    | (nee_applies(&mat) as u32) << 2
                    | (mixture_applies(&mat) as u32) << 3,
                dir: sc.dir.extend(sc.pdf).to_array(),
                weight: sc.weight.extend(0.0).to_array(),
                eval: bsdf_eval(&mat, &ray, &hit, wi)
                    .extend(bsdf_pdf(&mat, &ray, &hit, wi))
                    .to_array(),
                emitted: emitted(&mat, &hit).extend(0.0).to_array(),
                ..Default::default()
            }
        };
        let agree = |g: &MaterialReply, c: &MaterialReply| -> Result<(), &'static str> {
            if g.flags != c.flags {
                return Err("flags");
            }
            if !close3(g.eval, c.eval, 4) {
                return Err("eval or pdf toward wi");
            }
            if !close3(g.emitted, c.emitted, 3) {
                return Err("emitted");
            }
            if c.flags & 1 != 0
                && !(same_dir(g.dir, c.dir)
                    && close_pdf(g.dir[3], c.dir[3])
                    && close3(g.weight, c.weight, 3))
            {
                return Err("scatter");
            }
            Ok(())
        };
        let cpu_replies: Vec<MaterialReply> = queries.iter().map(cpu).collect();
        // strict shading normals in the first placement only: the others read the same records
        let places = if shading == "bend" { usize::MAX } else { 1 };
        for (place, tuning) in placements().into_iter().take(places) {
            let gpu = shade_materials(&ctx, &s, &tuning, &queries).expect("kernel dispatch");
            let mut disagree = Vec::new();
            let mut scattered = 0;
            for ((q, g), c) in queries.iter().zip(&gpu).zip(&cpu_replies) {
                scattered += (c.flags & 1) as usize;
                if let Err(what) = agree(g, c) {
                    disagree.push(format!(
                        "{} ({what}): {q:?}\n  gpu {g:?}\n  cpu {c:?}",
                        keys[q.material as usize]
                    ));
                }
            }
            assert!(
                disagree.len() * 1000 <= queries.len(),
                "records in {place}, {shading} shading normals: {} of {} queries differ, first: {}",
                disagree.len(),
                queries.len(),
                disagree[0]
            );
            assert!(scattered > queries.len() / 3, "only {scattered} scattered");
            eprintln!(
                "{place}, {shading} shading normals: {} materials, {} queries, {scattered} scattered, {} differ",
                keys.len(),
                queries.len(),
                disagree.len()
            );
        }
    }
}

/// Scenes of every kind of light (triangles of a quad and a polygon, a disk, spheres,
/// the image background, points, spots and a directional light), sampled from random
/// points (some inside a sphere light) toward random choices: the GPU's sample_light, the
/// light_pdf of what it sampled, light_pdf_total and background_radiance of a random
/// direction, and sample_punctual (point, spot, textured spot, directional, projector) agree with the CPU's query by query (at most 1 in 1000
/// may differ, as a choice within rounding of a CDF step may go either way).
#[test]
fn gpu_lights_match_cpu_query_by_query() {
    let ctx = common::gpu_context();
    const HEAD: &str = "[camera]\nlook_from = [0, 0, 10]\nlook_at = [0, 0, 0]\n[materials]\n\
        grey = { type = \"lambertian\", albedo = [0.5, 0.5, 0.5] }\n\
        lamp = { type = \"emissive\", radiance = [4, 3, 2] }\n\
        both = { type = \"emissive\", radiance = [1, 2, 3], two_sided = true }\n\
        [[objects]]\ntype = \"plane\"\npoint = [0, -3, 0]\nnormal = [0, 1, 0]\nmaterial = \"grey\"\n";
    let scenes = [
        (
            "triangles",
            "[[objects]]\ntype = \"polygon\"\nvertices = [[-1, 2, -1], [1, 2, -1], [1.4, 2.2, 1], [-1, 2.2, 1]]\nmaterial = \"lamp\"\n\
             [[objects]]\ntype = \"triangle\"\nvertices = [[2, -1, 0], [3, 0, 0.5], [2, 1, 0]]\nmaterial = \"both\"\n",
        ),
        (
            "disks",
            "[[objects]]\ntype = \"disk\"\ncenter = [0, 2.5, 0]\nnormal = [0.2, -1, 0.1]\nradius = 0.8\nmaterial = \"lamp\"\n\
             [[objects]]\ntype = \"disk\"\ncenter = [-2, 0, 0]\nnormal = [1, 0, 0]\nradius = 0.3\nmaterial = \"both\"\n",
        ),
        (
            "spheres",
            "[[objects]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1.5\nmaterial = \"lamp\"\n\
             [[objects]]\ntype = \"sphere\"\ncenter = [2.5, 1, -1]\nradius = 0.05\nmaterial = \"both\"\n",
        ),
        (
            "image background",
            "[textures]\nsky = { type = \"image\", path = \"textures/sky.hdr\" }\n\
             [background]\ntexture = \"sky\"\nrotation = 30\nstrength = 0.7\n\
             [[objects]]\ntype = \"sphere\"\ncenter = [0, 2, 0]\nradius = 0.5\nmaterial = \"lamp\"\n",
        ),
        (
            "punctual",
            "[background]\ntop = [0.4, 0.6, 1]\nbottom = [1, 1, 1]\n\
             [[lights]]\ntype = \"point\"\nposition = [0, 2, 0]\nintensity = [5, 5, 5]\n\
             [[lights]]\ntype = \"spot\"\nposition = [1, 2, 1]\nlook_at = [0, -3, 0]\nintensity = [20, 15, 10]\ninner_angle = 15\nouter_angle = 35\n\
             [[lights]]\ntype = \"spot\"\nposition = [-1, 2, 0.5]\nlook_at = [0, -3, 0]\nintensity = [8, 12, 10]\ninner_angle = 10\nouter_angle = 40\nfalloff = \"mitsuba\"\n\
             [[lights]]\ntype = \"directional\"\ndirection = [0.3, 1, 0.2]\nirradiance = [1, 1, 0.8]\n\
             [[objects]]\ntype = \"triangle\"\nvertices = [[-1, 2.5, -1], [1, 2.5, -1], [0, 2.5, 1]]\nmaterial = \"both\"\n",
        ),
        (
            "projectors",
            "[textures]\nsky = { type = \"image\", path = \"textures/sky.hdr\" }\n\
             [[lights]]\ntype = \"projector\"\nposition = [0, 3, 1]\nlook_at = [0, 0, 0]\nfov = 70\nirradiance = \"sky\"\nscale = 3\n\
             [[lights]]\ntype = \"projector\"\nposition = [1, -1, 2]\nlook_at = [0, 0, 0]\nup = [1, 0, 0]\nfov = 30\nirradiance = [1, 0.5, 0.25]\n\
             [[lights]]\ntype = \"spot\"\nposition = [-1, 2, 1]\nlook_at = [0, 0, 0]\nup = [1, 0, 0]\nintensity = [5, 4, 3]\nouter_angle = 50\nfalloff = \"mitsuba\"\ntexture = \"sky\"\n\
             [[objects]]\ntype = \"triangle\"\nvertices = [[-1, 2.5, -1], [1, 2.5, -1], [0, 2.5, 1]]\nmaterial = \"both\"\n",
        ),
    ];
    for (name, objects) in scenes {
        let s = common::scene_from_file_str(&format!("{HEAD}{objects}"), "scenes/lights-test.toml");
        let b = Bindings::new(&s, s.params(0, s.full_band()));
        let mut rng = 0xc0ffee_u32;
        let queries: Vec<LightQuery> = (0..4096)
            .map(|_| {
                let p = 1.6 * common::random_unit(&mut rng) * common::random_f32(&mut rng);
                let mut u = || common::random_f32(&mut rng);
                let (ul, u0, u1, u2) = (u(), u(), u(), u());
                LightQuery {
                    p: p.extend(ul).to_array(),
                    u: [u0, u1, u2, 0.0],
                    d: common::random_unit(&mut rng).extend(0.0).to_array(),
                }
            })
            .collect();
        let cpu = |q: &LightQuery| -> LightReply {
            let p = Vec3::from_slice(&q.p[..3]);
            let d = Vec3::from_slice(&q.d[..3]);
            let ls = sample_light(&b, p, q.p[3], [q.u[0], q.u[1]]);
            let sampled = if ls.light != NO_LIGHT {
                light_pdf(&b, ls.light, p, p + ls.dist * ls.dir, ls.dir)
            } else {
                0.0
            };
            let mut r = LightReply {
                light: ls.light,
                punctual: NO_LIGHT,
                dir: ls.dir.extend(ls.dist).to_array(),
                pdf: [ls.pdf, sampled, light_pdf_total(&b, p, d), 0.0],
                uv: [ls.uv.x, ls.uv.y, 0.0, 0.0],
                background: background_radiance(&b, d).extend(0.0).to_array(),
                ..Default::default()
            };
            if s.num_punctual != 0 {
                let ps = sample_punctual(&b, p, q.u[2]);
                r.punctual = ps.light;
                r.punctual_dir = ps.dir.extend(ps.d2).to_array();
                r.punctual_le = ps.le.extend(ps.prob).to_array();
            }
            r
        };
        let agree = |q: &LightQuery, g: &LightReply, c: &LightReply| -> Result<(), &'static str> {
            if (g.light, g.punctual) != (c.light, c.punctual) {
                return Err("the light chosen");
            }
            if !close3(g.pdf, c.pdf, 3) {
                return Err("a pdf");
            }
            if !close3(g.background, c.background, 3) {
                return Err("the background");
            }
            // the point sampled on a light: its direction from a point just off the light
            // is ill-conditioned (1e-6 of the scene over a distance of 1e-3), the point not
            let point = |r: &LightReply| {
                Vec3::from_slice(&q.p[..3]) + r.dir[3] * Vec3::from_slice(&r.dir[..3])
            };
            let sample_agrees = if c.dir[3] < FAR {
                (point(g) - point(c)).length() <= 1e-5 * (1.0 + point(c).length())
                    && close3(g.uv, c.uv, 2)
            } else {
                same_dir(g.dir, c.dir)
            };
            if c.light != NO_LIGHT && !sample_agrees {
                return Err("the sample");
            }
            if c.punctual != NO_LIGHT
                && !(same_dir(g.punctual_dir, c.punctual_dir)
                    && close3(g.punctual_dir, c.punctual_dir, 4)
                    && close3(g.punctual_le, c.punctual_le, 4))
            {
                return Err("the light without a surface");
            }
            Ok(())
        };
        let cpu_replies: Vec<LightReply> = queries.iter().map(cpu).collect();
        for (place, tuning) in placements() {
            let gpu = sample_lights(&ctx, &s, &tuning, &queries).expect("kernel dispatch");
            let mut disagree = Vec::new();
            let mut sampled = 0;
            for ((q, g), c) in queries.iter().zip(&gpu).zip(&cpu_replies) {
                sampled += (c.light != NO_LIGHT) as usize;
                if let Err(what) = agree(q, g, c) {
                    disagree.push(format!("{what}: {q:?}\n  gpu {g:?}\n  cpu {c:?}"));
                }
            }
            assert!(
                disagree.len() * 1000 <= queries.len(),
                "{name}, records in {place}: {} of {} queries differ, first: {}",
                disagree.len(),
                queries.len(),
                disagree[0]
            );
            assert!(
                sampled > queries.len() / 2,
                "{name}: only {sampled} sampled"
            );
            eprintln!(
                "{name}, {place}: {} lights, {sampled} of {} sampled, {} differ",
                s.emitters.len(),
                queries.len(),
                disagree.len()
            );
        }
    }
}

/// Whole camera paths on the GPU against the CPU reference, state by state: the
/// kernel's `paths_main` traces each pixel's path with the render's camera ray and
/// `extend_path`, and reports the ray, throughput and radiance after every bounce; the
/// CPU's `extend_path` gives the same states (`check::cpu_path_steps`). Scenes that
/// take each stage's branches: next-event estimation under MIS, the mixture and the
/// material's own sampling, lights without a surface, alpha pass-through, blends,
/// delta lobes, textures and normal maps, an environment light, Russian roulette, and
/// media (the fog box of scenes/fog.toml: free flights, scattering points, shadow rays'
/// transmittance through null boundaries, a glass sphere holding a medium; the smoke of
/// scenes/smoke.toml: delta and ratio tracking through a density grid). A
/// random number within rounding of a choice (a lobe, a roulette coin, a grazing edge)
/// may send a path another way on the two backends: at most 1 in 100 paths may differ
/// (the ray kernel's 1 in 1000 per decision, over a path's handful of bounces).
#[test]
fn gpu_paths_match_cpu_bounce_by_bounce() {
    use wgtrace::check::{cpu_path_steps, path_agree};
    use wgtrace::gpu::kernel::trace_paths;
    use wgtrace::scene::format::LightSampling;
    use wgtrace::scene::records::{PathQuery, PATH_STEPS};
    use wgtrace::Overrides;

    let ctx = common::gpu_context();
    let cases: &[(&str, Option<LightSampling>)] = &[
        ("scenes/cornell.toml", None),
        ("scenes/cornell.toml", Some(LightSampling::Mixture)),
        ("scenes/cornell.toml", Some(LightSampling::Bsdf)),
        ("scenes/materials.toml", None),
        ("scenes/punctual.toml", None),
        ("scenes/textures.toml", None),
        ("scenes/sky.toml", None),
        ("bench/mask.toml", None),
        ("bench/blend.toml", None),
        ("scenes/fog.toml", None),
        ("scenes/fog.toml", Some(LightSampling::Bsdf)),
        ("scenes/smoke.toml", None),
        ("scenes/smoke.toml", Some(LightSampling::Bsdf)),
    ];
    const SIDE: u32 = 16;
    for &(file, light_sampling) in cases {
        let overrides = Overrides {
            width: Some(SIDE),
            height: Some(SIDE),
            light_sampling,
            ..Overrides::default()
        };
        let scene = wgtrace::load_scene(&common::repo_path(file), &overrides)
            .unwrap_or_else(|e| panic!("{e}"));
        let queries: Vec<PathQuery> = (0..2 * SIDE * SIDE)
            .map(|i| PathQuery {
                x: i % SIDE,
                y: (i / SIDE) % SIDE,
                sample: 7 * (i / (SIDE * SIDE)),
                pad0: 0,
            })
            .collect();
        let gpu = trace_paths(&ctx, &scene, &Tuning::default(), &queries).expect("kernel dispatch");
        let n = PATH_STEPS as usize;
        let mut disagree = Vec::new();
        let mut bounces = 0.0;
        for (q, g) in queries.iter().zip(gpu.chunks_exact(n)) {
            let c = cpu_path_steps(&scene, q);
            bounces += c.iter().map(|s| s.throughput[3]).fold(0.0, f32::max);
            if let Err(e) = path_agree(g, &c) {
                disagree.push(format!("{q:?}: {e}"));
            }
        }
        let what = format!("{file} ({light_sampling:?})");
        let mean = bounces / queries.len() as f32;
        assert!(mean >= 1.5, "{what}: paths of {mean} bounces test little");
        assert!(
            disagree.len() * 100 <= queries.len(),
            "{what}: {} of {} paths differ, first: {}",
            disagree.len(),
            queries.len(),
            disagree[0]
        );
        eprintln!(
            "{what}: {} paths of {mean:.2} bounces on average, {} differ",
            queries.len(),
            disagree.len()
        );
    }
}
