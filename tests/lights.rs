//! Lights and light-sampling strategies against closed forms: irradiance from disk, sphere
//! and polygon lights, the solid angles light samplers cover, emission counted once, the
//! image background's distribution, and the three strategies agreeing on one image.

mod common;

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use common::{image_mean, random_f32, render_cpu, render_gpu, sample_variance, scene_from_str};
use glam::{DVec3, Vec2, Vec3};
use wgtrace::cpu::bindings::Bindings;
use wgtrace::cpu::lights::{
    choose_light, env_coords, env_direction, env_pdf, light_pdf, sample_light,
};
use wgtrace::scene::format::LightSampling;
use wgtrace::scene::records::NO_LIGHT;
use wgtrace::Accumulation;
use wgtrace::{FlatScene, Overrides};

const STRATEGIES: [LightSampling; 3] = [
    LightSampling::Bsdf,
    LightSampling::Mixture,
    LightSampling::Mis,
];

fn with_strategy(src: &str, strategy: LightSampling, dir: &Path) -> FlatScene {
    let o = Overrides {
        light_sampling: Some(strategy),
        ..Default::default()
    };
    wgtrace::load_scene_str(src, &dir.join("test.toml"), &o).unwrap_or_else(|e| panic!("{e}"))
}

/// Renders on both backends and checks every channel of the image mean against `expected`
/// to 4 standard errors (plus 1e-5 relative for zero-variance images).
fn assert_mean(what: &str, scene: &FlatScene, expected: [f64; 3]) {
    for (backend, img) in [("gpu", render_gpu(scene)), ("cpu", render_cpu(scene))] {
        let (mean, se) = image_mean(&img);
        eprintln!("{what} {backend}: {mean:.5?} +- {se:.5?}, expected {expected:.5?}");
        for c in 0..3 {
            assert!(
                (mean[c] - expected[c]).abs() <= 4.0 * se[c] + 1e-5 * expected[c].abs(),
                "{what} {backend} channel {c}: {} vs {} (standard error {})",
                mean[c],
                expected[c],
                se[c]
            );
        }
    }
}

/// A small Lambertian patch (radius 0.01, albedo 0.5, facing +y at the origin) filling a
/// camera's frame, lit by `light` only, direct lighting only.
fn patch_scene(light: &str) -> String {
    format!(
        r#"
[render]
width = 32
height = 32
spp = 64
max_depth = 2
[camera]
look_from = [0, 0.04, 0.04]
look_at = [0, 0, 0]
vfov = 4
[materials]
patch = {{ type = "lambertian", albedo = [0.5, 0.5, 0.5] }}
light = {{ type = "emissive", radiance = [4, 4, 4] }}
[[objects]]
type = "disk"
center = [0, 0, 0]
normal = [0, 1, 0]
radius = 0.01
material = "patch"
{light}
"#
    )
}

/// The patch of `patch_scene` seen straight from above, so that the points the camera sees
/// lie symmetrically about the origin: the irradiance at their mean is the origin's to
/// second order (a spot's falloff changes fast across its ramp).
fn patch_scene_from_above(light: &str) -> String {
    patch_scene(light).replace(
        "look_from = [0, 0.04, 0.04]",
        "look_from = [0, 0.05, 0]\nup = [0, 0, -1]",
    )
}

/// Lambert's formula: irradiance at the origin (normal +y) from a polygon of radiance L,
/// E = (L / 2) |sum theta_i (n . Gamma_i)|.
fn lambert_polygon(vertices: &[DVec3], l: f64) -> f64 {
    let n = DVec3::Y;
    let v: Vec<DVec3> = vertices.iter().map(|p| p.normalize()).collect();
    let mut sum = 0.0;
    for i in 0..v.len() {
        let (a, b) = (v[i], v[(i + 1) % v.len()]);
        let theta = a.dot(b).clamp(-1.0, 1.0).acos();
        sum += theta * n.dot(a.cross(b).normalize());
    }
    0.5 * l * sum.abs()
}

/// The patch shows albedo / pi x E for the closed-form irradiance E of a disk on its axis
/// (pi L R^2 / (R^2 + h^2)), a sphere above its horizon (pi L (R / d)^2 cos beta) and a
/// tilted quad (Lambert's formula), under every strategy, on both backends.
#[test]
fn area_lights_give_their_closed_form_irradiance_under_every_strategy() {
    let (l, albedo) = (4.0, 0.5);
    let quad = [
        DVec3::new(-0.5, 1.5, -0.5),
        DVec3::new(1.0, 1.5, -0.5),
        DVec3::new(1.0, 2.0, 1.0),
        DVec3::new(-0.5, 2.0, 1.0),
    ];
    let sphere_center = DVec3::new(0.6, 2.0, 0.3);
    let (r_s, d) = (0.5, sphere_center.length());
    let lights = [
        (
            "disk",
            "[[objects]]\ntype = \"disk\"\ncenter = [0, 2, 0]\nnormal = [0, -1, 0]\nradius = 1\nmaterial = \"light\"".to_string(),
            PI * l * 1.0 / (1.0 + 4.0),
        ),
        (
            "sphere",
            format!(
                "[[objects]]\ntype = \"sphere\"\ncenter = [{}, {}, {}]\nradius = {r_s}\nmaterial = \"light\"",
                sphere_center.x, sphere_center.y, sphere_center.z
            ),
            PI * l * (r_s / d).powi(2) * (sphere_center.y / d),
        ),
        (
            "polygon",
            format!(
                "[[objects]]\ntype = \"polygon\"\nvertices = {:?}\nmaterial = \"light\"",
                quad.map(|v| [v.x, v.y, v.z])
            ),
            lambert_polygon(&quad, l),
        ),
    ];
    let dir = std::env::temp_dir();
    for (name, light, e) in &lights {
        let src = patch_scene(light);
        for strategy in STRATEGIES {
            let scene = with_strategy(&src, strategy, &dir);
            let expected = albedo / PI * e;
            assert_mean(&format!("{name} {strategy:?}"), &scene, [expected; 3]);
        }
    }
}

