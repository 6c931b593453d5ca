//! Textures on the CPU reference against their definitions, and the GPU's look-ups against
//! the CPU's, one by one, for every texture type.

mod common;

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};
use wgtrace::cpu::bindings::Bindings;
use wgtrace::cpu::materials::material_at;
use wgtrace::cpu::textures::{perlin, texture_value};
use wgtrace::gpu::kernel::lookup_textures;
use wgtrace::scene::materials::{microfacet, pbr};
use wgtrace::scene::records::TextureLookup;
use wgtrace::scene::textures::srgb_to_linear;
use wgtrace::FlatScene;

/// A scene whose `[textures]` table is `textures`, loaded as if it sat in `dir`.
fn scene(textures: &str, dir: &Path) -> FlatScene {
    let src = format!(
        "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[textures]\n{textures}\n\
         [materials]\nm = {{ type = \"lambertian\", albedo = [0.5, 0.5, 0.5] }}\n"
    );
    wgtrace::load_scene_str(&src, &dir.join("t.toml"), &Default::default())
        .unwrap_or_else(|e| panic!("{e}"))
}

/// A folder holding a 2 x 2 PNG: top row red (255, 0, 0), white; bottom row black, sRGB 128
/// grey.
fn image_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("wgtrace-{test}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let img =
        image::RgbImage::from_raw(2, 2, vec![255, 0, 0, 255, 255, 255, 0, 0, 0, 128, 128, 128])
            .unwrap();
    img.save(dir.join("2x2.png")).unwrap();
    // and a 1 x 1 linear float image with a value above 1
    let hdr = image::Rgb32FImage::from_raw(1, 1, vec![2.5, 0.5, 0.25]).unwrap();
    hdr.save(dir.join("1x1.exr")).unwrap();
    dir
}

fn value(s: &FlatScene, index: u32, uv: [f32; 2], p: [f32; 3]) -> Vec3 {
    let b = Bindings::new(s, s.params(0, s.full_band()));
    texture_value(&b, index, Vec2::from(uv), Vec3::from(p))
}

#[track_caller]
fn assert_close(a: Vec3, b: Vec3) {
    assert!((a - b).abs().max_element() < 1e-5, "{a} vs {b}");
}

#[test]
fn checker_cells_alternate_in_uv_and_in_space() {
    let s = scene(
        "a = { type = \"constant\", color = [0.1, 0.2, 0.3] }\n\
         c = { type = \"checker\", even = \"a\", odd = [1, 1, 1], scale = 2 }\n\
         s = { type = \"checker\", even = [0, 0, 0], odd = [1, 0, 0], scale = 1, mapping = \"solid\" }",
        Path::new("."),
    );
    // textures are numbered in name order: a = 0, c = 1, s = 2
    assert_close(value(&s, 1, [0.1, 0.1], [0.0; 3]), Vec3::new(0.1, 0.2, 0.3));
    assert_close(value(&s, 1, [0.6, 0.1], [0.0; 3]), Vec3::ONE);
    assert_close(value(&s, 1, [0.6, 0.6], [0.0; 3]), Vec3::new(0.1, 0.2, 0.3));
    assert_close(value(&s, 1, [-0.1, 0.1], [0.0; 3]), Vec3::ONE);
    assert_close(value(&s, 2, [0.0; 2], [0.5, 0.5, 0.5]), Vec3::ZERO);
    assert_close(value(&s, 2, [0.0; 2], [1.5, 0.5, 0.5]), Vec3::X);
    assert_close(value(&s, 2, [0.0; 2], [1.5, -0.5, 0.5]), Vec3::ZERO);
}

