//! CPU unit tests: intersections (hit, miss, range, inside), sampling, RNG, scene loading.

mod common;

use std::path::Path;

use common::shapes::{intersect_sphere, intersect_triangle};
use glam::Vec3;
use wgtrace::cpu::bindings::Bindings;
use wgtrace::cpu::intersect::{intersect_scene, surface_at};
use wgtrace::cpu::rng::{pcg4d, rand_2d};
use wgtrace::cpu::sampling::{offset_ray, sample_cosine_hemisphere};
use wgtrace::cpu::types::{Ray, FAR, NO_HIT};
use wgtrace::Overrides;

fn ray(o: [f32; 3], d: [f32; 3]) -> Ray {
    Ray {
        origin: Vec3::from(o),
        dir: Vec3::from(d).normalize(),
    }
}

#[test]
fn sphere_hit_miss_range_and_inside() {
    let c = Vec3::new(0.0, 0.0, -5.0);
    // Hit from outside: the near root.
    let t = intersect_sphere(c, 1.0, &ray([0.0; 3], [0.0, 0.0, -1.0]), FAR);
    assert!((t - 4.0).abs() < 1e-5, "{t}");
    // Miss: passes beside.
    assert_eq!(
        intersect_sphere(c, 1.0, &ray([0.0; 3], [0.0, 1.0, -1.0]), FAR),
        FAR
    );
    // Behind the origin: miss.
    assert_eq!(
        intersect_sphere(c, 1.0, &ray([0.0; 3], [0.0, 0.0, 1.0]), FAR),
        FAR
    );
    // Range: t_max before the sphere.
    assert_eq!(
        intersect_sphere(c, 1.0, &ray([0.0; 3], [0.0, 0.0, -1.0]), 3.9),
        FAR
    );
    // Inside: the far root.
    let t = intersect_sphere(c, 1.0, &ray([0.0, 0.0, -5.0], [1.0, 0.0, 0.0]), FAR);
    assert!((t - 1.0).abs() < 1e-6, "{t}");
    // Tiny sphere far away, where the textbook quadratic loses every digit.
    let far_c = Vec3::new(0.0, 0.0, -1000.0);
    let t = intersect_sphere(far_c, 0.01, &ray([0.0; 3], [0.0, 0.0, -1.0]), FAR);
    assert!((t - 999.99).abs() < 1e-3, "{t}");
}

#[test]
fn triangle_hit_miss_range_both_sides_and_barycentrics() {
    let (v0, v1, v2) = (
        Vec3::new(0.0, 0.0, -2.0),
        Vec3::new(1.0, 0.0, -2.0),
        Vec3::new(0.0, 1.0, -2.0),
    );
    let h = intersect_triangle(v0, v1, v2, &ray([0.25, 0.25, 0.0], [0.0, 0.0, -1.0]), FAR);
    assert!((h.x - 2.0).abs() < 1e-6 && (h.y - 0.25).abs() < 1e-6 && (h.z - 0.25).abs() < 1e-6);
    // From behind: still a hit.
    let h = intersect_triangle(v0, v1, v2, &ray([0.25, 0.25, -4.0], [0.0, 0.0, 1.0]), FAR);
    assert!((h.x - 2.0).abs() < 1e-6);
    // Outside the edge v1-v2.
    let h = intersect_triangle(v0, v1, v2, &ray([0.6, 0.6, 0.0], [0.0, 0.0, -1.0]), FAR);
    assert_eq!(h.x, FAR);
    // Range.
    let h = intersect_triangle(v0, v1, v2, &ray([0.25, 0.25, 0.0], [0.0, 0.0, -1.0]), 1.5);
    assert_eq!(h.x, FAR);
    // Parallel to the plane.
    let h = intersect_triangle(v0, v1, v2, &ray([0.25, 0.25, -2.0], [1.0, 0.0, 0.0]), FAR);
    assert_eq!(h.x, FAR);
}

