//! AOVs (albedo, normal, depth, position, variance) on both backends, through
//! checkpoints, resume and merge and into EXR layers; and the adapter a cluster assigns.
//! Denoising and the Python module are tested by python/tests (tests/python.rs runs them).

mod common;

use std::path::Path;

use wgtrace::aov::Aov;
use wgtrace::gpu::select::{assigned, by_argument, format_uuid, parse_uuid, AdapterFacts};
use wgtrace::{Accumulation, FlatScene, Overrides};

/// The Cornell box (tests read scenes/cornell.toml: camera at z = 3.9 looking down -z,
/// vfov 39.3, back wall at z = -1) at `size` x `size`, summing the AOVs.
fn cornell(size: u32, spp: u32) -> FlatScene {
    let mut scene = wgtrace::load_scene(
        &common::repo_path("scenes/cornell.toml"),
        &Overrides {
            width: Some(size),
            height: Some(size),
            spp: Some(spp),
            ..Default::default()
        },
    )
    .unwrap();
    scene.aovs = true;
    scene
}

/// Pixel (x, y)'s values of `aov`.
fn at(acc: &Accumulation, aov: Aov, x: u32, y: u32) -> Vec<f32> {
    let k = aov.channels().len();
    let i = (y * acc.width + x) as usize;
    aov.values(acc)[k * i..k * (i + 1)].to_vec()
}

/// The distances from the Cornell camera to the back wall along the rays through the
/// corners of pixel (x, y): the depth of a pixel that sees only the wall lies between.
fn back_wall_depth_bounds(size: u32, x: u32, y: u32) -> (f32, f32) {
    let tan = (39.3f32.to_radians() / 2.0).tan();
    let mut d = Vec::new();
    for (cx, cy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
        let s = (x as f32 + cx) / size as f32;
        let t = (y as f32 + cy) / size as f32;
        let (u, v) = ((2.0 * s - 1.0) * tan, (1.0 - 2.0 * t) * tan);
        // a ray of forward component 1 reaches z = -1 after 4.9 of it
        d.push(4.9 * (1.0 + u * u + v * v).sqrt());
    }
    let lo = d.iter().copied().fold(f32::MAX, f32::min);
    let hi = d.iter().copied().fold(f32::MIN, f32::max);
    (lo * (1.0 - 1e-5), hi * (1.0 + 1e-5))
}

fn close(a: &[f32], b: &[f32], tol: f32) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

/// The issue's check on both backends: a wall's albedo is its reflectance, the back
/// wall's normal is +z and the left wall's +x, depth is the distance along the camera
/// ray, position the point on the wall. A Lambertian wall's albedo is f cos / pdf of a
/// cosine-sampled bounce, the reflectance in every sample, so only rounding is allowed.
#[test]
fn the_cornell_box_aovs_are_its_walls() {
    let size = 32;
    let scene = cornell(size, 16);
    for (name, acc) in [
        ("gpu", common::render_gpu(&scene)),
        ("cpu", common::render_cpu(&scene)),
    ] {
        assert!(acc.aovs, "{name}: the sums hold AOVs");
        // the back wall, at the centre
        let (x, y) = (size / 2, size / 2);
        let albedo = at(&acc, Aov::Albedo, x, y);
        assert!(
            close(&albedo, &[0.73; 3], 1e-5),
            "{name}: back wall albedo {albedo:?}"
        );
        let normal = at(&acc, Aov::Normal, x, y);
        assert!(
            close(&normal, &[0.0, 0.0, 1.0], 1e-6),
            "{name}: back wall normal {normal:?}"
        );
        let depth = at(&acc, Aov::Depth, x, y)[0];
        let (lo, hi) = back_wall_depth_bounds(size, x, y);
        assert!(
            lo <= depth && depth <= hi,
            "{name}: depth {depth} not in {lo}..{hi}"
        );
        let p = at(&acc, Aov::Position, x, y);
        assert!(
            (p[2] + 1.0).abs() < 1e-5 && p[0].abs() < 0.11 && p[1].abs() < 0.11,
            "{name}: position {p:?}"
        );
        // the left wall, near the left edge (the first two columns see past its front
        // edge)
        let albedo = at(&acc, Aov::Albedo, 2, y);
        assert!(
            close(&albedo, &[0.65, 0.05, 0.05], 1e-5),
            "{name}: left wall albedo {albedo:?}"
        );
        let normal = at(&acc, Aov::Normal, 2, y);
        assert!(
            close(&normal, &[1.0, 0.0, 0.0], 1e-6),
            "{name}: left wall normal {normal:?}"
        );
        assert!((at(&acc, Aov::Position, 2, y)[0] + 1.0).abs() < 1e-5);
        // the variance is the colour's own: a sample's variance over the samples
        let i = (y * size + x) as usize;
        let var = at(&acc, Aov::Variance, x, y);
        let expected = acc.variance(i).map(|v| v / acc.samples(i));
        assert_eq!(var, expected.to_vec(), "{name}");
        assert!(
            var.iter().all(|v| *v > 0.0),
            "{name}: a lit wall is noisy at 16 spp"
        );
    }
}