/// Lights without a surface over the patch, under every strategy, on both backends: a
/// point light gives E = I cos(theta) / d^2 (inverse square and cosine law, per channel);
/// a spot aimed straight down gives that times glTF's falloff, halfway up its ramp (and
/// times Mitsuba's, linear in the angle, with `falloff = "mitsuba"`); a
/// directional light gives E cos(theta); a sphere between a point light and the patch
/// casts its shadow; and a point light and a directional light together add up. The
/// patch shows albedo / pi x E.
#[test]
fn point_spot_and_directional_lights_give_their_closed_form_irradiance_under_every_strategy() {
    let albedo = 0.5;
    let intensity = [2.0, 3.0, 4.0];
    let p = DVec3::new(0.3, 2.0, 0.4);
    let (d, cos) = (p.length(), p.y / p.length());
    let point = |i: [f64; 3]| i.map(|c| c * cos / (d * d));
    // the spot's axis is -y: the patch is seen at theta from it, cos(theta) = cos
    let (inner, outer) = (5f64, 25f64);
    let ramp =
        (cos - outer.to_radians().cos()) / (inner.to_radians().cos() - outer.to_radians().cos());
    assert!(
        ramp > 0.2 && ramp < 0.8,
        "the patch should lie on the ramp: {ramp}"
    );
    let linear = (outer - cos.acos().to_degrees()) / (outer - inner);
    assert!(
        linear > 0.2 && linear < 0.8 && (linear - ramp * ramp).abs() > 0.03,
        "the two ramps should differ at the patch: {linear} against {}",
        ramp * ramp
    );
    let irradiance = [1.0, 0.5, 0.25];
    // travelling along (0.6, -0.8, 0): cos(theta) = 0.8 at the patch
    let directional = irradiance.map(|c| c * 0.8);
    let point_light =
        "[[lights]]\ntype = \"point\"\nposition = [0.3, 2, 0.4]\nintensity = [2, 3, 4]\n";
    let directional_light =
        "[[lights]]\ntype = \"directional\"\ndirection = [0.6, -0.8, 0]\nirradiance = [1, 0.5, 0.25]\n";
    let cases = [
        ("point", point_light.to_string(), point(intensity)),
        (
            "spot",
            format!(
                "[[lights]]\ntype = \"spot\"\nposition = [0.3, 2, 0.4]\ndirection = [0, -1, 0]\n\
                 intensity = [2, 3, 4]\ninner_angle = {inner}\nouter_angle = {outer}\n"
            ),
            point(intensity).map(|e| e * ramp * ramp),
        ),
        (
            "spot with Mitsuba's falloff",
            format!(
                "[[lights]]\ntype = \"spot\"\nposition = [0.3, 2, 0.4]\ndirection = [0, -1, 0]\n\
                 intensity = [2, 3, 4]\ninner_angle = {inner}\nouter_angle = {outer}\n\
                 falloff = \"mitsuba\"\n"
            ),
            point(intensity).map(|e| e * linear),
        ),
        ("directional", directional_light.to_string(), directional),
        (
            "point in shadow",
            format!(
                "{point_light}[[objects]]\ntype = \"sphere\"\ncenter = [0.15, 1, 0.2]\n\
                 radius = 0.1\nmaterial = \"patch\"\n"
            ),
            [0.0; 3],
        ),
        (
            "point and directional",
            format!("{point_light}{directional_light}"),
            [0, 1, 2].map(|c| point(intensity)[c] + directional[c]),
        ),
    ];
    let dir = std::env::temp_dir();
    for (name, light, e) in &cases {
        let src = patch_scene_from_above(light);
        for strategy in STRATEGIES {
            let scene = with_strategy(&src, strategy, &dir);
            assert_mean(
                &format!("{name} {strategy:?}"),
                &scene,
                e.map(|e| albedo / PI * e),
            );
        }
    }
}