const POLYGON_SCENE: &str = r#"
[camera]
look_from = [0, 0, 5]
look_at = [0, 0, 0]
[materials]
m = { type = "lambertian", albedo = [0.5, 0.5, 0.5] }
[[objects]]
type = "polygon"   # a regular hexagon of radius 1 in z = 0, facing +z
vertices = [[1, 0, 0], [0.5, 0.8660254, 0], [-0.5, 0.8660254, 0], [-1, 0, 0], [-0.5, -0.8660254, 0], [0.5, -0.8660254, 0]]
material = "m"
"#;

#[test]
fn polygon_fan_hits_inside_misses_outside_and_faces_by_vertex_order() {
    let scene = common::scene_from_str(POLYGON_SCENE);
    assert_eq!(scene.primitives.len(), 4, "hexagon -> 4 fan triangles");
    let b = Bindings::new(&scene, scene.params(0, scene.full_band()));
    for (x, y, hit) in [
        (0.0, 0.0, true),
        (0.9, 0.0, true),
        (0.0, 0.85, true),
        (-0.7, -0.5, true),
        (0.0, 0.9, false),
        (0.95, 0.5, false),
        (2.0, 0.0, false),
    ] {
        let r = ray([x, y, 1.0], [0.0, 0.0, -1.0]);
        let cand = intersect_scene(&b, &r, FAR);
        assert_eq!(cand.prim != NO_HIT, hit, "({x}, {y})");
        if hit {
            assert!((cand.t - 1.0).abs() < 1e-6);
            let h = surface_at(&b, &r, &cand);
            assert!(h.front_face, "ray from +z sees the front");
            assert!((h.ng - Vec3::Z).length() < 1e-6);
            assert!(h.p.z.abs() < 1e-6 && (h.p.x - x).abs() < 1e-6);
        }
    }
    let back = ray([0.0, 0.0, -1.0], [0.0, 0.0, 1.0]);
    let h = surface_at(&b, &back, &intersect_scene(&b, &back, FAR));
    assert!(!h.front_face);
}

fn sphere_scene(center: [f32; 3], radius: f32) -> wgtrace::FlatScene {
    common::scene_from_str(&format!(
        "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[materials]\n\
         m = {{ type = \"lambertian\", albedo = [0.5, 0.5, 0.5] }}\n[[objects]]\n\
         type = \"sphere\"\ncenter = {center:?}\nradius = {radius}\nmaterial = \"m\"\n"
    ))
}

/// Rays spawned from a sphere hit into the outward hemisphere never re-hit it (pbrt-v4's
/// re-intersection test), for radii from 1e-3 to 1e4 and centres far from the origin,
/// including the large ground sphere whose reprojected hit point carries an error of
/// ulp(radius) where |p| is small.
#[test]
fn rays_leaving_a_sphere_never_rehit_it_at_any_scale() {
    let cases = [
        ([0.3, -0.2, 0.7], 1e-3),
        ([0.3, -0.2, 0.7], 1.0),
        ([3e3, -2e3, 7e3], 1e4),
        ([0.0, -100.0, 0.0], 100.0),
        ([1e4, 1e4, -1e4], 0.5),
    ];
    for (center, radius) in cases {
        let scene = sphere_scene(center, radius);
        let b = Bindings::new(&scene, scene.params(0, scene.full_band()));
        let c = Vec3::from(center);
        for i in 0..2000 {
            // A ray from outside, above the sphere, aimed at a point inside it.
            let n0 = sample_cosine_hemisphere(Vec3::Y, rand_2d(i, 0, 0, 0, 7));
            let target = c + 0.5 * radius * n0;
            let origin = c + 3.0 * radius * sample_cosine_hemisphere(n0, rand_2d(i, 1, 0, 0, 7));
            let r = Ray {
                origin,
                dir: (target - origin).normalize(),
            };
            let cand = intersect_scene(&b, &r, FAR);
            assert_ne!(cand.prim, NO_HIT, "{center:?} r {radius}: aimed ray missed");
            let h = surface_at(&b, &r, &cand);
            let d = sample_cosine_hemisphere(h.ng, rand_2d(i, 2, 0, 0, 7));
            let out = Ray {
                origin: offset_ray(h.p, h.ng, h.err),
                dir: d,
            };
            let again = intersect_scene(&b, &out, FAR);
            assert_eq!(
                again.prim, NO_HIT,
                "{center:?} r {radius}: self-intersection at {:?}",
                h.p
            );
        }
    }
}

