//! Materials on the CPU reference. One table ([`common::MATERIALS`]: each material as a
//! scene file writes it, packed by the renderer's own code) drives the harnesses every
//! material passes, as pbrt-v4's bsdfs_test.cpp does: the white furnace (never above 1,
//! exactly 1 where the table says nothing is absorbed), the sampler against its pdf
//! (chi-square, and the pdf's integral), the sampler's weight and pdf against `eval` and
//! `pdf`, reciprocity, and no density for a delta. A new material adds rows there. Then
//! the closed forms of each type: mirror, Snell, Fresnel's and Schlick's Fresnel, total
//! internal reflection, absorbing glass as clear glass, the microfacet's mirror limit and sphere integral,
//! pbr's Lambertian limit, the conductor's Fresnel, the thin dielectric's summed
//! reflections, the plastic's white base and its tables' smooth limit. (tests/kernel.rs runs the same table on the GPU against these
//! functions; tests/gpu.rs renders white furnaces of every material on both backends.)

mod common;

use common::{material, TestMaterial, MATERIALS};
use glam::Vec3;
use wgtrace::cpu::bsdf::{fresnel_conductor, fresnel_dielectric, ggx_d, schlick, smith_lambda};
use wgtrace::cpu::materials::dielectric::rough_lobes;
use wgtrace::cpu::materials::{
    bent_normal, bsdf_eval, bsdf_pdf, bsdf_scatter, material_eval, scatter, scatter_pdf,
};
use wgtrace::cpu::types::{Hit, Ray};
use wgtrace::scene::records::{Material, MAT_FLAG_DELTA, MAT_FLAG_NEE, MAT_FLAG_STRICT_VIEW};

/// A hit on the plane z = 0 (front side +Z) at the origin, for a ray of direction d that
/// started at `origin`.
fn hit_at_origin(d: Vec3, origin: Vec3) -> (Ray, Hit) {
    let ray = Ray {
        origin,
        dir: d.normalize(),
    };
    let hit = Hit {
        p: Vec3::ZERO,
        ng: Vec3::Z,
        ns: Vec3::Z,
        unmapped: Vec3::Z,
        uv: glam::Vec4::ZERO,
        front_face: ray.dir.z < 0.0,
        material: 0,
        err: 0.0,
        tangent: glam::Vec4::ZERO,
        color: glam::Vec4::ONE,
        dpdu: glam::Vec3::ZERO,
        dpdv: glam::Vec3::ZERO,
    };
    (ray, hit)
}

/// The outgoing (view) direction at `theta` degrees from the normal +Z, in the xz-plane, and
/// the ray and hit that see the surface from it.
fn view(theta: f32) -> (Vec3, Ray, Hit) {
    let t = theta.to_radians();
    let wo = Vec3::new(t.sin(), 0.0, t.cos());
    let (ray, hit) = hit_at_origin(-wo, wo);
    (wo, ray, hit)
}

/// u values covering [0, 1)^2.
fn grid() -> impl Iterator<Item = [f32; 2]> {
    (0..32).flat_map(|i| (0..32).map(move |j| [(i as f32 + 0.5) / 32.0, (j as f32 + 0.5) / 32.0]))
}

/// View angles every harness looks from (degrees from the normal).
const VIEWS: [f32; 5] = [0.0, 30.0, 60.0, 80.0, 89.0];

/// Whether the material's record says it has a lobe with a density, and a delta one.
fn lobes(m: &Material) -> (bool, bool) {
    (m.flags & MAT_FLAG_NEE != 0, m.flags & MAT_FLAG_DELTA != 0)
}

// ------------------------------------------------------------- the table's harnesses

/// The red channel's directional albedo of `m` seen from `theta` degrees: the mean of
/// 40,000 sampler weights (absorbed ones 0) and its standard error; every weight must be
/// finite and not negative.
fn directional_albedo(m: &Material, theta: f32, seed: u32) -> (f64, f64) {
    let (_, ray, hit) = view(theta);
    sampled_mean(m, &ray, &hit, seed, |s| s.weight.x as f64)
}

/// The mean of `weight` over 40,000 of the material's samples toward `ray` at `hit` (0
/// where absorbed), and its standard error; every weight finite and never negative.
fn sampled_mean(
    m: &Material,
    ray: &Ray,
    hit: &Hit,
    seed: u32,
    weight: impl Fn(&wgtrace::cpu::bsdf::Scatter) -> f64,
) -> (f64, f64) {
    let mut rng = seed;
    let n = 40_000;
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let u = [common::random_f32(&mut rng), common::random_f32(&mut rng)];
        let s = scatter(m, ray, hit, u);
        let w = if s.ok { weight(&s) } else { 0.0 };
        assert!(w.is_finite() && w >= 0.0, "{w}");
        sum += w;
        sum2 += w * w;
    }
    let mean = sum / n as f64;
    (
        mean,
        ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt(),
    )
}

/// The white furnace, every material of the table from every view: the directional
/// albedo never above 1 (to 4 standard errors); where the table says the material loses
/// nothing there, every sample weighs exactly 1.
#[test]
fn every_material_stays_within_the_white_furnace() {
    for t in MATERIALS {
        let m = material(t.keys);
        let mut worst = 0.0f64;
        for theta in VIEWS {
            let (mean, sigma) = directional_albedo(&m, theta, 17);
            assert!(
                mean <= 1.0 + 4.0 * sigma + 1e-6,
                "{}, {theta} deg: albedo {mean} +- {sigma}",
                t.name
            );
            worst = worst.max(mean);
            if t.lossless {
                let (_, ray, hit) = view(theta);
                for u in grid() {
                    let s = scatter(&m, &ray, &hit, u);
                    assert!(s.ok, "{}, {theta} deg: absorbed", t.name);
                    assert!(
                        (s.weight - Vec3::ONE).abs().max_element() < 1e-5,
                        "{}, {theta} deg: weight {}",
                        t.name,
                        s.weight
                    );
                }
            }
        }
        eprintln!("{}: largest directional albedo {worst:.4}", t.name);
    }
}

/// Chi-square test of the directions `m`'s sampler draws, seen from `theta` degrees,
/// against its pdf (`bsdf_pdf`), as pbrt-v4 and Mitsuba 3 test their BSDFs: the upper
/// hemisphere in 20 (cos theta) x 40 (phi) cells, expected counts by integrating the pdf
/// over each cell, plus a cell for the directions the sampler absorbs (under the
/// surface); cells expecting fewer than 5 are pooled. Returns the p-value's bound: the
/// statistic against its critical value at significance 1e-3.
fn assert_sampling_matches_pdf(m: &Material, theta: f32, label: &str) {
    let (_, ray, hit) = view(theta);
    chi_square(
        &format!("{label}, {theta} deg"),
        false,
        |u| {
            let s = scatter(m, &ray, &hit, u);
            s.ok.then_some(s.dir)
        },
        |wi| bsdf_pdf(m, &ray, &hit, wi),
    );
}

/// The p-value of a chi-square statistic with `k` degrees of freedom: the upper tail of
/// the normal that the Wilson-Hilferty cube root makes of it (erfc after Abramowitz and
/// Stegun 7.1.26, within 1.5e-7).
fn chi2_p_value(chi2: f64, k: f64) -> f64 {
    let s = 2.0 / (9.0 * k);
    let z = ((chi2 / k).cbrt() - (1.0 - s)) / s.sqrt();
    let x = z.abs() / std::f64::consts::SQRT_2;
    let t = 1.0 / (1.0 + 0.3275911 * x);
    let poly = t
        * (0.254829592
            + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    let erfc = poly * (-x * x).exp();
    if z >= 0.0 {
        0.5 * erfc
    } else {
        1.0 - 0.5 * erfc
    }
}

/// The chi-square test of `sample`'s directions (None: absorbed) against `pdf`, over the
/// upper hemisphere in 20 x 40 cells, or the whole sphere in 40 x 40 (`sphere`).
fn chi_square(
    label: &str,
    sphere: bool,
    sample: impl Fn([f32; 2]) -> Option<Vec3>,
    pdf: impl Fn(Vec3) -> f32,
) {
    const N: usize = 200_000;
    const NP: usize = 40;
    // refraction narrows a lobe (by 1 - eta about the pole): finer steps over the sphere
    let sub: usize = if sphere { 64 } else { 16 };
    let nt: usize = if sphere { 40 } else { 20 };
    let z0 = if sphere { -1.0f32 } else { 0.0 };
    let dz = (1.0 - z0) / nt as f32;
    let cell_of = |d: Vec3| {
        let t = (((d.z - z0) / dz) as usize).min(nt - 1);
        let phi = d.y.atan2(d.x).rem_euclid(2.0 * std::f32::consts::PI);
        let p = ((phi / (2.0 * std::f32::consts::PI) * NP as f32) as usize).min(NP - 1);
        t * NP + p
    };
    const NT: usize = 40;
    let cells_total = nt * NP;
    let mut observed = vec![0f64; NT * NP + 1];
    let mut rng = 99u32;
    for _ in 0..N {
        let u = [common::random_f32(&mut rng), common::random_f32(&mut rng)];
        let k = sample(u).map_or(cells_total, cell_of);
        observed[k] += 1.0;
    }
    // expected: the midpoint rule on sub x sub points per cell, in theta and phi (d omega
    // = sin theta d theta d phi), so that a lobe peaked at the pole (a near-mirror seen
    // head-on) is sampled where it is, not only at the cell's cosines
    let mut expected = vec![0f64; NT * NP + 1];
    let dp = 2.0 * std::f64::consts::PI / NP as f64;
    for t in 0..nt {
        // the cell's cosines run from z0 + t dz to z0 + (t + 1) dz
        let theta_hi = (z0 as f64 + t as f64 * dz as f64).clamp(-1.0, 1.0).acos();
        let theta_lo = (z0 as f64 + (t + 1) as f64 * dz as f64)
            .clamp(-1.0, 1.0)
            .acos();
        let dt = (theta_hi - theta_lo) / sub as f64;
        for p in 0..NP {
            let mut integral = 0.0f64;
            for i in 0..sub {
                let theta = theta_lo + (i as f64 + 0.5) * dt;
                let (s, c) = theta.sin_cos();
                for j in 0..sub {
                    let phi = (p as f64 + (j as f64 + 0.5) / sub as f64) * dp;
                    let wi = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, c as f32);
                    integral += pdf(wi) as f64 * s * dt;
                }
            }
            expected[t * NP + p] = integral * dp / sub as f64 * N as f64;
        }
    }
    let upper: f64 = expected[..cells_total].iter().sum::<f64>() / N as f64;
    assert!(
        upper <= 1.0 + 2e-3,
        "{label}: the pdf integrates to {upper} > 1"
    );
    expected[cells_total] = (1.0 - upper).max(0.0) * N as f64;
    // pool the cells expecting fewer than 5
    let (mut chi2, mut cells, mut pool_e, mut pool_o) = (0.0f64, 0usize, 0.0f64, 0.0f64);
    for (e, o) in expected.iter().zip(&observed) {
        if *e < 5.0 {
            pool_e += e;
            pool_o += o;
        } else {
            chi2 += (o - e) * (o - e) / e;
            cells += 1;
        }
    }
    if pool_e >= 5.0 {
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        cells += 1;
    } else {
        assert!(
            pool_o <= 5.0 + 4.0 * pool_e.sqrt() + 5.0,
            "samples where the pdf is ~0: {pool_o}"
        );
    }
    // critical value at significance 1e-3 (Wilson-Hilferty)
    let k = (cells - 1) as f64;
    let z = 3.09;
    let critical = k * (1.0 - 2.0 / (9.0 * k) + z * (2.0 / (9.0 * k)).sqrt()).powi(3);
    assert!(
        chi2 < critical,
        "{label}: chi2 {chi2:.1} over {cells} cells, critical {critical:.1}"
    );
    eprintln!(
        "{label}: chi2 {chi2:.1} / critical {critical:.1} ({cells} cells, p = {:.3}), pdf \
         integral {upper:.4}",
        chi2_p_value(chi2, k)
    );
}