/// The furnace of the issue: a sphere whose inside emits Le = 1 (two-sided emission) and
/// reflects with albedo 0.5, seen from inside; and a closed box of inward-facing polygons
/// (twelve triangle lights) made the same way. Every camera ray sees Le / (1 - rho) = 2
/// (less 0.5^40 for the path length), whichever way the strategy finds the walls:
/// emission is counted exactly once. Inside the sphere light sampling draws by area (the
/// cone does not exist), on the walls of the box by triangle.
#[test]
fn an_emitting_furnace_converges_to_le_over_one_minus_albedo_under_every_strategy() {
    let mut walls = String::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
            let corner = |a: f32, b: f32| {
                let mut v = [0.0f32; 3];
                v[axis] = sign;
                v[i] = a;
                v[j] = b;
                Vec3::from(v)
            };
            let mut quad = [
                corner(-1.0, -1.0),
                corner(1.0, -1.0),
                corner(1.0, 1.0),
                corner(-1.0, 1.0),
            ];
            // front side (right-hand rule) toward the inside
            let n = (quad[1] - quad[0]).cross(quad[2] - quad[0]);
            if n[axis] * sign > 0.0 {
                quad.reverse();
            }
            let v: Vec<[f32; 3]> = quad.iter().map(|v| v.to_array()).collect();
            walls += &format!(
                "[[objects]]\ntype = \"polygon\"\nvertices = {v:?}\nmaterial = \"wall\"\n"
            );
        }
    }
    let sphere = "[[objects]]\ntype = \"sphere\"\ncenter = [0.2, 0.1, 0]\nradius = 1.5\nmaterial = \"wall\"\n";
    let dir = std::env::temp_dir();
    let expected = 2.0 * (1.0 - 0.5f64.powi(40));
    for (name, objects, lights) in [("sphere", sphere, 1), ("box", walls.as_str(), 12)] {
        let src = format!(
            r#"
[render]
width = 16
height = 16
spp = 64
max_depth = 40
[camera]
look_from = [0.1, 0.2, 0.3]
look_at = [0.5, -0.4, -1]
vfov = 100
[materials]
wall = {{ type = "lambertian", albedo = [0.5, 0.5, 0.5], emission = [1, 1, 1], two_sided = true }}
{objects}"#
        );
        for strategy in STRATEGIES {
            let scene = with_strategy(&src, strategy, &dir);
            assert_eq!(scene.emitters.len(), lights);
            assert_mean(
                &format!("{name} furnace {strategy:?}"),
                &scene,
                [expected; 3],
            );
        }
    }
}

/// Draws `n` light samples from p with a fixed stream of numbers.
fn light_samples(b: &Bindings, p: Vec3, n: usize) -> Vec<wgtrace::cpu::lights::LightSample> {
    let mut state = 0x1234_5678u32;
    (0..n)
        .map(|_| {
            let sel = random_f32(&mut state);
            let u = [random_f32(&mut state), random_f32(&mut state)];
            sample_light(b, p, sel, u)
        })
        .collect()
}

/// Mean and standard error of 1/pdf over the samples (0 for no sample): an unbiased
/// estimate of the solid angle the sampler covers.
fn mean_inverse_pdf(samples: &[wgtrace::cpu::lights::LightSample]) -> (f64, f64) {
    let v: Vec<f64> = samples
        .iter()
        .map(|s| {
            if s.light == NO_LIGHT {
                0.0
            } else {
                1.0 / s.pdf as f64
            }
        })
        .collect();
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

fn bindings(scene: &FlatScene) -> Bindings<'_> {
    Bindings::new(scene, scene.params(0, scene.full_band()))
}

const ONE_LIGHT: &str = r#"
[camera]
look_from = [0, 0, 5]
look_at = [0, 0, 0]
[materials]
light = { type = "emissive", radiance = [1, 1, 1], two_sided = true }
[[objects]]
"#;

/// E[1/pdf] is the solid angle a sampler covers: for a triangle, 2 atan2(a . (b x c),
/// 1 + a.b + a.c + b.c) (Van Oosterom and Strackee); for a disk seen on its axis,
/// 2 pi (1 - h / sqrt(h^2 + R^2)); for a sphere seen from outside, 2 pi (1 - cos theta_max)
/// (every sample), and from inside, the whole sphere, 4 pi. Each pdf the sampler reports
/// is also the one light_pdf gives for the same direction, as the MIS weights need.
#[test]
fn mean_inverse_pdf_of_each_light_sampler_is_the_solid_angle_it_covers() {
    let p = Vec3::new(0.3, -0.2, 0.1);
    let (a, b, c) = (
        Vec3::new(-1.0, 1.0, -2.0),
        Vec3::new(2.0, 1.5, -1.0),
        Vec3::new(0.0, 3.0, 1.0),
    );
    let (ua, ub, uc) = (
        (a - p).as_dvec3().normalize(),
        (b - p).as_dvec3().normalize(),
        (c - p).as_dvec3().normalize(),
    );
    let triangle_omega = 2.0
        * ua.dot(ub.cross(uc))
            .abs()
            .atan2(1.0 + ua.dot(ub) + ua.dot(uc) + ub.dot(uc));
    let (h, r) = (1.5f64, 0.8f64);
    let cases = [
        (
            "triangle",
            format!("type = \"triangle\"\nvertices = [{:?}, {:?}, {:?}]\nmaterial = \"light\"", a.to_array(), b.to_array(), c.to_array()),
            p,
            triangle_omega,
        ),
        (
            "disk",
            format!("type = \"disk\"\ncenter = [0, {h}, 0]\nnormal = [0, 1, 0]\nradius = {r}\nmaterial = \"light\""),
            Vec3::ZERO,
            2.0 * PI * (1.0 - h / (h * h + r * r).sqrt()),
        ),
        (
            "sphere outside",
            "type = \"sphere\"\ncenter = [0, 2, 0]\nradius = 0.5\nmaterial = \"light\"".into(),
            Vec3::ZERO,
            2.0 * PI * (1.0 - (1.0 - 0.25f64 / 4.0).sqrt()),
        ),
        (
            "tiny sphere far away",
            "type = \"sphere\"\ncenter = [0, 100, 0]\nradius = 0.01\nmaterial = \"light\"".into(),
            Vec3::ZERO,
            // 1 - cos(theta_max) by its series: the direct form cancels in f32
            2.0 * PI * (0.5 * 1e-8 + 0.125 * 1e-16),
        ),
        (
            "sphere inside",
            "type = \"sphere\"\ncenter = [0.2, 0, 0]\nradius = 1\nmaterial = \"light\"".into(),
            Vec3::new(0.0, 0.3, 0.1),
            4.0 * PI,
        ),
    ];
    for (name, object, from, omega) in cases {
        let scene = scene_from_str(&format!("{ONE_LIGHT}{object}\n"));
        let b = bindings(&scene);
        let samples = light_samples(&b, from, 100_000);
        let (mean, se) = mean_inverse_pdf(&samples);
        eprintln!("{name}: mean 1/pdf {mean:.6e} +- {se:.2e}, solid angle {omega:.6e}");
        assert!(
            (mean - omega).abs() <= 4.0 * se + 1e-5 * omega,
            "{name}: mean 1/pdf {mean} vs solid angle {omega} (standard error {se})"
        );
        for s in samples.iter().filter(|s| s.light != NO_LIGHT).take(1000) {
            let x = from + s.dist * s.dir;
            let again = light_pdf(&b, s.light, from, x, s.dir);
            assert!(
                (again - s.pdf).abs() <= 1e-3 * s.pdf,
                "{name}: light_pdf {again} vs the sampler's {}",
                s.pdf
            );
        }
    }
}

