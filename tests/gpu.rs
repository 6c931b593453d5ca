//! GPU tests on the first Vulkan adapter (lavapipe in CI). They fail, never skip, when no
//! adapter exists. Each compares the GPU with the CPU reference or with a closed form.

mod common;

use common::{compare, render_cpu, render_gpu, scene_from_str};
use wgtrace::Overrides;

/// Every scene in `scenes/` but the showcase (its own test, below), small, same seed: GPU
/// and CPU agree statistically per tile, and most pixels agree to 1e-3 (the random numbers
/// are identical; only the math library's last bits differ, and a path that flips a
/// decision near an edge diverges).
#[test]
fn gpu_matches_cpu_on_every_scene() {
    for path in common::scene_files_but_showcase() {
        gpu_matches_cpu_on(&path);
    }
}

/// [`gpu_matches_cpu_on_every_scene`] on the showcase (`common::SHOWCASE` says why apart).
#[test]
fn gpu_matches_cpu_on_the_showcase() {
    gpu_matches_cpu_on(&common::repo_path(common::SHOWCASE));
}

fn gpu_matches_cpu_on(path: &std::path::Path) {
    let o = Overrides {
        width: Some(64),
        height: Some(48),
        spp: Some(32),
        seed: Some(7),
        ..Default::default()
    };
    let scene = wgtrace::load_scene(path, &o).unwrap_or_else(|e| panic!("{e}"));
    let gpu = render_gpu(&scene);
    let cpu = render_cpu(&scene);
    let c = compare(&gpu, &cpu, 8);
    eprintln!(
        "{}: {} tiles, {} outside the bound, {:.4} of pixels agree to 1e-3",
        path.display(),
        c.tiles,
        c.failed_tiles.len(),
        c.agree_fraction
    );
    assert!(
        c.failed_tiles.is_empty(),
        "{}: GPU and CPU differ beyond noise:\n{}",
        path.display(),
        c.failed_tiles.join("\n")
    );
    assert!(
        c.agree_fraction >= 0.99,
        "{}: only {:.4} of pixels agree to 1e-3",
        path.display(),
        c.agree_fraction
    );
}

/// Every pixel sampler gives the same image on both backends (the default, Sobol', is
/// covered above on every scene).
#[test]
fn gpu_matches_cpu_with_every_sampler() {
    use wgtrace::scene::format::SamplerKind;
    for sampler in [
        SamplerKind::Random,
        SamplerKind::Jittered,
        SamplerKind::Hammersley,
    ] {
        let o = Overrides {
            width: Some(48),
            height: Some(48),
            spp: Some(16),
            seed: Some(3),
            sampler: Some(sampler),
            ..Default::default()
        };
        let scene = wgtrace::load_scene(&common::repo_path("scenes/cornell.toml"), &o).unwrap();
        let c = compare(&render_gpu(&scene), &render_cpu(&scene), 8);
        assert!(
            c.failed_tiles.is_empty() && c.agree_fraction >= 0.99,
            "{sampler:?}: {} tiles outside the bound, {:.4} of pixels agree",
            c.failed_tiles.len(),
            c.agree_fraction
        );
    }
}

/// The other light-sampling strategies give the same image on both backends too, on the
/// scenes with area lights of every kind and with an image background (mis, the default,
/// is covered above on every scene).
#[test]
fn gpu_matches_cpu_under_every_light_sampling_strategy() {
    use wgtrace::scene::format::LightSampling;
    for scene in ["scenes/lights.toml", "scenes/sky.toml"] {
        for strategy in [LightSampling::Bsdf, LightSampling::Mixture] {
            let o = Overrides {
                width: Some(48),
                height: Some(32),
                spp: Some(16),
                seed: Some(5),
                light_sampling: Some(strategy),
                ..Default::default()
            };
            let s = wgtrace::load_scene(&common::repo_path(scene), &o).unwrap();
            let c = compare(&render_gpu(&s), &render_cpu(&s), 8);
            assert!(
                c.failed_tiles.is_empty() && c.agree_fraction >= 0.99,
                "{scene} {strategy:?}: {} tiles outside the bound, {:.4} of pixels agree",
                c.failed_tiles.len(),
                c.agree_fraction
            );
        }
    }
}

const FURNACE: &str = r#"
[render]
width = 40
height = 30
spp = 16
max_depth = MAX_DEPTH
seed = 3

[camera]
look_from = [0, 0, 3]
look_at = [0, 0, 0]
vfov = 45

[background]
color = [0.8, 0.6, 1.0]

[materials]
grey = { type = "lambertian", albedo = [0.5, 0.25, 0.75] }