/// Every material whose sampler draws only from lobes with a density: its directions
/// against its pdf (chi-square), from every view but grazing.
#[test]
fn every_sampler_matches_its_pdf() {
    let mut tested = 0;
    for t in MATERIALS {
        let m = material(t.keys);
        if !t.chi2 {
            continue;
        }
        assert_eq!(
            lobes(&m),
            (true, false),
            "{}: chi-square needs a density only",
            t.name
        );
        for theta in [0.0, 40.0, 75.0] {
            assert_sampling_matches_pdf(&m, theta, t.name);
        }
        tested += 1;
    }
    assert!(
        tested >= 8,
        "the table has too few sampled materials: {tested}"
    );
}

/// The red channel of `bsdf_eval` integrated over directions within `theta_max` of +Z
/// (the midpoint rule, `nt` polar by 512 azimuthal cells).
fn eval_integral(m: &Material, ray: &Ray, hit: &Hit, theta_max: f64, nt: usize) -> f64 {
    let np = 512;
    let mut integral = 0.0f64;
    for i in 0..nt {
        let th = (i as f64 + 0.5) / nt as f64 * theta_max;
        for j in 0..np {
            let ph = (j as f64 + 0.5) / np as f64 * std::f64::consts::TAU;
            let wi = Vec3::new(
                (th.sin() * ph.cos()) as f32,
                (th.sin() * ph.sin()) as f32,
                th.cos() as f32,
            );
            integral += bsdf_eval(m, ray, hit, wi).x as f64 * th.sin();
        }
    }
    integral * theta_max / nt as f64 * std::f64::consts::TAU / np as f64
}

/// The Henyey-Greenstein phase function's sampler against its pdf over the whole sphere
/// (chi-square), about the direction of travel +z, from back-scattering to strongly
/// forward: the sampler inverts the cumulative distribution of cos theta that `hg_eval`
/// is the density of, with g > 0 forward.
#[test]
fn the_phase_function_samples_its_pdf() {
    use wgtrace::cpu::media::{hg_eval, hg_sample};
    for g in [-0.7f32, 0.0, 0.3, 0.8] {
        chi_square(
            &format!("Henyey-Greenstein g = {g}"),
            true,
            |u| Some(hg_sample(Vec3::Z, g, u)),
            |w| hg_eval(w.z, g),
        );
        // forward means along the direction of travel
        let forward = hg_eval(1.0, g) > hg_eval(-1.0, g);
        assert_eq!(forward, g > 0.0, "g = {g}");
    }
}

/// A shading normal tilted 35 degrees from the geometric one (+Z), seen from views that
/// leave the viewer over and under its horizon: after `bent_normal`, every material of the
/// chi-square rows samples directions over the geometric surface with the density
/// `bsdf_pdf` gives (chi-square; MIS weighs by it, `scatter_pdf`), and its mean weight is
/// the integral of `bsdf_eval` over the hemisphere (5 standard errors): what the lobes
/// send under the geometric surface comes back over it, and is counted once.
#[test]
fn shading_normals_sample_and_weigh_what_eval_and_pdf_say() {
    let tilt = 35f32.to_radians();
    let ns = Vec3::new(tilt.sin(), 0.0, tilt.cos());
    for t in MATERIALS.iter().filter(|t| t.chi2) {
        let m = material(t.keys);
        for theta in [-80.0f32, -50.0, 20.0, 70.0] {
            let (_, ray, mut hit) = view(theta);
            hit.ns = ns;
            let hit = bent_normal(&m, &hit, &ray);
            let label = format!("{}, tilted normal, {theta} deg", t.name);
            chi_square(
                &label,
                false,
                |u| {
                    let s = scatter(&m, &ray, &hit, u);
                    if s.ok {
                        let p = scatter_pdf(&m, &ray, &hit, &s);
                        let q = bsdf_pdf(&m, &ray, &hit, s.dir);
                        assert!((p - q).abs() <= 1e-4 * q.max(1e-3), "{label}: {p} vs {q}");
                        assert!(s.dir.z > 0.0, "{label}: {} under the surface", s.dir);
                    }
                    s.ok.then_some(s.dir)
                },
                |wi| bsdf_pdf(&m, &ray, &hit, wi),
            );
            // the mean weight against the integral of eval (midpoint rule, 256 x 512)
            let (mut sum, mut sq, n) = (0.0f64, 0.0f64, 100_000);
            let mut rng = 5u32;
            for _ in 0..n {
                let u = [common::random_f32(&mut rng), common::random_f32(&mut rng)];
                let s = scatter(&m, &ray, &hit, u);
                let w = if s.ok { s.weight.x as f64 } else { 0.0 };
                sum += w;
                sq += w * w;
            }
            let mean = sum / n as f64;
            let se = ((sq / n as f64 - mean * mean) / n as f64).sqrt();
            let integral = eval_integral(&m, &ray, &hit, std::f64::consts::FRAC_PI_2, 256);
            assert!(
                (mean - integral).abs() <= 5.0 * se + 3e-3,
                "{label}: mean weight {mean} +- {se} vs eval's integral {integral}"
            );
        }
    }
}

/// Shading normals taken strictly (`[render] shading_normals = "strict"`, Mitsuba 3's
/// way), a map turning the shading normal 35 degrees from the unmapped and geometric one
/// (+Z), seen from views over and under its horizon, for every material of the table:
/// `bsdf_scatter` keeps no direction on one side of the shading surface and the other of
/// the unmapped one, a sample of a lobe with a density weighs `bsdf_eval / bsdf_pdf` with
/// the pdf `bsdf_pdf`, and the mean weight of the chi-square rows is the integral of
/// `bsdf_eval` over the sphere (5 standard errors, the map's shadowing in both): what the
/// lobes send across is lost, not folded back, and eval says so. A material that only
/// reflects is black to a viewer under the shading normal (Mitsuba's one-sided lobes).
#[test]
fn strict_shading_normals_lose_what_crosses_and_weigh_what_eval_says() {
    let tilt = 35f32.to_radians();
    let ns = Vec3::new(tilt.sin(), 0.0, tilt.cos());
    let mut lost = 0;
    for t in MATERIALS {
        let desc: wgtrace::scene::materials::MaterialDesc = toml::from_str(t.keys).unwrap();
        let mut m = material(t.keys);
        m.flags |= desc.strict_shading_flags();
        let reflects = m.flags & MAT_FLAG_STRICT_VIEW != 0;
        let (density, _) = lobes(&m);
        for theta in [-80.0f32, -50.0, 20.0, 70.0] {
            let (wo, ray, mut hit) = view(theta);
            hit.ns = ns;
            let label = format!("{}, strict tilted normal, {theta} deg", t.name);
            let viewer_under = wo.dot(ns) <= 0.0;
            let (mut sum, mut sq, n) = (0.0f64, 0.0f64, 100_000);
            let mut rng = 5u32;
            for _ in 0..n {
                let u = [common::random_f32(&mut rng), common::random_f32(&mut rng)];
                let s = bsdf_scatter(&m, &ray, &hit, u);
                let w = if s.ok { s.weight.x as f64 } else { 0.0 };
                sum += w;
                sq += w * w;
                if !s.ok {
                    lost += !viewer_under as usize;
                    continue;
                }
                assert!(
                    s.dir.z * s.dir.dot(ns) > 0.0,
                    "{label}: {} crosses the surfaces",
                    s.dir
                );
                assert!(
                    !(reflects && viewer_under),
                    "{label}: lit from under the shading normal"
                );
                if density && !s.delta {
                    let (f, pdf) = (
                        bsdf_eval(&m, &ray, &hit, s.dir),
                        bsdf_pdf(&m, &ray, &hit, s.dir),
                    );
                    let rel = |a: f32, b: f32| (a - b).abs() <= 1e-3 * b.abs().max(1e-3);
                    assert!(rel(s.pdf, pdf), "{label}: pdf {} vs {pdf}", s.pdf);
                    assert!(
                        rel(s.weight.x, f.x / pdf),
                        "{label}: weight {} vs {}",
                        s.weight,
                        f / pdf
                    );
                }
            }
            if !t.chi2 {
                continue;
            }
            let mean = sum / n as f64;
            let se = ((sq / n as f64 - mean * mean) / n as f64).sqrt();
            let integral = eval_integral(&m, &ray, &hit, std::f64::consts::PI, 512);
            assert!(
                (mean - integral).abs() <= 5.0 * se + 3e-3,
                "{label}: mean weight {mean} +- {se} vs eval's integral {integral}"
            );
        }
    }
    // the rule is not idle: lobes about the tilted normal reach under the geometric
    // surface from views over both horizons, and what they send there is lost
    assert!(lost > 0, "nothing crossed");
}