/// Summing the AOVs leaves the colour as it was, bit for bit, on both backends.
#[test]
fn aovs_leave_the_colour_bit_for_bit() {
    let with = cornell(24, 8);
    let mut without = with.clone();
    without.aovs = false;
    for (name, a, b) in [
        (
            "gpu",
            common::render_gpu(&with),
            common::render_gpu(&without),
        ),
        (
            "cpu",
            common::render_cpu(&with),
            common::render_cpu(&without),
        ),
    ] {
        assert_eq!(a.to_rgb(), b.to_rgb(), "{name}");
        assert_eq!(a.non_finite(), b.non_finite());
    }
}

/// Through a perfect mirror the albedo and normal are those of the wall it shows (the
/// first vertex that is not a delta bounce), the depth is the mirror's.
const MIRROR: &str = r#"
[render]
width = 16
height = 16
spp = 8
max_depth = 4

[camera]
look_from = [0, 0, 0]
look_at = [0, 0, -1]
up = [0, 1, 0]
vfov = 20

[materials]
mirror = { type = "metal", albedo = [0.9, 0.9, 0.9], fuzz = 0 }
red = { type = "lambertian", albedo = [0.6, 0.1, 0.2] }
lamp = { type = "emissive", radiance = [1, 1, 1] }

[[objects]]  # the mirror, facing the camera
type = "polygon"
vertices = [[-5, -5, -2], [5, -5, -2], [5, 5, -2], [-5, 5, -2]]
material = "mirror"

[[objects]]  # a red wall behind the camera, facing the mirror
type = "polygon"
vertices = [[-5, -5, 2], [-5, 5, 2], [5, 5, 2], [5, -5, 2]]
material = "red"

[[objects]]
type = "sphere"
center = [0, 4, 0]
radius = 0.5
material = "lamp"
"#;

#[test]
fn a_mirror_shows_the_albedo_and_normal_of_what_it_reflects() {
    let mut scene = common::scene_from_str(MIRROR);
    scene.aovs = true;
    for (name, acc) in [
        ("gpu", common::render_gpu(&scene)),
        ("cpu", common::render_cpu(&scene)),
    ] {
        for (x, y) in [(8, 8), (3, 12)] {
            let albedo = at(&acc, Aov::Albedo, x, y);
            assert!(close(&albedo, &[0.6, 0.1, 0.2], 1e-5), "{name}: {albedo:?}");
            let normal = at(&acc, Aov::Normal, x, y);
            assert!(
                close(&normal, &[0.0, 0.0, -1.0], 1e-6),
                "{name}: {normal:?}"
            );
            let depth = at(&acc, Aov::Depth, x, y)[0];
            assert!(
                (2.0..2.1).contains(&depth),
                "{name}: the mirror is 2 away, got {depth}"
            );
        }
    }
}

/// Runs wgtrace with `args`; its stdout and stderr.
fn run<S: AsRef<str>>(args: &[S]) -> String {
    let args: Vec<&str> = args.iter().map(AsRef::as_ref).collect();
    let out = common::wgtrace(&args);
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "wgtrace {args:?} failed:\n{text}");
    text
}

