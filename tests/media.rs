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

/// A slab of sigma_t = (0.5, 1, 2) and albedo 0.5, 1 thick, between an orthographic camera
/// and an emitter of radiance 1 that fills the view; one ray per path, so what reaches the
/// camera is what crosses the slab unscattered: exp(-sigma_t) per channel, whichever
/// channel draws each free flight.
#[test]
fn a_homogeneous_slab_transmits_exp_of_minus_sigma_t_d() {
    let src = r#"
[render]
width = 16
height = 16
spp = 256
max_depth = 1

[camera]
look_from = [0, 0, 5]
look_at = [0, 0, 0]
projection = "orthographic"
height = 2

[media.slab]
type = "homogeneous"
sigma_t = [0.5, 1, 2]
albedo = 0.5

[materials]
light = { type = "emissive", radiance = [1, 1, 1] }
boundary = { type = "null" }

[[objects]]
type = "box"
min = [-5, -5, -1]
max = [5, 5, 0]
material = "boundary"
interior = "slab"

[[objects]]
type = "polygon"
vertices = [[-5, -5, -3], [5, -5, -3], [5, 5, -3], [-5, 5, -3]]
material = "light"
"#;
    let scene = common::scene_from_str(src);
    let z = common::sidak_z(1e-3, 6);
    for (name, render) in BACKENDS {
        let img = render(&scene);
        for (c, sigma) in [0.5f64, 1.0, 2.0].into_iter().enumerate() {
            let (m, se) = image_mean(&img, c);
            let expected = (-sigma).exp();
            assert!(
                (m - expected).abs() <= z * se + 1e-6,
                "{name} channel {c}: {m} against exp(-{sigma}) = {expected} (se {se})"
            );
            eprintln!("{name} channel {c}: {m:.5} against {expected:.5}, se {se:.5}");
        }
    }
}

/// A sphere of radius 1 holding a medium of albedo 0 (sigma_t = (1, 2, 3)) inside a null
/// boundary, before a uniform background of 1, seen by an orthographic camera: paths of
/// up to 8 rays, so every scattering event is absorbed and each pixel shows the
/// background times exp(-sigma_t chord), the chord 2 sqrt(1 - r^2) at distance r from the
/// axis. A pixel's expectation lies between the function's least and greatest value over
/// its square (monotonic in r): each pixel is held to that range widened by z standard
/// errors.
#[test]
fn a_medium_of_albedo_zero_is_pure_absorption() {
    let src = r#"
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
boundary = { type = "null" }

[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "boundary"
interior = "ink"
"#;
    let scene = common::scene_from_str(src);
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
                        "{name} pixel ({px}, {py}) channel {c}: {m} outside [{lo}, {hi}] (se {se})"
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
