//! The GPU intersection kernel against the CPU reference, ray by ray: for each primitive
//! type (and transformed and mesh variants), a batch of rays aimed at the object and rays
//! started inside it go through the GPU's closest-hit search and surface_at in one small
//! dispatch, and every field is compared with the CPU functions of the same names, the
//! shadow-ray search (`occluded`) included. The BVH and brute force give the same hits on
//! the GPU too.

mod common;

use glam::{Vec3, Vec4};
use wgtrace::cpu::bindings::Bindings;
use wgtrace::cpu::intersect::{intersect_scene, occluded, surface_at};
use wgtrace::cpu::types::{Ray, FAR, NO_HIT};
use wgtrace::gpu::kernel::intersect_rays;
use wgtrace::gpu::plan::{scene_features, Feature};
use wgtrace::scene::records::{KernelHit, KernelRay, BVH_COUNT_MASK};
use wgtrace::FlatScene;

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

/// The CPU reference's answer in the kernel's record.
fn cpu_hit(scene: &FlatScene, r: &Ray) -> KernelHit {
    let b = Bindings::new(scene, scene.params(0, scene.full_tile()));
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
    }
    out
}

/// Angles in uv wrap around: 0.999 and 0.001 are 0.002 apart.
fn uv_distance(a: f32, b: f32) -> f32 {
    let d = (a - b).abs();
    d.min((1.0 - d).abs())
}

/// Whether two answers for one ray agree: same primitive and side; t, point, normals and
/// uv within a few ulps of f32 on different math libraries (atan2, acos, sqrt).
fn agree(g: &KernelHit, c: &KernelHit) -> Result<(), String> {
    if g.prim != c.prim {
        return Err(format!("prim {} vs {}", g.prim, c.prim));
    }
    // a shadow ray to infinity is blocked exactly when there is a hit, and nothing lies
    // before the closest hit (0.999 t: at t itself, rounding decides)
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
        (
            "uv",
            uv_distance(g.uv[0], c.uv[0]) <= 1e-3 * (1.0 + c.uv[0].abs())
                && rel(g.uv[1], c.uv[1], 1e-3),
        ),
        (
            "candidate uv",
            rel(g.uv[2], c.uv[2], 1e-3) && rel(g.uv[3], c.uv[3], 1e-3),
        ),
    ];
    match checks.iter().find(|(_, ok)| !ok) {
        Some((what, _)) => Err(format!("{what} differs")),
        None => Ok(()),
    }
}

#[test]
fn gpu_kernel_matches_cpu_ray_by_ray_for_every_primitive() {
    let ctx = common::gpu_context();
    const N: usize = 4096;
    for (i, &(name, object, center, radius)) in OBJECTS.iter().enumerate() {
        let s = scene(object);
        let batch = rays(center.into(), radius, N, 0x9e37 + i as u32);
        let kernel: Vec<KernelRay> = batch.iter().map(common::to_kernel).collect();
        let gpu = intersect_rays(&ctx, &s, &kernel).expect("kernel dispatch");
        let mut hits = 0;
        let mut disagree = Vec::new();
        for (r, g) in batch.iter().zip(&gpu) {
            let c = cpu_hit(&s, r);
            hits += (c.prim != NO_HIT) as usize;
            if let Err(e) = agree(g, &c) {
                disagree.push(format!("{r:?}: {e}\n  gpu {g:?}\n  cpu {c:?}"));
            }
        }
        // Rays that graze an edge may land on either side of it on the two backends; any
        // other difference is a bug. At most 1 in 1000 rays may differ.
        assert!(
            disagree.len() * 1000 <= N,
            "{name}: {} of {N} rays differ, first: {}",
            disagree.len(),
            disagree[0]
        );
        assert!(
            hits >= N / 8,
            "{name}: only {hits} of {N} rays hit; the batch misses the object"
        );
        eprintln!("{name}: {hits} hits, {} rays differ", disagree.len());
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

/// Spheres about the origin have equal centroids (lo + hi = 0 exactly), so the builder keeps them in one leaf, larger
/// than a traversal stack entry's count holds: the walk must read that leaf's node
/// (HAS_BVH_LARGE_LEAVES) and find the same hits as brute force, on both backends.
#[test]
fn gpu_bvh_walks_a_leaf_of_many_primitives() {
    let ctx = common::gpu_context();
    let mut src = HEADER.trim_end_matches("[[objects]]\n").to_string();
    let count = 2 * BVH_COUNT_MASK + 3;
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
    let leaf = with.bvh.iter().map(|n| n.count).max().unwrap();
    assert!(
        leaf >= count,
        "the spheres are not one leaf (largest {leaf})"
    );
    assert!(with.bvh_has_large_leaves());
    assert!(scene_features(&with).contains(Feature::BvhLargeLeaves));
    bvh_matches_brute_force(&ctx, &src, 2000);
}

/// The GPU's closest-hit search and shadow rays with the BVH of `src` against brute force
/// (and the CPU's), ray by ray, over rays aimed at the scene's middle.
fn bvh_matches_brute_force(ctx: &wgtrace::gpu::GpuContext, src: &str, min_hits: usize) {
    let with = common::scene_from_str(src);
    let without = common::scene_without_bvh(src);
    let rs = rays(Vec3::ZERO, 4.0, 8192, 77);
    let batch: Vec<KernelRay> = rs.iter().map(common::to_kernel).collect();
    let a = intersect_rays(ctx, &with, &batch).unwrap();
    let b = intersect_rays(ctx, &without, &batch).unwrap();
    let hits = a.iter().filter(|h| h.prim != NO_HIT).count();
    assert!(hits > min_hits, "only {hits} hits");
    // the same rule as gpu_kernel_matches_cpu_ray_by_ray_for_every_primitive: rays that
    // graze an edge may land on either side of it, at most 1 in 1000
    let disagree: Vec<String> = a
        .iter()
        .zip(&rs)
        .filter_map(|(g, r)| {
            agree(g, &cpu_hit(&with, r))
                .err()
                .map(|e| format!("{r:?}: {e}"))
        })
        .collect();
    assert!(
        disagree.len() * 1000 <= rs.len(),
        "GPU vs CPU with the BVH: {} of {} rays differ, first: {}",
        disagree.len(),
        rs.len(),
        disagree[0]
    );
    // without the BVH the primitives are sorted by type, so the same primitive has another
    // index: compare everything else, and the primitive's record
    let record =
        |s: &wgtrace::FlatScene, prim: u32| (prim != NO_HIT).then(|| s.primitives[prim as usize]);
    for (k, (x, y)) in a.iter().zip(&b).enumerate() {
        assert_eq!(
            record(&with, x.prim),
            record(&without, y.prim),
            "ray {k}: BVH vs brute force"
        );
        let (mut x, mut y) = (*x, *y);
        x.prim = 0;
        y.prim = 0;
        assert_eq!(x, y, "ray {k}: BVH vs brute force");
    }
}
