//! Participating media against closed forms, on both backends: the transmittance of a
//! homogeneous slab is exp(-sigma_t d) per channel (chromatic extinction, the free flight's
//! spectral MIS); a medium of albedo 0 is pure absorption, exp(-sigma_t chord) through a
//! sphere pixel by pixel; a white furnace holding a scattering medium of albedo 1 inside a
//! null boundary stays 1 (energy kept over many scattering events, with next-event
//! estimation through the boundary toward an image background and MIS against the phase
//! function); the Henyey-Greenstein sampler against its pdf (chi-square, tests/materials.rs).
//! Each statistical bound comes from the render's own sample variance (Sidak threshold at
//! family-wise level 1e-3 over the test's comparisons).

mod common;

use wgtrace::{Accumulation, FlatScene};

type Render = fn(&FlatScene) -> Accumulation;

const BACKENDS: [(&str, Render); 2] = [("gpu", common::render_gpu), ("cpu", common::render_cpu)];

/// The mean over all pixels and samples of channel c, and its standard error.
fn image_mean(img: &Accumulation, c: usize) -> (f64, f64) {
    let n = img.pixel_count();
    let (mut sum, mut var, mut samples) = (0.0f64, 0.0f64, 0.0f64);
    for i in 0..n {
        sum += img.mean(i)[c] as f64;
        var += img.variance(i)[c] as f64 / img.samples(i) as f64;
        samples += img.samples(i) as f64;
    }
    assert!(samples > 0.0);
    (sum / n as f64, var.sqrt() / n as f64)
}

/// A homogeneous slab of sigma_t = (0.5, 1, 2) and albedo 0.5, 1 thick, between a tilted
/// orthographic camera and an emitter of radiance 1 that fills the view ([`slab`]); one
/// ray per path, so what reaches the camera is what crosses the slab unscattered:
/// exp(-sigma_t / cos) per channel, whichever channel draws each free flight.
#[test]
fn a_homogeneous_slab_transmits_exp_of_minus_sigma_t_d() {
    let scene = slab(
        "type = \"homogeneous\"\nsigma_t = [0.5, 1, 2]\nalbedo = 0.5",
        "{ type = \"emissive\", radiance = [1, 1, 1] }",
        1,
        "",
    );
    let cos = slab_cos();
    assert_image_means(&scene, [0.5f64, 1.0, 2.0].map(|s| (-s / cos).exp()));
}

/// A sphere of radius 1 holding a medium of albedo 0 (sigma_t = (1, 2, 3)) inside a null
/// boundary, before a uniform background of 1, seen by an orthographic camera: paths of
/// up to 8 rays, so every scattering event is absorbed and each pixel shows the
/// background times exp(-sigma_t chord), the chord 2 sqrt(1 - r^2) at distance r from the
/// axis. A pixel's expectation lies between the function's least and greatest value over
/// its square (monotonic in r): each pixel is held to that range widened by z standard
/// errors. The same with the sphere glass of ior 1 (invisible) whose `absorption` is
/// (1, 2, 3): the flattener makes it the same medium inside the glass.
#[test]
fn a_medium_of_albedo_zero_is_pure_absorption() {
    for boundary in [
        "boundary = { type = \"null\" }",
        "boundary = { type = \"dielectric\", ior = 1, absorption = [1, 2, 3] }",
    ] {
        pure_absorption(boundary);
    }
}

