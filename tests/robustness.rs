//! Hard cases stay numerically stable, on both backends: non-finite samples, watertight
//! meshes, scale and translation, tiny and huge spheres, degenerate directions, glass,
//! microfacet roughness near zero, tiny bright lights, very long paths, bad geometry, and
//! f32 intersections against f64. docs/robustness.md describes each case and its fix.

mod common;

use std::path::{Path, PathBuf};

use common::shapes::{intersect_box, intersect_cylinder, intersect_sphere, intersect_triangle};
use common::{image_mean, random_f32, random_unit, render_cpu, render_gpu};
use glam::{DVec3, Vec3};
use wgtrace::cpu::bindings::Bindings;
use wgtrace::cpu::geometry::intersect_plane;
use wgtrace::cpu::intersect::intersect_scene;
use wgtrace::cpu::trace::accumulate;
use wgtrace::cpu::types::{Ray, FAR, NO_HIT};
use wgtrace::gpu::kernel::intersect_rays;
use wgtrace::scene::records::KernelRay;
use wgtrace::{FlatScene, Overrides};

fn ray(o: Vec3, d: Vec3) -> Ray {
    Ray {
        origin: o,
        dir: d.normalize(),
    }
}

fn tmp_dir(name: &str) -> PathBuf {
    common::tmp_dir(&format!("robust-{name}"))
}

fn load(src: &str, dir: &Path, o: &Overrides) -> FlatScene {
    wgtrace::load_scene_str(src, &dir.join("scene.toml"), o).unwrap_or_else(|e| panic!("{e}"))
}

/// A sample that is NaN, infinite, or whose square overflows is dropped and counted; the
/// others add to the sums. (The shader's main does the same by the same bit test.)
#[test]
fn non_finite_samples_are_dropped_and_counted() {
    let (mut sum, mut sq) = ([0.0f32; 4], [0.0f32; 4]);
    for c in [
        Vec3::new(1.0, 2.0, 3.0),
        Vec3::new(f32::NAN, 0.0, 0.0),
        Vec3::new(0.0, f32::INFINITY, 0.0),
        Vec3::new(0.0, 0.0, f32::NEG_INFINITY),
        Vec3::new(2e19, 0.0, 0.0),
        Vec3::new(0.5, 0.5, 0.5),
    ] {
        accumulate(&mut sum, &mut sq, c);
    }
    assert_eq!(sum, [1.5, 2.5, 3.5, 2.0]);
    assert_eq!(sq, [1.25, 4.25, 9.25, 4.0]);
}

/// Reads the positions and triangles of an OBJ (only `v` and `f` lines).
fn read_obj(path: &Path) -> (Vec<Vec3>, Vec<[usize; 3]>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut v = Vec::new();
    let mut f = Vec::new();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let p: Vec<f32> = it.take(3).map(|x| x.parse().unwrap()).collect();
                v.push(Vec3::new(p[0], p[1], p[2]));
            }
            Some("f") => {
                let idx: Vec<usize> = it
                    .map(|x| x.split('/').next().unwrap().parse::<usize>().unwrap() - 1)
                    .collect();
                f.push([idx[0], idx[1], idx[2]]);
            }
            _ => {}
        }
    }
    (v, f)
}