/// Strict shading normals' two closed forms, Mitsuba 3's normalmap and bumpmap: a mapped
/// normal that leaves the viewer on its other side than the unmapped one's is mirrored
/// about that (and kept where the viewer is on the same side of both), and a map's bumps
/// weigh light toward wi by 2 / (1 + sqrt(1 + a2 tan^2 wi)), a2 = min(tan^2 n / 8, 1),
/// both angles from the unmapped normal (Estevez et al. 2019), which `bsdf_eval` carries.
#[test]
fn strict_shading_normals_flip_and_shadow_as_mitsuba_does() {
    let desc: wgtrace::scene::materials::MaterialDesc =
        toml::from_str("type = \"lambertian\"\nalbedo = [1, 1, 1]").unwrap();
    let mut m = material("type = \"lambertian\"\nalbedo = [1, 1, 1]");
    m.flags |= desc.strict_shading_flags();
    let tilt = 35f32.to_radians();
    let ns = Vec3::new(tilt.sin(), 0.0, tilt.cos());
    // the viewer at 70 degrees on the side the map turns the normal away from
    let (wo, ray, mut hit) = view(-70.0);
    hit.ns = ns;
    assert!(wo.dot(ns) < 0.0);
    let flipped = bent_normal(&m, &hit, &ray);
    let mirror = Vec3::new(-tilt.sin(), 0.0, tilt.cos());
    assert!((flipped.ns - mirror).length() < 1e-6, "{}", flipped.ns);
    assert!(wo.dot(flipped.ns) > 0.0);
    // from the other side, the map's normal is the viewer's side already: kept
    let (_, ray, mut hit) = view(70.0);
    hit.ns = ns;
    assert_eq!(bent_normal(&m, &hit, &ray).ns, ns);
    // the shadowing term against its closed form, over the light's angle
    let a2 = (tilt.tan().powi(2) / 8.0).min(1.0);
    let (_, ray, mut hit) = view(0.0);
    hit.ns = ns;
    let mut unmapped = hit;
    unmapped.unmapped = ns;
    for theta in [10.0f32, 45.0, 60.0, 80.0, 89.0] {
        let wi = Vec3::new(0.0, theta.to_radians().sin(), theta.to_radians().cos());
        let g = 2.0 / (1.0 + (1.0 + a2 * theta.to_radians().tan().powi(2)).sqrt());
        // the same lobe without a map: the same normal, no bumps to shadow it
        let f = bsdf_eval(&m, &ray, &hit, wi).x;
        let lobe = bsdf_eval(&m, &ray, &unmapped, wi).x;
        assert!(
            (f - g * lobe).abs() <= 1e-5 * lobe.max(1e-3),
            "{theta} deg: {f} vs {g} x {lobe}"
        );
        assert!(g < 1.0);
    }
}

/// An anisotropic roughness's frame: the hit's tangent, or taken strictly (Mitsuba's
/// frames) its dp/du, whatever the tangent says; `[render] shading_normals` sets the
/// record's flag on every material.
#[test]
fn strict_anisotropy_follows_dp_du() {
    for (shading, strict) in [("bend", false), ("strict", true)] {
        let s = common::scene_from_str(&format!(
            "[render]\nshading_normals = \"{shading}\"\n[camera]\nlook_from = [0, 0, 5]\n\
             look_at = [0, 0, 0]\n[materials.brushed]\ntype = \"conductor\"\nmaterial = \"Al\"\n\
             roughness_u = 0.5\nroughness_v = 0.2\n[[objects]]\ntype = \"sphere\"\n\
             center = [0, 0, 0]\nradius = 1\nmaterial = \"brushed\"\n"
        ));
        let b = wgtrace::cpu::bindings::Bindings::new(&s, s.params(0, s.full_band()));
        let (_, _, mut hit) = view(30.0);
        hit.tangent = glam::Vec4::new(1.0, 0.0, 0.0, 1.0);
        hit.dpdu = Vec3::new(0.0, 2.0, 0.0);
        let m = wgtrace::cpu::materials::material_at(&b, &s.materials[0], &hit);
        let t = wgtrace::scene::materials::conductor::Params::read(&m).tangent;
        assert_eq!(t, if strict { hit.dpdu } else { Vec3::X }, "{shading}");
    }
}

/// The weight and pdf a sampled direction comes with are `eval / pdf` and `pdf` of that
/// direction, for every material with a density (its non-delta samples); a material
/// without one weighs every direction 0.
#[test]
fn every_sample_agrees_with_eval_and_pdf() {
    for t in MATERIALS {
        let m = material(t.keys);
        let (density, _) = lobes(&m);
        for theta in VIEWS {
            let (_, ray, hit) = view(theta);
            for u in grid() {
                let s = scatter(&m, &ray, &hit, u);
                let f = bsdf_eval(&m, &ray, &hit, s.dir);
                let pdf = bsdf_pdf(&m, &ray, &hit, s.dir);
                if !density {
                    assert_eq!(
                        (f, pdf),
                        (Vec3::ZERO, 0.0),
                        "{}: a delta has no density",
                        t.name
                    );
                    continue;
                }
                if !s.ok || s.delta {
                    continue;
                }
                let rel = |a: f32, b: f32| (a - b).abs() <= 1e-4 * b.abs().max(1e-3);
                assert!(
                    rel(s.pdf, pdf),
                    "{}, {theta} deg: pdf {} vs {pdf}",
                    t.name,
                    s.pdf
                );
                let w = f / pdf;
                assert!(
                    (0..3).all(|c| rel(s.weight[c], w[c])),
                    "{}, {theta} deg: weight {} vs eval / pdf {w}",
                    t.name,
                    s.weight
                );
            }
        }
    }
}

/// f = eval / cos_i is symmetric in its two directions, for every material with a
/// density.
#[test]
fn every_bsdf_is_reciprocal() {
    let mut rng = 5u32;
    for t in MATERIALS {
        let m = material(t.keys);
        if !lobes(&m).0 {
            continue;
        }
        for _ in 0..2000 {
            let (a, b) = (common::random_unit(&mut rng), common::random_unit(&mut rng));
            let (wo, wi) = (
                Vec3::new(a.x, a.y, a.z.abs()),
                Vec3::new(b.x, b.y, b.z.abs()),
            );
            let f1 = material_eval(&m, Vec3::Z, wo, wi) / wi.z;
            let f2 = material_eval(&m, Vec3::Z, wi, wo) / wo.z;
            assert!(
                (f1 - f2).abs().max_element() <= 1e-4 * f1.max_element().max(1e-3),
                "{}: {f1} vs {f2}",
                t.name
            );
        }
    }
}

/// The table covers every material type, and each row is what its name says: a row's
/// `type` packs into that type's tag. A blend has no lobe of its own (it chooses one of
/// two materials, which have rows): its tests render it (tests/gpu.rs,
/// `blends_mix_their_parts_by_weight`).
#[test]
fn the_table_covers_every_material_type() {
    use wgtrace::scene::materials::MaterialKind;
    for k in MaterialKind::ALL
        .iter()
        .filter(|&&k| k != MaterialKind::Blend)
    {
        assert!(
            MATERIALS.iter().any(|t| material(t.keys).tag == k.tag()),
            "no row of {}",
            k.name()
        );
    }
    let unique: std::collections::BTreeSet<&str> = MATERIALS.iter().map(|t| t.name).collect();
    assert_eq!(unique.len(), MATERIALS.len(), "row names repeat");
    let _: &[TestMaterial] = MATERIALS;
}

// ----------------------------------------------------------------- closed forms

#[test]
fn schlick_matches_its_closed_forms() {
    // normal incidence, glass: ((1 - 1.5) / (1 + 1.5))^2 = 0.04, the same either way
    assert!((schlick(1.0, 1.0 / 1.5) - 0.04).abs() < 1e-6);
    assert!((schlick(1.0, 1.5) - 0.04).abs() < 1e-6);
    // grazing: 1
    assert!((schlick(0.0, 1.0 / 1.5) - 1.0).abs() < 1e-6);
}

#[test]
fn metal_mirrors_exactly_and_fuzz_never_goes_under_the_surface() {
    let mirror = material("type = \"metal\"\nalbedo = [0.8, 0.8, 0.8]");
    let d = Vec3::new(1.0, 0.5, -2.0);
    let (ray, hit) = hit_at_origin(d, -d);
    for u in grid() {
        let s = scatter(&mirror, &ray, &hit, u);
        let expected = Vec3::new(d.x, d.y, -d.z).normalize();
        assert!(s.ok && (s.dir - expected).length() < 1e-6, "{:?}", s.dir);
        assert_eq!(s.weight, Vec3::splat(0.8));
    }
    // grazing incidence with full fuzz: every scattered direction is above the surface
    let fuzzy = material("type = \"metal\"\nalbedo = [0.8, 0.8, 0.8]\nfuzz = 1");
    let d = Vec3::new(1.0, 0.0, -0.05);
    let (ray, hit) = hit_at_origin(d, -d);
    let mut absorbed = 0;
    for u in grid() {
        let s = scatter(&fuzzy, &ray, &hit, u);
        if s.ok {
            assert!(s.dir.z > 0.0 && s.dir.is_finite() && (s.dir.length() - 1.0).abs() < 1e-5);
        } else {
            absorbed += 1;
        }
    }
    assert!(
        absorbed > 0 && absorbed < 1024,
        "grazing fuzz absorbs some, not all: {absorbed}"
    );
}