/// A triangle seen exactly edge-on gives no sample and pdf 0, never an infinite weight.
#[test]
fn a_light_seen_edge_on_gives_no_sample() {
    let scene = scene_from_str(&format!(
        "{ONE_LIGHT}type = \"triangle\"\nvertices = [[1, 0, 0], [2, 0, 0], [1, 0, 1]]\nmaterial = \"light\"\n"
    ));
    let b = bindings(&scene);
    for s in light_samples(&b, Vec3::ZERO, 1000) {
        assert_eq!(s.light, NO_LIGHT);
        assert_eq!(s.pdf, 0.0);
    }
    let pdf = light_pdf(&b, 0, Vec3::ZERO, Vec3::new(1.5, 0.0, 0.2), Vec3::X);
    assert_eq!(pdf, 0.0);
}

/// Lights are chosen in proportion to power (pi x area x luminance x sides): counts over
/// 200,000 choices match the recorded probabilities (chi-square, 3 degrees of freedom, at
/// the 1e-4 level), and the probabilities are the differences of the CDF.
#[test]
fn lights_are_chosen_in_proportion_to_their_power() {
    let scene = scene_from_str(
        r#"
[camera]
look_from = [0, 0, 5]
look_at = [0, 0, 0]
[materials]
dim = { type = "emissive", radiance = [1, 1, 1] }
bright = { type = "emissive", radiance = [5, 5, 5] }
both = { type = "emissive", radiance = [1, 1, 1], two_sided = true }
[[objects]]
type = "disk"
center = [0, 0, 0]
normal = [0, 1, 0]
radius = 1
material = "dim"
[[objects]]
type = "disk"
center = [3, 0, 0]
normal = [0, 1, 0]
radius = 1
material = "bright"
[[objects]]
type = "sphere"
center = [0, 3, 0]
radius = 0.5
material = "dim"
[[objects]]
type = "triangle"
vertices = [[0, 0, 3], [1, 0, 3], [0, 1, 3]]
material = "both"
"#,
    );
    let b = bindings(&scene);
    let n = scene.emitters.len();
    assert_eq!(n, 4);
    let pi = std::f32::consts::PI;
    let mut power: Vec<f32> = scene.emitters.iter().map(|e| e.power).collect();
    power.sort_by(f32::total_cmp);
    // triangle: area 1/2, two sides; dim disk and sphere: area pi; bright disk: 5 x pi
    let want = [pi, pi * pi, pi * pi, 5.0 * pi * pi];
    for (p, w) in power.iter().zip(want) {
        assert!((p - w).abs() <= 1e-5 * w, "power {p} vs {w}");
    }
    let mut cdf = 0.0;
    for e in &scene.emitters {
        assert!((e.cdf - (cdf + e.prob)).abs() <= 1e-6);
        cdf = e.cdf;
    }
    assert_eq!(cdf, 1.0);
    let draws = 200_000;
    let mut counts = vec![0usize; n];
    let mut state = 99u32;
    for _ in 0..draws {
        counts[choose_light(&b, random_f32(&mut state)) as usize] += 1;
    }
    let chi2: f64 = counts
        .iter()
        .zip(&scene.emitters)
        .map(|(&k, e)| {
            let expected = draws as f64 * e.prob as f64;
            (k as f64 - expected).powi(2) / expected
        })
        .sum();
    // chi-square quantile at 1 - 1e-4 with 3 degrees of freedom
    assert!(chi2 < 21.11, "chi-square {chi2}: counts {counts:?}");
}