#[test]
fn rng_is_deterministic_uniform_and_keyed_by_every_input() {
    assert_eq!(pcg4d([1, 2, 3, 4]), pcg4d([1, 2, 3, 4]));
    let base = rand_2d(10, 20, 3, 2, 5);
    for other in [
        rand_2d(11, 20, 3, 2, 5),
        rand_2d(10, 21, 3, 2, 5),
        rand_2d(10, 20, 4, 2, 5),
        rand_2d(10, 20, 3, 3, 5),
        rand_2d(10, 20, 3, 2, 6),
    ] {
        assert_ne!(base, other);
    }
    // Mean and variance of 2^16 draws: U(0,1) has mean 1/2, variance 1/12.
    let n = 1 << 16;
    let xs: Vec<f32> = (0..n).flat_map(|i| rand_2d(i, 0, 0, 0, 0)).collect();
    let mean = xs.iter().map(|&x| x as f64).sum::<f64>() / xs.len() as f64;
    let var = xs.iter().map(|&x| (x as f64 - mean).powi(2)).sum::<f64>() / xs.len() as f64;
    // 5 standard errors.
    assert!(
        (mean - 0.5).abs() < 5.0 * (1.0f64 / 12.0 / xs.len() as f64).sqrt(),
        "{mean}"
    );
    assert!((var - 1.0 / 12.0).abs() < 1e-3, "{var}");
    assert!(xs.iter().all(|&x| (0.0..1.0).contains(&x)));
}

#[test]
fn cosine_hemisphere_has_the_cosine_moments() {
    // E[cos] = 2/3 and E[cos^2] = 1/2 under pdf cos/pi.
    let n = Vec3::new(0.3, -0.5, 0.8).normalize();
    let count = 1 << 16;
    let (mut m1, mut m2) = (0.0f64, 0.0f64);
    for i in 0..count {
        let d = sample_cosine_hemisphere(n, rand_2d(i, 0, 0, 2, 1));
        assert!((d.length() - 1.0).abs() < 1e-5);
        let c = d.dot(n) as f64;
        assert!(c >= -1e-6);
        m1 += c;
        m2 += c * c;
    }
    let (m1, m2) = (m1 / count as f64, m2 / count as f64);
    assert!((m1 - 2.0 / 3.0).abs() < 5e-3, "{m1}");
    assert!((m2 - 0.5).abs() < 5e-3, "{m2}");
}

fn load_err(src: &str) -> String {
    match wgtrace::load_scene_str(src, Path::new("bad.toml"), &Overrides::default()) {
        Ok(_) => panic!("scene should not load"),
        Err(e) => e.to_string(),
    }
}

/// Each (what, from, to, expected) of `table`, one edit of `base` (`from` replaced by `to`),
/// fails to load with an error containing `expected`.
fn each_edit_fails(base: &str, table: &[(&str, &str, &str, &str)]) {
    for (what, from, to, expected) in table {
        assert!(base.contains(from), "{what}: the edit does not apply");
        let e = load_err(&base.replacen(from, to, 1));
        assert!(e.contains(expected), "{what}: {e}");
    }
}