/// The exact Fresnel reflectance: 0.04 at normal incidence into or out of glass, 0 at every
/// angle at matched indices (where Schlick's approximation still reflects at grazing
/// angles), only the s part at Brewster's angle, 1 at grazing incidence.
#[test]
fn fresnel_matches_its_closed_forms() {
    let cos_t = |cos_i: f32, eta: f32| (1.0 - eta * eta * (1.0 - cos_i * cos_i)).sqrt();
    assert!((fresnel_dielectric(1.0, 1.0, 1.0 / 1.5) - 0.04).abs() < 1e-6);
    assert!((fresnel_dielectric(1.0, 1.0, 1.5) - 0.04).abs() < 1e-6);
    for deg in [0.0f32, 30.0, 60.0, 85.0, 89.9] {
        let c = deg.to_radians().cos();
        // cos_t comes back from 1 - (1 - c^2) rounded in f32: near grazing that leaves
        // a relative 1e-2 at 89.9 degrees, so F ~ 3e-5 there, not 0
        assert!(fresnel_dielectric(c, cos_t(c, 1.0), 1.0) < 1e-4, "{deg}");
    }
    assert!(schlick(0.1, 1.0) > 0.5, "Schlick's reflects at eta = 1");
    // Brewster: tan(theta_B) = 1.5; the p amplitude vanishes, F = r_s^2 / 2
    let cb = 1.5f32.atan().cos();
    let ct = cos_t(cb, 1.0 / 1.5);
    let r_s = (cb / 1.5 - ct) / (cb / 1.5 + ct);
    assert!((fresnel_dielectric(cb, ct, 1.0 / 1.5) - 0.5 * r_s * r_s).abs() < 1e-6);
    assert!((fresnel_dielectric(1e-7, cos_t(1e-7, 1.0 / 1.5), 1.0 / 1.5) - 1.0).abs() < 1e-5);
}

/// The conductor's Fresnel: head-on ((eta - 1)^2 + k^2) / ((eta + 1)^2 + k^2), 1 at grazing
/// incidence, the dielectric's where k = 0, 1 for eta = 0, k = 1 (a perfect mirror) and
/// for eta = k = 0 head-on (a measured table's clamped channel: 0 / 0 there, no NaN); a
/// smooth conductor's sample weighs exactly that, and a named metal reads its table's
/// index.
#[test]
fn conductor_fresnel_matches_its_closed_forms() {
    let eta = Vec3::new(0.2, 0.9, 1.4);
    let k = Vec3::new(3.9, 2.4, 1.6);
    let head_on = ((eta - 1.0) * (eta - 1.0) + k * k) / ((eta + 1.0) * (eta + 1.0) + k * k);
    assert!(
        (fresnel_conductor(1.0, eta, k) - head_on)
            .abs()
            .max_element()
            < 1e-6
    );
    assert!(
        (fresnel_conductor(0.0, eta, k) - Vec3::ONE)
            .abs()
            .max_element()
            < 1e-6
    );
    for deg in [0.0f32, 30.0, 60.0, 85.0] {
        let c = deg.to_radians().cos();
        let ct = (1.0 - (1.0 - c * c) / (1.5 * 1.5)).sqrt();
        let f = fresnel_conductor(c, Vec3::splat(1.5), Vec3::ZERO);
        assert!(
            (f - Vec3::splat(fresnel_dielectric(c, ct, 1.0 / 1.5)))
                .abs()
                .max_element()
                < 1e-5,
            "{deg}"
        );
        let mirror = fresnel_conductor(c, Vec3::ZERO, Vec3::ONE);
        assert!(
            (mirror - Vec3::ONE).abs().max_element() < 1e-6,
            "{deg}: {mirror}"
        );
    }
    let zero = fresnel_conductor(1.0, Vec3::ZERO, Vec3::ZERO);
    assert!(
        zero.is_finite() && (zero - Vec3::ONE).abs().max_element() < 1e-6,
        "{zero}"
    );
    let gold = material("type = \"conductor\"\nmaterial = \"Au\"");
    let (eta_au, k_au) = wgtrace::scene::metals::metal("Au").unwrap();
    let (_, ray, hit) = view(0.0);
    let s = scatter(&gold, &ray, &hit, [0.5, 0.5]);
    let expected = fresnel_conductor(1.0, Vec3::from(eta_au), Vec3::from(k_au));
    assert!(
        s.ok && s.delta && (s.weight - expected).abs().max_element() < 1e-5,
        "{s:?}"
    );
    // gold reflects red more than blue
    assert!(expected.x > 0.9 && expected.z < 0.5, "{expected}");
}

/// The thin dielectric's reflectance sums its inner reflections: R + T^2 R / (1 - R^2) =
/// 2 R / (1 + R) for the single face's Fresnel R; what it does not reflect goes straight
/// through, untinted by default.
#[test]
fn thin_dielectric_sums_the_reflections_between_its_faces() {
    for deg in [0.0f32, 40.0, 70.0, 88.0] {
        let c = deg.to_radians().cos();
        let ct = (1.0 - (1.0 - c * c) / (1.5 * 1.5)).sqrt();
        let r = fresnel_dielectric(c, ct, 1.0 / 1.5);
        let r2 = wgtrace::cpu::materials::thin_dielectric::reflectance(c, 1.5);
        assert!((r2 - 2.0 * r / (1.0 + r)).abs() < 1e-6, "{deg}: {r2}");
    }
    let window = material("type = \"thin_dielectric\"");
    let (_, ray, hit) = view(30.0);
    let through = scatter(&window, &ray, &hit, [0.99, 0.5]);
    assert!(through.ok && through.delta && through.dir == ray.dir && through.weight == Vec3::ONE);
    let reflected = scatter(&window, &ray, &hit, [0.0, 0.5]);
    assert!(reflected.ok && reflected.dir.z > 0.0);
}

/// A smooth plastic's coating over a white base reflects everything it receives (to the
/// furnace's noise); a rough coating's transmittance table tends to the smooth boundary's
/// 1 - F as its roughness goes to 0, and its internal reflectance to the smooth one's.
#[test]
fn plastic_keeps_a_white_base_and_its_rough_tables_tend_to_the_smooth_ones() {
    let white = material("type = \"plastic\"\nalbedo = [1, 1, 1]");
    for theta in VIEWS {
        let (mean, sigma) = directional_albedo(&white, theta, 29);
        assert!(
            (mean - 1.0).abs() < 4.0 * sigma + 1e-3,
            "{theta}: {mean} +- {sigma}"
        );
    }
    use wgtrace::scene::materials::plastic::{internal_reflectance, transmittance_table};
    for beckmann in [false, true] {
        let table = transmittance_table(0.002, 1.49, beckmann);
        for (i, t) in table.iter().enumerate().skip(8) {
            let c = i as f32 / (table.len() - 1) as f32;
            let f = wgtrace::cpu::materials::plastic::fresnel(c, 1.49);
            assert!(
                (t - (1.0 - f)).abs() < 2e-3,
                "{beckmann} {c}: {t} against {}",
                1.0 - f
            );
        }
        let rough = internal_reflectance(0.002, 1.49, beckmann);
        let smooth = internal_reflectance(0.0, 1.49, beckmann);
        // Mitsuba's 64-point mean of the rough one reads about 1.6% under the integral
        assert!(
            (rough / smooth - 0.984).abs() < 0.01,
            "{beckmann}: {rough} against {smooth}"
        );
    }
}

const GLASS: &str = "type = \"dielectric\"\nior = 1.5";

#[test]
fn dielectric_refracts_by_snell_reflects_by_fresnel_and_conserves_energy() {
    let glass = material(GLASS);
    for angle in [0.0f32, 20.0, 45.0, 70.0, 89.0] {
        let t = angle.to_radians();
        let d = Vec3::new(t.sin(), 0.0, -t.cos());
        let (ray, hit) = hit_at_origin(d, -d);
        let cos_t = (1.0 - (t.sin() / 1.5).powi(2)).sqrt();
        let f = fresnel_dielectric(t.cos(), cos_t, 1.0 / 1.5);
        let mut reflected = 0;
        for u in grid() {
            let s = scatter(&glass, &ray, &hit, u);
            assert!(s.ok && s.weight == Vec3::ONE, "lossless: weight 1");
            if s.dir.z > 0.0 {
                reflected += 1;
                assert!((s.dir - Vec3::new(d.x, d.y, -d.z)).length() < 1e-5);
            } else {
                // Snell: sin_t = sin_i / 1.5, in the plane of incidence
                let sin_t = (s.dir.x * s.dir.x + s.dir.y * s.dir.y).sqrt();
                assert!(
                    (sin_t - t.sin() / 1.5).abs() < 1e-5,
                    "angle {angle}: sin_t {sin_t}"
                );
                assert!(s.dir.y.abs() < 1e-6 && s.dir.x >= 0.0);
            }
        }
        // the reflected share is the Fresnel reflectance, up to the 1/32 grid of u
        assert!(
            ((reflected as f32 / 1024.0) - f).abs() <= 1.0 / 32.0 + 1e-6,
            "angle {angle}: {reflected} vs F = {f}"
        );
    }
}

/// Glass whose reflection and transmission are tinted apart (`specular` and `tint`,
/// Mitsuba's `specular_reflectance` and `specular_transmittance`): every reflection,
/// from outside, inside and by total internal reflection, weighs `specular`, every
/// refraction `tint`; without `specular` both weigh `tint`.
#[test]
fn glass_tints_its_reflection_and_its_transmission_apart() {
    let (tint, specular) = (Vec3::new(0.9, 0.7, 0.5), Vec3::new(0.4, 0.8, 1.0));
    let apart = material(&format!(
        "{GLASS}
tint = [0.9, 0.7, 0.5]
specular = [0.4, 0.8, 1]"
    ));
    let alike = material(&format!(
        "{GLASS}
tint = [0.9, 0.7, 0.5]"
    ));
    for (m, want_r) in [(&apart, specular), (&alike, tint)] {
        let (mut reflected, mut refracted) = (0, 0);
        for angle in [0.0f32, 45.0, 70.0] {
            let t = angle.to_radians();
            for inside in [false, true] {
                let d = Vec3::new(t.sin(), 0.0, -t.cos());
                let d = if inside { -d } else { d };
                let (ray, hit) = hit_at_origin(d, -d);
                for u in grid() {
                    let s = scatter(m, &ray, &hit, u);
                    let reflects = (s.dir.z > 0.0) == (d.z < 0.0);
                    let want = if reflects { want_r } else { tint };
                    assert!(
                        s.ok && (s.weight - want).abs().max_element() < 1e-6,
                        "{angle} deg, inside {inside}: {} vs {want}",
                        s.weight
                    );
                    if reflects {
                        reflected += 1;
                    } else {
                        refracted += 1;
                    }
                }
            }
        }
        assert!(reflected > 0 && refracted > 0, "{reflected} / {refracted}");
    }
}