/// Writes an equirectangular EXR image from a function of (x, y) and returns its folder.
fn write_env(name: &str, w: u32, h: u32, f: impl Fn(u32, u32) -> [f32; 3]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("wgtrace-lights-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let img = image::Rgb32FImage::from_fn(w, h, |x, y| image::Rgb(f(x, y)));
    img.save(dir.join("env.exr")).unwrap();
    dir
}

fn env_scene(rotation: f32, strength: f32, extra: &str) -> String {
    format!(
        r#"
[render]
width = 24
height = 24
spp = 64
max_depth = 2
[camera]
look_from = [0, 1, 0]
look_at = [0, 0, 0]
up = [0, 0, -1]
vfov = 30
[textures]
sky = {{ type = "image", path = "env.exr" }}
[background]
texture = "sky"
rotation = {rotation}
strength = {strength}
[materials]
floor = {{ type = "lambertian", albedo = [0.8, 0.6, 0.4] }}
[[objects]]
type = "plane"
point = [0, 0, 0]
normal = [0, 1, 0]
material = "floor"
{extra}
"#
    )
}

/// Directions and equirectangular coordinates map both ways; -z is the middle of the
/// image, +y its top row; a rotation of 90 degrees moves the middle to -x.
#[test]
fn environment_coordinates_round_trip_and_rotate() {
    let dir = write_env("coords", 8, 4, |_, _| [1.0; 3]);
    for rotation in [0.0f32, 90.0, -37.0] {
        let o = Overrides::default();
        let scene = wgtrace::load_scene_str(&env_scene(rotation, 1.0, ""), &dir.join("s.toml"), &o)
            .unwrap();
        let b = bindings(&scene);
        let mut state = 5u32;
        for _ in 0..1000 {
            let d = common::random_unit(&mut state);
            let back = env_direction(&b, env_coords(&b, d));
            assert!((back - d).length() < 1e-5, "{d} -> {back}");
        }
        let middle = env_direction(&b, Vec2::new(0.5, 0.5));
        let r = rotation.to_radians();
        let want = Vec3::new(-r.sin(), 0.0, -r.cos());
        assert!(
            (middle - want).length() < 1e-6,
            "rotation {rotation}: {middle}"
        );
        assert!((env_direction(&b, Vec2::new(0.3, 0.0)) - Vec3::Y).length() < 1e-6);
    }
}

/// The image background's distribution: its pdf integrates to 1 over the sphere (uniform
/// directions, 4 standard errors), mean 1/pdf of its samples is 4 pi (every direction can
/// be drawn), and each sample's pdf is env_pdf of its direction.
#[test]
fn environment_distribution_is_a_density_matching_its_samples() {
    // a dim sky with a sun 1000 times brighter, off-centre
    let dir = write_env("density", 64, 32, |x, y| {
        if (40..43).contains(&x) && (9..11).contains(&y) {
            [1000.0, 900.0, 800.0]
        } else {
            [0.2, 0.3, 0.5 + 0.01 * y as f32]
        }
    });
    let o = Overrides::default();
    let scene =
        wgtrace::load_scene_str(&env_scene(30.0, 2.0, ""), &dir.join("s.toml"), &o).unwrap();
    assert_eq!(scene.emitters.len(), 1);
    let b = bindings(&scene);
    let mut state = 17u32;
    let n = 400_000;
    let v: Vec<f64> = (0..n)
        .map(|_| 4.0 * PI * env_pdf(&b, common::random_unit(&mut state)) as f64)
        .collect();
    let mean = v.iter().sum::<f64>() / n as f64;
    let se =
        (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n as f64 - 1.0) / n as f64).sqrt();
    assert!(
        (mean - 1.0).abs() <= 4.0 * se,
        "integral of the pdf {mean} +- {se}"
    );
    let samples = light_samples(&b, Vec3::ZERO, 100_000);
    let (mean, se) = mean_inverse_pdf(&samples);
    assert!(
        (mean - 4.0 * PI).abs() <= 4.0 * se,
        "mean 1/pdf {mean} +- {se}"
    );
    for s in &samples[..1000] {
        let again = light_pdf(&b, s.light, Vec3::ZERO, Vec3::ZERO, s.dir);
        assert!(
            (again - s.pdf).abs() <= 1e-3 * s.pdf,
            "{again} vs {}",
            s.pdf
        );
    }
}

/// A Lambertian floor under a uniform image background of radiance c x strength shows
/// albedo x c x strength under every strategy, on both backends; under a sky with a bright
/// sun the strategies agree within their standard errors, and importance sampling the
/// image (mis) leaves far less noise than bsdf sampling.
#[test]
fn environment_lights_a_floor_under_every_strategy() {
    let c = [0.5f64, 1.0, 2.0];
    let uniform = write_env("uniform", 16, 8, |_, _| [0.5, 1.0, 2.0]);
    for strategy in STRATEGIES {
        let scene = with_strategy(&env_scene(45.0, 1.5, ""), strategy, &uniform);
        let a = [0.8, 0.6, 0.4];
        let expected = [0, 1, 2].map(|i| a[i] * c[i] * 1.5);
        assert_mean(&format!("uniform sky {strategy:?}"), &scene, expected);
    }
    let sun = write_env("sun", 64, 32, |x, y| {
        if (20..22).contains(&x) && (6..8).contains(&y) {
            [2000.0, 1800.0, 1500.0]
        } else {
            [0.1, 0.2, 0.4]
        }
    });
    let mut results: Vec<(LightSampling, Accumulation)> = Vec::new();
    for strategy in STRATEGIES {
        let scene = with_strategy(&env_scene(0.0, 1.0, ""), strategy, &sun);
        results.push((strategy, render_gpu(&scene)));
    }
    let (m_mis, se_mis) = image_mean(&results[2].1);
    for (strategy, img) in &results {
        let (m, se) = image_mean(img);
        eprintln!(
            "sun sky {strategy:?}: mean {m:.4?} +- {se:.4?}, variance per sample {:.4}",
            sample_variance(img)
        );
        for ch in 0..3 {
            let bound = 4.0 * (se[ch].powi(2) + se_mis[ch].powi(2)).sqrt();
            assert!(
                (m[ch] - m_mis[ch]).abs() <= bound,
                "{strategy:?} channel {ch}: {} vs mis {} (bound {bound})",
                m[ch],
                m_mis[ch]
            );
        }
    }
    let var = |i: usize| sample_variance(&results[i].1);
    assert!(var(2) * 10.0 < var(0), "mis {} vs bsdf {}", var(2), var(0));
}