#[test]
fn scene_errors_name_file_line_and_key_and_collect_all() {
    let src = r#"[camera]
look_from = [0, 0, 5]
look_at = [0, 0, 0]

[materials]
m = { type = "lambertian", albedo = [0.5, 0.5, 0.5] }

[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = -1
material = "nope"
"#;
    let e = load_err(src);
    assert!(
        e.contains("bad.toml:8:1: objects[0].material: unknown material \"nope\" (defined: m)"),
        "{e}"
    );
    assert!(
        e.contains("bad.toml:8:1: objects[0].radius: must be > 0, got -1"),
        "{e}"
    );

    let e = load_err("[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\nzoom = 2\n");
    assert!(e.contains("bad.toml:4:1") && e.contains("zoom"), "{e}");
    let e = load_err("[camera]\nlook_from = [0, 0, 5\n");
    assert!(e.starts_with("bad.toml:2:"), "{e}");
    let e = load_err("[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\nnear_clip = -1\n");
    assert!(e.contains("camera.near_clip: must be >= 0, got -1"), "{e}");
    let e = load_err("[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[render]\nspp = 0\n");
    assert!(
        e.contains("render.spp: must be in 1..=16777216, got 0"),
        "{e}"
    );
    let e = load_err(
        "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[render]\nspp = 16777217\n",
    );
    assert!(
        e.contains("render.spp: must be in 1..=16777216, got 16777217"),
        "{e}"
    );
    // a near miss of a key or a variant gets a suggestion, a far one does not
    let e = load_err("[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[render]\nwidht = 8\n");
    assert!(
        e.starts_with("bad.toml:5:1: unknown field `widht`")
            && e.ends_with("did you mean `width`?"),
        "{e}"
    );
    let e = load_err("[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[materials]\nm = { type = \"lambertain\" }\n");
    assert!(e.ends_with("did you mean `lambertian`?"), "{e}");
    let e = load_err("[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[render]\nzzz = 8\n");
    assert!(
        e.contains("unknown field `zzz`") && !e.contains("did you mean"),
        "{e}"
    );
    let e = load_err("[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[materials]\nm = { type = \"lambertian\", albedo = [1, 1, 1] }\n[[objects]]\ntype = \"polygon\"\nvertices = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0.2, 0.5, 0], [0, 1, 0]]\nmaterial = \"m\"\n");
    assert!(e.contains("convex"), "{e}");
}

/// The issue's table of broken scenes: each is one edit of a valid scene, and its error
/// names the file, the line and column, and the key.
#[test]
fn a_table_of_broken_scenes_names_file_line_and_key() {
    let base = r#"[camera]
look_from = [0, 0, 5]
look_at = [0, 0, 0]
[render]
width = 8
height = 8
[textures]
t = { type = "checker", even = [1, 1, 1], odd = [0, 0, 0], scale = 4 }
[materials]
m = { type = "lambertian", albedo = "t" }
g = { type = "dielectric", ior = 1.5 }
r = { type = "microfacet", albedo = [0.5, 0.5, 0.5], specular = [1, 1, 1], roughness = 0.3 }
[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "m"
"#;
    let sphere = "type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1";
    let checker = r#"t = { type = "checker", even = [1, 1, 1], odd = [0, 0, 0], scale = 4 }"#;
    let table: &[(&str, &str, &str, &str)] = &[
        // (what, from, to, expected)
        (
            "syntax",
            "look_at = [0, 0, 0]",
            "look_at = [0, 0, 0",
            "bad.toml:4:1: missing comma",
        ),
        (
            "unknown key",
            "height = 8",
            "heigth = 8",
            "bad.toml:6:1: unknown field `heigth`",
        ),
        (
            "wrong type",
            "width = 8",
            "width = \"8\"",
            "bad.toml:5:9: invalid type: string \"8\"",
        ),
        (
            "unknown material",
            "material = \"m\"",
            "material = \"nope\"",
            "bad.toml:13:1: objects[0].material: unknown material \"nope\"",
        ),
        (
            "unknown texture",
            "albedo = \"t\"",
            "albedo = \"tt\"",
            "bad.toml:10:5: materials.m.albedo: unknown texture \"tt\"",
        ),
        (
            "bump and normal map",
            "albedo = \"t\"",
            "albedo = \"t\", bump = \"t\", normal_map = \"t\"",
            "bad.toml:10:5: materials.m.normal_map: a material takes a bump map or a normal map, not both",
        ),
        (
            "unknown normal map",
            "albedo = \"t\"",
            "albedo = \"t\", normal_map = \"tt\"",
            "bad.toml:10:5: materials.m.normal_map: unknown texture \"tt\"",
        ),
        (
            "missing mesh",
            sphere,
            "type = \"mesh\"\npath = \"gone.obj\"",
            "bad.toml:13:1: objects[0].path: gone.obj:",
        ),
        (
            "missing image",
            checker,
            r#"t = { type = "image", path = "gone.png" }"#,
            "bad.toml:8:5: textures.t.path: gone.png:",
        ),
        (
            "negative radius",
            "radius = 1",
            "radius = -2",
            "bad.toml:13:1: objects[0].radius: must be > 0, got -2",
        ),
        (
            "spp 0",
            "height = 8",
            "height = 8\nspp = 0",
            "bad.toml:7:1: render.spp: must be in 1..=16777216, got 0",
        ),
        (
            "width 0",
            "width = 8",
            "width = 0",
            "bad.toml:5:1: render.width: must be in 1..=16384, got 0",
        ),
        (
            "crop",
            "height = 8",
            "height = 8\ncrop = [2, 0, 7, 8]",
            "bad.toml:7:1: render.crop: [x, y, width, height] = [2, 0, 7, 8] must be a rectangle of at least one pixel inside the 8 x 8 film",
        ),
        (
            "filter steps",
            "height = 8",
            "height = 8\nfilter = \"tent\"\nfilter_steps = 0",
            "bad.toml:8:1: render.filter_steps: must be in [1, 256], got 0",
        ),
        (
            "roughness",
            "roughness = 0.3",
            "roughness = 1.5",
            "bad.toml:12:5: materials.r.roughness: must be in [0, 1], got 1.5",
        ),
        (
            "ior",
            "ior = 1.5",
            "ior = 0",
            "bad.toml:11:5: materials.g.ior: must be > 0, got 0",
        ),
        (
            "nan",
            "center = [0, 0, 0]",
            "center = [nan, 0, 0]",
            "bad.toml:13:1: objects[0].center: must be finite",
        ),
        (
            "infinite",
            "radius = 1",
            "radius = inf",
            "bad.toml:13:1: objects[0].radius: must be > 0, got inf",
        ),
        (
            "degenerate",
            sphere,
            "type = \"triangle\"\nvertices = [[0, 0, 0], [1, 1, 1], [2, 2, 2]]",
            "bad.toml:13:1: objects[0].vertices: is degenerate",
        ),
        (
            "camera",
            "look_at = [0, 0, 0]",
            "look_at = [0, 0, 5]",
            "bad.toml:3:1: camera.look_at: must differ from look_from",
        ),
    ];
    assert!(wgtrace::load_scene_str(base, Path::new("bad.toml"), &Overrides::default()).is_ok());
    each_edit_fails(base, table);
    // every problem at once, each with its own place
    let many = base
        .replacen("width = 8", "width = 0", 1)
        .replacen("ior = 1.5", "ior = 0", 1)
        .replacen("radius = 1", "radius = -2", 1);
    let e = load_err(&many);
    for expected in [
        "bad.toml:5:1: render.width",
        "bad.toml:11:5: materials.g.ior",
        "bad.toml:13:1: objects[0].radius",
    ] {
        assert!(e.contains(expected), "{expected}: {e}");
    }
}

/// The conductor's and the thin dielectric's bad values: each one error naming the file,
/// line and key; an unknown metal lists the known ones.
#[test]
fn conductor_and_window_keys_are_checked_with_file_line_and_key() {
    let base = r#"[camera]
look_from = [0, 0, 5]
look_at = [0, 0, 0]
[render]
width = 8
height = 8
[materials]
m = { type = "conductor", material = "Au", roughness = 0.3 }
w = { type = "thin_dielectric", ior = 1.5 }
[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "m"
"#;
    assert!(wgtrace::load_scene_str(base, Path::new("bad.toml"), &Overrides::default()).is_ok());
    let table: &[(&str, &str, &[&str])] = &[
        (
            "material = \"Au\"",
            "material = \"Gold\"",
            &[
                "bad.toml:8:5: materials.m.material: unknown conductor \"Gold\" (known: Ag, Al,",
                "Au,",
                "Cu,",
                "none)",
            ],
        ),
        (
            "roughness = 0.3",
            "roughness = 1.2",
            &["bad.toml:8:5: materials.m.roughness: must be in [0, 1], got 1.2"],
        ),
        (
            "roughness = 0.3",
            "roughness_u = -0.1",
            &["bad.toml:8:5: materials.m.roughness_u: must be in [0, 1], got -0.1"],
        ),
        (
            "material = \"Au\"",
            "material = \"Au\", eta = [1, 1, 1], k = [2, 2, 2]",
            &["bad.toml:8:5: materials.m.material: give material, or eta and k, not both"],
        ),
        (
            "material = \"Au\"",
            "eta = [1, 1, 1]",
            &["bad.toml:8:5: materials.m.eta: needs k beside it"],
        ),
        (
            "material = \"Au\"",
            "eta = [1, -1, 1], k = [2, 2, 2]",
            &["bad.toml:8:5: materials.m.eta: must be >= 0"],
        ),
        (
            "roughness = 0.3 }",
            "roughness = 0.3, distribution = \"phong\" }",
            &[
                "bad.toml:8:",
                "unknown variant `phong`, expected `ggx` or `beckmann`",
            ],
        ),
        (
            "ior = 1.5",
            "ior = 0",
            &["bad.toml:9:5: materials.w.ior: must be > 0, got 0"],
        ),
        (
            "ior = 1.5",
            "ior = 1.5, tint = [1.2, 1, 1]",
            &["bad.toml:9:5: materials.w.tint: components must be <= 1"],
        ),
    ];
    for (from, to, expected) in table {
        assert!(base.contains(from), "{to}: the edit does not apply");
        let e = load_err(&base.replacen(from, to, 1));
        for x in expected.iter() {
            assert!(e.contains(x), "{to}: {x} not in {e}");
        }
    }
}

#[test]
fn overrides_replace_render_settings_and_are_validated() {
    let o = Overrides {
        width: Some(33),
        height: Some(17),
        spp: Some(3),
        max_depth: Some(2),
        seed: Some(9),
        sampler: None,
        light_sampling: Some(wgtrace::scene::format::LightSampling::Mixture),
        filter: Some(wgtrace::scene::format::FilterKind::Tent),
        background: Some([0.5, 0.25, 0.125]),
        camera: None,
        energy_compensation: false,
        defines: Vec::new(),
    };
    let s = wgtrace::load_scene_str(POLYGON_SCENE, Path::new("p.toml"), &o).unwrap();
    assert_eq!(s.background, [0.5, 0.25, 0.125]);
    assert_eq!(
        (s.width, s.height, s.spp, s.max_depth, s.seed),
        (33, 17, 3, 2, 9)
    );
    assert_eq!(
        s.light_sampling,
        wgtrace::scene::format::LightSampling::Mixture
    );
    assert_eq!(s.filter.kind, wgtrace::scene::format::FilterKind::Tent);
    assert_eq!(s.filter.radius, 1.0);
    let zero = Overrides {
        width: Some(0),
        ..Default::default()
    };
    let e = wgtrace::load_scene_str(POLYGON_SCENE, Path::new("p.toml"), &zero).unwrap_err();
    assert!(e.to_string().contains("render.width"), "{e}");
}

#[test]
fn every_shipped_scene_loads_and_has_emitters_or_a_background() {
    for path in common::scene_files() {
        let s = wgtrace::load_scene(&path, &Overrides::default()).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            !s.emitters.is_empty() || s.background.iter().any(|&c| c > 0.0),
            "{} is dark",
            path.display()
        );
    }
}

#[test]
fn background_mistakes_are_named() {
    let base = "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[background]\n";
    let e = load_err(&format!("{base}top = [1, 1, 1]\n"));
    assert!(
        e.contains("background: a gradient needs both top and bottom"),
        "{e}"
    );
    let e = load_err(&format!(
        "{base}top = [1, 1, 1]\nbottom = [0, 0, 0]\ncolor = [1, 1, 1]\n"
    ));
    assert!(
        e.contains("give one of color, top and bottom, or texture"),
        "{e}"
    );
    let e = load_err(&format!("{base}top = [1, -1, 1]\nbottom = [0, 0, 0]\n"));
    assert!(e.contains("background.top: must be >= 0"), "{e}");
    let e = load_err(&format!("{base}texture = \"sky\"\n"));
    assert!(
        e.contains("background.texture: no texture named \"sky\""),
        "{e}"
    );
    let e = load_err(&format!(
        "{base}texture = \"sky\"\n[textures]\nsky = {{ type = \"constant\", color = [1, 1, 1] }}\n"
    ));
    assert!(e.contains("\"sky\" is not an image texture"), "{e}");
    let e = load_err(&format!("{base}color = [1, 1, 1]\nstrength = 2\n"));
    assert!(e.contains("apply to a texture background only"), "{e}");
}

/// The Mitsuba comparison's scene (`bench/cornell.toml`) loads, and is `scenes/cornell.toml`
/// with independent random samples: the same records, camera and settings otherwise.
#[test]
fn the_benchmark_cornell_box_is_the_scenes_one_with_random_samples() {
    let bench = wgtrace::load_scene(
        &common::repo_path("bench/cornell.toml"),
        &Overrides::default(),
    )
    .unwrap();
    let scene = wgtrace::load_scene(
        &common::repo_path("scenes/cornell.toml"),
        &Overrides::default(),
    )
    .unwrap();
    assert_eq!(bench.sampler, wgtrace::scene::format::SamplerKind::Random);
    assert_eq!(
        bench.light_sampling,
        wgtrace::scene::format::LightSampling::Mis
    );
    assert_eq!(bench.primitives, scene.primitives);
    assert_eq!(bench.materials, scene.materials);
    assert_eq!(bench.camera, scene.camera);
    assert_eq!(
        (bench.width, bench.height, bench.spp, bench.max_depth),
        (scene.width, scene.height, scene.spp, scene.max_depth)
    );
}

/// Groups and instances that cannot render: each one edit of a valid scene, its error
/// naming the file, the line and the key (a group's object as `groups.NAME.objects[i]`).
#[test]
fn broken_groups_and_instances_name_file_line_and_key() {
    let base = r#"[camera]
look_from = [0, 0, 5]
look_at = [0, 0, 0]
[render]
width = 8
height = 8
[materials]
m = { type = "lambertian", albedo = [0.5, 0.5, 0.5] }
lamp = { type = "emissive", radiance = [1, 1, 1] }
[[objects]]
type = "instance"
group = "g"
transform = { translate = [1, 0, 0] }
[[groups.g.objects]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "m"
"#;
    let table: &[(&str, &str, &str, &str)] = &[
        (
            "unknown group",
            "group = \"g\"",
            "group = \"h\"",
            "bad.toml:10:1: objects[0].group: unknown group \"h\" (defined: g)",
        ),
        (
            "unknown material",
            "material = \"m\"",
            "material = \"nope\"",
            "bad.toml:14:1: groups.g.objects[0].material: unknown material \"nope\"",
        ),
        (
            "bad shape",
            "radius = 1",
            "radius = -1",
            "bad.toml:14:1: groups.g.objects[0].radius: must be > 0, got -1",
        ),
        (
            "plane",
            "type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1",
            "type = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 1, 0]",
            "bad.toml:14:1: groups.g.objects[0]: a plane has no bounds",
        ),
        (
            "emitting",
            "material = \"m\"",
            "material = \"lamp\"",
            "bad.toml:14:1: groups.g.objects[0]: an emitting material in a group",
        ),
        (
            "nested",
            "type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"",
            "type = \"instance\"\ngroup = \"g\"",
            "bad.toml:14:1: groups.g.objects[0]: an instance in a group: groups do not nest",
        ),
        (
            "empty",
            "[[groups.g.objects]]",
            "[groups.e]\nobjects = []\n[[groups.g.objects]]",
            "groups.e.objects: a group needs at least one object",
        ),
        (
            "singular",
            "translate = [1, 0, 0]",
            "scale = [1, 0, 1]",
            "bad.toml:10:1: objects[0].transform.scale",
        ),
    ];
    let scene = wgtrace::load_scene_str(base, Path::new("bad.toml"), &Overrides::default())
        .expect("the base scene loads");
    assert_eq!(
        scene.primitives.len(),
        2,
        "an instance and the group's sphere"
    );
    each_edit_fails(base, table);
}