fn pure_absorption(boundary: &str) {
    let interior = if boundary.contains("absorption") {
        ""
    } else {
        "interior = \"ink\""
    };
    let src = format!(
        r#"
[render]
width = 24
height = 24
spp = 64
max_depth = 8

[camera]
look_from = [0, 0, 5]
look_at = [0, 0, 0]
projection = "orthographic"
height = 2.4

[background]
color = [1, 1, 1]

[media.ink]
type = "homogeneous"
sigma_t = [1, 2, 3]
albedo = 0

[materials]
{boundary}

[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "boundary"
{interior}
"#
    );
    let scene = common::scene_from_str(&src);
    assert!(scene.has_media(), "{boundary}");
    let (w, h) = (24usize, 24usize);
    let side = 2.4 / h as f64;
    let z = common::sidak_z(1e-3, 2 * 3 * w * h);
    let transmitted = |x: f64, y: f64, sigma: f64| {
        let r2 = x * x + y * y;
        if r2 >= 1.0 {
            1.0
        } else {
            (-sigma * 2.0 * (1.0 - r2).sqrt()).exp()
        }
    };
    for (name, render) in BACKENDS {
        let img = render(&scene);
        let mut inside = 0;
        for py in 0..h {
            for px in 0..w {
                let i = py * w + px;
                // the pixel's square in the view plane (x right, y up)
                let x0 = -1.2 + px as f64 * side;
                let y0 = 1.2 - (py + 1) as f64 * side;
                let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)];
                for (c, sigma) in [1.0f64, 2.0, 3.0].into_iter().enumerate() {
                    // the extremes of a function monotonic in r over the square: at its
                    // corners, or at its point nearest the axis
                    let mut values: Vec<f64> = corners
                        .iter()
                        .map(|(a, b)| transmitted(x0 + a * side, y0 + b * side, sigma))
                        .collect();
                    let nx = 0f64.clamp(x0, x0 + side);
                    let ny = 0f64.clamp(y0, y0 + side);
                    values.push(transmitted(nx, ny, sigma));
                    let lo = values.iter().cloned().fold(f64::INFINITY, f64::min);
                    let hi = values.iter().cloned().fold(0.0, f64::max);
                    let m = img.mean(i)[c] as f64;
                    let se = (img.variance(i)[c] as f64 / img.samples(i) as f64).sqrt();
                    assert!(
                        m >= lo - z * se - 1e-6 && m <= hi + z * se + 1e-6,
                        "{boundary}, {name} pixel ({px}, {py}) channel {c}: {m} outside [{lo}, {hi}] (se {se})"
                    );
                }
                if (x0 + side / 2.0).hypot(y0 + side / 2.0) < 0.9 {
                    inside += 1;
                }
            }
        }
        assert!(inside > 200, "{name}: the sphere covers too few pixels");
    }
}