#[test]
fn total_internal_reflection_inside_glass_at_grazing_angles() {
    let glass = material(GLASS);
    // leaving glass (the ray hits the back of the surface from below) beyond the critical
    // angle asin(1 / 1.5) = 41.8 degrees: always reflected back down, never NaN
    for angle in [42.0f32, 60.0, 89.0, 89.999] {
        let t = angle.to_radians();
        let d = Vec3::new(t.sin(), 0.0, t.cos());
        let (ray, hit) = hit_at_origin(d, -d);
        assert!(!hit.front_face);
        for u in grid() {
            let s = scatter(&glass, &ray, &hit, u);
            assert!(
                s.ok && s.dir.is_finite() && s.dir.z < 0.0,
                "angle {angle}: {:?}",
                s.dir
            );
            assert!((s.dir - Vec3::new(d.x, d.y, -d.z)).length() < 1e-5);
        }
    }
    // just inside the critical angle some light escapes
    let t = 40.0f32.to_radians();
    let d = Vec3::new(t.sin(), 0.0, t.cos());
    let (ray, hit) = hit_at_origin(d, -d);
    assert!(grid().any(|u| scatter(&glass, &ray, &hit, u).dir.z > 0.0));
}

/// Glass with `absorption` scatters as clear glass: the flattener moves its absorption
/// into a medium of albedo 0 inside it (tests/media.rs renders it), so leaving it after
/// running inside weighs nothing more.
#[test]
fn absorbing_glass_scatters_as_clear_glass() {
    let amber = material("type = \"dielectric\"\nior = 1.5\nabsorption = [0.5, 0.5, 0.5]");
    let (ray, hit) = hit_at_origin(Vec3::Z, Vec3::new(0.0, 0.0, -2.0));
    assert_eq!(scatter(&amber, &ray, &hit, [0.9, 0.5]).weight, Vec3::ONE);
}

/// Rough glass (Walter et al. 2007): its sampler against its pdf over the whole sphere
/// (reflected and refracted directions), entering and leaving, from three views and
/// three roughnesses of GGX, Beckmann's, and anisotropic ones of both (the frame about
/// the world's up axis, as at a hit without tangents).
#[test]
fn rough_glass_samples_its_pdf_over_the_sphere() {
    let mut cases: Vec<String> = [0.3f32, 0.6, 1.0]
        .iter()
        .map(|r| format!("roughness = {r}"))
        .collect();
    cases.push("roughness = 0.4\ndistribution = \"beckmann\"".into());
    cases.push("roughness = 0.8\ndistribution = \"beckmann\"".into());
    cases.push("roughness_u = 0.2\nroughness_v = 0.7".into());
    // (a lobe as narrow across as alpha_v = 0.09 needs finer cells than the 64 x 64
    // midpoint rule at grazing views: the conductor's fails there too, and passes at 4x)
    cases.push("roughness_u = 0.8\nroughness_v = 0.5\ndistribution = \"beckmann\"".into());
    for roughness in cases {
        let m = material(&format!("type = \"dielectric\"\nior = 1.5\n{roughness}"));
        let p = wgtrace::scene::materials::dielectric::Params::read(&m);
        let roughness = roughness.replace('\n', " ");
        for theta in [0.0f32, 40.0, 75.0] {
            for entering in [true, false] {
                let t = theta.to_radians();
                let wo_up = Vec3::new(t.sin(), 0.0, t.cos());
                // the ray comes down onto the front, or up onto the back
                let wo = if entering { wo_up } else { -wo_up };
                let (ray, hit) = hit_at_origin(-wo, wo);
                assert_eq!(hit.front_face, entering);
                let n = if entering { Vec3::Z } else { -Vec3::Z };
                let eta = if entering { 1.0 / 1.5 } else { 1.5 };
                chi_square(
                    &format!("rough glass {roughness}, {theta} deg, entering {entering}"),
                    true,
                    |u| {
                        let s = scatter(&m, &ray, &hit, u);
                        s.ok.then_some(s.dir)
                    },
                    |wi| rough_lobes(&p, n, wo, wi, eta).1,
                );
            }
        }
    }
}

/// A material that transmits with a density, entering and leaving (`back_face` marks the
/// side as `material_at` does): each sampled direction's pdf and weight are `bsdf_pdf`
/// and `bsdf_eval / bsdf_pdf` of it, reflected and transmitted both occur, and the pdf
/// over the sphere is the one its sampler follows (chi-square through `bsdf_pdf`).
fn assert_transmitter_has_the_density_it_samples(
    name: &str,
    keys: &str,
    back_face: impl Fn(&mut Material, bool),
) {
    for entering in [true, false] {
        let mut m = material(keys);
        assert_eq!(lobes(&m), (true, false));
        back_face(&mut m, !entering);
        for theta in [0.0f32, 40.0, 75.0] {
            let t = theta.to_radians();
            let wo_up = Vec3::new(t.sin(), 0.0, t.cos());
            let wo = if entering { wo_up } else { -wo_up };
            let (ray, hit) = hit_at_origin(-wo, wo);
            let label = format!("{name}, {theta} deg, entering {entering}");
            let (mut reflected, mut transmitted) = (0, 0);
            for u in grid() {
                let s = scatter(&m, &ray, &hit, u);
                if !s.ok {
                    continue;
                }
                assert!(!s.delta, "{label}: a density");
                let pdf = bsdf_pdf(&m, &ray, &hit, s.dir);
                let f = bsdf_eval(&m, &ray, &hit, s.dir);
                let rel = |a: f32, b: f32| (a - b).abs() <= 1e-4 * b.abs().max(1e-3);
                assert!(rel(s.pdf, pdf), "{label}: pdf {} vs {pdf}", s.pdf);
                let w = f / pdf;
                assert!(
                    (0..3).all(|c| rel(s.weight[c], w[c])),
                    "{label}: weight {} vs eval / pdf {w}",
                    s.weight
                );
                if (s.dir.z > 0.0) == (wo.z > 0.0) {
                    reflected += 1;
                } else {
                    transmitted += 1;
                }
            }
            assert!(
                reflected > 0 && transmitted > 0,
                "{label}: {reflected} / {transmitted}"
            );
            chi_square(
                &label,
                true,
                |u| {
                    let s = scatter(&m, &ray, &hit, u);
                    s.ok.then_some(s.dir)
                },
                |wi| bsdf_pdf(&m, &ray, &hit, wi),
            );
        }
    }
}

/// Rough glass has a density, which light sampling weighs (the harness above); absorbing
/// rough glass too (its absorption is a medium inside it, which shadow rays cross).
#[test]
fn rough_glass_has_the_density_it_samples() {
    use wgtrace::scene::materials::dielectric::Params;
    let keys = "type = \"dielectric\"\nior = 1.5\nroughness = 0.5\ntint = [0.9, 0.8, 1]";
    let back_face = |m: &mut Material, back: bool| {
        let mut p = Params::read(m);
        p.back_face = if back { 1.0 } else { 0.0 };
        p.write(m);
    };
    assert_transmitter_has_the_density_it_samples("rough glass", keys, back_face);
    // its reflection and transmission tinted apart
    let apart = format!("{keys}\nspecular = [0.4, 0.7, 0.2]");
    assert_transmitter_has_the_density_it_samples("rough glass tinted apart", &apart, back_face);
    // with energy compensation: its lobe's cosine directions on both sides as well
    for compensated in [
        format!("{keys}\nenergy_compensation = true"),
        format!("{apart}\nenergy_compensation = true"),
        "type = \"dielectric\"\nior = 1.33\nroughness_u = 0.9\nroughness_v = 0.6\ndistribution = \"beckmann\"\nenergy_compensation = true".into(),
    ] {
        assert_transmitter_has_the_density_it_samples("compensated", &compensated, back_face);
    }
    let absorbing = material(&format!("{keys}\nabsorption = [0.5, 0.5, 0.5]"));
    assert_eq!(lobes(&absorbing), (true, false));
}

/// A principled material that transmits (spec_trans) has the density it samples over the
/// whole sphere, from outside and inside: glass, part glass part metal under a
/// clearcoat, and anisotropic.
#[test]
fn transmitting_principled_has_the_density_it_samples() {
    use wgtrace::scene::materials::principled::Params;
    for (name, keys) in [
        ("principled glass", "roughness = 0.5\nspec_trans = 1"),
        (
            "principled part glass",
            "base_color = [0.5, 0.7, 0.9]\nroughness = 0.6\nspec_trans = 0.5\nmetallic = 0.3\nclearcoat = 0.5\nsheen = 0.5",
        ),
        (
            "principled anisotropic glass",
            "roughness = 0.7\nanisotropic = 0.8\nspec_trans = 0.8\neta = 1.33",
        ),
    ] {
        let keys = format!("type = \"principled\"\n{keys}");
        assert_transmitter_has_the_density_it_samples(name, &keys, |m, back| {
            let mut p = Params::read(m);
            p.back_face = if back { 1.0 } else { 0.0 };
            p.write(m);
        });
    }
}