/// Runs wgtrace with `args`, which must fail; its stderr.
fn fails<S: AsRef<str>>(args: &[S]) -> String {
    let args: Vec<&str> = args.iter().map(AsRef::as_ref).collect();
    let out = common::wgtrace(&args);
    assert!(!out.status.success(), "wgtrace {args:?} should fail");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// `wgtrace render` of the Cornell box at `size` x `size`, then `extra`.
fn render_cornell(size: u32, extra: &[&str]) -> Vec<String> {
    let scene = common::repo_path("scenes/cornell.toml");
    let size = size.to_string();
    let base = [
        "render",
        &scene.display().to_string(),
        "--width",
        &size,
        "--height",
        &size,
        "-q",
    ]
    .map(String::from);
    base.into_iter()
        .chain(extra.iter().map(|s| s.to_string()))
        .collect()
}

fn channels(path: &Path) -> Vec<(String, Vec<f32>)> {
    wgtrace::image_io::read_exr(path)
        .unwrap_or_else(|e| panic!("{e}"))
        .channels
}

/// The CLI writes the AOVs as named EXR layers; a checkpoint carries their sums, so a
/// resumed render equals an uninterrupted one bit for bit, and ranges rendered apart
/// merge into the same AOVs up to the order of the additions.
#[test]
fn aovs_travel_through_checkpoints_resume_and_merge() {
    let dir = common::tmp_dir("aov-checkpoints");
    let p = |n: &str| dir.join(n).display().to_string();
    let all = "albedo,normal,depth,position,variance";
    let render = |extra: &[&str]| run(&render_cornell(24, extra));
    render(&["--spp", "8", "--aov", all, "-o", &p("whole.exr")]);
    // stopped at 4 (a checkpoint at the end), then resumed to 8
    render(&[
        "--spp",
        "4",
        "--aov",
        "depth",
        "--checkpoint",
        &p("part.ckpt"),
        "-o",
        &p("part.exr"),
    ]);
    render(&[
        "--spp",
        "8",
        "--aov",
        all,
        "--resume",
        &p("part.ckpt"),
        "-o",
        &p("resumed.exr"),
    ]);
    // two ranges, merged
    for (range, name) in [("0..3", "a"), ("3..8", "b")] {
        let ckpt = p(&format!("{name}.ckpt"));
        let exr = p(&format!("{name}.exr"));
        render(&[
            "--spp",
            "8",
            "--aov",
            "albedo",
            "--sample-range",
            range,
            "--checkpoint",
            &ckpt,
            "-o",
            &exr,
        ]);
    }
    run(&[
        "merge",
        &p("a.ckpt"),
        &p("b.ckpt"),
        "--aov",
        all,
        "-o",
        &p("merged.exr"),
    ]);

    let whole = channels(&dir.join("whole.exr"));
    let names: Vec<&str> = whole.iter().map(|(n, _)| n.as_str()).collect();
    for name in [
        "R",
        "G",
        "B",
        "albedo.R",
        "albedo.G",
        "albedo.B",
        "normal.X",
        "normal.Y",
        "normal.Z",
        "depth.Z",
        "position.X",
        "position.Y",
        "position.Z",
        "variance.R",
        "variance.G",
        "variance.B",
    ] {
        assert!(names.contains(&name), "no {name} in {names:?}");
    }
    assert_eq!(names.len(), 16, "{names:?}");
    assert_eq!(
        channels(&dir.join("resumed.exr")),
        whole,
        "resumed != uninterrupted"
    );
    let merged = channels(&dir.join("merged.exr"));
    for ((n, a), (m, b)) in whole.iter().zip(&merged) {
        assert_eq!(n, m);
        let scale = a.iter().fold(1.0f32, |s, x| s.max(x.abs()));
        // sums of 8 samples added in another order: a few ulps of the largest value
        assert!(
            close(a, b, scale * 4e-6),
            "{n}: merged differs from the whole render"
        );
    }
}

#[test]
fn aovs_are_refused_where_they_cannot_be_kept() {
    let dir = common::tmp_dir("aov-refusals");
    let p = |n: &str| dir.join(n).display().to_string();
    let refused = |extra: &[&str]| fails(&render_cornell(8, extra));
    let e = refused(&["--aov", "albedo", "-o", &p("x.png")]);
    assert!(
        e.contains("x.png") && e.contains("only an EXR file holds AOVs"),
        "{e}"
    );
    let e = refused(&["--aov", "albedo,shadow", "-o", &p("x.exr")]);
    assert!(
        e.contains("unknown AOV \"shadow\"") && e.contains("albedo, normal, depth"),
        "{e}"
    );
    // a checkpoint without the AOVs' sums cannot give them to the samples it holds
    run(&render_cornell(
        8,
        &[
            "--spp",
            "2",
            "--checkpoint",
            &p("plain.ckpt"),
            "-o",
            &p("plain.exr"),
        ],
    ));
    let e = refused(&[
        "--spp",
        "4",
        "--aov",
        "depth",
        "--resume",
        &p("plain.ckpt"),
        "-o",
        &p("y.exr"),
    ]);
    assert!(
        e.contains("plain.ckpt") && e.contains("holds no AOV sums"),
        "{e}"
    );
    let e = fails(&[
        "merge",
        &p("plain.ckpt"),
        "--aov",
        "normal",
        "-o",
        &p("m.exr"),
    ]);
    assert!(e.contains("holds no AOV sums"), "{e}");
}

/// A 4-GPU node as Vulkan lists it (not in PCI order), and llvmpipe.
fn node() -> Vec<AdapterFacts> {
    let gpu = |bus: &str, u: u8| AdapterFacts {
        name: "NVIDIA H100 80GB HBM3".into(),
        vendor: 0x10de,
        pci_bus_id: bus.into(),
        uuid: Some([u; 16]),
    };
    vec![
        gpu("0000:c1:00.0", 0xc1),
        gpu("0000:41:00.0", 0x41),
        gpu("0000:81:00.0", 0x81),
        gpu("0000:01:00.0", 0x01),
        AdapterFacts {
            name: "llvmpipe (LLVM 15.0.6, 256 bits)".into(),
            vendor: 0x10005,
            pci_bus_id: String::new(),
            uuid: Some([7; 16]),
        },
    ]
}

fn env<'a>(pairs: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
    move |name| {
        pairs
            .iter()
            .find(|(k, _)| *k == name)
            .map(|(_, v)| v.to_string())
    }
}

