//! Textures on the CPU reference against their definitions, and the GPU's look-ups against
//! the CPU's, one by one, for every texture type.

mod common;

use std::path::{Path, PathBuf};

use glam::{Vec3, Vec4};
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
    // and a 3 x 2 16-bit image: a ramp in red, green and blue
    let wide = image::ImageBuffer::<image::Rgb<u16>, _>::from_fn(3, 2, |x, y| {
        let v = (x + 3 * y) as u16 * 13107;
        image::Rgb([v, 65535 - v, 30000])
    });
    wide.save(dir.join("3x2.png")).unwrap();
    dir
}

fn value(s: &FlatScene, index: u32, uv: [f32; 2], p: [f32; 3]) -> Vec3 {
    let b = Bindings::new(s, s.params(0, s.full_band()));
    texture_value(
        &b,
        index,
        Vec4::new(uv[0], uv[1], uv[0], uv[1]),
        Vec3::from(p),
    )
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

/// A uv checker's `transform` maps uv before its `scale`: cells of scale x M (u, v, 1),
/// here M turning uv by 90 degrees and moving it by (0.25, 0), so the cell of (u, v) is
/// that of (0.25 - v, u) times 2; the rows of a matrix say the same.
#[test]
fn checker_cells_follow_their_uv_transform() {
    let s = scene(
        "t = { type = \"checker\", even = [0, 0, 0], odd = [1, 1, 1], scale = 2, transform = { rotation = 90, offset = [0.25, 0] } }\n\
         u = { type = \"checker\", even = [0, 0, 0], odd = [1, 1, 1], scale = 2, transform = { matrix = [[0, -1, 0.25], [1, 0, 0]] } }",
        Path::new("."),
    );
    for t in 0..2 {
        for uv in [
            [0.1f32, 0.1],
            [0.1, 0.3],
            [0.3, 0.1],
            [0.6, 0.2],
            [0.2, 0.6],
            [0.9, 0.7],
        ] {
            let (x, y) = (2.0 * (0.25 - uv[1]), 2.0 * uv[0]);
            let odd = (x.floor() as i32 + y.floor() as i32) & 1 == 1;
            let want = if odd { Vec3::ONE } else { Vec3::ZERO };
            assert_close(value(&s, t, uv, [0.0; 3]), want);
        }
    }
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
    let e = err("s = { type = \"checker\", even = [0, 0, 0], odd = [1, 1, 1], mapping = \"solid\", transform = { scale = [2, 1] } }", "");
    assert!(e.contains("textures.s.transform: maps uv"), "{e}");
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
         i_mirror = { type = \"image\", path = \"2x2.png\", wrap = \"mirror\" }\n\
         j_linear = { type = \"image\", path = \"2x2.png\", color_space = \"linear\" }\n\
         k_half = { type = \"image\", path = \"3x2.png\" }\n\
         l_half_linear = { type = \"image\", path = \"3x2.png\", color_space = \"linear\", wrap = \"clamp\" }\n\
         m_float = { type = \"image\", path = \"1x1.exr\" }\n\
         n_axes = { type = \"image\", path = \"3x2.png\", wrap = [\"clamp\", \"mirror\"] }\n\
         o_nearest = { type = \"image\", path = \"2x2.png\", filter = \"nearest\", uv_set = 1 }\n\
         p_set1 = { type = \"image\", path = \"3x2.png\", uv_set = 1, wrap = [\"mirror\", \"clamp\"] }",
        &dir,
    );
    let mut rng = 11u32;
    let mut lookups = Vec::new();
    for t in 0..s.textures.len() {
        for _ in 0..2000 {
            let mut r = || common::random_f32(&mut rng) * 6.0 - 3.0;
            lookups.push(TextureLookup {
                uv: [r(), r(), r(), r()],
                p: [r(), r(), r(), t as f32],
            });
        }
    }
    // 8-bit, half and float images: three texel banks, and the look-ups' switch over them
    assert_eq!(s.texels.banks.len(), 3);
    let gpu = lookup_textures(&ctx, &s, &Default::default(), &lookups).expect("texture kernel");
    let mut worst = 0.0f32;
    let b = Bindings::new(&s, s.params(0, s.full_band()));
    for (l, g) in lookups.iter().zip(&gpu) {
        let c = texture_value(
            &b,
            l.p[3] as u32,
            Vec4::from(l.uv),
            Vec3::from_slice(&l.p[..3]),
        );
        let d = (Vec3::from_slice(g) - c).abs().max_element();
        worst = worst.max(d);
        // f32 sin and the floor of products may differ by an ulp between the backends
        assert!(
            d < 1e-4,
            "texture {}: gpu {g:?} vs cpu {c} at {l:?}",
            l.p[3]
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
        unmapped: Vec3::Z,
        uv: Vec4::splat(0.5),
        front_face: true,
        material: 0,
        err: 0.0,
        tangent: glam::Vec4::ZERO,
        color: Vec4::ONE,
        dpdu: glam::Vec3::ZERO,
        dpdv: glam::Vec3::ZERO,
    };
    // materials are numbered in name order: a, b, c
    let at = |i: usize| material_at(&b, &s.materials[i], &hit);
    let pbr_specular = |i| pbr::Params::read(&at(i)).specular_color;
    assert_close(pbr_specular(0), Vec3::new(2.5, 0.5, 1.5));
    assert_close(pbr_specular(0), pbr_specular(1));
    let microfacet_specular = microfacet::Params::read(&at(2)).specular;
    assert_close(microfacet_specular, Vec3::new(1.0, 0.5, 1.0));
}

/// 16-bit images are half floats (decoded from sRGB first when they are colour); 8-bit ones
/// keep their bytes, decoded at look-up.
#[test]
fn images_keep_their_precision_in_the_texel_banks() {
    use wgtrace::scene::texels::TexelKind;
    let dir = image_dir("precision");
    let s = scene(
        "a = { type = \"image\", path = \"2x2.png\" }\n\
         b = { type = \"image\", path = \"3x2.png\", color_space = \"linear\" }\n\
         c = { type = \"image\", path = \"3x2.png\" }",
        &dir,
    );
    let kinds: Vec<TexelKind> = s.texels.banks.iter().map(|b| b.kind).collect();
    assert_eq!(kinds, [TexelKind::Unorm8, TexelKind::Half]);
    assert_eq!(
        s.texels.banks[0].data.len(),
        2 * 2 * 4,
        "4 bytes per 8-bit texel"
    );
    // texel (1, 1) of the 16-bit ramp: 4 x 13107 / 65535 = 0.8, as a half float
    let b = Bindings::new(&s, s.params(0, s.full_band()));
    let at = |t: u32, uv: [f32; 2]| {
        texture_value(&b, t, Vec4::new(uv[0], uv[1], uv[0], uv[1]), Vec3::ZERO)
    };
    let centre = [(1.0 + 0.5) / 3.0, 0.25];
    let linear = at(1, centre);
    assert!((linear.x - 0.8).abs() < 4e-4, "{linear}");
    assert!((linear.y - 0.2).abs() < 2e-4, "{linear}");
    let decoded = at(2, centre);
    assert!((decoded.x - srgb_to_linear(0.8)).abs() < 4e-4, "{decoded}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The texel banks: images of one kind share pages of the largest one's size, shelf by
/// shelf, never overlapping and always inside; pages fill banks up to their byte and layer
/// caps; a scene past the banks is refused with what it needs.
#[test]
fn texel_blocks_pack_into_pages_and_banks_without_overlap() {
    use wgtrace::scene::texels::{pack, Block, TexelKind, MAX_BANK_BYTES, MAX_BANK_LAYERS};
    let sizes: [(u32, u32); 8] = [
        (7, 5),
        (3, 3),
        (7, 2),
        (1, 1),
        (4, 5),
        (2, 4),
        (7, 5),
        (5, 1),
    ];
    let data: Vec<Vec<u8>> = sizes
        .iter()
        .enumerate()
        .map(|(i, &(w, h))| (0..w * h * 4).map(|k| (i as u32 * 31 + k) as u8).collect())
        .collect();
    let blocks: Vec<Block> = sizes
        .iter()
        .zip(&data)
        .map(|(&(w, h), d)| Block {
            kind: TexelKind::Unorm8,
            width: w,
            height: h,
            data: d,
        })
        .collect();
    let (regions, texels) = pack(&blocks).unwrap();
    assert_eq!(texels.banks.len(), 1);
    let bank = &texels.banks[0];
    assert_eq!((bank.width, bank.height), (7, 5));
    let mut covered = std::collections::HashSet::new();
    for (i, (r, b)) in regions.iter().zip(&blocks).enumerate() {
        assert!(r.x + b.width <= bank.width && r.y + b.height <= bank.height);
        assert!(r.layer < bank.layers);
        for y in 0..b.height {
            for x in 0..b.width {
                assert!(
                    covered.insert((r.layer, r.x + x, r.y + y)),
                    "block {i} overlaps"
                );
                let k = ((y * b.width + x) * 4) as usize;
                let t = bank.texel(r.layer, r.x + x, r.y + y, false);
                assert_eq!(t[0], b.data[k] as f32 / 255.0, "block {i} texel ({x}, {y})");
            }
        }
    }
    // fewer pages than blocks: the small ones share
    assert!(bank.layers < blocks.len() as u32, "{} pages", bank.layers);
    // a bank holds MAX_BANK_LAYERS pages at most: 1 x 1 pages of one texel each
    let one = [0u8; 4];
    let tiny: Vec<Block> = (0..MAX_BANK_LAYERS + 3)
        .map(|_| Block {
            kind: TexelKind::Unorm8,
            width: 1,
            height: 1,
            data: &one,
        })
        .collect();
    let (regions, texels) = pack(&tiny).unwrap();
    assert_eq!(texels.banks.len(), 2);
    assert_eq!(texels.banks[0].layers, MAX_BANK_LAYERS);
    assert_eq!(regions.last().unwrap().bank, 1);
    // and MAX_BANK_BYTES: a float page of 2^13 x 2^13 texels is 1 GiB, one to a bank; the
    // blocks are not read before their pages are sized, so nine empty claims show the
    // refusal without allocating
    let side = 1u32 << 13;
    assert_eq!(side as u64 * side as u64 * 16, MAX_BANK_BYTES);
    let e = pack(
        &(0..9)
            .map(|_| Block {
                kind: TexelKind::Float,
                width: side,
                height: side,
                data: &[],
            })
            .collect::<Vec<_>>(),
    )
    .unwrap_err();
    assert!(
        e.contains("float texels need 9216 MiB") && e.contains("8 banks"),
        "{e}"
    );
}

/// A scene of sixteen 4096 x 4096 8-bit maps: 1 GiB of texels (eight times what one
/// storage binding holds) renders on the GPU, each map's page read where it lies. Each
/// map is a solid colour on an emissive square seen head-on: every pixel of a square is
/// its map's colour.
#[test]
fn a_gigabyte_of_8_bit_texels_renders_on_the_gpu() {
    let dir = common::tmp_dir("gigabyte");
    let side = 4096usize;
    let colour = |i: usize| [(16 * i) as u8, 255 - (16 * i) as u8, (40 + 8 * i) as u8];
    let mut src = String::from(
        "[render]\nwidth = 64\nheight = 64\nspp = 1\nmax_depth = 1\n\
         [camera]\nprojection = \"orthographic\"\nheight = 4\n\
         look_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[textures]\n",
    );
    let mut objects = String::new();
    let mut materials = String::from("[materials]\n");
    for i in 0..16 {
        // a binary PPM: read fast, and 4 bytes a texel once loaded
        let mut ppm = format!("P6 {side} {side} 255\n").into_bytes();
        ppm.extend(colour(i).iter().copied().cycle().take(side * side * 3));
        std::fs::write(dir.join(format!("map{i}.ppm")), ppm).unwrap();
        src += &format!("t{i} = {{ type = \"image\", path = \"map{i}.ppm\" }}\n");
        materials += &format!("m{i} = {{ type = \"emissive\", radiance = \"t{i}\" }}\n");
        let (x, y) = ((i % 4) as f32 - 2.0, 1.0 - (i / 4) as f32);
        objects += &format!(
            "[[objects]]\ntype = \"polygon\"\nmaterial = \"m{i}\"\n\
             vertices = [[{x}, {y}, 0], [{}, {y}, 0], [{}, {}, 0], [{x}, {}, 0]]\n",
            x + 1.0,
            x + 1.0,
            y + 1.0,
            y + 1.0
        );
    }
    let src = src + &materials + &objects;
    let s = wgtrace::load_scene_str(&src, &dir.join("s.toml"), &Default::default())
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.texels.bytes(), 1 << 30, "sixteen 64 MiB pages");
    assert_eq!(s.texels.banks.len(), 1);
    let img = common::render_gpu(&s);
    for py in 0..64usize {
        for px in 0..64usize {
            let i = py / 16 * 4 + px / 16;
            let want = colour(i).map(|c| srgb_to_linear(c as f32 / 255.0));
            let got = img.mean(py * 64 + px);
            for c in 0..3 {
                assert!(
                    (got[c] - want[c]).abs() < 1e-5,
                    "pixel ({px}, {py}) of map {i}: {got:?}, not {want:?}"
                );
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Wrap modes apply per axis (u, then v); `filter = "nearest"` reads the texel the point
/// lies in; `uv_set = 1` reads the surface's second uv set.
#[test]
fn images_wrap_per_axis_filter_nearest_and_read_their_uv_set() {
    let dir = image_dir("axes");
    let s = scene(
        "a = { type = \"image\", path = \"2x2.png\", wrap = [\"clamp\", \"repeat\"] }\n\
         b = { type = \"image\", path = \"2x2.png\", filter = \"nearest\" }\n\
         c = { type = \"image\", path = \"2x2.png\", uv_set = 1 }",
        &dir,
    );
    let b = Bindings::new(&s, s.params(0, s.full_band()));
    let at = |t: u32, uv: [f32; 4]| texture_value(&b, t, Vec4::from(uv), Vec3::ZERO);
    let grey = Vec3::splat(srgb_to_linear(128.0 / 255.0));
    // u clamped: far left is the left column; v repeated: 1.75 is 0.75 (the top row)
    assert_close(at(0, [-3.0, 1.75, 0.0, 0.0]), Vec3::X);
    // u past the right edge clamps to the right column; v = -0.25 repeats to 0.75
    assert_close(at(0, [7.0, -0.25, 0.0, 0.0]), Vec3::ONE);
    // nearest: anywhere in a texel's square is that texel, no mix
    for (uv, want) in [
        ([0.01, 0.99], Vec3::X),
        ([0.49, 0.51], Vec3::X),
        ([0.51, 0.51], Vec3::ONE),
        ([0.99, 0.01], grey),
        ([0.3, 0.2], Vec3::ZERO),
    ] {
        assert_close(at(1, [uv[0], uv[1], 0.0, 0.0]), want);
    }
    // uv_set = 1 reads .zw: the bottom-right texel's centre there, whatever .xy holds
    assert_close(at(2, [0.25, 0.75, 0.75, 0.25]), grey);
    assert_close(at(2, [0.75, 0.25, 0.25, 0.75]), Vec3::X);
    let invalid = wgtrace::load_scene_str(
        "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[textures]\n\
         t = { type = \"image\", path = \"2x2.png\", uv_set = 2 }\n",
        &dir.join("t.toml"),
        &Default::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        invalid.contains("textures.t.uv_set: must be 0 or 1, got 2"),
        "{invalid}"
    );
    let bad_wrap = wgtrace::load_scene_str(
        "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[textures]\n\
         t = { type = \"image\", path = \"2x2.png\", wrap = [\"clamp\", \"sideways\"] }\n",
        &dir.join("t.toml"),
        &Default::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        bad_wrap.contains("t.toml:5:") && bad_wrap.contains("unknown variant `sideways`"),
        "{bad_wrap}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// An image's `transform = { matrix = ... }` (Mitsuba's `to_uv`) maps uv by any affine map
/// before the look-up, shear included, and equals the offset, rotation and scale it can
/// spell; giving both, or a non-finite entry, is an error naming the key.
#[test]
fn an_image_reads_uv_through_its_affine_matrix() {
    let dir = image_dir("matrix");
    let s = scene(
        "a = { type = \"image\", path = \"2x2.png\", transform = { matrix = [[0.5, 0.25, 0.125], [0, 1, -0.5]] } }\n\
         b = { type = \"image\", path = \"2x2.png\", transform = { matrix = [[0, -2, 0.5], [2, 0, 0]] } }\n\
         c = { type = \"image\", path = \"2x2.png\", transform = { rotation = 90, scale = [2, 2], offset = [0.5, 0] } }\n\
         plain = { type = \"image\", path = \"2x2.png\" }",
        &dir,
    );
    // names in order: a = 0, b = 1, c = 2, plain = 3
    for uv in [[0.1f32, 0.2], [0.7, 0.4], [0.33, 0.9]] {
        let [u, v] = uv;
        let sheared = [0.5 * u + 0.25 * v + 0.125, v - 0.5];
        assert_close(value(&s, 0, uv, [0.0; 3]), value(&s, 3, sheared, [0.0; 3]));
        // b's matrix is c's offset + R(90) (2 uv)
        assert_close(value(&s, 1, uv, [0.0; 3]), value(&s, 2, uv, [0.0; 3]));
    }
    let err = |t: &str| {
        let src =
            format!("[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[textures]\n{t}\n");
        wgtrace::load_scene_str(&src, &dir.join("bad.toml"), &Default::default())
            .unwrap_err()
            .to_string()
    };
    let e = err("i = { type = \"image\", path = \"2x2.png\", transform = { matrix = [[1, 0, 0], [0, 1, 0]], scale = [2, 2] } }");
    assert!(
        e.contains("bad.toml:5:") && e.contains("textures.i.transform.matrix: replaces offset"),
        "{e}"
    );
    let e = err("i = { type = \"image\", path = \"2x2.png\", transform = { matrix = [[1, 0, 0], [0, nan, 0]] } }");
    assert!(e.contains("textures.i.transform: must be finite"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// An opacity mask's mistakes, each named by its file, line and key: a value outside [0,
/// 1], a texture that does not exist, and a mask on a material that emits (a light cannot
/// be masked); the emissive type has no `opacity` at all.
#[test]
fn opacity_masks_are_validated() {
    let err = |t: &str, m: &str| {
        let src = format!("[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[textures]\n{t}\n[materials]\n{m}\n");
        wgtrace::load_scene_str(&src, Path::new("bad.toml"), &Default::default())
            .unwrap_err()
            .to_string()
    };
    let e = err(
        "",
        "m = { type = \"lambertian\", albedo = [0.5, 0.5, 0.5], opacity = 1.5 }",
    );
    assert!(
        e.contains("bad.toml:7:") && e.contains("materials.m.opacity: must be in [0, 1]"),
        "{e}"
    );
    let e = err("", "m = { type = \"conductor\", opacity = \"leaves\" }");
    assert!(
        e.contains("materials.m.opacity: unknown texture \"leaves\""),
        "{e}"
    );
    let e = err(
        "",
        "m = { type = \"lambertian\", albedo = [0.5, 0.5, 0.5], emission = [1, 1, 1], opacity = 0.5 }",
    );
    assert!(
        e.contains("bad.toml:7:") && e.contains("materials.m.opacity: a light cannot be masked"),
        "{e}"
    );
    let e = err(
        "",
        "m = { type = \"emissive\", radiance = [1, 1, 1], opacity = 0.5 }",
    );
    assert!(e.contains("bad.toml:7:") && e.contains("opacity"), "{e}");
}

/// A Portable FloatMap reads as linear float texels, top row first (the file stores the
/// bottom row first), in either byte order (a negative scale: little-endian), grey or RGB,
/// of an odd height too; a short or malformed file is an error saying what is wrong.
#[test]
fn pfm_images_read_top_row_first_in_either_byte_order() {
    use wgtrace::scene::textures::{image_size, load_image};
    let dir = image_dir("pfm");
    // 2 x 3 texels, the file's rows bottom first: the value of (x, y from the top) is
    // 10 y + x (+ 0.25, 0.5 in g and b)
    let pfm = |kind: &str, little: bool| {
        let grey = kind == "Pf";
        let mut bytes =
            format!("{kind}\n2 3\n{}\n", if little { "-1.0" } else { "1.0" }).into_bytes();
        for y in (0..3).rev() {
            for x in 0..2 {
                let v = 10.0 * y as f32 + x as f32;
                let texel: &[f32] = if grey { &[v] } else { &[v, v + 0.25, v + 0.5] };
                for f in texel {
                    bytes.extend(if little {
                        f.to_le_bytes()
                    } else {
                        f.to_be_bytes()
                    });
                }
            }
        }
        bytes
    };
    for (kind, little) in [("PF", true), ("PF", false), ("Pf", true)] {
        let path = dir.join(format!("{kind}-{little}.pfm"));
        std::fs::write(&path, pfm(kind, little)).unwrap();
        assert_eq!(image_size(&path), Ok((2, 3)));
        let img = load_image(&path, true).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((img.width, img.height), (2, 3));
        for y in 0..3 {
            for x in 0..2 {
                let v = 10.0 * y as f32 + x as f32;
                let want = if kind == "Pf" {
                    [v, v, v, 1.0]
                } else {
                    [v, v + 0.25, v + 0.5, 1.0]
                };
                assert_eq!(
                    img.texel(y * 2 + x),
                    want,
                    "{kind} little-endian {little}: ({x}, {y})"
                );
            }
        }
    }
    let short = pfm("PF", true);
    for (bytes, why) in [
        (
            short[..short.len() - 4].to_vec(),
            "PFM data is 68 bytes, 72 expected",
        ),
        (b"P6\n2 3\n255\n".to_vec(), "not a PFM file"),
        (
            b"PF\n2 x\n-1\n".to_vec(),
            "PFM size 2 x x: not two positive integers",
        ),
        (
            b"PF\n2 3\n0\n".to_vec(),
            "PFM scale \"0\": not a non-zero number",
        ),
    ] {
        let path = dir.join("bad.pfm");
        std::fs::write(&path, bytes).unwrap();
        let e = load_image(&path, false).unwrap_err();
        assert!(e.contains(why), "{e}");
    }
}

/// A Radiance HDR file signed `#?RGBE` (as Mitsuba writes one) reads as the same file signed
/// `#?RADIANCE`, the one signature the image crate's decoder takes; its size too.
#[test]
fn hdr_files_signed_rgbe_read_as_radiance_ones() {
    use wgtrace::scene::textures::{image_size, load_image};
    let dir = image_dir("rgbe");
    let texels: Vec<image::Rgb<f32>> = (0..6)
        .map(|k| image::Rgb([k as f32, 0.5, 2.0 + k as f32]))
        .collect();
    let mut bytes = Vec::new();
    image::codecs::hdr::HdrEncoder::new(&mut bytes)
        .encode(&texels, 3, 2)
        .unwrap();
    assert!(bytes.starts_with(b"#?RADIANCE\n"));
    let radiance = dir.join("radiance.hdr");
    std::fs::write(&radiance, &bytes).unwrap();
    let rgbe = dir.join("rgbe.hdr");
    std::fs::write(
        &rgbe,
        [b"#?RGBE".as_slice(), &bytes[b"#?RADIANCE".len()..]].concat(),
    )
    .unwrap();
    let (a, b) = (
        load_image(&radiance, false).unwrap(),
        load_image(&rgbe, false).unwrap(),
    );
    assert_eq!((b.width, b.height, &b.data), (3, 2, &a.data));
    assert_eq!(image_size(&rgbe), Ok((3, 2)));
}