#[test]
fn images_decode_srgb_filter_bilinearly_and_wrap() {
    let dir = image_dir("images");
    let s = scene(
        "r = { type = \"image\", path = \"2x2.png\" }\n\
         c = { type = \"image\", path = \"2x2.png\", wrap = \"clamp\" }\n\
         m = { type = \"image\", path = \"2x2.png\", wrap = \"mirror\" }",
        &dir,
    );
    let grey = srgb_to_linear(128.0 / 255.0);
    assert!((grey - 0.2158605).abs() < 1e-6);
    // names in order: c = 0, m = 1, r = 2. Texel centres (v = 0 is the bottom row).
    for t in 0..3 {
        assert_close(value(&s, t, [0.25, 0.75], [0.0; 3]), Vec3::X);
        assert_close(value(&s, t, [0.75, 0.75], [0.0; 3]), Vec3::ONE);
        assert_close(value(&s, t, [0.25, 0.25], [0.0; 3]), Vec3::ZERO);
        assert_close(value(&s, t, [0.75, 0.25], [0.0; 3]), Vec3::splat(grey));
        // the centre of the image: the mean of the four texels
        let mean = (Vec3::X + Vec3::ONE + Vec3::splat(grey)) / 4.0;
        assert_close(value(&s, t, [0.5, 0.5], [0.0; 3]), mean);
    }
    // at the left edge, between the centres of the two top texels' neighbours: repeat mixes
    // in the right column, clamp holds the edge texel, mirror reflects it
    assert_close(
        value(&s, 2, [0.0, 0.75], [0.0; 3]),
        (Vec3::X + Vec3::ONE) / 2.0,
    );
    assert_close(value(&s, 0, [0.0, 0.75], [0.0; 3]), Vec3::X);
    assert_close(value(&s, 1, [0.0, 0.75], [0.0; 3]), Vec3::X);
    // float formats are linear already: no sRGB decoding, values above 1 kept
    let f = scene("x = { type = \"image\", path = \"1x1.exr\" }", &dir);
    assert_close(
        value(&f, 0, [0.3, 0.9], [0.0; 3]),
        Vec3::new(2.5, 0.5, 0.25),
    );
    // repeat: u + 1 is u; mirror: -u is u
    assert_close(
        value(&s, 2, [1.3, 0.6], [0.0; 3]),
        value(&s, 2, [0.3, 0.6], [0.0; 3]),
    );
    assert_close(
        value(&s, 1, [-0.3, 0.6], [0.0; 3]),
        value(&s, 1, [0.3, 0.6], [0.0; 3]),
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn perlin_noise_is_bounded_smooth_and_zero_on_the_lattice() {
    let s = scene("n = { type = \"noise\", scale = 1 }", Path::new("."));
    let b = Bindings::new(&s, s.params(0, s.full_band()));
    let offset = s.textures[0].offset;
    let mut rng = 5u32;
    let (mut lo, mut hi) = (f32::MAX, f32::MIN);
    for _ in 0..20_000 {
        let p = Vec3::new(
            common::random_f32(&mut rng),
            common::random_f32(&mut rng),
            common::random_f32(&mut rng),
        ) * 20.0
            - 10.0;
        let n = perlin(&b, offset, p);
        lo = lo.min(n);
        hi = hi.max(n);
        // gradient noise is continuous: a step of 1e-3 changes it by a little
        let d = (perlin(&b, offset, p + Vec3::splat(1e-3)) - n).abs();
        assert!(d < 0.02, "jump of {d} at {p}");
    }
    assert!(
        lo > -1.05 && hi < 1.05 && lo < -0.3 && hi > 0.3,
        "range [{lo}, {hi}]"
    );
    // at lattice points the offset to the corner is 0, so gradient noise is 0
    for p in [Vec3::ZERO, Vec3::new(3.0, -2.0, 7.0)] {
        assert!(perlin(&b, offset, p).abs() < 1e-6);
    }
}

#[test]
fn textures_and_material_references_are_validated() {
    let err = |t: &str, m: &str| {
        let src = format!("[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[textures]\n{t}\n[materials]\n{m}\n");
        wgtrace::load_scene_str(&src, Path::new("bad.toml"), &Default::default())
            .unwrap_err()
            .to_string()
    };
    let e = err("", "m = { type = \"lambertian\", albedo = \"nope\" }");
    assert!(
        e.contains("materials.m.albedo: unknown texture \"nope\""),
        "{e}"
    );
    let e = err("a = { type = \"checker\", even = [0, 0, 0], odd = [1, 1, 1] }\nb = { type = \"checker\", even = \"a\", odd = [1, 1, 1] }", "");
    assert!(e.contains("textures.b.even: \"a\" is a checker"), "{e}");
    let e = err("i = { type = \"image\", path = \"missing.png\" }", "");
    assert!(
        e.contains("bad.toml:5:") && e.contains("textures.i.path") && e.contains("missing.png"),
        "{e}"
    );
    let e = err("n = { type = \"noise\", scale = 0 }", "");
    assert!(e.contains("textures.n.scale: must be > 0"), "{e}");
}

#[test]
fn gpu_texture_lookups_match_the_cpu_for_every_texture_type() {
    let ctx = common::gpu_context();
    let dir = image_dir("lookups");
    let s = scene(
        "a_const = { type = \"constant\", color = [0.2, 0.4, 0.6] }\n\
         b_uv = { type = \"checker\", even = \"e_img\", odd = [1, 0.5, 0], scale = 3 }\n\
         c_solid = { type = \"checker\", even = \"f_perlin\", odd = [0, 0, 1], scale = 2, mapping = \"solid\" }\n\
         d_clamp = { type = \"image\", path = \"2x2.png\", wrap = \"clamp\" }\n\
         e_img = { type = \"image\", path = \"2x2.png\" }\n\
         f_perlin = { type = \"noise\", scale = 3, color = [1, 0.9, 0.8] }\n\
         g_turb = { type = \"noise\", kind = \"turbulence\", scale = 2 }\n\
         h_marble = { type = \"noise\", kind = \"marble\", scale = 5 }\n\
         i_mirror = { type = \"image\", path = \"2x2.png\", wrap = \"mirror\" }",
        &dir,
    );
    let mut rng = 11u32;
    let mut lookups = Vec::new();
    for t in 0..s.textures.len() {
        for _ in 0..2000 {
            let mut r = || common::random_f32(&mut rng) * 6.0 - 3.0;
            lookups.push(TextureLookup {
                uv: [r(), r(), t as f32, 0.0],
                p: [r(), r(), r(), 0.0],
            });
        }
    }
    let gpu = lookup_textures(&ctx, &s, &lookups).expect("texture kernel");
    let mut worst = 0.0f32;
    for (l, g) in lookups.iter().zip(&gpu) {
        let c = value(
            &s,
            l.uv[2] as u32,
            [l.uv[0], l.uv[1]],
            [l.p[0], l.p[1], l.p[2]],
        );
        let d = (Vec3::from_slice(g) - c).abs().max_element();
        worst = worst.max(d);
        // f32 sin and the floor of products may differ by an ulp between the backends
        assert!(
            d < 1e-4,
            "texture {}: gpu {g:?} vs cpu {c} at {l:?}",
            l.uv[2]
        );
    }
    eprintln!(
        "{} look-ups over {} textures: largest difference {worst:e}",
        lookups.len(),
        s.textures.len()
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A texture in a material's second colour is clamped to 1 where it is a reflectance (the
/// microfacet's specular colour) but not as pbr's specular colour, which
/// KHR_materials_specular lets exceed 1: there a texture gives what the same constant
/// gives.
#[test]
fn pbr_specular_colour_textures_are_not_clamped_where_microfacet_ones_are() {
    let src = "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[textures]\n\
               t = { type = \"constant\", color = [2.5, 0.5, 1.5] }\n[materials]\n\
               a = { type = \"pbr\", specular_color = \"t\" }\n\
               b = { type = \"pbr\", specular_color = [2.5, 0.5, 1.5] }\n\
               c = { type = \"microfacet\", albedo = [0.5, 0.5, 0.5], specular = \"t\", roughness = 0.2 }\n";
    let s = wgtrace::load_scene_str(src, Path::new("t.toml"), &Default::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let b = Bindings::new(&s, s.params(0, s.full_band()));
    let hit = wgtrace::cpu::types::Hit {
        p: Vec3::ZERO,
        ng: Vec3::Z,
        ns: Vec3::Z,
        uv: Vec2::splat(0.5),
        front_face: true,
        material: 0,
        err: 0.0,
        tangent: glam::Vec4::ZERO,
    };
    // materials are numbered in name order: a, b, c
    let at = |i: usize| material_at(&b, &s.materials[i], &hit);
    let pbr_specular = |i| pbr::Params::read(&at(i)).specular_color;
    assert_close(pbr_specular(0), Vec3::new(2.5, 0.5, 1.5));
    assert_close(pbr_specular(0), pbr_specular(1));
    let microfacet_specular = microfacet::Params::read(&at(2)).specular;
    assert_close(microfacet_specular, Vec3::new(1.0, 0.5, 1.0));
}