[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "grey"
"#;

fn furnace(max_depth: u32) -> wgtrace::FlatScene {
    scene_from_str(&FURNACE.replace("MAX_DEPTH", &max_depth.to_string()))
}

/// A Lambertian sphere of albedo a under a uniform background L: one bounce leaves a convex
/// object for good, and cosine sampling weights it by exactly a, so every sample on the
/// sphere is a * L and every other is L, with no noise at all. The camera samples are the
/// same at every max_depth (same random numbers), so the max_depth = 1 image, where the
/// sphere is black, gives each pixel's sphere coverage f = 1 - I1 / L, and the furnace pixel
/// must be f a L + (1 - f) L = I1 + a (L - I1), on both backends, to float rounding. A
/// self-intersection (acne) or a leak breaks it at once.
#[test]
fn furnace_sphere_shows_albedo_times_background_on_both_backends() {
    let l = [0.8f32, 0.6, 1.0];
    let a = [0.5f32, 0.25, 0.75];
    for (name, render) in [
        (
            "gpu",
            render_gpu as fn(&wgtrace::FlatScene) -> wgtrace::Accumulation,
        ),
        ("cpu", render_cpu),
    ] {
        let coverage = render(&furnace(1));
        let mut interior = 0;
        for depth in [2, 5] {
            let img = render(&furnace(depth));
            for i in 0..img.pixel_count() {
                let (m, m1) = (img.mean(i), coverage.mean(i));
                for c in 0..3 {
                    let expected = m1[c] + a[c] * (l[c] - m1[c]);
                    assert!(
                        (m[c] - expected).abs() <= 1e-5,
                        "{name} depth {depth} pixel {i} channel {c}: {} vs {expected}",
                        m[c]
                    );
                }
                if m1 == [0.0; 3] {
                    interior += 1;
                    assert!((0..3).all(|c| (m[c] - a[c] * l[c]).abs() <= 1e-6));
                }
                // Noise only where the pixel straddles the silhouette.
                let noisy = img.variance(i).iter().sum::<f32>() > 1e-8;
                assert_eq!(noisy, m1 != [0.0; 3] && m1 != l, "{name} pixel {i}");
            }
        }
        assert!(
            interior > 200,
            "{name}: the sphere covers too few pixels ({interior})"
        );
    }
}

/// The furnace at extreme scales: a sphere of radius 1e-3 and one of radius 1e4 whose center
/// is 3.7e4 from the origin, each filling the whole frame. Every pixel sees the sphere, so
/// every pixel must be exactly albedo x background at max_depth 2 and 5 on both backends: a
/// hole (a missed primary ray) shows the background, a speckle (a bounce ray that re-hits
/// the sphere) darkens the pixel.
#[test]
fn tiny_and_huge_spheres_render_without_holes_or_speckles() {
    let l = [0.8f32, 0.6, 1.0];
    let a = [0.5f32, 0.25, 0.75];
    for (center, radius) in [([1.0f32, 2.0, 3.0], 1e-3f32), ([3e4, -2e4, 1e4], 1e4)] {
        for depth in [2, 5] {
            let [x, y, z] = center;
            let src = FURNACE
                .replace("MAX_DEPTH", &depth.to_string())
                .replace(
                    "center = [0, 0, 0]\nradius = 1",
                    &format!("center = [{x}, {y}, {z}]\nradius = {radius}"),
                )
                .replace(
                    "look_from = [0, 0, 3]",
                    &format!("look_from = [{x}, {y}, {}]", z + 3.0 * radius),
                )
                .replace("look_at = [0, 0, 0]", &format!("look_at = [{x}, {y}, {z}]"))
                .replace("vfov = 45", "vfov = 20");
            let s = scene_from_str(&src);
            for (name, img) in [("gpu", render_gpu(&s)), ("cpu", render_cpu(&s))] {
                let bad = (0..img.pixel_count())
                    .filter(|&i| (0..3).any(|c| (img.mean(i)[c] - a[c] * l[c]).abs() > 1e-5))
                    .count();
                assert_eq!(
                    bad, 0,
                    "{name}: radius {radius}, max_depth {depth}: {bad} pixels off"
                );
            }
        }
    }
}

/// A Lambertian floor of albedo a under the gradient sky L(d) = B + (T - B)(d.y + 1) / 2
/// receives E = pi (B + T) / 2 + 2 pi (T - B) / 6 (the cosine-weighted integral over the
/// upper hemisphere), so at max_depth 2 it shows a ((B + T) / 2 + (T - B) / 3). The image
/// mean holds it to 4 standard errors on both backends.
#[test]
fn gradient_sky_lights_a_floor_by_its_closed_form() {
    let src = r#"
[render]
width = 32
height = 32
spp = 64
max_depth = 2
[camera]
look_from = [0, 1, 0]
look_at = [0, 0, 0]
up = [0, 0, -1]
vfov = 30
[background]
top = [0.2, 0.5, 1.0]
bottom = [1.0, 0.6, 0.1]
[materials]
floor = { type = "lambertian", albedo = [0.8, 0.6, 0.4] }
[[objects]]
type = "plane"
point = [0, 0, 0]
normal = [0, 1, 0]
material = "floor"
"#;
    let (t, b, a) = ([0.2f64, 0.5, 1.0], [1.0f64, 0.6, 0.1], [0.8f64, 0.6, 0.4]);
    let s = scene_from_str(src);
    for (name, img) in [("gpu", render_gpu(&s)), ("cpu", render_cpu(&s))] {
        let (mean, se) = common::image_mean(&img);
        for c in 0..3 {
            let expected = a[c] * ((b[c] + t[c]) / 2.0 + (t[c] - b[c]) / 3.0);
            assert!(
                (mean[c] - expected).abs() <= 4.0 * se[c] + 1e-6,
                "{name} channel {c}: {} vs {expected} (standard error {})",
                mean[c],
                se[c]
            );
        }
    }
}

/// `one_sided`: a Lambertian floor of albedo 0.5 under a white sky shows exactly 0.5 from
/// its front, one-sided or not; seen from its back (the plane's normal turned away from
/// the camera) it shows 0.5 by default (both sides reflect) and exactly 0 when one-sided,
/// on both backends, every pixel.
#[test]
fn one_sided_materials_are_black_behind() {
    let src = r#"
[render]
width = 16
height = 16
spp = 8
max_depth = 2
[camera]
look_from = [0, 1, 0]
look_at = [0, 0, 0]
up = [0, 0, -1]
vfov = 30
[background]
color = [1, 1, 1]
[materials]
floor = { type = "lambertian", albedo = [0.5, 0.5, 0.5] ONE_SIDED }
[[objects]]
type = "plane"
point = [0, 0, 0]
normal = [0, NORMAL, 0]
material = "floor"
"#;
    for (one_sided, normal, expected) in [
        (false, "1", 0.5f32),
        (true, "1", 0.5),
        (false, "-1", 0.5),
        (true, "-1", 0.0),
    ] {
        let s = scene_from_str(
            &src.replace(
                "ONE_SIDED",
                if one_sided { ", one_sided = true" } else { "" },
            )
            .replace("NORMAL", normal),
        );
        for (name, img) in [("gpu", render_gpu(&s)), ("cpu", render_cpu(&s))] {
            let bad = (0..img.pixel_count())
                .filter(|&i| (0..3).any(|c| (img.mean(i)[c] - expected).abs() > 1e-5))
                .count();
            assert_eq!(
                bad, 0,
                "{name}: one_sided {one_sided}, normal y {normal}: {bad} pixels off"
            );
        }
    }
}

/// `blend`: under a white sky at max_depth 2, a blend of a white (albedo 1) and a black
/// Lambertian material returns 1 or 0 per sample, so its mean is the white part's share:
/// 1 - weight for a number; for a checker of weights (cells of 0.2 and 0.6) what a
/// Lambertian floor of the complementary checker (0.8 and 0.4) reflects, exactly; 1/4 for
/// a blend of a 50/50 blend and black at 1/2. Each image mean within 4 standard errors of
/// the Bernoulli mean, on both backends. Then under a small
/// light with MIS, a blend of a rough conductor and a Lambertian at 0.3 equals 0.7 x the
/// Lambertian's image plus 0.3 x the conductor's (each rendered on its own), within 4
/// combined standard errors of the image means.
#[test]
fn blends_mix_their_parts_by_weight() {
    let src = r#"
[render]
width = 16
height = 16
spp = 64
max_depth = 2
[camera]
look_from = [0, 1, 0]
look_at = [0, 0, 0]
up = [0, 0, -1]
vfov = 30
[background]
color = [1, 1, 1]
[textures]
cells = { type = "checker", scale = 40, even = [0.2, 0.2, 0.2], odd = [0.6, 0.6, 0.6] }
complement = { type = "checker", scale = 40, even = [0.8, 0.8, 0.8], odd = [0.4, 0.4, 0.4] }
[materials]
white = { type = "lambertian", albedo = [1, 1, 1] }
black = { type = "lambertian", albedo = [0, 0, 0] }
half = { type = "blend", first = "white", second = "black", weight = 0.5 }
floor = BLEND
[[objects]]
type = "plane"
point = [0, 0, 0]
normal = [0, 1, 0]
material = "floor"
"#;
    for (blend, expected) in [
        (
            "{ type = \"blend\", first = \"white\", second = \"black\", weight = 0.3 }",
            0.7f64,
        ),
        (
            "{ type = \"blend\", first = \"black\", second = \"white\", weight = 0.9 }",
            0.9,
        ),
        (
            "{ type = \"blend\", first = \"white\", second = \"black\", weight = \"cells\" }",
            -1.0,
        ),
        (
            "{ type = \"blend\", first = \"half\", second = \"black\", weight = 0.5 }",
            0.25,
        ),
    ] {
        let s = scene_from_str(&src.replace("BLEND", blend));
        // a textured weight: the white part's share is what a Lambertian floor of the
        // complementary checker reflects, exactly, sample by sample
        let exact = scene_from_str(&src.replace(
            "BLEND",
            "{ type = \"lambertian\", albedo = \"complement\" }",
        ));
        for (name, img, reference) in [
            ("gpu", render_gpu(&s), render_gpu(&exact)),
            ("cpu", render_cpu(&s), render_cpu(&exact)),
        ] {
            let (mean, _) = common::image_mean(&img);
            let expected = if expected < 0.0 {
                common::image_mean(&reference).0[0]
            } else {
                expected
            };
            let n = (img.pixel_count() * 64) as f64;
            // at most the Bernoulli spread of the mean share (a spread of shares has less)
            let se = (expected * (1.0 - expected) / n).sqrt();
            assert!(
                (mean[0] - expected).abs() <= 4.0 * se,
                "{name}: {blend}: {} vs {expected} (standard error {se})",
                mean[0]
            );
        }
    }
    let lit = r#"
[render]
width = 16
height = 16
spp = 256
max_depth = 3
light_sampling = "mis"
[camera]
look_from = [0, 2, 3]
look_at = [0, 0, 0]
vfov = 40
[materials]
gold = { type = "conductor", material = "Au", roughness = 0.4 }
clay = { type = "lambertian", albedo = [0.7, 0.5, 0.3] }
mix = { type = "blend", first = "clay", second = "gold", weight = 0.3 }
lamp = { type = "emissive", radiance = [20, 20, 20] }
[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "SURFACE"
[[objects]]
type = "sphere"
center = [1.5, 2.5, 1]
radius = 0.3
material = "lamp"
"#;
    let parts = |backend: fn(&wgtrace::FlatScene) -> wgtrace::Accumulation, m: &str| {
        common::image_mean(&backend(&scene_from_str(&lit.replace("SURFACE", m))))
    };
    for (name, backend) in [
        ("gpu", render_gpu as fn(&_) -> _),
        ("cpu", render_cpu as fn(&_) -> _),
    ] {
        let (mix, mix_se) = parts(backend, "mix");
        let (clay, clay_se) = parts(backend, "clay");
        let (gold, gold_se) = parts(backend, "gold");
        for c in 0..3 {
            let expected = 0.7 * clay[c] + 0.3 * gold[c];
            let se = (mix_se[c].powi(2) + (0.7 * clay_se[c]).powi(2) + (0.3 * gold_se[c]).powi(2))
                .sqrt();
            assert!(
                (mix[c] - expected).abs() <= 4.0 * se,
                "{name} channel {c}: blend {} vs parts {expected} (standard error {se})",
                mix[c]
            );
        }
    }
}

/// Bump maps by their closed form: a floor (normal +y, uv = 0.1 x (x, -z), so dp/du =
/// (10, 0, 0) and dp/dv = (0, 0, -10)) bumped by a 2 x 1 black-and-white image (clamped,
/// linear), whose height rises 2 per unit of u between its texel centres. With
/// `bump_scale` k the surface's slope along x is 2k / 10, so its normal tilts toward -x
/// by atan(0.2 k). Seen from above where u is in [0.4, 0.6], lit straight down by a
/// directional light of irradiance E and nothing else (black sky, max_depth 2), a white
/// Lambertian floor shows E cos(tilt) / pi in every pixel, exactly, on both backends: k =
/// 0 (no bump), 2.5 (cos 0.894427), -2.5 (the same tilt the other way). A light from
/// (-1, 1, 0) tells the two tilts apart: E cos(45 deg -+ tilt) / pi.
#[test]
fn bump_maps_tilt_the_normal_by_their_slope() {
    let dir = common::tmp_dir("bump");
    let img = image::ImageBuffer::<image::Rgb<u8>, _>::from_fn(2, 1, |x, _| {
        image::Rgb([(x * 255) as u8; 3])
    });
    img.save(dir.join("ramp.png")).unwrap();
    let src = r#"
[render]
width = 8
height = 8
spp = 4
max_depth = 2
[camera]
look_from = [5, 2, 0]
look_at = [5, 0, 0]
up = [0, 0, -1]
vfov = 20
[textures]
ramp = { type = "image", path = "ramp.png", wrap = "clamp", color_space = "linear" }
[materials]
floor = { type = "lambertian", albedo = [1, 1, 1], bump = "ramp", bump_scale = SCALE }
[[objects]]
type = "plane"
point = [0, 0, 0]
normal = [0, 1, 0]
uv_scale = 0.1
material = "floor"
[[lights]]
type = "directional"
direction = [DIRECTION]
irradiance = [2, 2, 2]
"#;
    let pi = std::f32::consts::PI;
    let tilt = |k: f32| (0.2 * k).atan();
    for (k, direction, expected) in [
        (0.0f32, "0, -1, 0", 2.0 / pi),
        (2.5, "0, -1, 0", 2.0 * tilt(2.5).cos() / pi),
        (-2.5, "0, -1, 0", 2.0 * tilt(2.5).cos() / pi),
        // the light comes from -x: a normal tilted toward -x faces it more
        (2.5, "1, -1, 0", 2.0 * (pi / 4.0 - tilt(2.5)).cos() / pi),
        (-2.5, "1, -1, 0", 2.0 * (pi / 4.0 + tilt(2.5)).cos() / pi),
    ] {
        let text = src
            .replace("SCALE", &k.to_string())
            .replace("DIRECTION", direction);
        let path = dir.join("bump.toml");
        let s = wgtrace::load_scene_str(&text, &path, &Default::default())
            .unwrap_or_else(|e| panic!("{e}"));
        for (name, img) in [("gpu", render_gpu(&s)), ("cpu", render_cpu(&s))] {
            let worst = (0..img.pixel_count())
                .map(|i| (img.mean(i)[0] - expected).abs())
                .fold(0.0f32, f32::max);
            assert!(
                worst <= 2e-4 * expected,
                "{name}: bump_scale {k}, light {direction}: off by {worst} from {expected}"
            );
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Bump maps on every shape (sphere, triangles of a mesh with uvs, plane, box, cylinder,
/// disk through a blend of two bumped parts, and a transformed sphere), with an image and
/// with noise for heights, render
/// alike on the GPU and the CPU: no tile's mean outside the z-test's bound, and the
/// pixels within what the spot check allows.
#[test]
fn bump_maps_render_alike_on_both_backends() {
    let dir = common::tmp_dir("bump-shapes");
    let img = image::ImageBuffer::<image::Rgb<u8>, _>::from_fn(16, 16, |x, y| {
        let v = (((x as f32 * 0.9).sin() * (y as f32 * 0.7).cos() * 0.5 + 0.5) * 255.0) as u8;
        image::Rgb([v; 3])
    });
    img.save(dir.join("bumps.png")).unwrap();
    std::fs::write(
        dir.join("quad.obj"),
        "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nvt 0 0\nvt 2 0\nvt 2 2\nvt 0 2\nf 1/1 4/4 3/3 2/2\n",
    )
    .unwrap();
    let src = r#"
[render]
width = 48
height = 32
spp = 64
max_depth = 3
[camera]
look_from = [0, 4, 9]
look_at = [0, 0.5, 0]
vfov = 45
[background]
top = [0.8, 0.9, 1.0]
bottom = [0.2, 0.2, 0.2]
[textures]
bumps = { type = "image", path = "bumps.png", color_space = "linear" }
noise = { type = "noise", scale = 4 }
[materials]
a = { type = "lambertian", albedo = [0.8, 0.6, 0.4], bump = "bumps", bump_scale = 0.05 }
b = { type = "conductor", material = "Cu", roughness = 0.3, bump = "noise", bump_scale = 0.3 }
c = { type = "plastic", albedo = [0.2, 0.4, 0.8], bump = "bumps", bump_scale = 0.02 }
d = { type = "blend", first = "c", second = "a", weight = 0.5 }
[[objects]]
type = "plane"
point = [0, -1, 0]
normal = [0, 1, 0]
material = "c"
[[objects]]
type = "sphere"
center = [-3, 0.5, 0]
radius = 1
material = "a"
[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "b"
transform = { scale = [1.5, 1, 1], translate = [0, 0.5, 2] }
[[objects]]
type = "mesh"
path = "quad.obj"
material = "a"
transform = { translate = [3, 1.5, 0], rotate = [60, 0, 0] }
[[objects]]
type = "box"
min = [1.5, -1, -3]
max = [3, 0.5, -1.5]
material = "b"
[[objects]]
type = "cylinder"
base = [-1, -1, -3]
top = [-1, 1, -3]
radius = 0.6
material = "a"
[[objects]]
type = "disk"
center = [-3, 1.8, -2]
normal = [0, 0.5, 1]
radius = 0.8
material = "d"
"#;
    let s = wgtrace::load_scene_str(src, &dir.join("shapes.toml"), &Default::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let (gpu, cpu) = (render_gpu(&s), render_cpu(&s));
    let c = compare(&gpu, &cpu, 8);
    assert!(c.failed_tiles.is_empty(), "{:?}", c.failed_tiles);
    // a bump map's slopes are differences of heights over a small step: they magnify the
    // last bits in which the backends' arithmetic differs (a noise's by 1e4), and a
    // glossy reflection or a far, minified bump turns those into a few percent of some
    // pixels: what the spot check allows a right GPU (PIXEL_TOLERANCE of the brightest
    // channel, MIN_AGREEMENT of the pixels) is asked here
    use wgtrace::spot_check::{MIN_AGREEMENT, PIXEL_TOLERANCE};
    let agree = (0..cpu.pixel_count())
        .filter(|&i| {
            let (a, b) = (gpu.mean(i), cpu.mean(i));
            let top = b[0].max(b[1]).max(b[2]);
            (0..3)
                .all(|k| (a[k] - b[k]).abs() <= 1e-3 * b[k].abs().max(1.0) + PIXEL_TOLERANCE * top)
        })
        .count();
    assert!(
        agree as f64 >= MIN_AGREEMENT * cpu.pixel_count() as f64,
        "{agree} of {} pixels agree",
        cpu.pixel_count()
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// `mesh_attribute` textures: a PLY quad under a white sky (max_depth 2, so a Lambertian
/// pixel is its albedo exactly) on both backends. With vertex colours (1, 1, 0), an albedo
/// of `vertex_color` shows (1, 1, 0), not its square; an albedo of 0.5 is tinted by them
/// as before, (0.5, 0.5, 0). With face colours, red and blue, `face_color` shows each
/// face's colour, constant over it: every pixel is red or blue, and both occur. A file
/// with both gives each material the set it reads. Named as Mitsuba writes them (`color_0`,
/// `color_1`, `color_2`, and a face `weight_0`, its `face_weight`), the colours read the
/// same, and a blend of a red and a blue material weighed by `face_weight` (0 and 1) shows
/// each face's part untinted by the weights, where face_color shows that face.
#[test]
fn mesh_attributes_read_vertex_and_face_colours() {
    let dir = common::tmp_dir("mesh-attribute");
    let header = |vertex_colours: bool, face_colours: bool| {
        let mut h = String::from("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n");
        if vertex_colours {
            h += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
        }
        h += "element face 2\nproperty list uchar int vertex_indices\n";
        if face_colours {
            h += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
        }
        h + "end_header\n"
    };
    let corners = ["-1 0 -1", "1 0 -1", "1 0 1", "-1 0 1"];
    let vertex_ply = header(true, false)
        + &corners.map(|c| format!("{c} 255 255 0\n")).concat()
        + "3 0 3 2\n3 0 2 1\n";
    let face_ply = header(false, true)
        + &corners.map(|c| format!("{c}\n")).concat()
        + "3 0 3 2 255 0 0\n3 0 2 1 0 0 255\n";
    let both_ply = header(true, true)
        + &corners.map(|c| format!("{c} 255 255 0\n")).concat()
        + "3 0 3 2 255 0 0\n3 0 2 1 0 0 255\n";
    let color = "property float color_0\nproperty float color_1\nproperty float color_2\n";
    let named_ply = format!(
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
         property float z\n{color}element face 2\nproperty list uchar int vertex_indices\n\
         {color}property float weight_0\nend_header\n"
    ) + &corners.map(|c| format!("{c} 1 1 0\n")).concat()
        + "3 0 3 2 1 0 0 1\n3 0 2 1 0 0 1 0\n";
    std::fs::write(dir.join("named.ply"), named_ply).unwrap();
    std::fs::write(dir.join("vertex.ply"), vertex_ply).unwrap();
    std::fs::write(dir.join("face.ply"), face_ply).unwrap();
    std::fs::write(dir.join("both.ply"), both_ply).unwrap();
    let src = |mesh: &str, albedo: &str| {
        let material = if albedo == "blend" {
            r#"{ type = "blend", first = "blue", second = "red", weight = "fw" }"#.to_string()
        } else {
            format!("{{ type = \"lambertian\", albedo = {albedo} }}")
        };
        format!(
            r#"
[render]
width = 16
height = 16
spp = 4
max_depth = 2
[camera]
look_from = [0, 3, 0]
look_at = [0, 0, 0]
up = [0, 0, -1]
vfov = 30
[background]
color = [1, 1, 1]
[textures]
vc = {{ type = "mesh_attribute", name = "vertex_color" }}
fc = {{ type = "mesh_attribute", name = "face_color" }}
fw = {{ type = "mesh_attribute", name = "face_weight" }}
[materials]
m = {material}
red = {{ type = "lambertian", albedo = [1, 0, 0] }}
blue = {{ type = "lambertian", albedo = [0, 0, 1] }}
[[objects]]
type = "mesh"
path = "{mesh}"
material = "m"
"#
        )
    };
    let load = |text: String| {
        wgtrace::load_scene_str(&text, &dir.join("s.toml"), &Default::default())
            .unwrap_or_else(|e| panic!("{e}"))
    };
    for (mesh, albedo, expected) in [
        ("vertex.ply", "\"vc\"", [1.0f32, 1.0, 0.0]),
        ("vertex.ply", "[0.5, 0.5, 0.5]", [0.5, 0.5, 0.0]),
        ("both.ply", "\"vc\"", [1.0, 1.0, 0.0]),
        ("named.ply", "\"vc\"", [1.0, 1.0, 0.0]),
    ] {
        let s = load(src(mesh, albedo));
        for (name, img) in [("gpu", render_gpu(&s)), ("cpu", render_cpu(&s))] {
            let bad = (0..img.pixel_count())
                .filter(|&i| (0..3).any(|c| (img.mean(i)[c] - expected[c]).abs() > 1e-5))
                .count();
            assert_eq!(
                bad,
                0,
                "{name}: albedo {albedo}: {bad} pixels off {expected:?} (first {:?})",
                img.mean(0)
            );
        }
    }
    let cases = [
        ("face.ply", "\"fc\""),
        ("both.ply", "\"fc\""),
        ("named.ply", "\"fc\""),
        ("named.ply", "blend"),
    ];
    let images: Vec<(String, wgtrace::Accumulation)> = cases
        .into_iter()
        .flat_map(|(mesh, albedo)| {
            let s = load(src(mesh, albedo));
            [
                (format!("{mesh}, {albedo}, gpu"), render_gpu(&s)),
                (format!("{mesh}, {albedo}, cpu"), render_cpu(&s)),
            ]
        })
        .collect();
    // the blend weighed by face_weight (1 on the red face, 0 on the blue) shows face_color's
    // image pixel for pixel: the weight read from its own column, not a colour's
    for backend in [0, 1] {
        let (fc, blend) = (&images[4 + backend].1, &images[6 + backend].1);
        let off = (0..fc.pixel_count())
            .filter(|&i| (0..3).any(|k| (fc.mean(i)[k] - blend.mean(i)[k]).abs() > 1e-5))
            .count();
        assert_eq!(
            off,
            0,
            "{}: {off} pixels off face_color's",
            images[6 + backend].0
        );
    }
    for (name, img) in images {
        let is = |i: usize, c: [f32; 3]| (0..3).all(|k| (img.mean(i)[k] - c[k]).abs() <= 1e-5);
        let red = (0..img.pixel_count())
            .filter(|&i| is(i, [1.0, 0.0, 0.0]))
            .count();
        let blue = (0..img.pixel_count())
            .filter(|&i| is(i, [0.0, 0.0, 1.0]))
            .count();
        assert!(red > 0 && blue > 0, "{name}: {red} red, {blue} blue");
        // pixels on the diagonal mix the two faces' samples
        let mixed = img.pixel_count() - red - blue;
        assert!(mixed <= 16, "{name}: {mixed} pixels neither red nor blue");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// White furnace per material: albedo 1 under a uniform background of radiance 1. Every
/// sample of a lossless material (Lambertian, mirror metal, clear glass, which splits light
/// between reflection and refraction) returns exactly 1; no material ever returns more than
/// 1; a fuzzy metal loses what its fuzz sends under the surface, and a microfacet surface
/// with kd = ks = 1 (where the naive sum of its lobes would exceed 1) stays below 1.
#[test]
fn white_furnace_returns_one_for_lossless_materials_and_never_more() {
    let template = r#"
[render]
width = 24
height = 24
spp = 16
max_depth = 64
[camera]
look_from = [0, 0, 3]
look_at = [0, 0, 0]
vfov = 45
[background]
color = [1, 1, 1]
[materials]
m = MATERIAL
[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "m"
"#;
    for (name, material, lossless) in [
        (
            "lambertian",
            r#"{ type = "lambertian", albedo = [1, 1, 1] }"#,
            true,
        ),
        ("mirror", r#"{ type = "metal", albedo = [1, 1, 1] }"#, true),
        (
            "fuzzy metal",
            r#"{ type = "metal", albedo = [1, 1, 1], fuzz = 0.7 }"#,
            false,
        ),
        ("glass", r#"{ type = "dielectric", ior = 1.5 }"#, true),
        (
            "rough microfacet",
            r#"{ type = "microfacet", albedo = [1, 1, 1], roughness = 0.3 }"#,
            false,
        ),
        (
            "smooth microfacet",
            r#"{ type = "microfacet", albedo = [1, 1, 1], roughness = 0 }"#,
            false,
        ),
        (
            "matte microfacet",
            r#"{ type = "microfacet", albedo = [1, 1, 1], roughness = 1, ior = 3 }"#,
            false,
        ),
        // glTF's metallic-roughness: its Lambertian limit (no specular layer) is lossless
        (
            "pbr without specular",
            r#"{ type = "pbr", metallic = 0, roughness = 0.5, specular = 0 }"#,
            true,
        ),
        (
            "rough pbr dielectric",
            r#"{ type = "pbr", metallic = 0, roughness = 0.5 }"#,
            false,
        ),
        // a white metal at roughness 0 (a GGX lobe of alpha 0.001) loses about 3e-6
        (
            "smooth pbr metal",
            r#"{ type = "pbr", metallic = 1, roughness = 0 }"#,
            true,
        ),
        (
            "rough pbr metal",
            r#"{ type = "pbr", metallic = 1, roughness = 0.6 }"#,
            false,
        ),
        (
            "half-metallic pbr",
            r#"{ type = "pbr", metallic = 0.5, roughness = 0.8, ior = 2 }"#,
            false,
        ),
        // pbr's layers: a coat over a white matte base, a white sheen over it, and both
        (
            "clearcoated pbr",
            r#"{ type = "pbr", metallic = 0, specular = 0, clearcoat = 1, clearcoat_roughness = 0.3 }"#,
            false,
        ),
        (
            "sheen pbr",
            r#"{ type = "pbr", metallic = 0, specular = 0, sheen_color = [1, 1, 1], sheen_roughness = 0.3 }"#,
            false,
        ),
        (
            "sheen under clearcoat",
            r#"{ type = "pbr", metallic = 0, roughness = 0.5, sheen_color = [1, 1, 1], sheen_roughness = 0.8, clearcoat = 1 }"#,
            false,
        ),
    ] {
        let s = scene_from_str(&template.replace("MATERIAL", material));
        for (backend, img) in [("gpu", render_gpu(&s)), ("cpu", render_cpu(&s))] {
            let mut total = 0.0f64;
            for i in 0..img.pixel_count() {
                let (m, var) = (img.mean(i), img.variance(i));
                let n = img.samples(i);
                for c in 0..3 {
                    // importance-sampled weights may exceed 1; their mean may not: allow
                    // 5 standard deviations of the pixel's mean
                    let bound = 1.0 + 5.0 * (var[c] / n).sqrt() + 1e-5;
                    assert!(
                        m[c] <= bound,
                        "{name} on {backend}, pixel {i}: mean {} > {bound}",
                        m[c]
                    );
                }
                total += m[0] as f64;
            }
            let mean = total / img.pixel_count() as f64;
            assert!(
                mean <= 1.0 + 1e-3,
                "{name} on {backend}: furnace mean {mean} > 1"
            );
            if lossless {
                // glass: a path still inside the sphere after 63 reflections is cut off
                assert!(
                    mean >= 1.0 - 1e-4,
                    "{name} on {backend}: furnace mean {mean}"
                );
            } else {
                assert!(
                    mean < 0.999,
                    "{name} on {backend}: fuzz should lose some light, mean {mean}"
                );
            }
        }
    }
}

/// With max_depth = 1 only emitters and the background are visible, exactly: a front-facing
/// light shows its radiance, a back-facing one-sided light is black, a back-facing
/// two-sided light shows its radiance, everything else shows the background. The camera's
/// focus plane is z = 0 and spans [-1, 1]^2, so a pixel's footprint there is known exactly.
#[test]
fn max_depth_one_shows_only_emitters_and_background_pixel_exact() {
    const W: u32 = 48;
    let src = r#"
[render]
width = 48
height = 48
spp = 8
max_depth = 1

[camera]
look_from = [0, 0, 2]
look_at = [0, 0, 0]
vfov = 53.130102354   # half height of the z = 0 plane: tan(26.565 deg) * 2 = 1

[background]
color = [0.5, 0.25, 0.75]

[materials]
front = { type = "emissive", radiance = [4, 2, 1] }
one_sided = { type = "emissive", radiance = [8, 8, 8] }
two_sided = { type = "emissive", radiance = [1, 2, 4], two_sided = true }
diffuse = { type = "lambertian", albedo = [0.9, 0.9, 0.9] }

[[objects]]   # faces the camera (+z)
type = "polygon"
vertices = [[-0.9, -0.5, 0], [-0.4, -0.5, 0], [-0.4, 0.5, 0], [-0.9, 0.5, 0]]
material = "front"

[[objects]]   # faces away
type = "polygon"
vertices = [[-0.25, 0.5, 0], [0.25, 0.5, 0], [0.25, -0.5, 0], [-0.25, -0.5, 0]]
material = "one_sided"

[[objects]]   # faces away, two-sided
type = "polygon"
vertices = [[0.4, 0.5, 0], [0.9, 0.5, 0], [0.9, -0.5, 0], [0.4, -0.5, 0]]
material = "two_sided"

[[objects]]   # not an emitter: black at max_depth = 1
type = "triangle"
vertices = [[-0.5, 0.7, 0], [0.5, 0.7, 0], [0, 0.95, 0]]
material = "diffuse"
"#;
    let rects: [([f32; 4], [f32; 3]); 4] = [
        ([-0.9, -0.4, -0.5, 0.5], [4.0, 2.0, 1.0]),
        ([-0.25, 0.25, -0.5, 0.5], [0.0, 0.0, 0.0]),
        ([0.4, 0.9, -0.5, 0.5], [1.0, 2.0, 4.0]),
        // A box inside the diffuse triangle: black at max_depth = 1.
        ([-0.1, 0.1, 0.72, 0.8], [0.0, 0.0, 0.0]),
    ];
    // Pixels touching none of these boxes show the background.
    let mut occupied: Vec<[f32; 4]> = rects.iter().map(|(r, _)| *r).collect();
    occupied.push([-0.5, 0.5, 0.7, 0.95]); // the triangle's bounding box
    let bg = [0.5f32, 0.25, 0.75];
    let scene = scene_from_str(src);
    let px = 2.0 / W as f32;
    for (name, render) in [
        (
            "gpu",
            render_gpu as fn(&wgtrace::FlatScene) -> wgtrace::Accumulation,
        ),
        ("cpu", render_cpu),
    ] {
        let img = render(&scene);
        let (mut inside, mut outside) = (0, 0);
        for y in 0..W {
            for x in 0..W {
                // Pixel footprint on z = 0, with a margin for rounding.
                let (x0, x1) = (-1.0 + x as f32 * px, -1.0 + (x + 1) as f32 * px);
                let (y1, y0) = (1.0 - y as f32 * px, 1.0 - (y + 1) as f32 * px);
                let m = img.mean((y * W + x) as usize);
                let eps = 1e-4;
                let within = |r: &[f32; 4]| {
                    x0 > r[0] + eps && x1 < r[1] - eps && y0 > r[2] + eps && y1 < r[3] - eps
                };
                let touches = |r: &[f32; 4]| {
                    !(x1 < r[0] - eps || x0 > r[1] + eps || y1 < r[2] - eps || y0 > r[3] + eps)
                };
                if let Some((_, value)) = rects.iter().find(|(r, _)| within(r)) {
                    assert_eq!(&m, value, "{name}: pixel ({x}, {y})");
                    inside += 1;
                } else if !occupied.iter().any(touches) {
                    assert_eq!(m, bg, "{name}: pixel ({x}, {y}) should be background");
                    outside += 1;
                }
            }
        }
        assert!(
            inside > 300 && outside > 600,
            "{name}: {inside} inside, {outside} outside"
        );
    }
}

/// Same scene, seed and backend: the same accumulation, bit for bit.
#[test]
fn renders_are_bit_identical_for_the_same_seed() {
    let o = Overrides {
        width: Some(48),
        height: Some(32),
        spp: Some(4),
        ..Default::default()
    };
    let scene = wgtrace::load_scene(&common::repo_path("scenes/cornell.toml"), &o).unwrap();
    let (g1, g2) = (render_gpu(&scene), render_gpu(&scene));
    assert!(g1
        .data
        .iter()
        .zip(&g2.data)
        .all(|(a, b)| a.map(f32::to_bits) == b.map(f32::to_bits)));
    let (c1, c2) = (render_cpu(&scene), render_cpu(&scene));
    assert!(c1
        .data
        .iter()
        .zip(&c2.data)
        .all(|(a, b)| a.map(f32::to_bits) == b.map(f32::to_bits)));
    // And a different seed gives a different image.
    let other = wgtrace::load_scene(
        &common::repo_path("scenes/cornell.toml"),
        &Overrides { seed: Some(1), ..o },
    )
    .unwrap();
    assert_ne!(render_cpu(&other).data, c1.data);
}

/// The shader specialized to each scene's features and the full shader render the same
/// image from the same seed on every scene but those said below (and on two scenes under
/// every sampler, every
/// light-sampling strategy and without the BVH): the taken code is the same, so pixels
/// agree bit for bit unless the compiler arranged the arithmetic differently (printed),
/// and every tile agrees within the statistical bound.
#[test]
fn specialized_and_full_shaders_render_the_same_image() {
    use wgtrace::scene::format::{LightSampling as L, SamplerKind as S};
    // sampler, light sampling, no BVH
    type Variant = Option<(S, L, bool)>;
    // A scene whose full shader holds shading normals, rough glass, pbr's layers or a
    // material added after pbr (ShaderSpec::OPTIONAL_IN_FULL) is a variant of its own,
    // and each is a cold compile of several minutes on llvmpipe, which CI's budget does
    // not hold: those scenes (scenes/coated.toml, the smooth-shaded meshes,
    // scenes/conductors.toml, scenes/plastics.toml, scenes/principled.toml and
    // scenes/energy.toml) are left out here. Their code is
    // the same under both shaders (the same #ifdef blocks), and
    // gpu_matches_cpu_on_every_scene renders them against the CPU.
    use wgtrace::gpu::plan::{scene_features, Feature};
    use wgtrace::scene::materials::MaterialKind;
    let heavy = [
        Feature::ShadingNormals,
        Feature::RoughDielectric,
        Feature::Clearcoat,
        Feature::Sheen,
        Feature::PbrLayers,
        Feature::Material(MaterialKind::Conductor),
        Feature::Material(MaterialKind::ThinDielectric),
        Feature::Material(MaterialKind::Plastic),
        Feature::Material(MaterialKind::Principled),
        Feature::Beckmann,
        Feature::EnergyCompensation,
    ];
    let mut cases: Vec<(std::path::PathBuf, Variant)> = common::scene_files()
        .into_iter()
        .filter(|p| {
            let scene = wgtrace::load_scene(p, &Overrides::default()).unwrap();
            let features = scene_features(&scene);
            !heavy.iter().any(|&f| features.contains(f))
        })
        .map(|p| (p, None))
        .collect();
    for scene in ["scenes/cornell.toml", "scenes/lights.toml"] {
        for variant in [
            (S::Random, L::Bsdf, true),
            (S::Jittered, L::Mixture, false),
            (S::Hammersley, L::Mis, true),
        ] {
            cases.push((common::repo_path(scene), Some(variant)));
        }
    }
    for (path, variant) in cases {
        let o = Overrides {
            width: Some(32),
            height: Some(24),
            spp: Some(4),
            seed: Some(11),
            sampler: variant.map(|v| v.0),
            light_sampling: variant.map(|v| v.1),
            ..Default::default()
        };
        let no_bvh = if variant.is_some_and(|v| v.2) {
            "no-bvh"
        } else {
            ""
        };
        let scene = common::load_tuned(&path, &o, no_bvh);
        let a = common::render_gpu_tuned(&scene, no_bvh);
        let b = common::render_gpu_tuned(&scene, &format!("{no_bvh},no-specialize"));
        let name = format!("{} {variant:?}", path.display());
        assert_same_image(&name, "specialized and full shaders", &a, &b);
    }
}

/// Two renders of the same code under different shaders: bit for bit unless the compiler
/// arranged the arithmetic differently (the share printed), and every tile of `a` within
/// the statistical bound of `b`'s, 99% of pixels within rounding.
fn assert_same_image(name: &str, what: &str, a: &wgtrace::Accumulation, b: &wgtrace::Accumulation) {
    let identical = (0..a.pixel_count())
        .filter(|&i| a.mean(i) == b.mean(i))
        .count() as f64
        / a.pixel_count() as f64;
    let c = compare(a, b, 8);
    eprintln!(
        "{name}: {identical:.4} of pixels bit-identical, {} of {} tiles outside the bound",
        c.failed_tiles.len(),
        c.tiles
    );
    assert!(
        c.failed_tiles.is_empty() && c.agree_fraction >= 0.99,
        "{name}: {what} differ:\n{}",
        c.failed_tiles.join("\n")
    );
}

/// The BVH walk's stack in registers (gpu::plan::REGISTER_STACK) renders what the stack
/// in workgroup memory renders: the same walk, so the pixels agree bit for bit unless the
/// compiler arranged the arithmetic differently (printed), and every tile within the
/// statistical bound. On scenes whose trees are shallow enough: meshes, planes before
/// the BVH, punctual lights, delta lobes, transformed shapes.
#[test]
fn the_walk_stack_in_registers_renders_the_same_image() {
    for file in [
        "scenes/mesh.toml",
        "scenes/area-lights.toml",
        "scenes/gltf-spheres.toml",
        "scenes/lights.toml",
        "scenes/transforms.toml",
    ] {
        let o = Overrides {
            width: Some(32),
            height: Some(24),
            spp: Some(4),
            seed: Some(5),
            ..Default::default()
        };
        let scene = common::load_tuned(&common::repo_path(file), &o, "");
        let fit = wgtrace::gpu::limits::DeviceFit::portable();
        let plan = wgtrace::gpu::plan::GpuPlan::new(&scene, &fit, &wgtrace::Tuning::default());
        assert!(
            plan.shader
                .defines()
                .contains(wgtrace::gpu::plan::REGISTER_STACK),
            "{file}: its walk's stack is not in registers"
        );
        let a = common::render_gpu_tuned(&scene, "");
        let b = common::render_gpu_tuned(&scene, "no-register-stack");
        assert_same_image(
            file,
            "the stack in registers and in workgroup memory",
            &a,
            &b,
        );
    }
}

/// A scene where nothing emits renders black without tracing a path (its shader has no
/// HAS_EMISSION and binds only the parameters and the sums), as the full shader does.
#[test]
fn a_scene_without_emission_renders_black() {
    let src = r#"
[camera]
look_from = [0, 0, 3]
look_at = [0, 0, 0]
[render]
width = 16
height = 16
spp = 2
[materials.grey]
type = "lambertian"
albedo = [0.5, 0.5, 0.5]
[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "grey"
"#;
    let scene = common::scene_from_str(src);
    let features = wgtrace::gpu::plan::scene_features(&scene);
    assert!(!features.contains(wgtrace::gpu::plan::Feature::Emission));
    for acc in [
        render_gpu(&scene),
        common::render_gpu_tuned(&scene, "no-specialize"),
    ] {
        assert!((0..acc.pixel_count()).all(|i| acc.mean(i) == [0.0; 3]));
    }
}

/// Renders in one process share one device, and a feature set's pipeline is compiled once:
/// a second request gets the same pipeline, another feature set another one.
#[test]
fn pipelines_are_compiled_once_per_feature_set_and_process() {
    use std::sync::Arc;
    use wgtrace::gpu::plan::{GpuPlan, ShaderSpec};
    let ctx = wgtrace::gpu::GpuContext::shared(0)
        .unwrap_or_else(|e| panic!("GPU tests need a Vulkan adapter: {e}"));
    assert!(Arc::ptr_eq(
        &ctx,
        &wgtrace::gpu::GpuContext::shared(0).unwrap()
    ));
    let scene =
        wgtrace::load_scene(&common::repo_path("scenes/box.toml"), &Overrides::default()).unwrap();
    let plan = GpuPlan::new(&scene, &ctx.fit(), &wgtrace::Tuning::default());
    let a = ctx.trace_pipeline(&plan.shader).unwrap();
    let b = ctx.trace_pipeline(&plan.shader).unwrap();
    let no_specialize = wgtrace::Tuning::parse("no-specialize").unwrap();
    let full_plan = GpuPlan::new(&scene, &ctx.fit(), &no_specialize);
    let full_for = ShaderSpec {
        banks: plan.shader.banks,
        ..ShaderSpec::full_for(plan.shader.features)
    };
    assert_eq!(full_plan.shader, full_for);
    let full = ctx.trace_pipeline(&full_plan.shader).unwrap();
    assert!(Arc::ptr_eq(&a, &b));
    assert!(!Arc::ptr_eq(&a, &full));
    assert!(a.shader_bytes < full.shader_bytes && a.slots.len() < full.slots.len());
}

/// A thin-lens camera (aperture > 0): both backends agree on the blurred image, and it
/// differs from the pinhole's.
#[test]
fn a_thin_lens_renders_the_same_on_both_backends() {
    let path = common::repo_path("scenes/spheres.toml");
    let src = std::fs::read_to_string(&path).unwrap().replace(
        "vfov = 35",
        "vfov = 35\naperture = 0.5\nfocus_distance = 1.5",
    );
    assert!(src.contains("aperture = 0.5"));
    let o = Overrides {
        width: Some(48),
        height: Some(32),
        spp: Some(16),
        ..Default::default()
    };
    let lens = wgtrace::load_scene_str(&src, &path, &o).unwrap();
    let pinhole = wgtrace::load_scene(&path, &o).unwrap();
    let blurred = render_gpu(&lens);
    let c = compare(&blurred, &render_cpu(&lens), 8);
    assert!(
        c.failed_tiles.is_empty() && c.agree_fraction >= 0.99,
        "{} tiles outside, {:.4} agree",
        c.failed_tiles.len(),
        c.agree_fraction
    );
    let sharp = compare(&blurred, &render_gpu(&pinhole), 2);
    assert!(
        !sharp.failed_tiles.is_empty(),
        "the lens changed nothing: {} of {} tiles differ",
        sharp.failed_tiles.len(),
        sharp.tiles
    );
}

/// The work per submission follows the time submissions take: a tiny target splits each
/// pass into submissions of a few rows, a long one puts several samples into one
/// submission; either way every pixel adds its samples in index order, so the two images
/// are identical to the bit.
#[test]
fn submissions_adapt_to_their_time_and_leave_the_image_unchanged() {
    use std::time::Duration;
    use wgtrace::{Engine, Session, SessionOptions, StopRule};
    let o = Overrides {
        width: Some(64),
        height: Some(48),
        spp: Some(64),
        ..Default::default()
    };
    let scene = wgtrace::load_scene(&common::repo_path("scenes/cornell.toml"), &o).unwrap();
    let run = |target: Duration| {
        let opts = SessionOptions {
            submission_target: target,
            ..Default::default()
        };
        let mut session =
            Session::with_engine(scene.clone(), common::gpu_engine(&scene), opts).unwrap();
        let acc = session
            .run(&StopRule::default(), |_| {})
            .expect("render")
            .accumulation;
        let Engine::Gpu(g) = session.engine() else {
            unreachable!("a GPU engine")
        };
        let (count, budget) = (g.submission_count(), g.submission_budget());
        (acc, count, budget)
    };
    let (sliced, sliced_count, sliced_budget) = run(Duration::from_micros(1));
    let (batched, batched_count, _) = run(Duration::from_secs(60));
    // a microsecond is never met: the budget falls to one row of one sample group per
    // submission
    let group = wgtrace::gpu::plan::SAMPLE_GROUP;
    assert_eq!(
        sliced_budget,
        64 * group as u64,
        "budget {sliced_budget} pixel samples"
    );
    // most of the 64 / group groups of samples go one row of 48 at a time
    assert!(
        sliced_count > 48 * 64 / group as u64 / 2,
        "{sliced_count} submissions for 64 samples of 48 rows in groups of {group}"
    );
    assert!(
        batched_count * 4 <= 64,
        "{batched_count} submissions for 64 passes"
    );
    assert!(sliced.data == batched.data, "the split changed the sums");
    assert_eq!(sliced.samples(0), 64.0);
}

/// A dispatch traces a group of at most SAMPLE_GROUP consecutive samples.
#[test]
fn samples_go_to_dispatches_in_consecutive_groups() {
    use wgtrace::gpu::plan::SAMPLE_GROUP as G;
    use wgtrace::gpu::render::group_parts;
    assert_eq!(
        group_parts(3..2 * G + 5, G),
        vec![3..G + 3, G + 3..2 * G + 3, 2 * G + 3..2 * G + 5]
    );
    assert_eq!(group_parts(G..2 * G, G), vec![G..2 * G]);
    assert_eq!(group_parts(7..8, G), vec![7..8]);
    assert!(group_parts(4..4, G).is_empty());
    assert_eq!(group_parts(u32::MAX - 3..u32::MAX, G).len(), 1);
    assert_eq!(group_parts(0..3, 1), vec![0..1, 1..2, 2..3]);
}

/// The budget rule: scaled toward the target, at most 2x up and 4x down per step, within
/// its bounds; the last, smaller submission of a render does not lower it when it was quick.
#[test]
fn the_submission_budget_moves_toward_the_target_in_bounded_steps() {
    use std::time::Duration;
    use wgtrace::gpu::render::next_budget;
    let ms = Duration::from_millis;
    let target = ms(500);
    // four times too fast: doubles (no more)
    assert_eq!(next_budget(1000, 1000, ms(125), target, 10, 1 << 30), 2000);
    // twice too slow: halves
    assert_eq!(next_budget(1000, 1000, ms(1000), target, 10, 1 << 30), 500);
    // far too slow: a quarter (no less)
    assert_eq!(
        next_budget(1000, 1000, ms(60_000), target, 10, 1 << 30),
        250
    );
    // bounds
    assert_eq!(
        next_budget(1000, 1000, ms(60_000), target, 400, 1 << 30),
        400
    );
    assert_eq!(next_budget(1000, 1000, ms(1), target, 10, 1500), 1500);
    // a quick partial submission keeps the budget
    assert_eq!(next_budget(1000, 100, ms(10), target, 10, 1 << 30), 1000);
    // a slow partial one lowers it from the work it did
    assert_eq!(next_budget(1000, 100, ms(1000), target, 10, 1 << 30), 50);
}

/// A device lost mid-render (destroyed here, as a driver reset would end it) is an error
/// from the next call, not a panic. The test opens a device of its own, as the shared one
/// serves the tests running beside it.
#[test]
fn a_lost_device_is_an_error_not_a_panic() {
    use std::sync::Arc;
    use wgtrace::gpu::{GpuError, GpuRenderer};
    use wgtrace::Engine;
    let o = Overrides {
        width: Some(16),
        height: Some(16),
        spp: Some(4),
        ..Default::default()
    };
    let scene = wgtrace::load_scene(&common::repo_path("scenes/spheres.toml"), &o).unwrap();
    let ctx = Arc::new(common::gpu_context());
    let mut engine = Engine::Gpu(Box::new(
        GpuRenderer::new(ctx.clone(), &scene, &wgtrace::Tuning::default()).unwrap(),
    ));
    engine.render_pass(0).expect("a pass before the loss");
    assert!(ctx.check().is_ok());
    // what a driver reset does to a device
    ctx.device.destroy();
    let err = engine.render_pass(1).expect_err("a pass on a lost device");
    assert!(matches!(err, GpuError::Lost(_)), "{err}");
    assert!(matches!(engine.accumulation(), Err(GpuError::Lost(_))));
    assert!(matches!(ctx.check(), Err(GpuError::Lost(_))));
}

/// A device lost mid-render (destroyed from the progress callback of the third batch, as a
/// driver reset would end it) ends the session with `DeviceLost`, having written the
/// samples last read back (here after every batch) as image and checkpoint, to the
/// checkpoint the user gave or beside the image; resuming that checkpoint gives the
/// uninterrupted sums bit for bit. The lost session runs on a device of its own, as the
/// shared one serves the tests beside it. (main.rs's `a_lost_device_says_how_to_continue`
/// holds the message.)
#[test]
fn a_device_lost_mid_render_keeps_the_samples_read_back() {
    use std::sync::Arc;
    use wgtrace::gpu::GpuRenderer;
    use wgtrace::session::{Output, Passes, Saving, SessionError};
    use wgtrace::Engine;
    use wgtrace::{Session, SessionOptions, StopRule};
    let dir = common::tmp_dir("lost");
    let o = Overrides {
        width: Some(32),
        height: Some(24),
        spp: Some(64),
        ..Default::default()
    };
    let scene = wgtrace::load_scene(&common::repo_path("scenes/cornell.toml"), &o).unwrap();
    let whole = common::render(common::gpu_engine(&scene), &scene);
    for periodic in [false, true] {
        let (image, ckpt) = (
            dir.join(format!("l{periodic}.exr")),
            dir.join(format!("l{periodic}.ckpt")),
        );
        let opts = SessionOptions {
            saving: Some(Saving {
                path: ckpt.clone(),
                periodic,
                every: std::time::Duration::ZERO,
                at_end: periodic,
            }),
            output: Some(Output {
                image: image.clone(),
                error_map: None,
                preview_every: None,
                aovs: Vec::new(),
                denoise: false,
            }),
            submission_target: std::time::Duration::from_millis(1),
            ..Default::default()
        };
        let ctx = Arc::new(common::gpu_context());
        let engine = Engine::Gpu(Box::new(
            GpuRenderer::new(ctx.clone(), &scene, &wgtrace::Tuning::default()).unwrap(),
        ));
        let mut session = Session::with_engine(scene.clone(), engine, opts).unwrap();
        let mut batches = 0;
        let err = session
            .run(&StopRule::default(), |_| {
                batches += 1;
                if batches == 3 {
                    ctx.device.destroy();
                }
            })
            .expect_err("a render on a lost device");
        let SessionError::DeviceLost(lost) = &err else {
            panic!("not a lost device: {err}");
        };
        let saved = lost
            .saved
            .clone()
            .expect("samples read back before the loss");
        assert!(
            saved.start == 0 && (2..64).contains(&saved.end),
            "{saved:?}"
        );
        assert_eq!(err.resumable(), Some(ckpt.as_path()));
        assert!(err.to_string().contains("wrote samples"), "{err}");
        assert!(image.exists());
        let held = wgtrace::checkpoint::Checkpoint::read(&ckpt)
            .unwrap()
            .samples;
        assert_eq!(held, vec![saved.clone()]);
        let resumed = SessionOptions {
            resume: Some(ckpt.clone()),
            passes: Passes::Scene,
            ..Default::default()
        };
        let done = Session::open(scene.clone(), resumed)
            .unwrap()
            .run(&StopRule::default(), |_| {})
            .unwrap();
        assert!(
            done.accumulation == whole,
            "resumed after a loss at {saved:?} differs from the uninterrupted render"
        );
    }
}

/// Every pixel filter gives the same image on both backends: the tent, Mitsuba's Gaussian
/// (radius 4 deviations) and pbrt-v4's (radius 1.5), each sample's position drawn from
/// the filter on both; and splatted (a Gaussian, a wide tent), the GPU's gather pass
/// reading the sample buffer as the CPU's reads its samples.
#[test]
fn gpu_matches_cpu_with_every_pixel_filter() {
    use wgtrace::scene::format::FilterKind;
    let src = std::fs::read_to_string(common::repo_path("scenes/cornell.toml")).unwrap();
    for (filter, extra) in [
        (FilterKind::Tent, ""),
        (FilterKind::Gaussian, ""),
        (FilterKind::Gaussian, "filter_radius = 1.5\n"),
        (FilterKind::Gaussian, "reconstruction = \"splat\"\n"),
        (
            FilterKind::Tent,
            "reconstruction = \"splat\"\nfilter_radius = 2\n",
        ),
    ] {
        let src = src.replacen("[render]\n", &format!("[render]\n{extra}"), 1);
        let o = Overrides {
            width: Some(48),
            height: Some(48),
            spp: Some(16),
            seed: Some(5),
            filter: Some(filter),
            ..Default::default()
        };
        let scene = wgtrace::load_scene_str(&src, &common::repo_path("scenes/cornell.toml"), &o)
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(scene.filter.kind, filter);
        let c = compare(&render_gpu(&scene), &render_cpu(&scene), 8);
        assert!(
            c.failed_tiles.is_empty() && c.agree_fraction >= 0.99,
            "{filter:?} {extra}: {} tiles outside the bound, {:.4} of pixels agree",
            c.failed_tiles.len(),
            c.agree_fraction
        );
    }
}

/// A step edge through each pixel filter renders the filter's CDF, on both backends: an
/// orthographic view, one pixel a unit, of an emitter of radiance 1 over x > 0.25 (pixel
/// coordinate 8.25 of 16), black elsewhere, at max_depth 1. Pixel i is the chance that a
/// sample at i + 0.5 + offset lands past the edge, 1 - F(7.75 - i) for the filter's CDF F
/// (integrated in f64 here): exactly 0 and 1 outside the filter's radius, and within
/// 5 standard errors of a Bernoulli mean over the column's 4 x 256 samples inside it.
/// The stepped filters (`filter_steps`: Mitsuba's table of 31 steps, and a tent of 3
/// steps, 1, 2/3 and 1/3, far from the tent itself) render their step functions' CDFs.
#[test]
fn a_step_edge_renders_each_pixel_filters_cdf() {
    assert_step_edge_renders_cdfs(
        &[
            ("box", "", 0.5f64, 0.0f64, 0u32),
            ("tent", "", 1.0, 0.0, 0),
            ("tent", "filter_radius = 2", 2.0, 0.0, 0),
            ("gaussian", "", 2.0, 0.5, 0),
            ("gaussian", "filter_radius = 1.5", 1.5, 0.5, 0),
            ("gaussian", "filter_steps = 31", 2.0, 0.5, 31),
            ("tent", "filter_radius = 2\nfilter_steps = 3", 2.0, 0.0, 3),
        ],
        "spp = 256",
        |p| (p * (1.0 - p) / 1024.0).sqrt() + 2e-3 / 5.0,
        false,
    );
}

/// Splat reconstruction (`reconstruction = "splat"`, Mitsuba 3's film) renders the same
/// step edge, on both backends: each sample uniform in its pixel and weighed into every
/// pixel its filter reaches, pixel i converges to the same 1 - F(7.75 - i) (the expected
/// image does not change, only how the noise spreads). Pixels the filter keeps on one
/// side read exactly 0 or 1 (a ratio of equal sums), those within it are within 5
/// standard errors of the weighted Bernoulli mean: p (1 - p) x 1.3 / n for the n = 1024
/// samples of a pixel (1.27 is sum w^2 / (sum w)^2 of Mitsuba's Gaussian over a pixel's
/// neighbours), with the four rows counted as one (they share samples). With the AOVs,
/// every pixel on the emitter reads its distance 2: the AOVs stay each pixel's own
/// samples' mean.
#[test]
fn splatted_samples_render_each_pixel_filters_cdf() {
    assert_step_edge_renders_cdfs(
        &[
            ("tent", "", 1.0f64, 0.0f64, 0u32),
            ("gaussian", "", 2.0, 0.5, 0),
            ("gaussian", "filter_radius = 1.5", 1.5, 0.5, 0),
            ("gaussian", "filter_steps = 31", 2.0, 0.5, 31),
        ],
        "spp = 1024\nreconstruction = \"splat\"\nsample_border = false",
        |p| (p * (1.0 - p) * 1.3 / 1024.0).sqrt() + 1e-6 / 5.0,
        true,
    );
}

/// The step edge of `a_step_edge_renders_each_pixel_filters_cdf` under each (filter,
/// extra keys, radius, standard deviation, steps), with `render` keys added: each
/// column's mean within 5 `se(p)` of 1 - F(7.75 - i), exactly 0 or 1 outside the radius;
/// with `aovs`, every pixel on the emitter's depth 2.
fn assert_step_edge_renders_cdfs(
    cases: &[(&str, &str, f64, f64, u32)],
    render: &str,
    se: impl Fn(f64) -> f64,
    aovs: bool,
) {
    for &(filter, extra, r, sd, steps) in cases {
        let src = format!(
            r#"
[render]
width = 16
height = 4
max_depth = 1
filter = "{filter}"
{render}
{extra}

[camera]
projection = "orthographic"
height = 4
look_from = [0, 0, 2]
look_at = [0, 0, 0]

[materials]
light = {{ type = "emissive", radiance = [1, 1, 1] }}

[[objects]]
type = "polygon"
vertices = [[0.25, -10, 0], [20, -10, 0], [20, 10, 0], [0.25, 10, 0]]
material = "light"
"#
        );
        let mut scene = scene_from_str(&src);
        scene.aovs = aovs;
        // a stepped filter keeps its value at each step's inner end
        let step = |x: f64| match steps {
            0 => x,
            n => (x.abs() * n as f64 / r).floor() * r / n as f64,
        };
        let profile = |x: f64| match filter {
            _ if x.abs() >= r && steps != 0 => 0.0,
            "box" => f64::from(x.abs() <= 0.5),
            "tent" => (1.0 - step(x).abs() / r).max(0.0),
            _ => {
                let g = |t: f64| (-t * t / (2.0 * sd * sd)).exp();
                (g(step(x)) - g(r)).max(0.0)
            }
        };
        // the CDF by the midpoint rule on 20,000 steps
        let cdf = |x: f64| {
            let n = 20_000;
            let h = 2.0 * r / n as f64;
            let part = |hi: f64| {
                (0..n)
                    .map(|i| -r + (i as f64 + 0.5) * h)
                    .filter(|&t| t < hi)
                    .map(profile)
                    .sum::<f64>()
            };
            part(x) / part(r + 1.0)
        };
        for (name, render) in [
            (
                "gpu",
                render_gpu as fn(&wgtrace::FlatScene) -> wgtrace::Accumulation,
            ),
            ("cpu", render_cpu),
        ] {
            let img = render(&scene);
            for i in 0..16u32 {
                let mean = (0..4)
                    .map(|y| img.mean((y * 16 + i) as usize)[0] as f64)
                    .sum::<f64>()
                    / 4.0;
                let d = 7.75 - i as f64;
                let label = format!("{filter} {extra}, {name}, pixel {i}");
                if d.abs() >= r {
                    let want = if d > 0.0 { 0.0 } else { 1.0 };
                    assert_eq!(mean, want, "{label}: outside the radius");
                } else {
                    let p = 1.0 - cdf(d);
                    assert!(
                        (mean - p).abs() <= 5.0 * se(p),
                        "{label}: {mean} against {p} (standard error {})",
                        se(p)
                    );
                }
                if aovs && d < -1.0 {
                    for y in 0..4 {
                        let depth = img.aov_mean((y * 16 + i) as usize, 2)[3];
                        assert!((depth - 2.0).abs() < 1e-5, "{label}: depth {depth}");
                    }
                }
            }
        }
    }
}

/// `hide_emitters`: camera rays see neither an emitter nor the background, which still
/// light what the camera sees. An emitting quad of radiance 2 before a background of 0.5,
/// and a white Lambertian quad lit by both: with the flag the emitter and the sky read 0
/// exactly, the lit quad as without it (the same random numbers, so the same value).
#[test]
fn hidden_emitters_light_the_scene_but_are_not_seen() {
    let src = |hide: bool| {
        format!(
            r#"
[render]
width = 8
height = 4
spp = 16
max_depth = 3
hide_emitters = {hide}

[camera]
projection = "orthographic"
height = 4
look_from = [0, 0, 3]
look_at = [0, 0, 0]

[background]
color = [0.5, 0.5, 0.5]

[materials]
light = {{ type = "emissive", radiance = [2, 2, 2], two_sided = true }}
white = {{ type = "lambertian", albedo = [0.8, 0.8, 0.8] }}

[[objects]]
type = "polygon"
vertices = [[-4, 0, 0], [-1, 0, 0], [-1, 2, 0], [-4, 2, 0]]
material = "light"

[[objects]]
type = "polygon"
vertices = [[0, -2, 0], [4, -2, 0], [4, 2, 0], [0, 2, 0]]
material = "white"
"#
        )
    };
    let (shown, hidden) = (scene_from_str(&src(false)), scene_from_str(&src(true)));
    for (name, render) in [
        (
            "gpu",
            render_gpu as fn(&wgtrace::FlatScene) -> wgtrace::Accumulation,
        ),
        ("cpu", render_cpu),
    ] {
        let (a, b) = (render(&shown), render(&hidden));
        // pixel (1, 0): the emitter; (1, 3): the sky; (6, 1): the lit quad
        assert_eq!(a.mean(1), [2.0; 3], "{name}");
        assert_eq!(b.mean(1), [0.0; 3], "{name}");
        assert_eq!(a.mean(3 * 8 + 1), [0.5; 3], "{name}");
        assert_eq!(b.mean(3 * 8 + 1), [0.0; 3], "{name}");
        let lit = a.mean(8 + 6);
        assert!(lit[0] > 0.1, "{name}: {lit:?}");
        assert_eq!(b.mean(8 + 6), lit, "{name}");
    }
}

/// `[camera] near_clip` (Mitsuba's): camera rays start at the plane that far in front of
/// the camera, so a surface nearer than it is not seen and what lies behind it is, for a
/// perspective camera (its rays leave the plane at an angle, each at near_clip / cos) and an
/// orthographic one; exact values, on both backends. A sheet at distance 1 fills the view:
/// near_clip 0.5 shows it (radiance 3), near_clip 1.5 the sheet behind it at distance 3
/// (radiance 2), and near_clip 4 the background; a sheet seen at the edge of the view
/// (0.9 along the axis from a plane at 1) is kept by 0.95 and clipped by 1.05, which a
/// clip by distance along the ray instead of by the plane would not tell apart.
#[test]
fn near_clip_hides_what_lies_in_front_of_its_plane() {
    let src = |projection: &str, near: f32| {
        format!(
            r#"
[render]
width = 8
height = 8
spp = 4
max_depth = 1

[camera]
{projection}
look_from = [0, 0, 0]
look_at = [0, 0, -1]
near_clip = {near}

[background]
color = [0.25, 0.25, 0.25]

[materials]
near = {{ type = "emissive", radiance = [3, 3, 3], two_sided = true }}
far = {{ type = "emissive", radiance = [2, 2, 2], two_sided = true }}

[[objects]]
type = "polygon"
vertices = [[-9, -9, -1], [9, -9, -1], [9, 9, -1], [-9, 9, -1]]
material = "near"

[[objects]]
type = "polygon"
vertices = [[-99, -99, -3], [99, -99, -3], [99, 99, -3], [-99, 99, -3]]
material = "far"
"#
        )
    };
    let perspective = "vfov = 90";
    let orthographic = "projection = \"orthographic\"\nheight = 2";
    let cases = [
        (perspective, 0.5, 3.0),
        (perspective, 1.5, 2.0),
        (perspective, 4.0, 0.25),
        (orthographic, 0.5, 3.0),
        (orthographic, 1.5, 2.0),
        (orthographic, 4.0, 0.25),
    ];
    for (projection, near, want) in cases {
        let scene = scene_from_str(&src(projection, near));
        for (name, render) in [
            (
                "gpu",
                render_gpu as fn(&wgtrace::FlatScene) -> wgtrace::Accumulation,
            ),
            ("cpu", render_cpu),
        ] {
            let acc = render(&scene);
            for pixel in [0, 27, 63] {
                assert_eq!(
                    acc.mean(pixel),
                    [want; 3],
                    "{name}: {projection} near_clip {near}, pixel {pixel}"
                );
            }
        }
    }
    // the corner pixel of the 90-degree view looks 54.7 degrees off the axis: its ray
    // crosses the sheet at distance 1 along the axis, past a plane at 0.95 and before one at
    // 1.05
    for (near, want) in [(0.95, 3.0), (1.05, 2.0)] {
        let scene = scene_from_str(&src(perspective, near));
        for acc in [render_gpu(&scene), render_cpu(&scene)] {
            assert_eq!(acc.mean(0), [want; 3], "near_clip {near}");
        }
    }
}

/// Masks decide independently of each other: two sheets of opacity 0.5 one behind the
/// other pass a quarter of the rays, 0.25 of an emitter behind them (a Bernoulli mean, to 5
/// standard errors), on both backends. Each surface along a ray draws its own uniform
/// number; the golden-ratio shift of one number they once shared passed 0.118.
#[test]
fn stacked_masks_pass_the_product_of_their_transparencies() {
    let src = r#"
[render]
width = 8
height = 4
spp = 512
max_depth = 1

[camera]
projection = "orthographic"
height = 4
look_from = [0, 0, 3]
look_at = [0, 0, 0]

[materials]
light = { type = "emissive", radiance = [1, 1, 1] }
veil = { type = "lambertian", albedo = [0, 0, 0], opacity = 0.5 }

[[objects]]
type = "polygon"
vertices = [[-10, -10, -1], [10, -10, -1], [10, 10, -1], [-10, 10, -1]]
material = "light"

[[objects]]
type = "polygon"
vertices = [[-10, -10, 0.5], [10, -10, 0.5], [10, 10, 0.5], [-10, 10, 0.5]]
material = "veil"

[[objects]]
type = "polygon"
vertices = [[-10, -10, 0], [10, -10, 0], [10, 10, 0], [-10, 10, 0]]
material = "veil"
"#;
    let scene = scene_from_str(src);
    for (name, render) in [
        (
            "gpu",
            render_gpu as fn(&wgtrace::FlatScene) -> wgtrace::Accumulation,
        ),
        ("cpu", render_cpu),
    ] {
        let img = render(&scene);
        let n = (32 * 512) as f64;
        let mean = (0..32).map(|i| img.mean(i)[0] as f64).sum::<f64>() / 32.0;
        let se = (0.25f64 * 0.75 / n).sqrt();
        assert!(
            (mean - 0.25).abs() <= 5.0 * se,
            "{name}: two veils pass {mean} (0.25 +- {se})"
        );
    }
}

/// An opacity mask on any material, on both backends. Before an emitter of radiance 1, seen
/// by an orthographic camera at max_depth 1 (a pixel a unit): a black Lambertian sheet of
/// opacity 0.3 shows 0.7 (a Bernoulli mean, to 5 standard errors); a black conductor
/// sheet masked by a solid checker (2-unit cells, black: opacity 0, white: 1) shows the
/// emitter exactly where its cell is black and nothing where white. And shadow rays pass
/// through masks: a sheet of opacity 0.25 between a point light and a white floor leaves
/// the floor 0.75 of its light.
#[test]
fn opacity_masks_any_material_for_camera_and_shadow_rays() {
    let src = r#"
[render]
width = 16
height = 4
spp = 256
max_depth = 1

[camera]
projection = "orthographic"
height = 4
look_from = [0, 0, 3]
look_at = [0, 0, 0]

[textures]
cells = { type = "checker", even = [0, 0, 0], odd = [1, 1, 1], scale = 0.5, mapping = "solid" }

[materials]
light = { type = "emissive", radiance = [1, 1, 1] }
veil = { type = "lambertian", albedo = [0, 0, 0], opacity = 0.3 }
grid = { type = "conductor", material = "none", specular = [0, 0, 0], opacity = "cells" }

[[objects]]
type = "polygon"
vertices = [[-10, -10, -1], [10, -10, -1], [10, 10, -1], [-10, 10, -1]]
material = "light"

[[objects]]
type = "polygon"
vertices = [[-10, -10, 0.5], [0, -10, 0.5], [0, 10, 0.5], [-10, 10, 0.5]]
material = "veil"

[[objects]]
type = "polygon"
vertices = [[0, -10, 0.5], [10, -10, 0.5], [10, 10, 0.5], [0, 10, 0.5]]
material = "grid"
"#;
    let scene = scene_from_str(src);
    for (name, render) in [
        (
            "gpu",
            render_gpu as fn(&wgtrace::FlatScene) -> wgtrace::Accumulation,
        ),
        ("cpu", render_cpu),
    ] {
        let img = render(&scene);
        // the veil: columns 0..8, 4 x 256 samples each
        for x in 0..8u32 {
            let mean = (0..4u32)
                .map(|y| img.mean((y * 16 + x) as usize)[0] as f64)
                .sum::<f64>()
                / 4.0;
            let se = (0.7f64 * 0.3 / 1024.0).sqrt();
            assert!(
                (mean - 0.7).abs() <= 5.0 * se,
                "{name}: veil column {x} reads {mean}"
            );
        }
        // the checker: x in [k, k + 1] for column k + 8, y in [1 - row, 2 - row]
        for y in 0..4u32 {
            for x in 8..16u32 {
                let (wx, wy) = (x as i32 - 8, 1 - y as i32);
                let white = (wx.div_euclid(2) + wy.div_euclid(2)).rem_euclid(2) == 1;
                let want = if white { 0.0 } else { 1.0 };
                let got = img.mean((y * 16 + x) as usize);
                assert_eq!(got, [want; 3], "{name}: pixel ({x}, {y})");
            }
        }
    }
    // shadow rays: a floor lit by a point light above it, through a sheet of opacity 0.25
    let shadow = |veil: &str| {
        format!(
            r#"
[render]
width = 8
height = 8
spp = 256
max_depth = 2

[camera]   # below the veil: only the shadow rays cross it
projection = "orthographic"
height = 0.5
look_from = [0, 0.5, 0]
look_at = [0, 0, 0]
up = [0, 0, -1]

[materials]
floor = {{ type = "lambertian", albedo = [1, 1, 1] }}
veil = {{ type = "lambertian", albedo = [0, 0, 0], opacity = {veil} }}

[[objects]]
type = "polygon"
vertices = [[-5, 0, 5], [5, 0, 5], [5, 0, -5], [-5, 0, -5]]
material = "floor"

[[objects]]   # faces down, between the light and the floor
type = "polygon"
vertices = [[-5, 1, -5], [5, 1, -5], [5, 1, 5], [-5, 1, 5]]
material = "veil"

[[lights]]
type = "point"
position = [0, 2, 0]
intensity = [4, 4, 4]
"#
        )
    };
    let open = scene_from_str(&shadow("0.0"));
    let veiled = scene_from_str(&shadow("0.25"));
    for (name, render) in [
        (
            "gpu",
            render_gpu as fn(&wgtrace::FlatScene) -> wgtrace::Accumulation,
        ),
        ("cpu", render_cpu),
    ] {
        let (a, b) = (render(&open), render(&veiled));
        let mean = |img: &wgtrace::Accumulation| {
            (0..64).map(|i| img.mean(i)[0] as f64).sum::<f64>() / 64.0
        };
        let (lit, through) = (mean(&a), mean(&b));
        assert!(lit > 0.0, "{name}: the open floor is lit");
        // 64 x 256 Bernoulli shadow tests of p = 0.75 on a nearly constant light
        let se = (0.75f64 * 0.25 / (64.0 * 256.0)).sqrt();
        assert!(
            (through / lit - 0.75).abs() <= 5.0 * se + 0.002,
            "{name}: the veiled floor reads {through} against {lit} open"
        );
    }
}

/// Shadow rays that pass through a transparent surface stop short of the light they aim
/// at on both backends: a canopy of opacity 0.5 between a floor and an area light, first
/// samples of three seeds, GPU and CPU agree on every pixel but at most 2 of 18,432. The
/// rest of a segment after a pass-through, recomputed from the offset origin, reached the
/// light's own surface on some rays (rounding that differs between the backends) and
/// shadowed them: 13 to 32 pixels of 6,144 per seed differed, and the spot check refused
/// such scenes for some seeds.
#[test]
fn shadow_rays_through_masks_stop_short_of_the_light_on_both_backends() {
    let src = r#"
[render]
width = 96
height = 64
spp = 1
max_depth = 8
sampler = "random"

[camera]
look_from = [0, 4, 5]
look_at = [0, 0, 0]
vfov = 40

[materials]
floor = { type = "lambertian", albedo = [0.5, 0.5, 0.5] }
canopy = { type = "lambertian", albedo = [0.2, 0.7, 0.3], opacity = 0.5 }
light = { type = "emissive", radiance = [6, 6, 6] }

[[objects]]
type = "polygon"
vertices = [[-5, -0.75, 5], [5, -0.75, 5], [5, -0.75, -5], [-5, -0.75, -5]]
material = "floor"

[[objects]]
type = "polygon"
vertices = [[-3, 0, 3], [3, 0, 3], [3, 0, -3], [-3, 0, -3]]
material = "canopy"

[[objects]]   # faces down
type = "polygon"
vertices = [[-1, 3, -1], [1, 3, -1], [1, 3, 1], [-1, 3, 1]]
material = "light"
"#;
    let mut differ = 0.0;
    for seed in [3u32, 7, 11] {
        let scene = scene_from_str(&src.replace("spp = 1", &format!("spp = 1\nseed = {seed}")));
        let c = compare(&render_gpu(&scene), &render_cpu(&scene), 8);
        differ += (1.0 - c.agree_fraction) * 6144.0;
    }
    assert!(differ.round() <= 2.0, "{differ} pixels differ");
}

/// A principled material's ten scalars read from textures (constant ones, each of its own
/// value) render as the same numbers given in place, on both backends: each texture
/// stands for its own scalar, none for another's. The GPU image agrees with the CPU one.
#[test]
fn principled_textures_stand_for_their_scalars() {
    let values = [
        ("roughness", 0.35),
        ("anisotropic", 0.6),
        ("metallic", 0.25),
        ("spec_trans", 0.3),
        ("spec_tint", 0.7),
        ("sheen", 0.9),
        ("sheen_tint", 0.4),
        ("flatness", 0.5),
        ("clearcoat", 0.8),
        ("clearcoat_gloss", 0.2),
    ];
    let src = r#"
[render]
width = 24
height = 24
spp = 32
max_depth = 4
light_sampling = "mis"
[camera]
look_from = [0, 0.6, 3]
look_at = [0, 0, 0]
vfov = 40
[background]
color = [0.3, 0.35, 0.4]
[textures]
TEXTURES
[materials]
lamp = { type = "emissive", radiance = [8, 8, 8] }
floor = { type = "lambertian", albedo = [0.5, 0.5, 0.5] }
ball = { type = "principled", base_color = [0.8, 0.5, 0.3], MATERIAL }
[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "ball"
[[objects]]
type = "plane"
point = [0, -1, 0]
normal = [0, 1, 0]
material = "floor"
[[objects]]
type = "sphere"
center = [2, 3, 2]
radius = 0.7
material = "lamp"
"#;
    let textures: Vec<String> = values
        .iter()
        .map(|(k, v)| format!("t_{k} = {{ type = \"constant\", color = [{v}, {v}, {v}] }}"))
        .collect();
    let textured: Vec<String> = values
        .iter()
        .map(|(k, _)| format!("{k} = \"t_{k}\""))
        .collect();
    let numbers: Vec<String> = values.iter().map(|(k, v)| format!("{k} = {v}")).collect();
    let with = |material: &[String]| {
        scene_from_str(
            &src.replace("TEXTURES", &textures.join("\n"))
                .replace("MATERIAL", &material.join(", ")),
        )
    };
    let (a, b) = (with(&textured), with(&numbers));
    let (gpu_a, cpu_a) = (render_gpu(&a), render_cpu(&a));
    for (name, x, y) in [
        ("gpu", &gpu_a, render_gpu(&b)),
        ("cpu", &cpu_a, render_cpu(&b)),
    ] {
        let (mx, _) = common::image_mean(x);
        let (my, _) = common::image_mean(&y);
        let n = x.pixel_count();
        // the luminance of a grey texel may round by an ulp, and a path then turn: the
        // same image but for a few pixels
        let differ = (0..n)
            .filter(|&i| (0..3).any(|c| (x.mean(i)[c] - y.mean(i)[c]).abs() > 1e-4))
            .count();
        assert!(
            differ * 50 <= n && (0..3).all(|c| (mx[c] - my[c]).abs() <= 2e-3 * my[c]),
            "{name}: {differ} of {n} pixels differ, means {mx:?} vs {my:?}"
        );
    }
    let c = compare(&gpu_a, &cpu_a, 8);
    assert!(
        c.failed_tiles.is_empty(),
        "gpu vs cpu: {:?}",
        c.failed_tiles
    );
}

/// The issue's white glTF sphere (a white base under glTF's default specular, F90 = 1,
/// roughness 1), clear rough glass (GGX roughness 1, ior 1.5) and a white rough plastic
/// (roughness 0.8), side by side in a white furnace: without energy compensation they
/// read less than the background (their lobes lose what scatters between microfacets,
/// most at the rim, and glass loses it at every crossing); with `--energy-compensation`
/// (the override of `[render] energy_compensation`) they vanish into the background
/// within 4 standard errors and 0.5%, on both backends. A material's own
/// `energy_compensation = false` keeps it off under the override.
#[test]
fn energy_compensation_makes_a_white_sphere_vanish_in_a_white_furnace() {
    let src = r#"
[render]
width = 48
height = 16
spp = 64
max_depth = 64
[camera]
look_from = [0, 0, 5]
look_at = [0, 0, 0]
vfov = 24
[background]
color = [1, 1, 1]
[materials]
white = { type = "pbr", base_color = [1, 1, 1], metallic = 0, roughness = 1 OWN }
glass = { type = "dielectric", ior = 1.5, roughness = 1 OWN }
plastic = { type = "plastic", albedo = [1, 1, 1], roughness = 0.8 OWN }
[[objects]]
type = "sphere"
center = [-2.1, 0, 0]
radius = 1
material = "white"
[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "glass"
[[objects]]
type = "sphere"
center = [2.1, 0, 0]
radius = 1
material = "plastic"
"#;
    let load = |own: &str, on: bool| {
        let o = Overrides {
            energy_compensation: on,
            ..Default::default()
        };
        wgtrace::load_scene_str(&src.replace("OWN", own), std::path::Path::new("f.toml"), &o)
            .unwrap_or_else(|e| panic!("{e}"))
    };
    let (plain, compensated, kept_off) = (
        load("", false),
        load("", true),
        load(", energy_compensation = false", true),
    );
    for (name, render) in [
        (
            "gpu",
            render_gpu as fn(&wgtrace::FlatScene) -> wgtrace::Accumulation,
        ),
        ("cpu", render_cpu),
    ] {
        let (p, _) = common::image_mean(&render(&plain));
        let (c, se) = common::image_mean(&render(&compensated));
        let (k, _) = common::image_mean(&render(&kept_off));
        eprintln!(
            "{name}: image mean {:.4} plain, {:.4} +- {:.4} compensated",
            p[0], c[0], se[0]
        );
        assert!(p[0] < 0.97, "{name}: plain {p:?}");
        assert!(
            (k[0] - p[0]).abs() < 1e-6,
            "{name}: kept off {k:?} vs plain {p:?}"
        );
        for ch in 0..3 {
            assert!(
                (c[ch] - 1.0).abs() <= 4.0 * se[ch] + 5e-3,
                "{name}: compensated {c:?} +- {se:?}"
            );
        }
    }
}

/// Instances of a group (analytic shapes, transformed ones and a smooth mesh, placed by a
/// translation, a rotation and uniform scale, a non-uniform scale and a mirror) render as
/// the expanded scene does (every object written out under the product of the matrices),
/// on the GPU with the same random numbers, and as the CPU renders them.
#[test]
fn instances_render_as_the_expanded_scene_and_on_the_cpu() {
    for shading in ["bend", "strict"] {
        instances_render_as_expanded(shading);
    }
}

/// `instances_render_as_the_expanded_scene_and_on_the_cpu` with `[render] shading_normals`
/// set to `shading` (strict reads the unmapped shading normal, which an instance turns too).
fn instances_render_as_expanded(shading: &str) {
    let head = format!(
        "[render]\nwidth = 48\nheight = 48\nspp = 32\nseed = 5\nmax_depth = 4\n\
        shading_normals = \"{shading}\"\n\
        [camera]\nlook_from = [0, 1, 7]\nlook_at = [0, 0, 0]\nvfov = 50\n\
        [background]\ncolor = [0.5, 0.6, 0.8]\n\
        [textures]\nc = {{ type = \"checker\", even = [0.8, 0.8, 0.8], odd = [0.2, 0.3, 0.6], scale = 8 }}\n\
        [materials]\nm = {{ type = \"lambertian\", albedo = \"c\" }}\n\
        [[lights]]\ntype = \"directional\"\ndirection = [-0.3, -1, -0.5]\nirradiance = [2, 2, 2]\n"
    );
    let (a, b) = common::instances::instanced_and_expanded(&head);
    let load = |src: &str| common::scene_from_file_str(src, "scenes/instances-test.toml");
    let (instanced, expanded) = (load(&a), load(&b));
    let image = render_gpu(&instanced);
    // the expanded mesh's vertex normals are transformed before they are interpolated, an
    // instance's after (under a non-uniform scale the two differ by a little), and the
    // shapes' points by one matrix or two: most pixels, not all, agree to 1e-3
    for (what, other, share) in [
        ("the expanded scene", render_gpu(&expanded), 0.95),
        ("the CPU", render_cpu(&instanced), 0.98),
    ] {
        let c = compare(&image, &other, 8);
        assert!(
            c.failed_tiles.is_empty() && c.agree_fraction >= share,
            "{shading}, against {what}: {} tiles outside the bound (first: {:?}), {:.4} of pixels agree",
            c.failed_tiles.len(),
            c.failed_tiles.first(),
            c.agree_fraction
        );
        eprintln!(
            "{shading}, against {what}: {:.4} of pixels agree",
            c.agree_fraction
        );
    }
}

/// The pixels `[x, y, width, height]` of an accumulation, as one of that size.
fn window(a: &wgtrace::Accumulation, [x, y, w, h]: [u32; 4]) -> wgtrace::Accumulation {
    let e = a.entries();
    let mut out = wgtrace::Accumulation::zeros(w, h, a.aovs);
    for row in 0..h {
        let from = ((y + row) * a.width + x) as usize * e;
        let to = (row * w) as usize * e;
        out.data[to..to + w as usize * e].copy_from_slice(&a.data[from..from + w as usize * e]);
    }
    out
}

/// `[render] crop` renders that rectangle of the film: its image agrees, tile by tile,
/// with the same rectangle cut from the whole film's image, for a thin-lens camera under
/// a Gaussian filter whose samples leave the rectangle (`sample_border`, so the crop's
/// edge pixels weigh what lies beyond it) and for an orthographic one; `--width` and
/// `--height` scale the rectangle with the film.
#[test]
fn crop_windows_render_that_part_of_the_film() {
    let body = "[background]\ncolor = [0.4, 0.5, 0.7]\n\
        [textures]\nc = { type = \"checker\", even = [0.9, 0.9, 0.9], odd = [0.1, 0.2, 0.5], scale = 6 }\n\
        [materials]\nm = { type = \"lambertian\", albedo = \"c\" }\n\
        shiny = { type = \"metal\", albedo = [0.9, 0.7, 0.5], fuzz = 0.2 }\n\
        [[objects]]\ntype = \"plane\"\npoint = [0, -1, 0]\nnormal = [0, 1, 0]\nmaterial = \"m\"\n\
        [[objects]]\ntype = \"sphere\"\ncenter = [-0.6, 0, 0]\nradius = 1\nmaterial = \"shiny\"\n\
        [[objects]]\ntype = \"sphere\"\ncenter = [1.2, -0.5, 1]\nradius = 0.5\nmaterial = \"m\"\n\
        [[lights]]\ntype = \"directional\"\ndirection = [-0.3, -1, -0.5]\nirradiance = [2, 2, 2]\n";
    let cameras = [
        "[camera]\nlook_from = [1, 1.5, 6]\nlook_at = [0, 0, 0]\nvfov = 45\naperture = 0.2\nfocus_distance = 5.5\n",
        "[camera]\nprojection = \"orthographic\"\nheight = 5\nlook_from = [1, 2, 6]\nlook_at = [0, 0, 0]\n",
    ];
    let crop = [13, 5, 22, 27];
    for camera in cameras {
        let render = "[render]\nwidth = 48\nheight = 40\nspp = 64\nseed = 3\nmax_depth = 3\n\
            filter = \"gaussian\"\n";
        let whole = common::scene_from_str(&format!("{render}{camera}{body}"));
        let cropped = common::scene_from_str(&format!("{render}crop = {crop:?}\n{camera}{body}"));
        assert_eq!((cropped.width, cropped.height), (22, 27));
        let (a, b) = (render_gpu(&cropped), window(&render_gpu(&whole), crop));
        let c = compare(&a, &b, 4);
        assert!(
            c.failed_tiles.is_empty(),
            "{camera}: {} tiles outside the bound (first: {:?})",
            c.failed_tiles.len(),
            c.failed_tiles.first()
        );
    }
    let halved = wgtrace::load_scene_str(
        &format!(
            "[render]\nwidth = 48\nheight = 40\ncrop = {crop:?}\n{}{body}",
            cameras[0]
        ),
        std::path::Path::new("test.toml"),
        &Overrides {
            width: Some(24),
            height: Some(20),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!((halved.width, halved.height), (11, 13));
    // in its place: the same pixels of the halved film, [7, 3, 11, 13]
    let half_film = common::scene_from_str(&format!(
        "[render]\nwidth = 24\nheight = 20\n{}{body}",
        cameras[0]
    ));
    let c = compare(
        &render_gpu(&halved),
        &window(&render_gpu(&half_film), [7, 3, 11, 13]),
        4,
    );
    assert!(
        c.failed_tiles.is_empty(),
        "halved: {:?}",
        c.failed_tiles.first()
    );
    // a crop at the film's edge stays on a smaller film
    let edge = wgtrace::load_scene_str(
        &format!(
            "[render]\nwidth = 100\nheight = 40\ncrop = [99, 0, 1, 40]\n{}{body}",
            cameras[0]
        ),
        std::path::Path::new("test.toml"),
        &Overrides {
            width: Some(10),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!((edge.width, edge.height), (1, 40));
}