/// A white furnace: a sphere of radius 1 holding a scattering medium of albedo 1
/// (sigma_t = 3, forward-scattering g = 0.5) inside a null boundary, under a uniform
/// image background of 1, which next-event estimation samples through the boundary and
/// weighs against the phase function by MIS. Nothing absorbs, so every pixel's
/// expectation is 1 however many times its paths scatter (up to 256 rays; Russian
/// roulette keeps it unbiased).
#[test]
fn a_white_furnace_with_a_scattering_medium_stays_one() {
    let dir = common::tmp_dir("media-furnace");
    // a uniform image background: a 4 x 2 PFM of ones
    let mut pfm = b"PF\n4 2\n-1.0\n".to_vec();
    for _ in 0..8 * 3 {
        pfm.extend_from_slice(&1.0f32.to_le_bytes());
    }
    std::fs::write(dir.join("white.pfm"), pfm).unwrap();
    let src = r#"
[render]
width = 16
height = 16
spp = 256
max_depth = 256

[camera]
look_from = [0, 0, 4]
look_at = [0, 0, 0]
vfov = 35

[background]
texture = "white"

[textures]
white = { type = "image", path = "white.pfm" }

[media.cloud]
type = "homogeneous"
sigma_t = 3
albedo = 1
g = 0.5

[materials]
boundary = { type = "null" }

[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "boundary"
interior = "cloud"
"#;
    let path = dir.join("furnace.toml");
    std::fs::write(&path, src).unwrap();
    let scene = wgtrace::load_scene(&path, &wgtrace::Overrides::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let z = common::sidak_z(1e-3, 6);
    for (name, render) in BACKENDS {
        let img = render(&scene);
        for c in 0..3 {
            let (m, se) = image_mean(&img, c);
            assert!(
                (m - 1.0).abs() <= z * se + 1e-5,
                "{name} channel {c}: {m} against 1 (se {se})"
            );
            eprintln!("{name} channel {c}: {m:.5} against 1, se {se:.5}");
        }
        // the medium does scatter: its pixels are noisy
        let noisy = (0..img.pixel_count())
            .filter(|&i| img.variance(i)[0] > 1e-4)
            .count();
        assert!(
            noisy > 50,
            "{name}: only {noisy} pixels see the medium scatter"
        );
    }
}

/// Bad media are refused with the key and line: an unknown medium (of an object, of the
/// camera), both ways of giving the coefficients at once, an albedo over 1, a phase
/// asymmetry of 1, an extinction that overflows, media on a mesh that takes its OBJ
/// file's own materials.
#[test]
fn bad_media_are_refused_with_their_keys() {
    let base = |camera: &str, media: &str, object: &str| {
        format!(
            "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n{camera}\n\
             [materials]\nb = {{ type = \"null\" }}\n{media}\n\
             [[objects]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"b\"\n{object}\n"
        )
    };
    let fog = "[media.fog]\ntype = \"homogeneous\"\nsigma_t = 1\n";
    let cases = [
        (
            base("", fog, "interior = \"smoke\""),
            "objects[0].interior: unknown medium \"smoke\" (defined: fog)",
        ),
        (
            base("medium = \"haze\"", fog, ""),
            "camera.medium: unknown medium \"haze\"",
        ),
        (
            base(
                "",
                "[media.fog]\ntype = \"homogeneous\"\nsigma_t = 1\nsigma_a = 0.5\n",
                "interior = \"fog\"",
            ),
            "media.fog.sigma_t: give sigma_t and albedo, or sigma_a and sigma_s, not both",
        ),
        (
            base(
                "",
                "[media.fog]\ntype = \"homogeneous\"\nalbedo = [0.5, 1.5, 0.5]\n",
                "interior = \"fog\"",
            ),
            "media.fog.albedo: must be in [0, 1]",
        ),
        (
            base(
                "",
                "[media.fog]\ntype = \"homogeneous\"\ng = 1\n",
                "interior = \"fog\"",
            ),
            "media.fog.g: must be in (-1, 1), got 1",
        ),
        (
            base(
                "",
                "[media.fog]\ntype = \"homogeneous\"\nsigma_t = 1e30\nscale = 1e30\n",
                "interior = \"fog\"",
            ),
            "media.fog.scale: times the coefficients gives an infinite extinction",
        ),
        (
            format!(
                "{}[[objects]]\ntype = \"mesh\"\npath = \"m.obj\"\ninterior = \"fog\"\n",
                base("", fog, "")
            ),
            "objects[1].interior: a mesh with media needs its `material`",
        ),
        (
            base("", fog, "interior = \"fog\"").replace(
                "b = { type = \"null\" }",
                "b = { type = \"dielectric\", ior = 1.5, absorption = [1, 1, 1] }",
            ),
            "objects[0].interior: its glass has an `absorption`, which is a medium inside it",
        ),
        (
            base("", fog, "interior = \"fog\"").replace(
                "b = { type = \"null\" }",
                "b = { type = \"null\" }\namber = { type = \"dielectric\", ior = 1.5, \
                 absorption = [1, 1, 1] }\nwhite = { type = \"lambertian\", albedo = [1, 1, 1] }\n\
                 mix = { type = \"blend\", first = \"white\", second = \"amber\", weight = 0.5 }",
            ),
            "materials.mix.second: \"amber\" absorbs",
        ),
        (
            base(
                "",
                "[media.fog]\ntype = \"heterogeneous\"\ngrid = \"missing.vol\"\n",
                "interior = \"fog\"",
            ),
            "media.fog.grid: missing.vol",
        ),
    ];
    for (src, says) in cases {
        let err = wgtrace::load_scene_str(
            &src,
            std::path::Path::new("media.toml"),
            &wgtrace::Overrides::default(),
        )
        .expect_err(says)
        .to_string();
        assert!(err.contains(says), "{err}\n  should say: {says}");
        assert!(err.contains("media.toml:"), "{err}: no file and line");
    }
}

/// A density grid of nz voxels along z whose values rise linearly, (k + 0.5) / nz at the
/// centre of voxel k, and 3 x 5 across (so its majorant cells are partial): its trilinear
/// density (clamped at the faces) integrates to 0.5 over the unit cube's depth. Written
/// as a `.vol` file in a fresh folder; returns the file.
fn ramp_grid(name: &str, nz: u32) -> std::path::PathBuf {
    ramp_grid_of(name, nz, &[1.0])
}

/// [`ramp_grid`] with a channel per factor, each the ramp times its factor.
fn ramp_grid_of(name: &str, nz: u32, factors: &[f32]) -> std::path::PathBuf {
    let res = [3, 5, nz];
    let mut values = Vec::new();
    for k in 0..nz {
        let v = (k as f32 + 0.5) / nz as f32;
        for _ in 0..15 {
            values.extend(factors.iter().map(|f| f * v));
        }
    }
    let path = common::tmp_dir(name).join("ramp.vol");
    let bytes = wgtrace::scene::volume::write_vol(res, &values, ([0.0; 3], [1.0; 3]));
    std::fs::write(&path, bytes).unwrap();
    path
}

/// A slab 1 thick whose density grid rises linearly with depth, sigma_t = (1, 2, 4) times
/// it and albedo 0.5, between a tilted orthographic camera and an emitter of radiance 1:
/// one ray per path, so what reaches the camera is what crosses unscattered, by delta
/// tracking through the grid's majorant cells: exp(-sigma_t 0.5 / cos theta), theta the
/// rays' angle to the slab's normal.
#[test]
fn delta_tracking_through_a_density_grid_transmits_exp_of_minus_its_integral() {
    delta_tracking(&ramp_grid("delta", 20), "[1, 2, 4]");
}

/// The same slab whose grid holds a density per colour channel (the ramp times 1, 2 and
/// 4, Mitsuba's RGB extinction grids), of extinction 1: the same transmittance.
#[test]
fn an_rgb_density_grid_extinguishes_each_channel_by_its_own_density() {
    delta_tracking(&ramp_grid_of("rgb", 20, &[1.0, 2.0, 4.0]), "1");
}

fn delta_tracking(grid: &std::path::Path, sigma_t: &str) {
    let scene = slab(
        &format!(
            "type = \"heterogeneous\"\ngrid = \"{}\"\nsigma_t = {sigma_t}\nalbedo = 0.5\n{SLAB}",
            grid.display()
        ),
        "{ type = \"emissive\", radiance = [1, 1, 1] }",
        1,
        "",
    );
    let cos = slab_cos();
    assert_image_means(&scene, [1.0f64, 2.0, 4.0].map(|s| (-s * 0.5 / cos).exp()));
}

/// The placement of a grid's unit cube on [`slab`]'s slab.
const SLAB: &str = "transform = { scale = [10, 10, 1], translate = [-5, -5, -1] }";

/// A heterogeneous medium without a grid (Mitsuba's constant extinction in a
/// heterogeneous medium) has density 1 in the unit cube its transform places, none
/// elsewhere: here the slab's back half, 0.5 thick, transmitting exp(-sigma_t 0.5 / cos).
#[test]
fn a_heterogeneous_medium_without_a_grid_fills_its_placed_cube() {
    let scene = slab(
        "type = \"heterogeneous\"\nsigma_t = [1, 2, 4]\nalbedo = 0.5\n\
         transform = { scale = [10, 10, 0.5], translate = [-5, -5, -1] }",
        "{ type = \"emissive\", radiance = [1, 1, 1] }",
        1,
        "",
    );
    let cos = slab_cos();
    assert_image_means(&scene, [1.0f64, 2.0, 4.0].map(|s| (-s * 0.5 / cos).exp()));
}

/// The cosine of the angle between [`slab`]'s camera rays and the slab's normal.
fn slab_cos() -> f64 {
    5.0 / (1.0f64 + 0.25 + 25.0).sqrt()
}

/// A slab 1 thick (z from -1 to 0, 10 wide) of a medium in its null box (the medium's
/// keys: `medium`; a grid's unit cube placed on the slab by [`SLAB`]),
/// seen by an orthographic camera tilted by [`slab_cos`], above a floor of material
/// `floor` at z = -3; paths of `max_depth` rays; `extra` appended to the file.
fn slab(medium: &str, floor: &str, max_depth: u32, extra: &str) -> wgtrace::FlatScene {
    common::scene_from_str(&format!(
        r#"
[render]
width = 16
height = 16
spp = 256
max_depth = {max_depth}

[camera]
look_from = [1, 0.5, 5]
look_at = [0, 0, 0]
projection = "orthographic"
height = 1

[media.smoke]
{medium}

[materials]
floor = {floor}
boundary = {{ type = "null" }}

[[objects]]
type = "box"
min = [-5, -5, -1]
max = [5, 5, 0]
material = "boundary"
interior = "smoke"

[[objects]]
type = "polygon"
vertices = [[-9, -9, -3], [9, -9, -3], [9, 9, -3], [-9, 9, -3]]
material = "floor"
{extra}
"#
    ))
}

/// Each channel's mean over the image against `expected`, on both backends, within the
/// render's standard error (Sidak over the six comparisons).
fn assert_image_means(scene: &FlatScene, expected: [f64; 3]) {
    let z = common::sidak_z(1e-3, 6);
    for (name, render) in BACKENDS {
        let img = render(scene);
        for (c, want) in expected.into_iter().enumerate() {
            let (m, se) = image_mean(&img, c);
            eprintln!("{name} channel {c}: {m:.5} against {want:.5}, se {se:.5}");
            assert!(
                (m - want).abs() <= z * se + 2e-6,
                "{name} channel {c}: {m} against {want} (se {se})"
            );
        }
    }
}

/// The same grid of albedo 0 above a white Lambertian floor, lit straight down by a
/// directional light of irradiance pi: the camera ray and the shadow ray each cross the
/// slab, both by ratio tracking (no collision scatters), so a pixel is exp(-tau_camera)
/// exp(-tau_light), tau = sigma_t 0.5 / cos. Ratio tracking is unbiased: the mean over
/// the image matches the closed form within its standard error.
#[test]
fn ratio_tracking_through_a_density_grid_is_unbiased() {
    let scene = slab(
        &format!(
            "type = \"heterogeneous\"\ngrid = \"{}\"\nsigma_t = [0.5, 1, 2]\nalbedo = 0\n{SLAB}",
            ramp_grid("ratio", 12).display()
        ),
        "{ type = \"lambertian\", albedo = [1, 1, 1] }",
        2,
        "[[lights]]\ntype = \"directional\"\ndirection = [0, 0, -1]\n\
         irradiance = [3.14159265, 3.14159265, 3.14159265]",
    );
    let cos = slab_cos();
    assert_image_means(
        &scene,
        [0.5f64, 1.0, 2.0].map(|s| (-s * 0.5 / cos).exp() * (-s * 0.5).exp()),
    );
}

/// An albedo grid varies a heterogeneous medium's albedo: one of three channels holding
/// (0.2, 0.5, 0.8) in every voxel renders as `albedo = [0.2, 0.5, 0.8]` does, and one of
/// one channel holding 0.6 as `albedo = 0.6` (a box of the ramp grid under a uniform
/// background, scattering many times; image means within their standard errors).
#[test]
fn an_albedo_grid_renders_as_the_albedo_it_holds() {
    let density = ramp_grid("albedo", 10);
    let dir = density.parent().unwrap().to_path_buf();
    let voxels = 4 * 4 * 4;
    let colour: Vec<f32> = (0..voxels).flat_map(|_| [0.2, 0.5, 0.8]).collect();
    let grey = vec![0.6f32; voxels];
    for (name, values) in [("colour.vol", &colour), ("grey.vol", &grey)] {
        let bytes = wgtrace::scene::volume::write_vol([4, 4, 4], values, ([0.0; 3], [1.0; 3]));
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    let scene = |albedo: &str| {
        common::scene_from_str(&format!(
            r#"
[render]
width = 12
height = 12
spp = 256
max_depth = 32

[camera]
look_from = [0, 0, 4]
look_at = [0, 0, 0]
vfov = 40

[background]
color = [1, 1, 1]

[media.smoke]
type = "heterogeneous"
grid = "{}"
sigma_t = 6
{albedo}
transform = {{ translate = [-0.5, -0.5, -0.5] }}

[materials]
boundary = {{ type = "null" }}

[[objects]]
type = "box"
min = [-0.5, -0.5, -0.5]
max = [0.5, 0.5, 0.5]
material = "boundary"
interior = "smoke"
"#,
            density.display()
        ))
    };
    let z = common::sidak_z(1e-3, 2 * 2 * 3);
    for (grid, albedo) in [("colour.vol", "[0.2, 0.5, 0.8]"), ("grey.vol", "0.6")] {
        let with_grid = scene(&format!("albedo_grid = \"{}\"", dir.join(grid).display()));
        let constant = scene(&format!("albedo = {albedo}"));
        for (name, render) in BACKENDS {
            let (a, b) = (render(&with_grid), render(&constant));
            for c in 0..3 {
                let ((ma, sa), (mb, sb)) = (image_mean(&a, c), image_mean(&b, c));
                eprintln!("{grid} {name} channel {c}: {ma:.5} against {mb:.5}");
                assert!(
                    (ma - mb).abs() <= z * (sa * sa + sb * sb).sqrt() + 1e-6,
                    "{grid} {name} channel {c}: {ma} with the grid, {mb} without (se {sa}, {sb})"
                );
            }
        }
    }
}

/// A `.vol` file whose header lies is one error, never a panic: voxel counts whose
/// product overflows, a box that is not finite, a length that does not match, a grid of
/// two channels.
#[test]
fn bad_grid_files_are_errors() {
    use wgtrace::scene::volume::{parse_vol, write_vol};
    let header = |res: [i32; 3], channels: i32, bbox: [f32; 6]| {
        let mut b = b"VOL\x03".to_vec();
        for i in [1, res[0], res[1], res[2], channels] {
            b.extend(i.to_le_bytes());
        }
        for f in bbox {
            b.extend(f.to_le_bytes());
        }
        b
    };
    let unit = [0.0, 0.0, 0.0, 1.0, 1.0, 1.0];
    let cases = [
        (header([1 << 21, 1 << 21, 1 << 22], 1, unit), "at most"),
        (header([1 << 30, 1 << 30, 1 << 30], 3, unit), "at most"),
        (
            {
                let mut b = header([1, 1, 1], 1, [0.0, 0.0, 0.0, f32::NAN, 1.0, 1.0]);
                b.extend(1.0f32.to_le_bytes());
                b
            },
            "not finite",
        ),
        (header([2, 2, 2], 1, unit), "bytes of values"),
        (header([1, 1, 1], 2, unit), "2 channels"),
        (b"VOL".to_vec(), "not a Mitsuba .vol grid"),
    ];
    for (bytes, says) in cases {
        let err = parse_vol(&bytes).expect_err(says);
        assert!(err.contains(says), "{err}: should say {says}");
    }
    // and a good one reads back
    let g = parse_vol(&write_vol([2, 1, 1], &[0.5, 1.5], ([0.0; 3], [1.0; 3]))).unwrap();
    assert_eq!(
        (g.res, g.channels, g.values),
        ([2, 1, 1], 1, vec![0.5, 1.5])
    );
}

/// Absorbing glass in a fog that fills the scene (the camera's medium) leaves into the
/// fog: its record's media word holds the absorption's medium inside and the fog outside.
#[test]
fn absorbing_glass_in_a_scene_wide_fog_leaves_into_the_fog() {
    let scene = common::scene_from_str(
        r#"
[camera]
look_from = [0, 0, 5]
look_at = [0, 0, 0]
medium = "fog"

[media.fog]
type = "homogeneous"
sigma_t = 0.1

[materials]
amber = { type = "dielectric", ior = 1.5, absorption = [0.5, 1, 2] }

[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "amber"
"#,
    );
    use wgtrace::scene::records::MEDIA_SIDE;
    assert_eq!(scene.num_media, 2);
    let word = (scene.material_media * 4) as usize;
    // the glass's medium is number 1 (after the fog, 0), the fog outside
    assert_eq!(scene.tables[word >> 2][word & 3] as u32, 2 + MEDIA_SIDE);
}