/// A small bright sphere light and a large dim panel, both out of the frame, seen in a
/// glossy floor; and the Cornell box: the three strategies converge to the same image (tile
/// by tile, within both images' standard errors), and MIS leaves the least noise (the
/// figures are printed).
#[test]
fn strategies_agree_and_mis_leaves_the_least_noise() {
    let glossy = r#"
[render]
width = 32
height = 24
spp = 256
max_depth = 3
[camera]
look_from = [0, 1.2, 4]
look_at = [0, 0, 0]
vfov = 40
[materials]
floor = { type = "microfacet", albedo = [0.3, 0.3, 0.3], specular = [0.9, 0.9, 0.9], roughness = 0.2 }
small = { type = "emissive", radiance = [20, 18, 16] }
panel = { type = "emissive", radiance = [0.6, 0.7, 1.0] }
[[objects]]
type = "plane"
point = [0, 0, 0]
normal = [0, 1, 0]
material = "floor"
[[objects]]
type = "sphere"
center = [0.3, 2.5, -4]
radius = 0.4
material = "small"
[[objects]]
type = "polygon"
vertices = [[-4, 4, -5], [4, 4, -5], [4, 2, -6], [-4, 2, -6]]
material = "panel"
"#;
    // a smooth-shaded icosphere of glossy pbr lit from behind and beside: at its rim the
    // shading normals are bent and directions sent over the geometric surface, whose
    // densities (bsdf_eval, bsdf_pdf, scatter_pdf) every strategy must agree on
    let smooth = format!(
        r#"
[render]
width = 32
height = 24
spp = 256
max_depth = 3
[camera]
look_from = [0, 0.3, 3.2]
look_at = [0, 0, 0]
vfov = 45
[materials]
ball = {{ type = "pbr", base_color = [0.8, 0.5, 0.3], metallic = 0, roughness = 0.35 }}
side = {{ type = "emissive", radiance = [2, 1.8, 1.6] }}
panel = {{ type = "emissive", radiance = [0.6, 0.7, 1.0] }}
[[objects]]
type = "mesh"
path = "{}"
material = "ball"
[[objects]]
type = "polygon"
vertices = [[2.5, -2, 1], [2.5, 2, 1], [2.5, 2, -2], [2.5, -2, -2]]
material = "side"
[[objects]]
type = "polygon"
vertices = [[-3, 3, -3], [3, 3, -3], [3, -1, -3.5], [-3, -1, -3.5]]
material = "panel"
"#,
        common::repo_path("scenes/meshes/icosphere.obj").display()
    );
    // rough glass (it has a density) over a floor, lit by a panel above:
    // light sampling weighs its reflection and its transmission out of the sphere
    let rough_glass = r#"
[render]
width = 32
height = 24
spp = 256
max_depth = 6
[camera]
look_from = [0, 1.0, 3.5]
look_at = [0, 0.6, 0]
vfov = 40
[materials]
floor = { type = "lambertian", albedo = [0.5, 0.5, 0.5] }
frosted = { type = "dielectric", ior = 1.5, roughness = 0.4, tint = [0.9, 0.95, 1] }
panel = { type = "emissive", radiance = [4, 3.8, 3.5] }
[[objects]]
type = "plane"
point = [0, 0, 0]
normal = [0, 1, 0]
material = "floor"
[[objects]]
type = "sphere"
center = [0, 0.7, 0]
radius = 0.7
material = "frosted"
[[objects]]
type = "polygon"
vertices = [[-1, 3, -1], [1, 3, -1], [1, 3, 1], [-1, 3, 1]]
material = "panel"
"#;
    let cornell = std::fs::read_to_string(common::repo_path("scenes/cornell.toml")).unwrap();
    let dir = std::env::temp_dir();
    for (name, src, size) in [
        ("glossy", glossy.to_string(), None),
        ("smooth-shaded", smooth, None),
        ("rough glass", rough_glass.to_string(), None),
        ("cornell", cornell, Some(32)),
    ] {
        let mut imgs = Vec::new();
        for strategy in STRATEGIES {
            let o = Overrides {
                light_sampling: Some(strategy),
                width: size,
                height: size,
                spp: size.map(|_| 64),
                ..Default::default()
            };
            let scene = wgtrace::load_scene_str(&src, &dir.join("test.toml"), &o).unwrap();
            imgs.push(render_gpu(&scene));
        }
        let var: Vec<f64> = imgs.iter().map(sample_variance).collect();
        eprintln!(
            "{name}: variance per sample: bsdf {:.5}, mixture {:.5}, mis {:.5}",
            var[0], var[1], var[2]
        );
        for (i, j) in [(0, 2), (1, 2), (0, 1)] {
            let c = common::compare(&imgs[i], &imgs[j], 8);
            assert!(
                c.failed_tiles.is_empty(),
                "{name}: {:?} and {:?} differ:\n{}",
                STRATEGIES[i],
                STRATEGIES[j],
                c.failed_tiles.join("\n")
            );
        }
        assert!(var[2] < var[1] && var[2] < var[0], "{name}: {var:?}");
    }
}