/// Rough glass's BSDF is reciprocal as radiance's is across a boundary (Veach 1997,
/// 5.14): f(wo, wi) = f(wi, wo) in reflection, f(wo, wi) = eta^2 f(wi, wo) in refraction
/// (eta = eta_o / eta_i); its weights are finite and never negative. GGX, Beckmann and
/// anisotropic microfacets, and with energy compensation (its lobes' shares on the two
/// sides are reciprocal by construction: shared/bsdf.wgsl's rough dielectrics).
#[test]
fn rough_glass_is_reciprocal_for_radiance() {
    let mut rng = 3u32;
    // in f64 the two agree to 1e-11 (checked outside the tests); in f32 a sharp D turns
    // the half vector's rounding into a few percent
    for (roughness, tolerance) in [
        ("roughness = 0.3", 5e-2f32),
        ("roughness = 0.7071", 5e-3),
        ("roughness = 1", 5e-3),
        ("roughness = 0.6\ndistribution = \"beckmann\"", 5e-3),
        ("roughness_u = 0.5\nroughness_v = 0.9", 5e-3),
        (
            "roughness_u = 0.9\nroughness_v = 0.6\ndistribution = \"beckmann\"",
            5e-3,
        ),
        ("roughness = 1\nenergy_compensation = true", 5e-3),
        ("roughness = 0.7071\nenergy_compensation = true", 5e-3),
        (
            "roughness_u = 0.9\nroughness_v = 0.6\ndistribution = \"beckmann\"\nenergy_compensation = true",
            5e-3,
        ),
    ] {
        let m = material(&format!("type = \"dielectric\"\nior = 1.5\n{roughness}"));
        let p = wgtrace::scene::materials::dielectric::Params::read(&m);
        let rough_lobes = wgtrace::cpu::materials::dielectric::lobes;
        for eta in [1.0 / 1.5, 1.5] {
            for _ in 0..2000 {
                let (a, b) = (common::random_unit(&mut rng), common::random_unit(&mut rng));
                let wo = Vec3::new(a.x, a.y, a.z.abs());
                let wi = b;
                // the generalized half vector eta wo + wi of a refraction near grazing
                // cancels in f32: its direction, and a sharp D, are lost there
                if wi.z < 0.0 && (eta * wo + wi).length() < 0.3 {
                    continue;
                }
                let f1 = rough_lobes(&p, Vec3::Z, wo, wi, eta).0 / wi.z.abs();
                let f2 = if wi.z > 0.0 {
                    rough_lobes(&p, Vec3::Z, wi, wo, eta).0 / wo.z
                } else {
                    eta * eta * rough_lobes(&p, -Vec3::Z, wi, wo, 1.0 / eta).0 / wo.z
                };
                assert!(f1.is_finite() && f1 >= 0.0, "{f1}");
                assert!(
                    (f1 - f2).abs() <= tolerance * f1.max(1e-3),
                    "{roughness}, eta {eta}, wi.z {}: {f1} vs {f2}",
                    wi.z
                );
            }
        }
    }
}

/// Nearly smooth rough glass (roughness 0.05) reflects and transmits as smooth glass
/// does: from outside, reflected weight F and transmitted weight (1 - F) / ior^2 (the
/// radiance scaling across the boundary), to 1%; from inside, transmitted (1 - F) ior^2.
#[test]
fn rough_glass_near_smooth_matches_fresnel_and_the_radiance_scaling() {
    let m = material("type = \"dielectric\"\nior = 1.5\nroughness = 0.05");
    for (theta, entering) in [(0.0f32, true), (30.0, true), (60.0, true), (20.0, false)] {
        let t = theta.to_radians();
        let wo_up = Vec3::new(t.sin(), 0.0, t.cos());
        let wo = if entering { wo_up } else { -wo_up };
        let (ray, hit) = hit_at_origin(-wo, wo);
        let eta = if entering { 1.0 / 1.5 } else { 1.5f32 };
        let sin2_t = eta * eta * (1.0 - t.cos() * t.cos());
        let f = fresnel_dielectric(t.cos(), (1.0 - sin2_t).sqrt(), eta);
        let (mut r, mut tr) = (0.0f64, 0.0f64);
        let mut rng = 8u32;
        let n = 100_000;
        for _ in 0..n {
            let u = [common::random_f32(&mut rng), common::random_f32(&mut rng)];
            let s = scatter(&m, &ray, &hit, u);
            if s.ok {
                if s.dir.z * wo.z > 0.0 {
                    r += s.weight.x as f64;
                } else {
                    tr += s.weight.x as f64;
                }
            }
        }
        let (r, tr) = (r / n as f64, tr / n as f64);
        let want_t = (1.0 - f) as f64 * (eta * eta) as f64;
        assert!(
            (r - f as f64).abs() < 0.01 * f as f64 + 2e-3,
            "{theta} deg, entering {entering}: reflected {r} vs F {f}"
        );
        assert!(
            (tr - want_t).abs() < 0.01 * want_t,
            "{theta} deg, entering {entering}: transmitted {tr} vs {want_t}"
        );
    }
}

#[test]
fn roughness_zero_is_a_mirror_without_dividing_by_zero() {
    let m =
        material("type = \"microfacet\"\nalbedo = [0, 0, 0]\nspecular = [1, 1, 1]\nroughness = 0");
    let (wo, ray, hit) = view(40.0);
    let mirror = Vec3::new(-wo.x, -wo.y, wo.z);
    for u in grid() {
        let s = scatter(&m, &ray, &hit, u);
        assert!(s.ok && s.weight.is_finite() && s.dir.is_finite());
        assert!(
            (s.dir - mirror).length() < 1e-6,
            "{:?} is not the mirror direction",
            s.dir
        );
        // weight = F(cos 40 degrees), the Fresnel reflectance, exactly
        assert!((s.weight.x - schlick(40f32.to_radians().cos(), 1.5)).abs() < 1e-6);
    }
}

/// The sampler's density over the whole sphere integrates to one: the specular lobe's
/// visible-normal density mapped through the reflection, G1(wo) D(h) / (4 cos_o) wherever
/// wo . h > 0 (including the directions under the surface, which the sampler draws and then
/// absorbs), mixed with the cosine lobe. The microfacet's pdf is this density above the
/// surface.
#[test]
fn microfacet_sampling_density_integrates_to_one_over_the_sphere() {
    use wgtrace::cpu::materials::material_pdf;
    use wgtrace::cpu::materials::microfacet::spec_prob;
    use wgtrace::scene::materials::microfacet::Params;
    const NT: usize = 400;
    const NP: usize = 400;
    for (roughness, theta) in [(0.3f32, 0.0f32), (0.3, 60.0), (0.6, 45.0), (1.0, 80.0)] {
        let m = material(&format!(
            "type = \"microfacet\"\nalbedo = [0.5, 0.5, 0.5]\nspecular = [1, 1, 1]\n\
             roughness = {roughness}"
        ));
        let (wo, _, _) = view(theta);
        let p_s = spec_prob(&Params::read(&m), wo.z) as f64;
        let g1 = 1.0 / (1.0 + smith_lambda(wo.z, roughness)) as f64;
        let (mut total, mut upper) = (0.0f64, 0.0f64);
        for t in 0..NT {
            for p in 0..NP {
                // midpoint cells of equal solid angle: z uniform in [-1, 1], phi in [0, 2 pi)
                let z = -1.0 + 2.0 * (t as f64 + 0.5) / NT as f64;
                let phi = 2.0 * std::f64::consts::PI * (p as f64 + 0.5) / NP as f64;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let wi = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
                let h = (wo + wi).normalize();
                let spec = if wo.dot(h) > 0.0 && h.z > 0.0 {
                    g1 * ggx_d(h.z, roughness) as f64 / (4.0 * wo.z as f64)
                } else {
                    0.0
                };
                let diff = (z.max(0.0)) / std::f64::consts::PI;
                let d = p_s * spec + (1.0 - p_s) * diff;
                let cell = 4.0 * std::f64::consts::PI / (NT * NP) as f64;
                total += d * cell;
                if z > 0.0 {
                    upper += material_pdf(&m, Vec3::Z, wo, wi) as f64 * cell;
                }
            }
        }
        assert!(
            (total - 1.0).abs() < 5e-3,
            "roughness {roughness}, {theta} deg: density integrates to {total}"
        );
        assert!(
            upper <= total + 1e-9,
            "the pdf above the surface is part of it: {upper} vs {total}"
        );
        eprintln!(
            "roughness {roughness}, {theta} deg: sphere {total:.4}, above the surface {upper:.4}"
        );
    }
}

/// Without its specular layer (specular = 0) pbr's dielectric is exactly Lambertian:
/// every weight is 1 (the table's lossless row), and so is its BSDF: base / pi x cos.
#[test]
fn pbr_without_a_specular_layer_is_lambertian() {
    let m = material(
        "type = \"pbr\"\nbase_color = [0.8, 0.5, 0.2]\nmetallic = 0\nroughness = 0.5\nspecular = 0",
    );
    let mut rng = 11u32;
    for _ in 0..1000 {
        let (a, b) = (common::random_unit(&mut rng), common::random_unit(&mut rng));
        let (wo, wi) = (
            Vec3::new(a.x, a.y, a.z.abs()),
            Vec3::new(b.x, b.y, b.z.abs()),
        );
        let f = material_eval(&m, Vec3::Z, wo, wi);
        let lambert = Vec3::new(0.8, 0.5, 0.2) * wi.z / std::f32::consts::PI;
        assert!((f - lambert).abs().max_element() < 1e-6, "{f} vs {lambert}");
    }
}

/// Rough glass stays finite at every index of refraction, the index-matched ior = 1 of
/// glTF's transmission test grids included (where the generalized half vector eta wo + wi
/// of the straight-through refraction is the zero vector): over a sweep of ior, roughness,
/// views from both sides and the u grid, every sampled weight and pdf is finite and not
/// negative, and so are eval and pdf toward each sampled direction.
#[test]
fn rough_glass_is_finite_at_every_index_index_matched_included() {
    use wgtrace::scene::materials::dielectric::Params;
    let mut bad = Vec::new();
    for ior in [1.0f32, 1.0 + 1e-6, 1.0001, 1.01, 1.1, 1.5, 2.0, 3.0] {
        for roughness in [0.032f32, 0.1, 0.3, 0.6, 1.0] {
            let keys = format!("type = \"dielectric\"\nior = {ior}\nroughness = {roughness}");
            for entering in [true, false] {
                let mut m = material(&keys);
                let mut p = Params::read(&m);
                p.back_face = if entering { 0.0 } else { 1.0 };
                p.write(&mut m);
                for theta in [0.0f32, 1.0, 15.0, 30.0, 45.0, 60.0, 75.0, 85.0, 89.0, 89.9] {
                    let t = theta.to_radians();
                    let wo_up = Vec3::new(t.sin(), 0.0, t.cos());
                    let wo = if entering { wo_up } else { -wo_up };
                    let (ray, hit) = hit_at_origin(-wo, wo);
                    for u in grid() {
                        let s = scatter(&m, &ray, &hit, u);
                        if !s.ok {
                            continue;
                        }
                        let f = bsdf_eval(&m, &ray, &hit, s.dir);
                        let pdf = bsdf_pdf(&m, &ray, &hit, s.dir);
                        let finite = s.weight.is_finite()
                            && s.weight.min_element() >= 0.0
                            && s.pdf.is_finite()
                            && s.pdf >= 0.0
                            && f.is_finite()
                            && pdf.is_finite();
                        if !finite {
                            bad.push(format!(
                                "ior {ior}, roughness {roughness}, {theta} deg, entering \
                                 {entering}, u {u:?}: weight {}, pdf {}, eval {f}, pdf {pdf}",
                                s.weight, s.pdf
                            ));
                        }
                    }
                }
            }
        }
    }
    let iors: std::collections::BTreeSet<&str> =
        bad.iter().map(|b| b.split(',').next().unwrap()).collect();
    assert!(
        bad.is_empty(),
        "{} non-finite samples at {iors:?}, first: {:?}",
        bad.len(),
        &bad[..bad.len().min(3)]
    );
}