#[test]
fn a_scheduler_s_gpu_is_the_adapter_chosen() {
    let node = node();
    let pick = |pairs: &[(&str, &str)]| assigned(&env(pairs), &node);
    // indices count the vendor's GPUs in PCI bus order
    for (k, bus) in [
        ("0", "0000:01"),
        ("1", "0000:41"),
        ("2", "0000:81"),
        ("3", "0000:c1"),
    ] {
        let s = pick(&[("CUDA_VISIBLE_DEVICES", k)]).unwrap().unwrap();
        assert!(node[s.index].pci_bus_id.starts_with(bus), "{k}: {:?}", s);
        assert!(s.reason.unwrap().contains(bus));
    }
    // the first of a list; a UUID by Vulkan's device UUID
    let s = pick(&[("CUDA_VISIBLE_DEVICES", "2,3")]).unwrap().unwrap();
    assert_eq!(node[s.index].pci_bus_id, "0000:81:00.0");
    let uuid = format_uuid([0x41; 16]);
    assert_eq!(parse_uuid(&uuid), Some([0x41; 16]));
    let s = pick(&[("CUDA_VISIBLE_DEVICES", &uuid)]).unwrap().unwrap();
    assert_eq!(node[s.index].pci_bus_id, "0000:41:00.0");
    // nothing assigned: the default
    assert_eq!(pick(&[]).unwrap(), None);
    assert_eq!(pick(&[("CUDA_VISIBLE_DEVICES", "")]).unwrap(), None);
    assert_eq!(
        pick(&[("CUDA_VISIBLE_DEVICES", "NoDevFiles")]).unwrap(),
        None
    );
    // a device no adapter is: refused with the reason
    let e = pick(&[("CUDA_VISIBLE_DEVICES", "4")]).unwrap_err();
    assert!(
        e.contains("CUDA_VISIBLE_DEVICES=4") && e.contains("4 NVIDIA GPUs"),
        "{e}"
    );
    let e = pick(&[("CUDA_VISIBLE_DEVICES", &format_uuid([9; 16]))]).unwrap_err();
    assert!(e.contains("no Vulkan adapter has the UUID"), "{e}");
    let e = pick(&[("CUDA_VISIBLE_DEVICES", "GPU-x")]).unwrap_err();
    assert!(e.contains("neither a GPU index nor a GPU UUID"), "{e}");
    // a MIG instance: Vulkan cannot render on one
    let s = pick(&[("CUDA_VISIBLE_DEVICES", "MIG-3f1e")])
        .unwrap()
        .unwrap();
    assert!(s.index == 0 && s.reason.unwrap().contains("MIG instance"));
    // AMD's variables where Vulkan sees no AMD GPU: the default, with a note
    let amd = |bus: &str| AdapterFacts {
        name: "AMD Instinct MI250X".into(),
        vendor: 0x1002,
        pci_bus_id: bus.into(),
        uuid: None,
    };
    let amd_node = [
        amd("0000:c1:00.0"),
        amd("0000:01:00.0"),
        amd("0000:41:00.0"),
    ];
    let on_amd = |pairs: &[(&str, &str)]| {
        let s = assigned(&env(pairs), &amd_node).unwrap().unwrap();
        amd_node[s.index].pci_bus_id.clone()
    };
    assert_eq!(on_amd(&[("ROCR_VISIBLE_DEVICES", "1")]), "0000:41:00.0");
    assert_eq!(on_amd(&[("HIP_VISIBLE_DEVICES", "2")]), "0000:c1:00.0");
    // HIP's index counts among the devices ROCR leaves visible: ROCR's second, GPU 0
    assert_eq!(
        on_amd(&[
            ("ROCR_VISIBLE_DEVICES", "2,0"),
            ("HIP_VISIBLE_DEVICES", "1")
        ]),
        "0000:01:00.0"
    );
    let s = pick(&[("ROCR_VISIBLE_DEVICES", "0")]).unwrap().unwrap();
    assert_eq!(s.index, 0);
    assert!(s.reason.unwrap().contains("Vulkan sees none"));
    // --adapter: an index, or part of a name
    assert_eq!(by_argument("4", &node).unwrap().index, 4);
    assert_eq!(by_argument("LLVMpipe", &node).unwrap().index, 4);
    assert!(by_argument("5", &node).unwrap_err().contains("there are 5"));
    assert!(by_argument("radeon", &node)
        .unwrap_err()
        .contains("names no Vulkan adapter"));
}