/// The mixture tests every light at every bounce: 1280 emissive triangles x 64 bounces is
/// more loop iterations than llvmpipe runs, so the GPU backend refuses the render with a
/// message naming the cause instead of returning a silently truncated image; MIS needs no
/// such loop and renders.
#[test]
fn a_mixture_over_many_lights_is_refused_on_llvmpipe_rather_than_cut_short() {
    let src = r#"
[render]
width = 8
height = 8
spp = 1
max_depth = 64
light_sampling = "mixture"
[camera]
look_from = [0, 0, 5]
look_at = [0, 0, 0]
[materials]
glow = { type = "lambertian", albedo = [0.5, 0.5, 0.5], emission = [1, 1, 1] }
[[objects]]
type = "mesh"
path = "meshes/icosphere.obj"
material = "glow"
"#;
    let scene = common::scene_from_file_str(src, "scenes/test.toml");
    assert_eq!(scene.emitters.len(), 1280);
    assert_eq!(
        wgtrace::gpu::GpuPlan::new(
            &scene,
            &wgtrace::gpu::limits::DeviceFit::portable(),
            &wgtrace::Tuning::default()
        )
        .path_loops,
        64 * (1 + 1280)
    );
    let llvmpipe = common::gpu_context().info.name.contains("llvmpipe");
    match wgtrace::Engine::gpu(&scene, 0) {
        Err(e) => {
            assert!(llvmpipe, "{e}");
            assert!(
                e.to_string().contains("light_sampling = \"mixture\""),
                "{e}"
            );
        }
        Ok(_) => assert!(
            !llvmpipe,
            "llvmpipe accepted 81920 loop iterations per path"
        ),
    }
    let mut mis = scene.clone();
    mis.light_sampling = wgtrace::scene::format::LightSampling::Mis;
    assert!(wgtrace::Engine::gpu(&mis, 0).is_ok());
}

/// Mistakes in `[[lights]]` are named with the file, the line of the light's table and
/// its key, all of them at once; a spot with a hard edge (equal angles) loads.
#[test]
fn light_mistakes_are_named_with_their_line_and_key() {
    let base = "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n";
    let cases = [
        (
            "[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = [1, -1, 1]\n",
            vec!["bad.toml:4:1: lights[0].intensity: must be >= 0, got [1.0, -1.0, 1.0]"],
        ),
        (
            "[[lights]]\ntype = \"spot\"\nposition = [0, 1, 0]\nintensity = [1, 1, 1]\n",
            vec!["bad.toml:4:1: lights[0]: needs exactly one of direction and look_at"],
        ),
        (
            "[[lights]]\ntype = \"spot\"\nposition = [0, 1, 0]\nlook_at = [0, 1, 0]\n\
             intensity = [1, 1, 1]\ninner_angle = 30\nouter_angle = 20\n",
            vec![
                "bad.toml:4:1: lights[0].look_at: must differ from position",
                "bad.toml:4:1: lights[0].inner_angle: must be in [0, outer_angle = 20] degrees, got 30",
            ],
        ),
        (
            "[[lights]]\ntype = \"spot\"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\n\
             intensity = [1, 1, 1]\nouter_angle = 120\n",
            vec!["bad.toml:4:1: lights[0].outer_angle: must be in (0, 90] degrees, got 120"],
        ),
        (
            "[[lights]]\ntype = \"spot\"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\n\
             intensity = [1, 1, 1]\nouter_angle = 90\ntexture = \"slides\"\nup = [0, 2, 0]\n",
            vec![
                "bad.toml:4:1: lights[0].texture: unknown texture \"slides\" (defined: none)",
                "bad.toml:4:1: lights[0].up: must not be parallel to the spot's axis",
                "bad.toml:4:1: lights[0].outer_angle: must be under 90 degrees with a texture, got 90",
            ],
        ),
        (
            "[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = [1, 1, 1]\n\
             [[lights]]\ntype = \"directional\"\ndirection = [0, 0, 0]\nirradiance = [1, 1, 1]\n",
            vec!["bad.toml:8:1: lights[1].direction: must be non-zero"],
        ),
        (
            "[[lights]]\ntype = \"projector\"\nposition = [0, 1, 0]\nlook_at = [0, 0, 0]\n\
             up = [0, 2, 0]\nfov = 180\nirradiance = \"slides\"\nscale = -1\n",
            vec![
                "bad.toml:4:1: lights[0].up: must not be parallel to the projector's axis",
                "bad.toml:4:1: lights[0].fov: must be in (0, 180) degrees, got 180",
                "bad.toml:4:1: lights[0].irradiance: unknown texture \"slides\" (defined: none)",
                "bad.toml:4:1: lights[0].scale: must be >= 0, got -1",
            ],
        ),
        (
            "[[lights]]\ntype = \"sun\"\ndirection = [0, -1, 0]\n",
            vec!["bad.toml:5:8: unknown variant `sun`, expected one of `point`, `spot`, `directional`, `projector`"],
        ),
    ];
    for (lights, expected) in cases {
        let src = format!("{base}{lights}");
        let e = match wgtrace::load_scene_str(&src, Path::new("bad.toml"), &Overrides::default()) {
            Ok(_) => panic!("should not load:\n{src}"),
            Err(e) => e.to_string(),
        };
        for want in expected {
            assert!(e.contains(want), "{want}\nnot in:\n{e}");
        }
    }
    let hard = format!(
        "{base}[[lights]]\ntype = \"spot\"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\n\
         intensity = [1, 1, 1]\ninner_angle = 20\nouter_angle = 20\n"
    );
    let scene = wgtrace::load_scene_str(&hard, Path::new("hard.toml"), &Overrides::default())
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.num_punctual, 1);
    assert!(scene.emits());
}