/// The committed icosphere (642 vertices, 1280 triangles) with every vertex moved by up to
/// 5% of the radius, shared vertices moving together: closed, irregular, no symmetric edges.
fn jittered_sphere(dir: &Path) -> (Vec<Vec3>, Vec<[usize; 3]>) {
    let (mut v, f) = read_obj(&common::repo_path("scenes/meshes/icosphere.obj"));
    let mut state = 777u32;
    for p in &mut v {
        *p = *p * (1.0 + 0.1 * (random_f32(&mut state) - 0.5)) + 0.03 * random_unit(&mut state);
    }
    let mut obj = String::new();
    for p in &v {
        obj += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    for t in &f {
        obj += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    std::fs::write(dir.join("jittered.obj"), obj).unwrap();
    (v, f)
}

/// Moeller-Trumbore as the renderer had it before the watertight test, for comparison.
fn moeller_trumbore(v0: Vec3, v1: Vec3, v2: Vec3, r: &Ray) -> bool {
    let (e1, e2) = (v1 - v0, v2 - v0);
    let pv = r.dir.cross(e2);
    let det = e1.dot(pv);
    if det == 0.0 {
        return false;
    }
    let inv = 1.0 / det;
    let tv = r.origin - v0;
    let b1 = tv.dot(pv) * inv;
    if !(0.0..=1.0).contains(&b1) {
        return false;
    }
    let qv = tv.cross(e1);
    let b2 = r.dir.dot(qv) * inv;
    if b2 < 0.0 || b1 + b2 > 1.0 {
        return false;
    }
    e2.dot(qv) * inv > 0.0
}

/// 100,000 rays from inside a closed, jittered triangulated sphere, a third of them aimed
/// exactly at vertices and a third at edge midpoints: every one hits, on the CPU and on the
/// GPU (the kernel runs the shader's search). Moeller-Trumbore on the same rays lets some
/// through (printed). A furnace inside it (walls emitting 1, albedo 0.5) shows exactly
/// 2 (1 - 0.5^24) in every pixel under BSDF sampling without Russian roulette, on both
/// backends: no light leaks.
#[test]
fn a_closed_mesh_is_watertight_and_its_furnace_does_not_leak() {
    let dir = tmp_dir("watertight");
    let (v, f) = jittered_sphere(&dir);
    let src = r#"
[render]
width = 24
height = 24
spp = 16
max_depth = 24
light_sampling = "bsdf"
[camera]
look_from = [0.05, 0.02, 0.1]
look_at = [0.4, -0.3, -1]
vfov = 110
[materials]
wall = { type = "lambertian", albedo = [0.5, 0.5, 0.5], emission = [1, 1, 1], two_sided = true }
[[objects]]
type = "mesh"
path = "jittered.obj"
material = "wall"
"#;
    // every path runs all 24 rays, so each pixel is exactly the sum (Russian roulette
    // would make it a random estimate of it)
    let no_rr = wgtrace::Tuning::parse("no-russian-roulette")
        .unwrap()
        .build();
    let scene =
        wgtrace::scene::load_str(src, &dir.join("scene.toml"), &Overrides::default(), no_rr)
            .unwrap_or_else(|e| panic!("{e}"));
    let b = Bindings::new(&scene, scene.params(0, scene.full_band()));
    let mut state = 4242u32;
    let mut rays = Vec::new();
    for i in 0..100_000 {
        let o = random_unit(&mut state) * (0.4 * random_f32(&mut state));
        let t = &f[i % f.len()];
        let target = match i % 3 {
            0 => v[t[i % 3]],
            1 => 0.5 * (v[t[0]] + v[t[1]]),
            _ => o + random_unit(&mut state),
        };
        rays.push(ray(o, target - o));
    }
    let cpu_miss = rays
        .iter()
        .filter(|r| intersect_scene(&b, r, FAR).prim == NO_HIT)
        .count();
    let kernel: Vec<KernelRay> = rays.iter().map(common::to_kernel).collect();
    let gpu = intersect_rays(&common::gpu_context(), &scene, &Default::default(), &kernel).unwrap();
    let gpu_miss = gpu.iter().filter(|h| h.prim == NO_HIT).count();
    let mt_miss = rays
        .iter()
        .filter(|r| {
            !f.iter()
                .any(|t| moeller_trumbore(v[t[0]], v[t[1]], v[t[2]], r))
        })
        .count();
    eprintln!(
        "watertight: CPU {cpu_miss}, GPU {gpu_miss} of 100000 rays miss; \
         Moeller-Trumbore {mt_miss}"
    );
    assert_eq!((cpu_miss, gpu_miss), (0, 0));

    let expected = 2.0 * (1.0 - 0.5f32.powi(24));
    for (name, img) in [("gpu", render_gpu(&scene)), ("cpu", render_cpu(&scene))] {
        let bad = (0..img.pixel_count())
            .filter(|&i| (0..3).any(|c| (img.mean(i)[c] - expected).abs() > 1e-4))
            .count();
        assert_eq!(bad, 0, "{name}: {bad} pixels leak");
    }
    // with Russian roulette (the default) each pixel is a random estimate of the same
    // value, and unbiased: the image mean lies within 4 standard errors of it (the error
    // from the pixels' own sample variances), and paths did end early (the variance is
    // not zero)
    let scene = load(src, &dir, &Overrides::default());
    for (name, img) in [("gpu", render_gpu(&scene)), ("cpu", render_cpu(&scene))] {
        let n = img.pixel_count();
        let mean = (0..n).map(|i| img.mean(i)[0] as f64).sum::<f64>() / n as f64;
        let var_of_mean = (0..n)
            .map(|i| img.variance(i)[0] as f64 / img.samples(i) as f64)
            .sum::<f64>()
            / (n * n) as f64;
        let se = var_of_mean.sqrt();
        assert!(se > 0.0, "{name}: no path was stopped early");
        assert!(
            (mean - expected as f64).abs() <= 4.0 * se,
            "{name}: mean {mean} against {expected}, standard error {se}"
        );
    }
}

/// The Cornell box scaled by 1e-3 and 1e4, and moved 1e4 along each axis (camera with it),
/// renders the same image within noise on the GPU: no acne, no leaks, the light (2e-3
/// below the ceiling) still separate from it.
#[test]
fn the_cornell_box_is_the_same_at_every_scale_and_position() {
    let text = std::fs::read_to_string(common::repo_path("scenes/cornell.toml")).unwrap();
    let place = |scale: f64, shift: [f64; 3]| -> String {
        let mut doc: toml::Table = text.parse().unwrap();
        let map = |v: &toml::Value| -> toml::Value {
            let a: Vec<f64> = v
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_float().or(x.as_integer().map(|i| i as f64)).unwrap())
                .collect();
            toml::Value::Array(
                (0..3)
                    .map(|i| toml::Value::Float(a[i] * scale + shift[i]))
                    .collect(),
            )
        };
        let cam = doc["camera"].as_table_mut().unwrap();
        for key in ["look_from", "look_at"] {
            let v = map(&cam[key]);
            cam.insert(key.into(), v);
        }
        for obj in doc["objects"].as_array_mut().unwrap() {
            let t = obj.as_table_mut().unwrap();
            if let Some(vs) = t.get("vertices").cloned() {
                let moved = vs.as_array().unwrap().iter().map(map).collect();
                t.insert("vertices".into(), toml::Value::Array(moved));
            }
            if let Some(c) = t.get("center").cloned() {
                t.insert("center".into(), map(&c));
                let r = t["radius"].as_float().unwrap();
                t.insert("radius".into(), toml::Value::Float(r * scale));
            }
        }
        toml::to_string(&doc).unwrap()
    };
    let o = Overrides {
        width: Some(32),
        height: Some(32),
        spp: Some(64),
        ..Default::default()
    };
    let dir = tmp_dir("scale");
    let base = render_gpu(&load(&place(1.0, [0.0; 3]), &dir, &o));
    for (scale, shift) in [
        (1e-3, [0.0; 3]),
        (1e4, [0.0; 3]),
        (1.0, [1e4, 0.0, 0.0]),
        (1.0, [0.0, 1e4, 0.0]),
        (1.0, [0.0, 0.0, 1e4]),
    ] {
        let img = render_gpu(&load(&place(scale, shift), &dir, &o));
        let c = common::compare(&img, &base, 8);
        let (m, _) = image_mean(&img);
        eprintln!(
            "scale {scale} shift {shift:?}: mean {m:.4?}, {} of {} tiles outside the bound",
            c.failed_tiles.len(),
            c.tiles
        );
        assert!(
            c.failed_tiles.is_empty(),
            "scale {scale}, shift {shift:?}:\n{}",
            c.failed_tiles.join("\n")
        );
    }
}

/// A sphere of radius 0.01 at distance 100: rays aimed 0.5r, 0.99r from its centre hit and
/// 1.01r misses, on both backends; rays grazing its silhouette give finite distances.
#[test]
fn a_small_far_sphere_is_hit_exactly_when_it_should_be() {
    let src = r#"
[camera]
look_from = [0, 0, 5]
look_at = [0, 0, 0]
[materials]
m = { type = "lambertian", albedo = [0.5, 0.5, 0.5] }
[[objects]]
type = "sphere"
center = [100, 20, -30]
radius = 0.01
material = "m"
"#;
    let scene = common::scene_from_str(src);
    let b = Bindings::new(&scene, scene.params(0, scene.full_band()));
    let c = Vec3::new(100.0, 20.0, -30.0);
    let mut rays = Vec::new();
    let mut want = Vec::new();
    let mut state = 3u32;
    for _ in 0..200 {
        let d = (c - Vec3::ZERO).normalize();
        let side = d.cross(random_unit(&mut state)).normalize();
        for (k, hit) in [(0.5f32, true), (0.99, true), (1.01, false)] {
            rays.push(ray(Vec3::ZERO, c + side * (0.01 * k)));
            want.push(hit);
        }
    }
    let kernel: Vec<KernelRay> = rays.iter().map(common::to_kernel).collect();
    let gpu = intersect_rays(&common::gpu_context(), &scene, &Default::default(), &kernel).unwrap();
    for ((r, w), g) in rays.iter().zip(&want).zip(&gpu) {
        let h = intersect_scene(&b, r, FAR);
        assert_eq!(h.prim != NO_HIT, *w, "CPU {r:?}");
        assert_eq!(g.prim != NO_HIT, *w, "GPU {r:?}");
        if *w {
            assert!(h.t.is_finite() && (h.t - 105.8).abs() < 1.0, "{}", h.t);
        }
    }
    // grazing the silhouette: hit or miss, never a non-finite distance
    let d = c.normalize();
    let side = d.cross(Vec3::Y).normalize();
    for k in 0..1000 {
        let r = ray(Vec3::ZERO, c + side * (0.01 * (0.999 + 2e-6 * k as f32)));
        let t = intersect_sphere(c, 0.01, &r, FAR);
        assert!(t == FAR || t.is_finite());
    }
}

/// Degenerate directions: a ray parallel to a plane, inside it or beside it, misses; a ray
/// with zero direction components starting on a box face finds the far face; a ray along
/// a cylinder's axis hits only its caps (or nothing without them); all distances finite.
#[test]
fn degenerate_directions_give_finite_answers() {
    let n = Vec3::Y;
    for o in [
        Vec3::ZERO,
        Vec3::new(0.0, 1e-30, 0.0),
        Vec3::new(3.0, 2.0, 1.0),
    ] {
        assert_eq!(intersect_plane(Vec3::ZERO, n, &ray(o, Vec3::X), FAR), FAR);
    }
    // on the face x = -1 of the unit box, moving along +x only: the far face at t = 2
    let r = Ray {
        origin: Vec3::new(-1.0, 0.2, 0.3),
        dir: Vec3::X,
    };
    let h = intersect_box(-Vec3::ONE, Vec3::ONE, &r, FAR);
    assert!((h.x - 2.0).abs() < 1e-6 && h.y == 0.0, "{h}");
    // exactly on an edge of the box (y = 1 face and x = -1 face), moving along +x
    let r = Ray {
        origin: Vec3::new(-1.0, 1.0, 0.0),
        dir: Vec3::X,
    };
    let h = intersect_box(-Vec3::ONE, Vec3::ONE, &r, FAR);
    assert!(h.x == FAR || h.x.is_finite());
    // along the axis of a cylinder from below: the base cap at t = 1, or nothing
    let r = Ray {
        origin: Vec3::new(0.1, -1.0, 0.0),
        dir: Vec3::Y,
    };
    let h = intersect_cylinder(Vec3::ZERO, Vec3::Y, 0.5, true, &r, FAR);
    assert_eq!((h.x, h.y), (1.0, 1.0));
    let h = intersect_cylinder(Vec3::ZERO, Vec3::Y, 0.5, false, &r, FAR);
    assert_eq!(h.x, FAR);
    // inside, along the axis: the top cap
    let r = Ray {
        origin: Vec3::new(0.0, 0.5, 0.0),
        dir: Vec3::Y,
    };
    assert_eq!(
        intersect_cylinder(Vec3::ZERO, Vec3::Y, 0.5, true, &r, FAR).y,
        2.0
    );
}

/// The camera at the centre of a glass sphere (ior 1.5) holding a medium of albedo 0 and
/// extinction sigma, the camera in it, under a uniform background L: every ray meets the
/// surface at normal incidence, leaves with probability 1 - R (R = 0.04) after running
/// r, else runs 2r more: the pixel shows L (1 - R) e^(-sigma r) / (1 - R e^(-2 sigma r)),
/// on both backends. And a glass ball of ior 1 is invisible: the scene renders the same
/// with and without it.
#[test]
fn glass_matches_its_series_and_ior_one_is_invisible() {
    let (sigma, r) = (0.3f64, 1.0f64);
    let src = format!(
        r#"
[render]
width = 16
height = 16
spp = 256
max_depth = 64
[camera]
look_from = [0, 0, 0]
look_at = [0, 0, -1]
vfov = 60
medium = "amber"
[background]
color = [1, 1, 1]
[media.amber]
type = "homogeneous"
sigma_t = {sigma}
albedo = 0
[materials]
glass = {{ type = "dielectric", ior = 1.5 }}
[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = {r}
material = "glass"
interior = "amber"
"#
    );
    let scene = common::scene_from_str(&src);
    let rr = 0.04f64;
    let a = (-sigma * r).exp();
    let expected = (1.0 - rr) * a / (1.0 - rr * a * a);
    for (name, img) in [("gpu", render_gpu(&scene)), ("cpu", render_cpu(&scene))] {
        let (m, se) = image_mean(&img);
        eprintln!("glass sphere {name}: {m:.5?} +- {se:.5?}, series {expected:.5}");
        for c in 0..3 {
            assert!(
                (m[c] - expected).abs() <= 4.0 * se[c] + 1e-5,
                "{name}: {} vs {expected}",
                m[c]
            );
        }
    }

    let floor = r#"
[render]
width = 24
height = 24
spp = 64
[camera]
look_from = [0, 1, 3]
look_at = [0, 0.3, 0]
[background]
top = [0.4, 0.6, 1.0]
bottom = [1, 1, 1]
[materials]
floor = { type = "lambertian", albedo = [0.6, 0.5, 0.4] }
air = { type = "dielectric", ior = 1.0 }
[[objects]]
type = "plane"
point = [0, 0, 0]
normal = [0, 1, 0]
material = "floor"
"#;
    let ball =
        "[[objects]]\ntype = \"sphere\"\ncenter = [0, 0.5, 0]\nradius = 0.5\nmaterial = \"air\"\n";
    let without = render_gpu(&common::scene_from_str(floor));
    let with = render_gpu(&common::scene_from_str(&format!("{floor}{ball}")));
    let c = common::compare(&with, &without, 8);
    assert!(c.failed_tiles.is_empty(), "{}", c.failed_tiles.join("\n"));
}

/// Microfacet roughness from 0 to 1, including 1e-6 and 1e-4 below the mirror cut-off:
/// every sampled weight is finite, the white furnace mean of f cos / pdf stays at most 1.01,
/// and the sampled directions approach the mirror direction continuously as roughness falls.
#[test]
fn microfacet_roughness_near_zero_is_finite_and_continuous() {
    use wgtrace::cpu::materials::scatter;
    use wgtrace::cpu::types::Hit;
    let wo_in = Vec3::new(0.6, -0.8, 0.0); // incoming ray direction
    let mirror = Vec3::new(0.6, 0.8, 0.0);
    let hit = Hit {
        p: Vec3::ZERO,
        ng: Vec3::Y,
        ns: Vec3::Y,
        unmapped: Vec3::Y,
        uv: glam::Vec4::ZERO,
        front_face: true,
        material: 0,
        err: 1e-6,
        tangent: glam::Vec4::ZERO,
        color: glam::Vec4::ONE,
        dpdu: glam::Vec3::ZERO,
        dpdv: glam::Vec3::ZERO,
    };
    let mut last_spread = 0.0f64;
    for alpha in [1.0f32, 1e-2, 1e-3, 1e-4, 1e-6, 0.0] {
        // white (kd = ks = 1) for the furnace; specular only for the spread about the mirror
        let material = |kd: f32| {
            common::material(&format!(
                "type = \"microfacet\"\nalbedo = [{kd}, {kd}, {kd}]\nspecular = [1, 1, 1]\n\
                 roughness = {alpha}\nior = 1.5"
            ))
        };
        let r = ray(Vec3::new(-0.6, 0.8, 0.0), wo_in);
        let mut state = 9u32;
        let (mut sum, mut spread) = (0.0f64, 0.0f64);
        let n = 20_000;
        for _ in 0..n {
            let u = [random_f32(&mut state), random_f32(&mut state)];
            for (kd, white) in [(1.0, true), (0.0, false)] {
                let s = scatter(&material(kd), &r, &hit, u);
                if s.ok {
                    assert!(s.weight.is_finite() && s.dir.is_finite(), "alpha {alpha}");
                    if white {
                        sum += f64::from(s.weight.x);
                    } else {
                        spread += f64::from(1.0 - s.dir.dot(mirror));
                    }
                }
            }
        }
        let mean = sum / f64::from(n);
        let spread = spread / f64::from(n);
        eprintln!(
            "alpha {alpha}: white furnace {mean:.4}, mean 1 - cos to the mirror {spread:.2e}"
        );
        assert!(mean <= 1.01, "alpha {alpha}: {mean}");
        if alpha < 1.0 {
            assert!(
                spread <= last_spread + 1e-9,
                "alpha {alpha}: {spread} after {last_spread}"
            );
        }
        last_spread = spread;
    }
    assert!(last_spread < 1e-6);
}

/// A light of radiance 1e6 on a disk of radius 1e-3, 2 units above a Lambertian patch:
/// the patch shows albedo L R^2 / (R^2 + h^2) under MIS on both backends, with no
/// non-finite sample; and a shadow ray toward a sampled point of a light, ending short of
/// it, never hits that light.
#[test]
fn a_tiny_bright_light_is_finite_and_shadow_rays_stop_short_of_it() {
    let src = r#"
[render]
width = 16
height = 16
spp = 256
max_depth = 2
[camera]
look_from = [0, 0.04, 0.04]
look_at = [0, 0, 0]
vfov = 4
[materials]
patch = { type = "lambertian", albedo = [0.5, 0.5, 0.5] }
light = { type = "emissive", radiance = [1e6, 1e6, 1e6] }
[[objects]]
type = "disk"
center = [0, 0, 0]
normal = [0, 1, 0]
radius = 0.01
material = "patch"
[[objects]]
type = "disk"
center = [0, 2, 0]
normal = [0, -1, 0]
radius = 1e-3
material = "light"
"#;
    let scene = common::scene_from_str(src);
    let (l, rad, h) = (1e6f64, 1e-3f64, 2.0f64);
    let expected = 0.5 * l * rad * rad / (rad * rad + h * h);
    for (name, img) in [("gpu", render_gpu(&scene)), ("cpu", render_cpu(&scene))] {
        let (m, se) = image_mean(&img);
        assert!(
            (m[0] - expected).abs() <= 4.0 * se[0] + 1e-4 * expected,
            "{name}: {} vs {expected}",
            m[0]
        );
    }
    // shadow rays toward sampled light points, from the patch, stop short of the light
    use wgtrace::cpu::lights::sample_light;
    use wgtrace::cpu::sampling::offset_ray;
    let b = Bindings::new(&scene, scene.params(0, scene.full_band()));
    let mut state = 1u32;
    for _ in 0..10_000 {
        let p = Vec3::new(
            0.01 * (random_f32(&mut state) - 0.5),
            0.0,
            0.01 * (random_f32(&mut state) - 0.5),
        );
        let ls = sample_light(
            &b,
            p,
            random_f32(&mut state),
            [random_f32(&mut state), random_f32(&mut state)],
        );
        assert_ne!(ls.light, wgtrace::scene::records::NO_LIGHT);
        let x = p + ls.dist * ls.dir;
        let origin = offset_ray(p, Vec3::Y, 1e-7);
        let end = offset_ray(x, -Vec3::Y, 1e-7);
        let v = end - origin;
        let shadow = Ray {
            origin,
            dir: v.normalize(),
        };
        let hit = intersect_scene(&b, &shadow, v.length());
        assert_eq!(
            hit.prim, NO_HIT,
            "the shadow ray reached the light it aims at"
        );
    }
}

/// max_depth 1000 in a closed box of mirrors (albedo 0.95) lit by a small emitter inside:
/// every path ends, the image is finite, the two backends agree.
#[test]
fn a_thousand_bounces_between_mirrors_end_and_stay_finite() {
    let mut walls = String::new();
    for (lo, hi) in [
        ([-1.0, -1.0, -1.0], [1.0, -0.9, 1.0]),
        ([-1.0, 0.9, -1.0], [1.0, 1.0, 1.0]),
        ([-1.0, -1.0, -1.0], [-0.9, 1.0, 1.0]),
        ([0.9, -1.0, -1.0], [1.0, 1.0, 1.0]),
        ([-1.0, -1.0, -1.0], [1.0, 1.0, -0.9]),
        ([-1.0, -1.0, 0.9], [1.0, 1.0, 1.0]),
    ] {
        walls += &format!(
            "[[objects]]\ntype = \"box\"\nmin = {lo:?}\nmax = {hi:?}\nmaterial = \"mirror\"\n"
        );
    }
    let src = format!(
        r#"
[render]
width = 12
height = 12
spp = 4
max_depth = 1000
[camera]
look_from = [0, 0, 0.5]
look_at = [0.3, 0.2, -1]
vfov = 80
[materials]
mirror = {{ type = "metal", albedo = [0.95, 0.95, 0.95] }}
glow = {{ type = "emissive", radiance = [5, 5, 5] }}
[[objects]]
type = "sphere"
center = [0.2, -0.3, -0.4]
radius = 0.1
material = "glow"
{walls}"#
    );
    let scene = common::scene_from_str(&src);
    let gpu = render_gpu(&scene);
    let cpu = render_cpu(&scene);
    assert!(gpu.to_rgb().iter().all(|x| x.is_finite() && *x >= 0.0));
    let c = common::compare(&gpu, &cpu, 4);
    assert!(c.agree_fraction >= 0.95, "{}", c.agree_fraction);
}

/// Bad geometry is a load-time error naming the key, never a NaN in an image.
#[test]
fn bad_geometry_is_refused_at_load_time() {
    let base = "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[materials]\nm = { type = \"lambertian\", albedo = [0.5, 0.5, 0.5] }\n[[objects]]\nmaterial = \"m\"\n";
    for (object, message) in [
        (
            "type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 0",
            "objects[0].radius: must be > 0",
        ),
        (
            "type = \"triangle\"\nvertices = [[0, 0, 0], [1, 1, 1], [2, 2, 2]]",
            "objects[0].vertices: is degenerate (zero area)",
        ),
        (
            "type = \"polygon\"\nvertices = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]]",
            "objects[0].vertices: is degenerate (zero area)",
        ),
        (
            "type = \"polygon\"\nvertices = [[0, 0, 0], [1, 0, 0], [1, 1, 0.5], [0, 1, 0]]",
            "objects[0].vertices: are not coplanar",
        ),
        (
            "type = \"sphere\"\ncenter = [nan, 0, 0]\nradius = 1",
            "objects[0].center: must be finite",
        ),
        (
            "type = \"triangle\"\nvertices = [[0, 0, 0], [inf, 1, 1], [2, 0, 2]]",
            "objects[0].vertices: must be finite",
        ),
        (
            "type = \"sphere\"\ncenter = [0, 0, 0]\nradius = inf",
            "objects[0].radius",
        ),
    ] {
        let e = wgtrace::load_scene_str(
            &format!("{base}{object}\n"),
            Path::new("bad.toml"),
            &Overrides::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("bad.toml:6:1") && e.contains(message),
            "{object}: {e}"
        );
    }
}

/// The same sphere and triangle tests in f64, for the randomized comparison.
fn sphere_f64(c: DVec3, r: f64, o: DVec3, d: DVec3) -> Option<f64> {
    let f = o - c;
    let b = f.dot(d);
    let disc = b * b - (f.dot(f) - r * r);
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    [-b - s, -b + s].into_iter().find(|&t| t > 0.0)
}

fn triangle_f64(v: [DVec3; 3], o: DVec3, d: DVec3) -> Option<f64> {
    let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
    let n = e1.cross(e2);
    let denom = n.dot(d);
    if denom == 0.0 {
        return None;
    }
    let t = n.dot(v[0] - o) / denom;
    let p = o + t * d;
    let inside = (0..3).all(|i| {
        let (a, b) = (v[i], v[(i + 1) % 3]);
        (b - a).cross(p - a).dot(n) >= 0.0
    });
    (t > 0.0 && inside).then_some(t)
}

/// 200,000 random rays against random spheres and triangles (sizes 1e-3 to 1e3, distances
/// to 1e3): the f32 answer (hit or miss) differs from the f64 one only for rays within a
/// few ulps of a silhouette or an edge. Such rays are a fraction of about 1e-6 of those that
/// come near, so the bound is 1e-4; where both hit, t agrees to 1e-4 relative.
#[test]
fn f32_intersections_agree_with_f64() {
    let mut state = 2024u32;
    let mut disagree = 0usize;
    let mut worst_t = 0.0f64;
    let n = 200_000;
    for i in 0..n {
        let scale = 10f32.powf(6.0 * random_f32(&mut state) - 3.0);
        let center = random_unit(&mut state) * (scale * 10.0 * random_f32(&mut state));
        let o = center + random_unit(&mut state) * (scale * (2.0 + 20.0 * random_f32(&mut state)));
        // aim near the primitive so that about half the rays hit
        let aim = center + random_unit(&mut state) * (scale * 1.2 * random_f32(&mut state));
        let r = ray(o, aim - o);
        let (od, dd) = (r.origin.as_dvec3(), r.dir.as_dvec3());
        let (t32, t64) = if i % 2 == 0 {
            let t = intersect_sphere(center, scale, &r, FAR);
            (t, sphere_f64(center.as_dvec3(), f64::from(scale), od, dd))
        } else {
            let v = [0, 1, 2].map(|_| center + random_unit(&mut state) * scale);
            let t = intersect_triangle(v[0], v[1], v[2], &r, FAR).x;
            (t, triangle_f64(v.map(|p| p.as_dvec3()), od, dd))
        };
        match (t32 < FAR, t64) {
            (true, Some(t)) => worst_t = worst_t.max((f64::from(t32) - t).abs() / t),
            (false, None) => {}
            _ => disagree += 1,
        }
    }
    let rate = disagree as f64 / n as f64;
    eprintln!("f32 against f64: {disagree} of {n} rays disagree ({rate:.1e}); worst relative t error {worst_t:.1e}");
    assert!(rate < 1e-4, "{rate}");
    assert!(worst_t < 1e-4, "{worst_t}");
}

/// From hit points on spheres of radius 1e-4 to 1e4, centred up to 1e5 from the origin, and
/// on triangles with coordinates from 1e-6 to 1e6, 1000 rays into the outward hemisphere
/// (spawned as the renderer spawns them: off the error box, then 4 ulps) never hit the same
/// surface again.
#[test]
fn rays_leaving_a_surface_never_hit_it_again() {
    use wgtrace::cpu::intersect::surface_at;
    use wgtrace::cpu::path::spawn_ray;
    let mut state = 31u32;
    let mut cases = Vec::new();
    for r in [1e-4f32, 1e-2, 1.0, 1e2, 1e4] {
        for shift in [0.0f32, 1e3, 1e5] {
            let c = Vec3::new(shift, -0.5 * shift, 0.25 * shift);
            cases.push(format!(
                "type = \"sphere\"\ncenter = [{}, {}, {}]\nradius = {r}",
                c.x, c.y, c.z
            ));
        }
    }
    for s in [1e-6f32, 1e-3, 1.0, 1e3, 1e6] {
        let v: Vec<[f32; 3]> = (0..3)
            .map(|_| (Vec3::splat(s) + random_unit(&mut state) * s).to_array())
            .collect();
        cases.push(format!("type = \"triangle\"\nvertices = {v:?}"));
    }
    for object in cases {
        let src = format!(
            "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[materials]\nm = {{ type = \"lambertian\", albedo = [0.5, 0.5, 0.5] }}\n[[objects]]\nmaterial = \"m\"\n{object}\n"
        );
        let scene = common::scene_from_str(&src);
        let b = Bindings::new(&scene, scene.params(0, scene.full_band()));
        let p = &scene.primitives[0];
        let target = if p.tag == wgtrace::scene::primitives::PrimitiveKind::Sphere.tag() {
            Vec3::from_slice(&p.a)
        } else {
            (Vec3::from_slice(&p.a) + Vec3::from_slice(&p.b) + Vec3::from_slice(&p.c)) / 3.0
        };
        // start near the shape: a few radii, or a few triangle sizes, away
        let reach = if p.tag == wgtrace::scene::primitives::PrimitiveKind::Sphere.tag() {
            3.0 * p.a[3]
        } else {
            4.0 * (Vec3::from_slice(&p.b) - Vec3::from_slice(&p.a)).length()
        };
        let mut hits = 0;
        for _ in 0..40 {
            // a ray from outside toward the shape
            let from = target + random_unit(&mut state) * reach;
            let r = ray(from, target - from);
            let cand = intersect_scene(&b, &r, FAR);
            if cand.prim == NO_HIT {
                continue;
            }
            hits += 1;
            let hit = surface_at(&b, &r, &cand);
            let out = if hit.front_face { hit.ng } else { -hit.ng };
            for _ in 0..25 {
                let mut d = random_unit(&mut state);
                if d.dot(out) < 0.0 {
                    d = -d;
                }
                let again = intersect_scene(&b, &spawn_ray(&hit, d), FAR);
                assert_eq!(again.prim, NO_HIT, "{object}: re-hit at t = {}", again.t);
            }
        }
        // a sphere far smaller than the f32 spacing at its position (radius 1e-4 at 1e5,
        // where that spacing is 0.0078) cannot be aimed at; only what is hit is checked
        let spacing = |x: f32| f32::from_bits(x.abs().to_bits() + 1) - x.abs();
        let representable = p.tag != wgtrace::scene::primitives::PrimitiveKind::Sphere.tag()
            || p.a[3] >= 100.0 * spacing(target.abs().max_element());
        if representable {
            assert!(hits >= 20, "{object}: only {hits} of 40 rays hit");
        }
    }
}

/// Inside a wide glass slab (ior 1.5, critical angle 41.8 degrees) under an emitting plane:
/// looking up at 60 degrees from the normal, every ray is totally reflected between the two
/// faces and never reaches the light (the pixel is black, on both backends); at 20 degrees
/// the light shows through, dimmed by the Fresnel reflectance.
#[test]
fn a_glass_slab_beyond_the_critical_angle_transmits_nothing() {
    let scene_at = |deg: f32| {
        let t = deg.to_radians();
        format!(
            r#"
[render]
width = 8
height = 8
spp = 32
max_depth = 64
[camera]
look_from = [0, 0, 0]
look_at = [{}, {}, 0]
vfov = 2
[materials]
glass = {{ type = "dielectric", ior = 1.5 }}
sky = {{ type = "emissive", radiance = [1, 1, 1] }}
[[objects]]
type = "box"
min = [-1000, -0.5, -1000]
max = [1000, 0.5, 1000]
material = "glass"
[[objects]]
type = "plane"
point = [0, 2, 0]
normal = [0, -1, 0]
material = "sky"
"#,
            t.sin(),
            t.cos()
        )
    };
    let beyond = common::scene_from_str(&scene_at(60.0));
    for (name, img) in [("gpu", render_gpu(&beyond)), ("cpu", render_cpu(&beyond))] {
        let (m, _) = image_mean(&img);
        assert_eq!(
            m, [0.0; 3],
            "{name}: light came through beyond the critical angle"
        );
    }
    let below = common::scene_from_str(&scene_at(20.0));
    let (m, _) = image_mean(&render_gpu(&below));
    assert!(m[0] > 0.8 && m[0] <= 1.0, "{m:?}");
}

/// A ground sphere of radius 1e4 with the camera 1 unit above it, under a uniform sky of
/// radiance 1, at max_depth 2: a bounce ray leaving a convex sphere only sees the sky, so
/// every pixel is exactly the albedo (ground) or 1 (sky) on both backends. A re-hit of the
/// ground (acne) would show as a black speckle, a missed primary ray as a sky-coloured hole.
#[test]
fn a_huge_ground_sphere_under_the_camera_has_no_speckles() {
    let src = r#"
[render]
width = 48
height = 32
spp = 4
max_depth = 2
[camera]
look_from = [0, 1, 0]
look_at = [0, 0.2, -10]
vfov = 60
[background]
color = [1, 1, 1]
[materials]
ground = { type = "lambertian", albedo = [0.5, 0.5, 0.5] }
[[objects]]
type = "sphere"
center = [0, -10000, 0]
radius = 10000
material = "ground"
"#;
    let scene = common::scene_from_str(src);
    for (name, img) in [("gpu", render_gpu(&scene)), ("cpu", render_cpu(&scene))] {
        let (mut ground, mut sky) = (0, 0);
        for i in 0..img.pixel_count() {
            let v = img.mean(i)[0];
            if (v - 0.5).abs() < 1e-5 {
                ground += 1;
            } else if (v - 1.0).abs() < 1e-5 {
                sky += 1;
            } else {
                // a pixel straddling the horizon mixes the two, never goes below the ground
                assert!(v > 0.5 && v < 1.0, "{name}: pixel {i} = {v}");
            }
        }
        assert!(
            ground > 600 && sky > 300,
            "{name}: {ground} ground, {sky} sky pixels"
        );
    }
}

/// An icosphere of radius 1 with `level` subdivisions (20 x 4^level triangles, level 3 or
/// more) as OBJ text, each corner's normal its unit position: smooth shading.
fn icosphere_obj(level: u32) -> String {
    let mut obj = String::new();
    for (k, t) in common::icosphere(level, 1.0).iter().enumerate() {
        for p in t {
            obj += &format!("v {} {} {}\nvn {} {} {}\n", p.x, p.y, p.z, p.x, p.y, p.z);
        }
        let i = 3 * k + 1;
        obj += &format!("f {0}//{0} {1}//{1} {2}//{2}\n", i, i + 1, i + 2);
    }
    obj
}

/// A tangent-space normal map of 8 x 8 round bumps (a height field of cosine domes, the
/// normal tilted up to about 50 degrees at their flanks), as 8-bit linear RGB.
fn bump_normal_map(path: &Path) {
    let n = 256u32;
    let img = image::RgbImage::from_fn(n, n, |x, y| {
        let (u, v) = ((x as f32 + 0.5) / n as f32, (y as f32 + 0.5) / n as f32);
        let k = 8.0 * std::f32::consts::TAU;
        // height h = 0.04 sin(k u) sin(k v): its slopes give the normal
        let (dx, dy) = (
            0.04 * k * (k * u).cos() * (k * v).sin(),
            0.04 * k * (k * u).sin() * (k * v).cos(),
        );
        let nrm = Vec3::new(-dx, dy, 1.0).normalize();
        let c = (nrm + Vec3::ONE) * 0.5 * 255.0;
        image::Rgb([c.x.round() as u8, c.y.round() as u8, c.z.round() as u8])
    });
    img.save(path).unwrap();
}

/// The worst and the mean pixel of a white furnace render, and whether every pixel lies
/// within `tolerance` of 1 (below, 5 standard errors of the pixel's own samples allowed;
/// never above 1 by more than that).
fn furnace_rim(name: &str, img: &wgtrace::Accumulation, tolerance: f32) -> (f32, f64) {
    let (mut worst, mut total) = (f32::MAX, 0.0f64);
    for i in 0..img.pixel_count() {
        let (m, var, n) = (img.mean(i), img.variance(i), img.samples(i));
        for c in 0..3 {
            let se = 5.0 * (var[c] / n).sqrt() + 1e-5;
            assert!(m[c] <= 1.0 + se, "{name}: pixel {i} reads {} > 1", m[c]);
            assert!(
                m[c] >= 1.0 - tolerance - se,
                "{name}: pixel {i} reads {} (more than {tolerance} below 1)",
                m[c]
            );
            worst = worst.min(m[c]);
        }
        total += m[0] as f64;
    }
    (worst, total / img.pixel_count() as f64)
}

/// Shading normals keep energy: a smooth-shaded icosphere of 5,120 triangles (albedo 1) and
/// a normal-mapped plane of pbr's lossless limit (no specular), each in a white furnace,
/// read 1 in every pixel, their silhouettes and grazing views included, within 2%, on
/// both backends (docs/robustness.md: the shading normal is bent toward the viewer where
/// the viewer would be under it, and what would leave under the geometric surface is
/// mirrored back over it).
#[test]
fn shading_normals_keep_the_white_furnace_to_the_rim() {
    let dir = tmp_dir("shading-normals");
    std::fs::write(dir.join("ico.obj"), icosphere_obj(4)).unwrap();
    std::fs::write(
        dir.join("plane.obj"),
        "v -1 0 1\nv 1 0 1\nv 1 0 -1\nv -1 0 -1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 1 0\n\
         f 1/1/1 2/2/1 3/3/1 4/4/1\n",
    )
    .unwrap();
    bump_normal_map(&dir.join("bumps.png"));
    let header = r#"
[render]
width = 48
height = 48
spp = 64
max_depth = 64
[background]
color = [1, 1, 1]
"#;
    // pbr's lossless limit, as a glTF asset's white matte material, seen whole and with
    // its rim magnified (the silhouette's tangent point is near (0.968, 0, 0.25))
    let sphere = |look_at: &str, vfov: f32| {
        format!(
            "{header}{}",
            r#"
[camera]
look_from = [0, 0, 4]
look_at = LOOK_AT
vfov = VFOV
[materials]
white = { type = "pbr", metallic = 0, specular = 0 }
[[objects]]
type = "mesh"
path = "ico.obj"
material = "white"
"#
            .replace("LOOK_AT", look_at)
            .replace("VFOV", &vfov.to_string())
        )
    };
    let plane = format!(
        "{header}{}",
        r#"
[camera]
look_from = [0, 0.9, 2.6]
look_at = [0, 0, 0]
vfov = 40
[textures]
bumps = { type = "image", path = "bumps.png", color_space = "linear" }
[materials]
bumpy = { type = "pbr", metallic = 0, specular = 0, normal_map = "bumps" }
[[objects]]
type = "mesh"
path = "plane.obj"
material = "bumpy"
"#
    );
    for (name, src) in [
        ("smooth icosphere", sphere("[0, 0, 0]", 32.0)),
        ("smooth icosphere's rim", sphere("[0.968, 0, 0.25]", 4.0)),
        ("normal-mapped plane", plane),
    ] {
        let scene = load(&src, &dir, &Overrides::default());
        for (backend, img) in [("gpu", render_gpu(&scene)), ("cpu", render_cpu(&scene))] {
            let label = format!("{name} on {backend}");
            let (worst, mean) = furnace_rim(&label, &img, 0.02);
            eprintln!("{label}: furnace mean {mean:.5}, worst pixel {worst:.5}");
        }
    }
}