/// A blend's mistakes, each named by its file, line and key: a part that is not a
/// material, a weight outside [0, 1] or an unknown weight texture, a part that emits or
/// is masked, a cycle of parts, and nesting deeper than `MAX_BLEND_DEPTH`.
#[test]
fn blends_are_validated() {
    let err = |m: &str| {
        let src = format!(
            "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[materials]\na = {{ type = \"lambertian\", albedo = [0.5, 0.5, 0.5] }}\n{m}\n"
        );
        wgtrace::load_scene_str(&src, std::path::Path::new("bad.toml"), &Default::default())
            .unwrap_err()
            .to_string()
    };
    let e = err("b = { type = \"blend\", first = \"a\", second = \"nope\", weight = 0.5 }");
    assert!(
        e.contains("bad.toml:6:")
            && e.contains("materials.b.second: unknown material \"nope\" (defined: a, b)"),
        "{e}"
    );
    let e = err("b = { type = \"blend\", first = \"a\", second = \"a\", weight = 1.5 }");
    assert!(
        e.contains("bad.toml:6:") && e.contains("materials.b.weight: must be in [0, 1]"),
        "{e}"
    );
    let e = err("b = { type = \"blend\", first = \"a\", second = \"a\", weight = \"w\" }");
    assert!(
        e.contains("materials.b.weight: unknown texture \"w\""),
        "{e}"
    );
    let e = err("l = { type = \"emissive\", radiance = [1, 1, 1] }\nb = { type = \"blend\", first = \"a\", second = \"l\", weight = 0.5 }");
    assert!(
        e.contains("bad.toml:7:") && e.contains("materials.b.second: \"l\" emits"),
        "{e}"
    );
    let e = err("m = { type = \"lambertian\", albedo = [1, 1, 1], opacity = 0.5 }\nb = { type = \"blend\", first = \"m\", second = \"a\", weight = 0.5 }");
    assert!(
        e.contains("materials.b.first: \"m\" has an opacity mask"),
        "{e}"
    );
    let e = err("b = { type = \"blend\", first = \"a\", second = \"c\", weight = 0.5 }\nc = { type = \"blend\", first = \"b\", second = \"a\", weight = 0.5 }");
    assert!(
        e.contains("materials.b: a blend that contains itself"),
        "{e}"
    );
    let chain: String = (1..=5)
        .map(|i| {
            format!(
                "b{i} = {{ type = \"blend\", first = \"a\", second = \"{}\", weight = 0.5 }}\n",
                if i == 5 {
                    "a".to_string()
                } else {
                    format!("b{}", i + 1)
                }
            )
        })
        .collect();
    let e = err(&chain);
    assert!(
        e.contains("materials.b1: blends nest 5 deep; at most 4"),
        "{e}"
    );
    assert!(!e.contains("materials.b2:"), "{e}");
}

/// A bump map's mistakes, named by file, line and key: a texture that does not exist, a
/// scale that is not finite.
#[test]
fn bump_maps_are_validated() {
    let err = |m: &str| {
        let src = format!(
            "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[textures]\nn = {{ type = \"noise\" }}\n[materials]\n{m}\n"
        );
        wgtrace::load_scene_str(&src, std::path::Path::new("bad.toml"), &Default::default())
            .unwrap_err()
            .to_string()
    };
    let e = err("a = { type = \"lambertian\", albedo = [0.5, 0.5, 0.5], bump = \"h\" }");
    assert!(
        e.contains("bad.toml:7:") && e.contains("materials.a.bump: unknown texture \"h\""),
        "{e}"
    );
    let e = err("a = { type = \"conductor\", bump = \"n\", bump_scale = nan }");
    assert!(
        e.contains("bad.toml:7:") && e.contains("materials.a.bump_scale"),
        "{e}"
    );
}

/// A mesh attribute's mistakes: an unknown name (the known ones listed), and a checker
/// whose cell is one (looked up without a mesh).
#[test]
fn mesh_attributes_are_validated() {
    let err = |t: &str| {
        let src =
            format!("[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[textures]\n{t}\n");
        wgtrace::load_scene_str(&src, std::path::Path::new("bad.toml"), &Default::default())
            .unwrap_err()
            .to_string()
    };
    let e = err("a = { type = \"mesh_attribute\", name = \"face_\" }");
    assert!(
        e.contains("textures.a.name: unknown mesh attribute \"face_\""),
        "{e}"
    );
    let e = err("a = { type = \"mesh_attribute\", name = \"corner_color\" }");
    assert!(
        e.contains("bad.toml:5:")
            && e.contains("textures.a.name: unknown mesh attribute \"corner_color\" (known: vertex_color, face_color, or a PLY file's vertex_NAME or face_NAME)"),
        "{e}"
    );
    let e = err("a = { type = \"mesh_attribute\", name = \"face_color\" }\nc = { type = \"checker\", even = \"a\", odd = [0, 0, 0] }");
    assert!(
        e.contains("bad.toml:6:") && e.contains("textures.c.even: \"a\" is a mesh attribute"),
        "{e}"
    );
}