/// The scene of the projector tests: a diffuse plane (albedo 0.5) at z = 0 facing +z, seen
/// by an orthographic camera 4 units tall on 16 x 16 pixels (a pixel a quarter unit), lit
/// only by `light` at max_depth 2.
fn projector_scene(light: &str, textures: &str) -> String {
    format!(
        r#"
[render]
width = 16
height = 16
spp = 4
max_depth = 2

[camera]
projection = "orthographic"
height = 4
look_from = [0, 0, 3]
look_at = [0, 0, 0]

[background]
color = [0, 0, 0]

{textures}

[materials]
plane = {{ type = "lambertian", albedo = [0.5, 0.5, 0.5] }}

[[objects]]
type = "polygon"
vertices = [[-10, -10, 0], [10, -10, 0], [10, 10, 0], [-10, 10, 0]]
material = "plane"

[[lights]]
type = "projector"
position = [0, 0, 2]
look_at = [0, 0, 0]
fov = 53.13010235415598   # tan(fov / 2) = 0.5: the frustum is 2 units wide at the plane
{light}
"#
    )
}

/// A projector of irradiance E times `scale` lights a diffuse plane facing it at distance D
/// with pi E scale / D^2 everywhere inside its frustum (Mitsuba 3's projector: a flat
/// projection stays flat) and nothing outside, so every pixel of the orthographic view
/// wholly inside reads albedo E scale / D^2 and every pixel wholly outside 0, on both
/// backends. An image lands upright and unmirrored (a 2 x 2 image's top-right texel, green,
/// on the plane's top right), and its aspect sets the frustum's height (a 2 x 1 image
/// lights half as tall a band).
#[test]
fn a_projector_lights_its_frustum_flat_upright_and_at_its_images_aspect() {
    let dir = common::tmp_dir("projector");
    let png = |name: &str, w: u32, h: u32, texels: &[[u8; 3]]| {
        let mut img = image::RgbImage::new(w, h);
        for (i, t) in texels.iter().enumerate() {
            img.put_pixel(i as u32 % w, i as u32 / w, image::Rgb(*t));
        }
        let path = dir.join(name);
        img.save(&path).unwrap();
        path.display().to_string().replace('\\', "/")
    };
    let quad = png(
        "quad.png",
        2,
        2,
        &[[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255]],
    );
    let wide = png("wide.png", 2, 1, &[[255, 255, 255], [255, 255, 255]]);
    let textures = format!(
        "[textures]\nquad = {{ type = \"image\", path = \"{quad}\", filter = \"nearest\" }}\n\
         wide = {{ type = \"image\", path = \"{wide}\", filter = \"nearest\" }}\n"
    );
    // pixel (x, y) covers x in [-2 + x / 4, -2 + (x + 1) / 4] and y in [2 - (y + 1) / 4,
    // 2 - y / 4]: pixels 4..12 lie inside [-1, 1], the frustum's width at the plane
    let inside = |i: u32, lo: u32, hi: u32| (lo..hi).contains(&i);
    let red = [1.0f32, 0.0, 0.0];
    let green = [0.0f32, 1.0, 0.0];
    let blue = [0.0f32, 0.0, 1.0];
    let white = [1.0f32; 3];
    type Expect = Box<dyn Fn(u32, u32) -> Option<[f32; 3]>>;
    let cases: [(&str, &str, Expect); 3] = [
        (
            "constant",
            "irradiance = [1, 2, 4]\nscale = 2",
            // 0.5 x 2 x E / 2^2
            Box::new(move |x, y| {
                let lit = inside(x, 4, 12) && inside(y, 4, 12);
                let dark = !inside(x, 3, 13) || !inside(y, 3, 13);
                (lit || dark).then_some(if lit { [0.25, 0.5, 1.0] } else { [0.0; 3] })
            }),
        ),
        (
            "2 x 2 image",
            "irradiance = \"quad\"",
            Box::new(move |x, y| {
                let q = match (
                    inside(x, 4, 8),
                    inside(x, 8, 12),
                    inside(y, 4, 8),
                    inside(y, 8, 12),
                ) {
                    (true, _, true, _) => red,
                    (_, true, true, _) => green,
                    (true, _, _, true) => blue,
                    (_, true, _, true) => white,
                    _ => return (!inside(x, 3, 13) || !inside(y, 3, 13)).then_some([0.0; 3]),
                };
                Some(q.map(|c| 0.125 * c))
            }),
        ),
        (
            "2 x 1 image",
            "irradiance = \"wide\"",
            // tan of half the height's angle 0.25: y in [-0.5, 0.5], rows 6..10
            Box::new(move |x, y| {
                let lit = inside(x, 4, 12) && inside(y, 6, 10);
                let dark = !inside(x, 3, 13) || !inside(y, 5, 11);
                (lit || dark).then_some(if lit { [0.125; 3] } else { [0.0; 3] })
            }),
        ),
    ];
    for (name, light, expect) in &cases {
        let scene = wgtrace::load_scene_str(
            &projector_scene(light, &textures),
            &dir.join("projector.toml"),
            &Overrides::default(),
        )
        .unwrap_or_else(|e| panic!("{name}: {e}"));
        for (backend, img) in [("gpu", render_gpu(&scene)), ("cpu", render_cpu(&scene))] {
            let mut checked = 0;
            for y in 0..16u32 {
                for x in 0..16u32 {
                    let Some(want) = expect(x, y) else { continue };
                    let got = img.mean((y * 16 + x) as usize);
                    for c in 0..3 {
                        assert!(
                            (got[c] - want[c]).abs() <= 1e-4 * want[c].max(1e-3),
                            "{name}, {backend}: pixel ({x}, {y}) reads {got:?}, expected {want:?}"
                        );
                    }
                    checked += 1;
                }
            }
            assert!(
                checked >= 150,
                "{name}, {backend}: {checked} pixels checked"
            );
        }
    }
}
