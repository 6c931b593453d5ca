//! Helpers shared by the integration tests.
#![allow(dead_code)]
// The quantile coefficients are quoted as published.
#![allow(clippy::excessive_precision)]

use std::path::{Path, PathBuf};

use wgtrace::{Accumulation, Engine, FlatScene, Overrides, Session, SessionOptions, StopRule};

/// Opens the GPU backend or fails the test: GPU tests never skip.
pub fn gpu_engine(scene: &FlatScene) -> Engine {
    match Engine::gpu(scene, 0) {
        Ok(e) => e,
        // GpuError::NoAdapter already says how to install lavapipe.
        Err(e) => panic!("GPU tests need a Vulkan adapter: {e}"),
    }
}

/// Opens the first Vulkan adapter or fails the test.
pub fn gpu_context() -> wgtrace::gpu::GpuContext {
    wgtrace::gpu::GpuContext::new(0)
        .unwrap_or_else(|e| panic!("GPU tests need a Vulkan adapter: {e}"))
}

/// Renders all passes of `scene` on `engine` in a session and returns the sums.
pub fn render(engine: Engine, scene: &FlatScene) -> Accumulation {
    let mut session =
        Session::with_engine(scene.clone(), engine, SessionOptions::default()).expect("session");
    let acc = session
        .run(&StopRule::default(), |_| {})
        .expect("render")
        .accumulation;
    // the renderer drops and counts samples that are not finite: every test render has none
    assert_eq!(
        acc.non_finite(),
        0,
        "{} non-finite samples",
        acc.non_finite()
    );
    acc
}

pub fn render_gpu(scene: &FlatScene) -> Accumulation {
    render(gpu_engine(scene), scene)
}

/// Renders `scene` on the GPU under the tuning knobs `knobs` (`--tune`'s list).
pub fn render_gpu_tuned(scene: &FlatScene, knobs: &str) -> Accumulation {
    let tuning = wgtrace::Tuning::parse(knobs).unwrap();
    let engine = Engine::gpu_tuned(scene, 0, &tuning)
        .unwrap_or_else(|e| panic!("GPU tests need a Vulkan adapter: {e}"));
    render(engine, scene)
}

pub fn render_cpu(scene: &FlatScene) -> Accumulation {
    render(Engine::cpu(scene), scene)
}

/// Parses scene text (named `test.toml` in errors).
pub fn scene_from_str(src: &str) -> FlatScene {
    wgtrace::load_scene_str(src, Path::new("test.toml"), &Overrides::default())
        .unwrap_or_else(|e| panic!("{e}"))
}