/// On this machine: `--adapter` by name renders; a name no adapter has fails naming the
/// adapters; CUDA_VISIBLE_DEVICES without an NVIDIA adapter renders on the default with
/// a note.
#[test]
fn the_cli_chooses_its_adapter() {
    let dir = common::tmp_dir("aov-adapter");
    let out = dir.join("a.png").display().to_string();
    let args = |extra: &[&str]| {
        let mut a = render_cornell(8, &["--spp", "1", "-o", &out]);
        a.retain(|s| s != "-q");
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    let name = wgtrace::gpu::list_adapters()
        .first()
        .map(|a| a.name.clone())
        .expect("GPU tests need a Vulkan adapter");
    let word = name.split_whitespace().next().unwrap().to_string();
    let text = run(&args(&["--adapter", &word]));
    assert!(text.contains(&word), "{text}");
    let e = fails(&args(&["--adapter", "no-such-gpu"]));
    assert!(e.contains("no-such-gpu") && e.contains(&name), "{e}");
    let facts = wgtrace::gpu::context::adapter_facts();
    if !facts.iter().any(|f| f.vendor == 0x10de) {
        let cmd = std::process::Command::new(env!("CARGO_BIN_EXE_wgtrace"))
            .args(args(&[]))
            .env("CUDA_VISIBLE_DEVICES", "1")
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&cmd.stderr);
        assert!(
            cmd.status.success()
                && e.contains("CUDA_VISIBLE_DEVICES=1")
                && e.contains("Vulkan sees none"),
            "{e}"
        );
    }
}

/// The backends trace the same paths with the same random numbers, so their AOVs agree
/// pixel by pixel wherever rounding does not send a path another way: under the mixture
/// strategy (whose albedo is f / pdf of the mixture), an image background seen through
/// glass (the background's albedo), pbr, and a normal-mapped glTF model.
#[test]
fn both_backends_give_the_same_aovs() {
    use wgtrace::scene::format::LightSampling;
    let cases = [
        ("scenes/cornell.toml", Some(LightSampling::Mixture)),
        ("scenes/sky.toml", None),
        ("scenes/pbr.toml", None),
        ("scenes/gltf/brick.glb", None),
        ("scenes/smoke.toml", None),
    ];
    for (file, light_sampling) in cases {
        let mut scene = wgtrace::load_scene(
            &common::repo_path(file),
            &Overrides {
                width: Some(32),
                height: Some(24),
                spp: Some(4),
                light_sampling,
                ..Default::default()
            },
        )
        .unwrap();
        scene.aovs = true;
        let (gpu, cpu) = (common::render_gpu(&scene), common::render_cpu(&scene));
        for aov in [Aov::Albedo, Aov::Normal, Aov::Depth, Aov::Position] {
            let k = aov.channels().len();
            let (g, c) = (aov.values(&gpu), aov.values(&cpu));
            let differ = g
                .chunks(k)
                .zip(c.chunks(k))
                .filter(|(a, b)| {
                    let scale = b.iter().fold(1.0f32, |s, x| s.max(x.abs()));
                    !close(a, b, 1e-3 * scale)
                })
                .count();
            println!("{file} {aov}: {differ} of {} pixels differ", g.len() / k);
            assert!(
                differ * 50 <= g.len() / k,
                "{file} {aov}: {differ} of {} pixels differ",
                g.len() / k
            );
        }
    }
}