/// A PLY file's named attributes are found by Mitsuba's names or refused with the file,
/// the key and the attributes the element has: one that is missing, one of two channels,
/// one asked of an OBJ file, and a material that reads two.
#[test]
fn named_mesh_attributes_are_found_or_refused_by_name() {
    let dir = common::tmp_dir("named-attributes");
    std::fs::write(
        dir.join("a.ply"),
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nproperty float uv_0\nproperty float uv_1\nelement face 1\n\
         property list uchar int vertex_indices\nproperty uchar tint_r\nproperty uchar tint_g\n\
         property uchar tint_b\nproperty float weight_x\nend_header\n\
         0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2 255 0 0 0.5\n",
    )
    .unwrap();
    std::fs::write(dir.join("a.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let load = |mesh: &str, albedo: &str, weight: &str| {
        let src = format!(
            "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[textures]\n\
             a = {{ type = \"mesh_attribute\", name = \"{albedo}\" }}\n\
             w = {{ type = \"mesh_attribute\", name = \"{weight}\" }}\n[materials]\n\
             p = {{ type = \"lambertian\", albedo = \"a\" }}\nq = {{ type = \"lambertian\", albedo = [1, 1, 1] }}\n\
             m = {{ type = \"blend\", first = \"p\", second = \"q\", weight = \"w\" }}\n\
             [[objects]]\ntype = \"mesh\"\npath = \"{mesh}\"\nmaterial = \"m\"\n"
        );
        wgtrace::load_scene_str(&src, &dir.join("s.toml"), &Default::default())
            .map(|_| ())
            .map_err(|e| e.to_string())
    };
    // found: three channels named _r _g _b (`face_tint_color`), one named _x
    load("a.ply", "face_tint_color", "face_tint_color").unwrap();
    load("a.ply", "face_weight", "face_weight").unwrap();
    let e = load("a.ply", "face_tint", "face_tint").unwrap_err();
    assert!(
        e.contains("s.toml:") && e.contains("objects[0].path") && e.contains("a.ply")
            && e.contains("has no face attribute \"face_tint\" (its face attributes: face_tint_color, face_weight)"),
        "{e}"
    );
    let e = load("a.ply", "vertex_uv", "vertex_uv").unwrap_err();
    assert!(
        e.contains("has the vertex attribute \"vertex_uv\" with 2 channels"),
        "{e}"
    );
    let e = load("a.obj", "face_weight", "face_weight").unwrap_err();
    assert!(
        e.contains("reads the mesh attribute face_weight, which only a PLY file names"),
        "{e}"
    );
    let e = load("a.ply", "face_tint_color", "face_weight").unwrap_err();
    assert!(
        e.contains("reads the mesh attributes face_tint_color and face_weight"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Mitsuba's principled BSDF is not energy-conserving (its diffuse retro-reflection,
/// sheen and clearcoat add to the specular reflection), and neither is wgtrace's, which
/// follows its formulas: a white one at roughness 1 reflects more than it receives. Its
/// sampler stays unbiased there: the mean weight from each view is the integral of
/// `bsdf_eval` over the hemisphere (a 256 x 256 midpoint rule), within 4 standard errors.
#[test]
fn principled_sampler_is_unbiased_where_the_model_gains_energy() {
    let m = material(
        "type = \"principled\"\nbase_color = [1, 1, 1]\nroughness = 1\nsheen = 1\nclearcoat = 1",
    );
    for theta in [0.0f32, 50.0, 80.0] {
        let (mean, sigma) = directional_albedo(&m, theta, 23);
        let (_, ray, hit) = view(theta);
        let k = 256;
        let mut integral = 0.0f64;
        for i in 0..k {
            // uniform in cos theta: d omega = d cos d phi
            let c = (i as f64 + 0.5) / k as f64;
            let s = (1.0 - c * c).sqrt();
            for j in 0..k {
                let phi = (j as f64 + 0.5) / k as f64 * std::f64::consts::TAU;
                let wi = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, c as f32);
                integral += bsdf_eval(&m, &ray, &hit, wi).x as f64;
            }
        }
        integral *= std::f64::consts::TAU / (k * k) as f64;
        eprintln!("{theta} deg: sampled {mean:.4} +- {sigma:.4}, integral {integral:.4}");
        assert!(
            (mean - integral).abs() <= 4.0 * sigma + 2e-3 * integral,
            "{theta} deg: sampled {mean} +- {sigma}, integral {integral}"
        );
        if theta == 0.0 {
            assert!(
                integral > 1.0,
                "a white principled reflects {integral} head-on"
            );
        }
    }
}

/// A principled material's mistakes, each one error with the file, line and key: a
/// scalar outside [0, 1], an unknown texture, both `eta` and `specular`, `eta` <= 0, and
/// `one_sided` on one that transmits.
#[test]
fn principled_materials_are_validated() {
    let err = |m: &str| {
        let src = format!(
            "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[textures]\nn = {{ type = \"noise\" }}\n[materials]\n{m}\n"
        );
        wgtrace::load_scene_str(&src, std::path::Path::new("bad.toml"), &Default::default())
            .unwrap_err()
            .to_string()
    };
    for (m, key, message) in [
        ("roughness = 1.5", "roughness", "must be in [0, 1]"),
        ("sheen = -0.1", "sheen", "must be in [0, 1]"),
        (
            "clearcoat_gloss = \"gloss\"",
            "clearcoat_gloss",
            "unknown texture \"gloss\"",
        ),
        ("eta = 1.5, specular = 0.5", "eta", "not both"),
        ("eta = 0", "eta", ""),
        (
            "spec_trans = \"n\", one_sided = true",
            "one_sided",
            "inside",
        ),
    ] {
        let e = err(&format!("a = {{ type = \"principled\", {m} }}"));
        assert!(
            e.contains("bad.toml:7:")
                && e.contains(&format!("materials.a.{key}"))
                && e.contains(message),
            "{m}: {e}"
        );
    }
    // a texture on every scalar is accepted
    let ok = "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[textures]\nn = { type = \"noise\" }\n[materials]\na = { type = \"principled\", roughness = \"n\", anisotropic = \"n\", metallic = \"n\", spec_trans = \"n\", spec_tint = \"n\", sheen = \"n\", sheen_tint = \"n\", flatness = \"n\", clearcoat = \"n\", clearcoat_gloss = \"n\", base_color = \"n\" }\n";
    wgtrace::load_scene_str(ok, std::path::Path::new("ok.toml"), &Default::default()).unwrap();
}

/// (view, directional albedo without compensation, with it, the latter's standard
/// error) of the material `keys` from every view.
fn albedo_without_and_with_compensation(keys: &str) -> Vec<(f32, f64, f64, f64)> {
    let plain = material(keys);
    let compensated = material(&format!("{keys}\nenergy_compensation = true"));
    VIEWS
        .iter()
        .map(|&theta| {
            let (before, _) = directional_albedo(&plain, theta, 29);
            let (after, sigma) = directional_albedo(&compensated, theta, 31);
            (theta, before, after, sigma)
        })
        .collect()
}

/// Multiple-scattering energy compensation (Kulla and Conty): white rough lobes reflect
/// all the light that arrives, from every view, within 2% (the albedo tables' 32 x 32
/// cells and their interpolation), where without it they lose up to 91% of it. Among them
/// the glTF material of the issue: a white base under glTF's default specular at
/// roughness 1, and under a rough clearcoat (0.086 at 89 degrees without: the coat's
/// layer weighs what lies under it by the Fresnel at the normal, a smooth coat's
/// albedo). An anisotropic lobe is compensated as the isotropic one of its alphas'
/// mean, which falls short of 1 as the two part (alphas 0.64 and 1: 0.95 at 80 degrees;
/// 0.16 and 1: 0.80 at 80) and does not go over it.
#[test]
fn energy_compensation_gives_white_rough_lobes_back_their_energy() {
    for (keys, lowest) in [
        ("type = \"conductor\"\nroughness = 1", 0.98),
        ("type = \"conductor\"\nroughness = 0.5", 0.98),
        (
            "type = \"conductor\"\nroughness = 1\ndistribution = \"beckmann\"",
            0.98,
        ),
        (
            "type = \"conductor\"\nroughness_u = 0.8\nroughness_v = 1",
            0.95,
        ),
        (
            "type = \"conductor\"\nroughness_u = 0.4\nroughness_v = 1",
            0.75,
        ),
        (
            "type = \"microfacet\"\nalbedo = [1, 1, 1]\nspecular = [1, 1, 1]\nroughness = 1",
            0.98,
        ),
        (
            "type = \"pbr\"\nbase_color = [1, 1, 1]\nmetallic = 0\nroughness = 1",
            0.98,
        ),
        (
            "type = \"pbr\"\nbase_color = [1, 1, 1]\nmetallic = 1\nroughness = 0.7",
            0.98,
        ),
        (
            "type = \"pbr\"\nbase_color = [1, 1, 1]\nmetallic = 0\nroughness = 1\nclearcoat = 1\nclearcoat_roughness = 1",
            0.98,
        ),
        (
            "type = \"pbr\"\nbase_color = [1, 1, 1]\nmetallic = 0\nroughness = 0.5\nclearcoat = 0.7\nclearcoat_roughness = 0.4",
            0.98,
        ),
        (
            "type = \"principled\"\nbase_color = [1, 1, 1]\nmetallic = 1\nroughness = 1",
            0.98,
        ),
    ] {
        let mut report = String::new();
        for (theta, before, after, sigma) in albedo_without_and_with_compensation(keys) {
            report += &format!(" {theta}: {before:.3} -> {after:.3};");
            assert!(
                after <= 1.02 + 4.0 * sigma && after >= lowest - 4.0 * sigma && after >= before,
                "{keys}, {theta} deg: {before} -> {after} +- {sigma}"
            );
        }
        eprintln!("{}:{report}", keys.replace('\n', " "));
    }
}

/// The energy rough glass keeps seen from `theta` degrees, from outside or inside: the
/// mean of its sampled weights, a transmitted one over eta^2 (radiance's scaling across
/// the boundary, eta = eta_o / eta_i), and its standard error.
fn glass_energy(keys: &str, ior: f32, theta: f32, entering: bool, seed: u32) -> (f64, f64) {
    use wgtrace::scene::materials::dielectric::Params;
    let mut m = material(keys);
    let mut p = Params::read(&m);
    p.back_face = if entering { 0.0 } else { 1.0 };
    p.write(&mut m);
    let t = theta.to_radians();
    let wo_up = Vec3::new(t.sin(), 0.0, t.cos());
    let wo = if entering { wo_up } else { -wo_up };
    let (ray, hit) = hit_at_origin(-wo, wo);
    let eta = if entering { 1.0 / ior } else { ior };
    sampled_mean(&m, &ray, &hit, seed, |s| {
        let w = s.weight.x as f64;
        if (s.dir.z > 0.0) != (wo.z > 0.0) {
            w / (eta * eta) as f64
        } else {
            w
        }
    })
}

/// Energy compensation of rough dielectrics: rough glass keeps all the energy that
/// arrives, reflected and transmitted, from outside and from inside (where light that
/// reflects totally loses most to masking), within 2% (the tables' cells and their
/// interpolation between indices), where without it it loses up to 58%. Anisotropic
/// glass is compensated as the isotropic one of its alphas' mean, which misses where a
/// view sees one alpha only: roughness 0.8 x 1 keeps 0.94 to 1.10 seen from inside (the
/// most at 89 degrees), 1.00 to 1.02 from outside. A white rough plastic reflects all
/// of it within 3% (without, as little as 0.15), its coating's multiple scattering
/// shared between the coating's reflection and the base as the coating's Fresnel
/// average says: what it lacks is Mitsuba's internal reflectance, 1.6% under the
/// integral, kept so that plastics agree with Mitsuba's.
#[test]
fn energy_compensation_gives_rough_glass_and_plastic_back_their_energy() {
    for (keys, ior, lowest, highest) in [
        (
            "type = \"dielectric\"\nior = 1.5\nroughness = 1",
            1.5,
            0.98,
            1.02,
        ),
        (
            "type = \"dielectric\"\nior = 1.5\nroughness = 0.5",
            1.5,
            0.98,
            1.02,
        ),
        (
            "type = \"dielectric\"\nior = 1.33\nroughness = 0.8",
            1.33,
            0.98,
            1.02,
        ),
        (
            "type = \"dielectric\"\nior = 2.4\nroughness = 0.7",
            2.4,
            0.98,
            1.02,
        ),
        (
            "type = \"dielectric\"\nior = 1.5\nroughness = 0.9\ndistribution = \"beckmann\"",
            1.5,
            0.98,
            1.02,
        ),
        (
            "type = \"dielectric\"\nior = 1.5\nroughness_u = 0.8\nroughness_v = 1",
            1.5,
            0.93,
            1.11,
        ),
    ] {
        let mut report = String::new();
        for entering in [true, false] {
            for theta in VIEWS {
                let (before, _) = glass_energy(keys, ior, theta, entering, 29);
                let compensated = format!("{keys}\nenergy_compensation = true");
                let (after, sigma) = glass_energy(&compensated, ior, theta, entering, 31);
                report += &format!(" {entering} {theta}: {before:.3} -> {after:.3};");
                assert!(
                    after <= highest + 4.0 * sigma
                        && after >= lowest - 4.0 * sigma
                        && after >= before - 4.0 * sigma,
                    "{keys}, entering {entering}, {theta} deg: {before} -> {after} +- {sigma}"
                );
            }
        }
        eprintln!("{}:{report}", keys.replace('\n', " "));
    }
    for keys in [
        "type = \"plastic\"\nalbedo = [1, 1, 1]\nroughness = 1",
        "type = \"plastic\"\nalbedo = [1, 1, 1]\nroughness = 0.5\nior = 1.7",
        "type = \"plastic\"\nalbedo = [1, 1, 1]\nroughness = 0.8\ndistribution = \"beckmann\"",
        "type = \"plastic\"\nalbedo = [1, 1, 1]\nroughness = 1\nnonlinear = true",
    ] {
        let mut report = String::new();
        for (theta, before, after, sigma) in albedo_without_and_with_compensation(keys) {
            report += &format!(" {theta}: {before:.3} -> {after:.3};");
            assert!(
                after <= 1.02 + 4.0 * sigma
                    && after >= 0.97 - 4.0 * sigma
                    && after >= before - 4.0 * sigma,
                "{keys}, {theta} deg: {before} -> {after} +- {sigma}"
            );
        }
        eprintln!("{}:{report}", keys.replace('\n', " "));
    }
}