/// Parses scene text with every primitive tested on every ray (no BVH).
pub fn scene_without_bvh(src: &str) -> FlatScene {
    let tuning = wgtrace::Tuning::parse("no-bvh").unwrap();
    wgtrace::scene::load_str(
        src,
        Path::new("test.toml"),
        &Overrides::default(),
        tuning.build(),
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

/// Loads a scene file under the tuning knobs `knobs` (`--tune`'s list).
pub fn load_tuned(path: &Path, overrides: &Overrides, knobs: &str) -> FlatScene {
    let tuning = wgtrace::Tuning::parse(knobs).unwrap();
    wgtrace::scene::load(path, overrides, tuning.build()).unwrap_or_else(|e| panic!("{e}"))
}

/// Parses scene text as if it were the file `rel` of the repository (mesh paths resolve
/// against its folder).
pub fn scene_from_file_str(src: &str, rel: &str) -> FlatScene {
    wgtrace::load_scene_str(src, &repo_path(rel), &Overrides::default())
        .unwrap_or_else(|e| panic!("{e}"))
}

/// A uniform f32 in [0, 1) from a xorshift state (tests need no rand crate).
pub fn random_f32(state: &mut u32) -> f32 {
    *state ^= *state << 13;
    *state ^= *state >> 17;
    *state ^= *state << 5;
    (*state >> 8) as f32 / (1u32 << 24) as f32
}

/// A uniform direction on the unit sphere.
pub fn random_unit(state: &mut u32) -> glam::Vec3 {
    let z = 2.0 * random_f32(state) - 1.0;
    let phi = 2.0 * std::f32::consts::PI * random_f32(state);
    let r = (1.0 - z * z).max(0.0).sqrt();
    glam::Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

pub fn repo_path(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// The showcase scene: every primitive, material and texture kind at once, so nearly the
/// full shader. Mesa 25's llvmpipe (LLVM 15) compiles its shader cold in over 28 minutes
/// on 2 cores (Mesa 22's in 91 s), so the GPU tests that render every scene give it a test
/// of its own, which CI's second-driver pass leaves to the first (.ci/run).
pub const SHOWCASE: &str = "scenes/showcase.toml";

/// Every scene file in `scenes/` but the [`SHOWCASE`].
pub fn scene_files_but_showcase() -> Vec<PathBuf> {
    let showcase = repo_path(SHOWCASE);
    scene_files()
        .into_iter()
        .filter(|p| *p != showcase)
        .collect()
}

/// Every scene file in `scenes/`.
pub fn scene_files() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(repo_path("scenes"))
        .expect("scenes/")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(!files.is_empty(), "no scenes in scenes/");
    files
}

/// Standard normal quantile (Acklam's rational approximation, relative error < 1.2e-9).
pub fn normal_quantile(p: f64) -> f64 {
    assert!(p > 0.0 && p < 1.0);
    const A: [f64; 6] = [
        -3.969683028665376e1,
        2.209460984245205e2,
        -2.759285104469687e2,
        1.383577518672690e2,
        -3.066479806614716e1,
        2.506628277459239,
    ];
    const B: [f64; 5] = [
        -5.447609879822406e1,
        1.615858368580409e2,
        -1.556989798598866e2,
        6.680131188771972e1,
        -1.328068155288572e1,
    ];
    const C: [f64; 6] = [
        -7.784894002430293e-3,
        -3.223964580411365e-1,
        -2.400758277161838,
        -2.549732539343734,
        4.374664141464968,
        2.938163982698783,
    ];
    const D: [f64; 4] = [
        7.784695709041462e-3,
        3.224671290700398e-1,
        2.445134137142996,
        3.754408661907416,
    ];
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    if p < 0.02425 {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - 0.02425 {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
}

/// Two-sided z threshold for `tests` simultaneous tests at family-wise level `alpha`
/// (Sidak correction).
pub fn sidak_z(alpha: f64, tests: usize) -> f64 {
    let per_test = 1.0 - (1.0 - alpha).powf(1.0 / tests as f64);
    normal_quantile(1.0 - per_test / 2.0)
}

/// Result of comparing two renders of one scene tile by tile.
#[derive(Debug)]
pub struct Comparison {
    /// Tiles x channels whose means differ by more than the statistical bound.
    pub failed_tiles: Vec<String>,
    pub tiles: usize,
    /// Fraction of pixels whose three channels agree to 1e-3 (relative above 1).
    pub agree_fraction: f64,
}

/// Compares two accumulations of the same scene and sample count.
///
/// Per `tile` x `tile` block and channel, the difference of the two block means must stay
/// within z x the standard error of that difference, sqrt(se_a^2 + se_ref^2), each block
/// mean's standard error coming from its pixels' sample variances and sample counts, and z
/// is the Sidak threshold at family-wise level 1e-3 over all blocks and channels. A small
/// floor (1e-5 relative) absorbs float rounding in zero-variance blocks.
pub fn compare(a: &Accumulation, reference: &Accumulation, tile: u32) -> Comparison {
    assert_eq!((a.width, a.height), (reference.width, reference.height));
    let (w, h) = (a.width, a.height);
    let tiles_x = w.div_ceil(tile);
    let tiles_y = h.div_ceil(tile);
    let n_tests = (tiles_x * tiles_y * 3) as usize;
    let z = sidak_z(1e-3, n_tests);
    let mut failed = Vec::new();
    for ty in 0..tiles_y {
        for tx in 0..tiles_x {
            let mut sum_a = [0f64; 3];
            let mut sum_r = [0f64; 3];
            let mut var_sum = [0f64; 3];
            let mut count = 0f64;
            for y in ty * tile..((ty + 1) * tile).min(h) {
                for x in tx * tile..((tx + 1) * tile).min(w) {
                    let i = (y * w + x) as usize;
                    let (ma, mr) = (a.mean(i), reference.mean(i));
                    let (va, vr) = (a.variance(i), reference.variance(i));
                    let (na, nr) = (a.samples(i) as f64, reference.samples(i) as f64);
                    for c in 0..3 {
                        sum_a[c] += ma[c] as f64;
                        sum_r[c] += mr[c] as f64;
                        var_sum[c] += va[c] as f64 / na + vr[c] as f64 / nr;
                    }
                    count += 1.0;
                }
            }
            for c in 0..3 {
                let (ma, mr) = (sum_a[c] / count, sum_r[c] / count);
                let se = var_sum[c].sqrt() / count;
                let bound = z * se + 1e-5 * mr.abs().max(1e-3);
                if (ma - mr).abs() > bound {
                    failed.push(format!(
                        "tile ({tx}, {ty}) channel {c}: {ma:.6} vs {mr:.6}, bound {bound:.6}"
                    ));
                }
            }
        }
    }
    let agree = (0..a.pixel_count())
        .filter(|&i| {
            let (ma, mr) = (a.mean(i), reference.mean(i));
            (0..3).all(|c| (ma[c] - mr[c]).abs() <= 1e-3 * mr[c].abs().max(1.0))
        })
        .count();
    Comparison {
        failed_tiles: failed,
        tiles: (tiles_x * tiles_y) as usize,
        agree_fraction: agree as f64 / a.pixel_count() as f64,
    }
}

/// The mean of every pixel of an image per channel, and its standard error (pixels are
/// independent, so the variances of the pixel means add).
pub fn image_mean(img: &Accumulation) -> ([f64; 3], [f64; 3]) {
    let n = img.pixel_count();
    let mut mean = [0.0; 3];
    let mut se = [0.0; 3];
    for c in 0..3 {
        mean[c] = (0..n).map(|i| img.mean(i)[c] as f64).sum::<f64>() / n as f64;
        let var: f64 = (0..n)
            .map(|i| img.variance(i)[c] as f64 / img.samples(i) as f64)
            .sum::<f64>()
            / (n * n) as f64;
        se[c] = var.sqrt();
    }
    (mean, se)
}

/// Variance of one sample, averaged over pixels and channels: the noise a strategy leaves.
pub fn sample_variance(img: &Accumulation) -> f64 {
    let n = img.pixel_count();
    (0..n)
        .map(|i| img.variance(i).iter().map(|&v| v as f64).sum::<f64>() / 3.0)
        .sum::<f64>()
        / n as f64
}

/// Runs the `wgtrace` binary with `args` and returns its output.
pub fn wgtrace(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_wgtrace"))
        .args(args)
        .output()
        .expect("run wgtrace")
}

/// An empty folder for one test: `wgtrace-<name>-<pid>` in the system's temporary folder.
pub fn tmp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("wgtrace-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A CPU ray as the intersection kernel's input record.
pub fn to_kernel(r: &wgtrace::cpu::types::Ray) -> wgtrace::scene::records::KernelRay {
    wgtrace::scene::records::KernelRay {
        origin: r.origin.extend(0.0).to_array(),
        dir: r.dir.extend(0.0).to_array(),
    }
}

/// A material's record from its `[materials.NAME]` keys (`type = "pbr"\nroughness = 0.3`),
/// checked and packed as the renderer does (`MaterialDesc::record`): tests never pack
/// records by hand, so a change to the packing is a change to what they test.
pub fn material(keys: &str) -> wgtrace::scene::records::Material {
    let desc: wgtrace::scene::materials::MaterialDesc =
        toml::from_str(keys).unwrap_or_else(|e| panic!("{keys}: {e}"));
    let problems = desc.check(&|field| field.to_string(), &[]);
    assert!(problems.is_empty(), "{keys}: {problems:?}");
    desc.record(&[])
}

/// A material the material tests run every harness on (tests/materials.rs on the CPU,
/// tests/kernel.rs on the GPU against the CPU).
pub struct TestMaterial {
    pub name: &'static str,
    /// Its keys in a scene file (packed by [`material`]).
    pub keys: &'static str,
    /// It absorbs nothing: every sample of the white furnace weighs exactly 1.
    pub lossless: bool,
    /// Its pdf is smooth enough for the chi-square test's 20 x 40 cells (not a near-mirror).
    pub chi2: bool,
}

const fn row(name: &'static str, keys: &'static str, lossless: bool, chi2: bool) -> TestMaterial {
    TestMaterial {
        name,
        keys,
        lossless,
        chi2,
    }
}

/// The materials every harness runs on: each type, its lobes and the extremes of its
/// parameters (white for the furnace, roughness 0 and 1, high ior, grazing-prone ones).
pub const MATERIALS: &[TestMaterial] = &[
    row("lambertian white", "type = \"lambertian\"\nalbedo = [1, 1, 1]", true, true),
    row("lambertian coloured", "type = \"lambertian\"\nalbedo = [0.8, 0.4, 0.1]", false, true),
    row(
        "lambertian one-sided",
        "type = \"lambertian\"\nalbedo = [0.7, 0.7, 0.7]\none_sided = true",
        false,
        true,
    ),
    row("emissive", "type = \"emissive\"\nradiance = [1, 1, 1]", false, false),
    row("metal mirror", "type = \"metal\"\nalbedo = [1, 1, 1]", true, false),
    row("metal fuzz 0.4", "type = \"metal\"\nalbedo = [0.9, 0.9, 0.9]\nfuzz = 0.4", false, false),
    row("dielectric 1.5", "type = \"dielectric\"\nior = 1.5", true, false),
    row(
        "dielectric 1.33 tinted",
        "type = \"dielectric\"\nior = 1.33\ntint = [0.9, 0.8, 0.7]",
        false,
        false,
    ),
    row(
        "dielectric rough 0.3",
        "type = \"dielectric\"\nior = 1.5\nroughness = 0.3",
        false,
        false,
    ),
    row(
        "dielectric rough 1.0 tinted",
        "type = \"dielectric\"\nior = 1.33\nroughness = 1\ntint = [0.9, 0.8, 0.7]",
        false,
        false,
    ),
    row(
        "dielectric beckmann 0.5",
        "type = \"dielectric\"\nior = 1.5\nroughness = 0.5\ndistribution = \"beckmann\"",
        false,
        false,
    ),
    row(
        "dielectric anisotropic 0.2 x 0.7",
        "type = \"dielectric\"\nior = 1.5\nroughness_u = 0.2\nroughness_v = 0.7",
        false,
        false,
    ),
    row(
        "dielectric rough 0.8 compensated",
        "type = \"dielectric\"\nior = 1.5\nroughness = 0.8\nenergy_compensation = true",
        false,
        false,
    ),
    row(
        "dielectric beckmann anisotropic compensated",
        "type = \"dielectric\"\nior = 1.33\nroughness_u = 0.9\nroughness_v = 0.6\ndistribution = \"beckmann\"\nenergy_compensation = true",
        false,
        false,
    ),
    row(
        "glass 1.5 reflecting and transmitting apart",
        "type = \"dielectric\"\nior = 1.5\ntint = [0.9, 0.7, 0.5]\nspecular = [0.4, 0.8, 1]",
        false,
        false,
    ),
    row(
        "rough glass 0.5 reflecting and transmitting apart",
        "type = \"dielectric\"\nior = 1.5\nroughness = 0.5\ntint = [0.9, 0.7, 0.5]\nspecular = [0.4, 0.8, 1]",
        false,
        false,
    ),
    row(
        "microfacet smooth",
        "type = \"microfacet\"\nalbedo = [1, 1, 1]\nspecular = [1, 1, 1]\nroughness = 0",
        false,
        false,
    ),
    row(
        "microfacet 0.05 ior 3",
        "type = \"microfacet\"\nalbedo = [1, 1, 1]\nspecular = [1, 1, 1]\nroughness = 0.05\nior = 3",
        false,
        false,
    ),
    row(
        "microfacet 0.1",
        "type = \"microfacet\"\nalbedo = [0.5, 0.5, 0.5]\nspecular = [1, 1, 1]\nroughness = 0.1",
        false,
        true,
    ),
    row(
        "microfacet 0.4",
        "type = \"microfacet\"\nalbedo = [0.5, 0.5, 0.5]\nspecular = [1, 1, 1]\nroughness = 0.4",
        false,
        true,
    ),
    row(
        "microfacet white 1.0",
        "type = \"microfacet\"\nalbedo = [1, 1, 1]\nspecular = [1, 1, 1]\nroughness = 1",
        false,
        true,
    ),
    row(
        "pbr clearcoat 0.5 over white",
        "type = \"pbr\"\nbase_color = [1, 1, 1]\nmetallic = 0\nspecular = 0\nclearcoat = 1\nclearcoat_roughness = 0.5",
        false,
        true,
    ),
    row(
        "pbr smooth clearcoat over red",
        "type = \"pbr\"\nbase_color = [0.8, 0.1, 0.1]\nmetallic = 0\nroughness = 0.5\nclearcoat = 1",
        false,
        false,
    ),
    row(
        "pbr white sheen 0.5 over white",
        "type = \"pbr\"\nbase_color = [1, 1, 1]\nmetallic = 0\nspecular = 0\nsheen_color = [1, 1, 1]\nsheen_roughness = 0.5",
        false,
        true,
    ),
    row(
        "pbr velvet sheen 0.3",
        "type = \"pbr\"\nbase_color = [0.2, 0.05, 0.1]\nmetallic = 0\nroughness = 0.8\nsheen_color = [0.9, 0.4, 0.6]\nsheen_roughness = 0.3",
        false,
        true,
    ),
    row(
        "pbr sheen under clearcoat",
        "type = \"pbr\"\nbase_color = [0.5, 0.5, 0.8]\nmetallic = 0\nroughness = 0.6\nsheen_color = [0.5, 0.5, 0.5]\nsheen_roughness = 0.8\nclearcoat = 0.7\nclearcoat_roughness = 0.3",
        false,
        true,
    ),
    row(
        "pbr white smooth",
        "type = \"pbr\"\nbase_color = [1, 1, 1]\nmetallic = 0\nroughness = 0",
        false,
        false,
    ),
    row(
        "pbr white 0.1 ior 3",
        "type = \"pbr\"\nbase_color = [1, 1, 1]\nmetallic = 0\nroughness = 0.1\nior = 3",
        false,
        false,
    ),
    row(
        "pbr dielectric 0.3",
        "type = \"pbr\"\nbase_color = [0.9, 0.6, 0.3]\nmetallic = 0\nroughness = 0.3",
        false,
        true,
    ),
    row(
        "pbr metal 0.3",
        "type = \"pbr\"\nbase_color = [0.9, 0.6, 0.3]\nmetallic = 1\nroughness = 0.3",
        false,
        true,
    ),
    row(
        "pbr half 0.7",
        "type = \"pbr\"\nbase_color = [0.9, 0.6, 0.3]\nmetallic = 0.5\nroughness = 0.7",
        false,
        true,
    ),
    row(
        "pbr white metal 1.0",
        "type = \"pbr\"\nbase_color = [1, 1, 1]\nmetallic = 1\nroughness = 1",
        false,
        true,
    ),
    row(
        "pbr white 0.6 ior 3",
        "type = \"pbr\"\nbase_color = [1, 1, 1]\nmetallic = 0.5\nroughness = 0.6\nior = 3",
        false,
        true,
    ),
    row(
        "conductor mirror none",
        "type = \"conductor\"",
        true,
        false,
    ),
    row(
        "conductor smooth Au",
        "type = \"conductor\"\nmaterial = \"Au\"",
        false,
        false,
    ),
    row(
        "conductor ggx 0.5 Cu",
        "type = \"conductor\"\nmaterial = \"Cu\"\nroughness = 0.5",
        false,
        true,
    ),
    row(
        "conductor white ggx 1.0",
        "type = \"conductor\"\nroughness = 1",
        false,
        true,
    ),
    row(
        "conductor beckmann 0.6 Al",
        "type = \"conductor\"\nmaterial = \"Al\"\nroughness = 0.6\ndistribution = \"beckmann\"",
        false,
        true,
    ),
    row(
        "conductor white beckmann 1.0",
        "type = \"conductor\"\nroughness = 1\ndistribution = \"beckmann\"",
        false,
        true,
    ),
    row(
        "conductor anisotropic ggx 0.3 x 0.8",
        "type = \"conductor\"\nmaterial = \"Ag\"\nroughness_u = 0.3\nroughness_v = 0.8",
        false,
        true,
    ),
    row(
        "conductor anisotropic beckmann 0.9 x 0.4",
        "type = \"conductor\"\neta = [1.5, 1.0, 0.5]\nk = [3, 2.5, 2]\nroughness_u = 0.9\nroughness_v = 0.4\ndistribution = \"beckmann\"",
        false,
        true,
    ),
    row("thin dielectric 1.5", "type = \"thin_dielectric\"", true, false),
    // a boundary with no surface: straight on, weight 1
    row("null", "type = \"null\"", true, false),
    row(
        "thin dielectric 1.33 tinted",
        "type = \"thin_dielectric\"\nior = 1.33\ntint = [0.9, 0.7, 0.5]\nspecular = [0.8, 0.8, 1]",
        false,
        false,
    ),
    row(
        "plastic smooth white",
        "type = \"plastic\"\nalbedo = [1, 1, 1]",
        false,
        false,
    ),
    row(
        "plastic smooth red nonlinear ior 1.7",
        "type = \"plastic\"\nalbedo = [0.8, 0.1, 0.1]\nior = 1.7\nnonlinear = true",
        false,
        false,
    ),
    row(
        "plastic ggx 0.3 white",
        "type = \"plastic\"\nalbedo = [1, 1, 1]\nroughness = 0.3",
        false,
        true,
    ),
    row(
        "plastic beckmann 0.6 blue",
        "type = \"plastic\"\nalbedo = [0.1, 0.2, 0.7]\nroughness = 0.6\ndistribution = \"beckmann\"",
        false,
        true,
    ),
    row(
        "plastic ggx 1.0 white compensated",
        "type = \"plastic\"\nalbedo = [1, 1, 1]\nroughness = 1\nenergy_compensation = true",
        false,
        true,
    ),
    row(
        "plastic beckmann 0.7 red nonlinear compensated",
        "type = \"plastic\"\nalbedo = [0.8, 0.2, 0.1]\nroughness = 0.7\ndistribution = \"beckmann\"\nnonlinear = true\nior = 1.7\nenergy_compensation = true",
        false,
        true,
    ),
    row(
        "plastic ggx 1.0 white nonlinear",
        "type = \"plastic\"\nalbedo = [1, 1, 1]\nroughness = 1\nnonlinear = true",
        false,
        true,
    ),
    row(
        "principled default",
        "type = \"principled\"",
        false,
        true,
    ),
    row(
        "principled anisotropic metal",
        "type = \"principled\"\nbase_color = [0.9, 0.6, 0.3]\nmetallic = 1\nroughness = 0.5\nanisotropic = 0.7",
        false,
        true,
    ),
    row(
        "principled every reflecting lobe",
        "type = \"principled\"\nbase_color = [0.6, 0.3, 0.2]\nroughness = 0.7\nmetallic = 0.2\nspec_tint = 0.5\nsheen = 0.8\nsheen_tint = 0.5\nclearcoat = 0.8\nclearcoat_gloss = 0.3\nflatness = 0.3",
        false,
        true,
    ),
    row(
        "principled rough",
        "type = \"principled\"\nbase_color = [0.6, 0.6, 0.6]\nroughness = 1",
        false,
        true,
    ),
    row(
        "principled glass",
        "type = \"principled\"\nbase_color = [0.9, 0.9, 0.8]\nroughness = 0.4\nspec_trans = 1\neta = 1.5",
        false,
        false,
    ),
    row(
        "principled half glass",
        "type = \"principled\"\nbase_color = [0.5, 0.7, 0.9]\nroughness = 0.6\nspec_trans = 0.5\nmetallic = 0.3\nclearcoat = 0.5",
        false,
        false,
    ),
    row(
        "conductor white ggx 1.0 compensated",
        "type = \"conductor\"\nroughness = 1\nenergy_compensation = true",
        false,
        true,
    ),
    row(
        "conductor anisotropic beckmann Cu compensated",
        "type = \"conductor\"\nmaterial = \"Cu\"\nroughness_u = 0.9\nroughness_v = 0.5\ndistribution = \"beckmann\"\nenergy_compensation = true",
        false,
        true,
    ),
    row(
        "microfacet 0.6 compensated",
        "type = \"microfacet\"\nalbedo = [0.7, 0.5, 0.3]\nspecular = [0.9, 0.9, 0.9]\nroughness = 0.6\nenergy_compensation = true",
        false,
        true,
    ),
    row(
        "pbr glTF default compensated",
        "type = \"pbr\"\nbase_color = [1, 1, 1]\nmetallic = 0\nroughness = 1\nenergy_compensation = true",
        false,
        true,
    ),
    row(
        "pbr half metal 0.5 compensated",
        "type = \"pbr\"\nbase_color = [0.9, 0.6, 0.3]\nmetallic = 0.5\nroughness = 0.7\nenergy_compensation = true",
        false,
        true,
    ),
    row(
        "pbr clearcoat over white compensated",
        "type = \"pbr\"\nbase_color = [1, 1, 1]\nmetallic = 0\nroughness = 0.8\nclearcoat = 1\nclearcoat_roughness = 0.9\nenergy_compensation = true",
        false,
        true,
    ),
    row(
        "principled metal compensated",
        "type = \"principled\"\nbase_color = [0.9, 0.8, 0.7]\nmetallic = 1\nroughness = 0.8\nenergy_compensation = true",
        false,
        true,
    ),
    row(
        "pbr lambertian limit",
        "type = \"pbr\"\nbase_color = [1, 1, 1]\nmetallic = 0\nroughness = 0.5\nspecular = 0",
        true,
        true,
    ),
];

/// Triangles of an icosphere of radius `r` with 20 * 4^levels triangles (levels >= 3): the
/// shipped level-3 icosphere, subdivided further.
pub fn icosphere(levels: u32, r: f32) -> Vec<[glam::Vec3; 3]> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meshes/icosphere.obj");
    let mesh = wgtrace::scene::mesh::load_mesh(&path, Default::default())
        .expect("scenes/meshes/icosphere.obj");
    let mut tris: Vec<[glam::Vec3; 3]> = mesh
        .triangles
        .iter()
        .map(|t| t.map(|i| mesh.positions[i as usize].normalize()))
        .collect();
    for _ in 3..levels {
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            let ab = ((a + b) * 0.5).normalize();
            let bc = ((b + c) * 0.5).normalize();
            let ca = ((c + a) * 0.5).normalize();
            next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        tris = next;
    }
    for tri in &mut tris {
        for p in tri.iter_mut() {
            *p *= r;
        }
    }
    tris
}

/// The primitive types' CPU tests through their views (`scene::primitives`), by their
/// places: what the intersection tests of the tests call.
pub mod shapes {
    use glam::Vec3;
    use wgtrace::cpu::primitives::ShapeTest;
    use wgtrace::cpu::types::Ray;
    use wgtrace::scene::primitives::{cylinder, r#box, sphere, triangle};
    use wgtrace::scene::records::PRIM_FLAG_CAPS;

    /// t of the nearest hit in (0, t_max), else FAR.
    pub fn intersect_sphere(center: Vec3, radius: f32, r: &Ray, t_max: f32) -> f32 {
        sphere::Params { center, radius }.intersect(r, t_max).x
    }

    /// (t, b1, b2).
    pub fn intersect_triangle(v0: Vec3, v1: Vec3, v2: Vec3, r: &Ray, t_max: f32) -> Vec3 {
        let (flags, data) = (0, 0);
        let p = triangle::Params {
            v0,
            v1,
            v2,
            flags,
            data,
        };
        p.intersect(r, t_max)
    }

    /// (t, axis of the face, 0).
    pub fn intersect_box(lo: Vec3, hi: Vec3, r: &Ray, t_max: f32) -> Vec3 {
        r#box::Params { lo, hi }.intersect(r, t_max)
    }

    /// (t, part, 0): 0 side, 1 base cap, 2 top cap.
    pub fn intersect_cylinder(
        base: Vec3,
        top: Vec3,
        radius: f32,
        caps: bool,
        r: &Ray,
        t_max: f32,
    ) -> Vec3 {
        let flags = if caps { PRIM_FLAG_CAPS } else { 0 };
        let p = cylinder::Params {
            base,
            top,
            radius,
            flags,
        };
        p.intersect(r, t_max)
    }
}

/// A group of objects and its instances, as TOML (the kernel and render tests of
/// instancing).
#[allow(dead_code)]
pub mod instances {
    /// A group's objects (analytic shapes with and without their own transforms, a mesh) as
    /// TOML, each under `m` after its own matrix (the identity for none): the instance
    /// tests' group, and, placed by hand, their expanded scene.
    pub fn group_objects(m: glam::Affine3A) -> String {
        use glam::{Affine3A, Mat3};
        let own = [
            ("type = \"sphere\"\ncenter = [0, 0.3, 0]\nradius = 0.4", Affine3A::from_scale(glam::Vec3::new(1.0, 1.6, 0.8))),
            ("type = \"box\"\nmin = [-0.5, -0.4, -0.3]\nmax = [0.4, 0.0, 0.5]", Affine3A::from_rotation_y(0.5)),
            ("type = \"cylinder\"\nbase = [0.6, -0.4, 0]\ntop = [0.7, 0.4, 0.1]\nradius = 0.2", Affine3A::IDENTITY),
            ("type = \"disk\"\ncenter = [-0.6, 0.2, 0.3]\nnormal = [0.2, 1, 0.1]\nradius = 0.3", Affine3A::IDENTITY),
            ("type = \"tetrahedron\"\nvertices = [[0.2, 0.5, 0], [0.6, 0.5, 0.2], [0.4, 0.9, 0.1], [0.4, 0.5, 0.5]]", Affine3A::IDENTITY),
            ("type = \"mesh\"\npath = \"meshes/icosphere.obj\"", Affine3A::from_mat3_translation(Mat3::from_diagonal(glam::Vec3::splat(0.3)), glam::Vec3::new(-0.3, -0.7, -0.4))),
        ];
        own.iter()
            .map(|(shape, t)| {
                let a = m * *t;
                let rows: Vec<String> = (0..3)
                    .map(|r| {
                        let l = Mat3::from(a.matrix3).row(r);
                        format!("[{}, {}, {}, {}]", l.x, l.y, l.z, a.translation[r])
                    })
                    .collect();
                format!(
                    "{shape}\nmaterial = \"m\"\ntransform = {{ matrix = [{}, [0, 0, 0, 1]] }}\n",
                    rows.join(", ")
                )
            })
            .collect::<Vec<_>>()
            .join("")
    }

    /// The instances' placements: a translation, a rotation with a uniform scale, a
    /// non-uniform scale with a shear's worth of rotation, and a mirror.
    pub fn placements() -> Vec<glam::Affine3A> {
        use glam::{Affine3A, Quat};
        vec![
            Affine3A::from_translation(glam::Vec3::new(-1.6, 0.0, 0.0)),
            Affine3A::from_scale_rotation_translation(
                glam::Vec3::splat(1.3),
                Quat::from_rotation_y(0.8),
                glam::Vec3::new(1.5, 0.2, 0.3),
            ),
            Affine3A::from_translation(glam::Vec3::new(0.0, 1.6, -0.5))
                * Affine3A::from_rotation_z(0.4)
                * Affine3A::from_scale(glam::Vec3::new(1.5, 0.7, 1.1)),
            Affine3A::from_translation(glam::Vec3::new(0.1, -1.5, 0.4))
                * Affine3A::from_scale(glam::Vec3::new(-1.0, 1.0, 1.0)),
        ]
    }

    pub fn matrix_toml(a: glam::Affine3A) -> String {
        let rows: Vec<String> = (0..3)
            .map(|r| {
                let l = glam::Mat3::from(a.matrix3).row(r);
                format!("[{}, {}, {}, {}]", l.x, l.y, l.z, a.translation[r])
            })
            .collect();
        format!("{{ matrix = [{}, [0, 0, 0, 1]] }}", rows.join(", "))
    }

    /// The same objects as TOML after `head` (which names a material `m`): as a group placed
    /// by instances, and expanded, every object written once per placement under the
    /// placement's matrix times its own.
    pub fn instanced_and_expanded(head: &str) -> (String, String) {
        let mut instanced = head.to_string();
        let mut expanded = head.to_string();
        for m in placements() {
            instanced += &format!(
                "[[objects]]\ntype = \"instance\"\ngroup = \"g\"\ntransform = {}\n",
                matrix_toml(m)
            );
            for obj in group_objects(m).split("type = ").skip(1) {
                expanded += &format!("[[objects]]\ntype = {obj}");
            }
        }
        for obj in group_objects(glam::Affine3A::IDENTITY)
            .split("type = ")
            .skip(1)
        {
            instanced += &format!("[[groups.g.objects]]\ntype = {obj}");
        }
        (instanced, expanded)
    }
}