/// A camera inside a dense medium (sigma_t 50, albedo (0.2, 0.5, 0.8)) and nothing else:
/// every path's first vertex is a point where it scatters, whose albedo is the medium's,
/// whose normal faces the camera ray, and whose depth is exponential with mean 1 / 50
/// (the image's mean depth within 5 standard errors of it), on both backends.
#[test]
fn a_first_vertex_in_a_medium_gives_the_medium_s_albedo_and_its_distance() {
    let src = r#"
[render]
width = 16
height = 16
spp = 64
[camera]
look_from = [0, 0, 0]
look_at = [0, 0, -1]
vfov = 20
medium = "ink"
[media.ink]
type = "homogeneous"
sigma_t = 50
albedo = [0.2, 0.5, 0.8]
[materials]
white = { type = "lambertian", albedo = [1, 1, 1] }
[[objects]]
type = "sphere"
center = [0, 0, -100]
radius = 1
material = "white"
"#;
    let mut scene = common::scene_from_str(src);
    scene.aovs = true;
    for (name, acc) in [
        ("gpu", common::render_gpu(&scene)),
        ("cpu", common::render_cpu(&scene)),
    ] {
        let albedo = Aov::Albedo.values(&acc);
        let normal = Aov::Normal.values(&acc);
        let depth = Aov::Depth.values(&acc);
        for px in albedo.chunks(3) {
            assert!(close(px, &[0.2, 0.5, 0.8], 1e-6), "{name}: albedo {px:?}");
        }
        // the rays of a 20 degree view run within 15 degrees of -z
        for n in normal.chunks(3) {
            assert!(
                n[2] > 0.96,
                "{name}: normal {n:?} does not face the camera ray"
            );
        }
        let n = (16 * 16 * 64) as f64;
        let mean = depth.iter().map(|&d| d as f64).sum::<f64>() / depth.len() as f64;
        // the exponential's standard deviation is its mean
        let se = 0.02 / n.sqrt();
        assert!(
            (mean - 0.02).abs() < 5.0 * se,
            "{name}: mean depth {mean}, 0.02 expected (se {se})"
        );
    }
}

/// A checkpoint written before AOVs existed (no `aovs` line) still reads, without them;
/// one with them reads back whole.
#[test]
fn checkpoints_say_whether_they_hold_aovs() {
    use wgtrace::checkpoint::Checkpoint;
    let scene = cornell(4, 2);
    let mut acc = Accumulation::zeros(4, 4, false);
    acc.data[0] = [1.0, 2.0, 3.0, 2.0];
    let old = Checkpoint::new(&scene, 0..2, acc).to_bytes();
    let line = b"aovs = no\n";
    let at = old
        .windows(line.len())
        .position(|w| w == line)
        .expect("the header says aovs = no");
    let stripped: Vec<u8> = [&old[..at], &old[at + line.len()..]].concat();
    let read = Checkpoint::from_bytes(&stripped, Path::new("old.ckpt")).unwrap();
    assert!(!read.accumulation.aovs && read.accumulation.data[0] == [1.0, 2.0, 3.0, 2.0]);
    let mut with = Accumulation::zeros(4, 4, true);
    with.data[4] = [0.5; 4];
    let bytes = Checkpoint::new(&scene, 0..2, with.clone()).to_bytes();
    let back = Checkpoint::from_bytes(&bytes, Path::new("new.ckpt")).unwrap();
    assert_eq!(back.accumulation, with);
    // the sums' length follows the header: AOV sums cut off are refused
    let e = Checkpoint::from_bytes(&bytes[..bytes.len() - 16], Path::new("cut.ckpt"));
    assert!(e.unwrap_err().to_string().contains("truncated"));
}
