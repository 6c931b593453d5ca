//! Materials on the CPU reference, against physics: mirror reflection, Snell's law, Fresnel's and Schlick's
//! Fresnel, total internal reflection, absorption, and fuzz that never scatters under the
//! surface. (tests/gpu.rs renders white furnaces of every material on both backends.)

use glam::{Vec2, Vec3};
use wgtrace::cpu::materials::{fresnel_dielectric, scatter, schlick};
use wgtrace::cpu::types::{Hit, Ray};
use wgtrace::scene::records::{Material, MAT_DIELECTRIC, MAT_METAL};

fn material(tag: u32, albedo: f32, param: f32, absorption: f32) -> Material {
    Material {
        tag,
        albedo: [albedo, albedo, albedo, 0.0],
        params: [param, 0.0, 0.0, 0.0],
        extra: [absorption; 4],
        ..Default::default()
    }
}

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
        uv: Vec2::ZERO,
        front_face: ray.dir.z < 0.0,
        material: 0,
        err: 0.0,
        tangent: glam::Vec4::ZERO,
    };
    (ray, hit)
}

/// u values covering [0, 1)^2.
fn grid() -> impl Iterator<Item = [f32; 2]> {
    (0..32).flat_map(|i| (0..32).map(move |j| [(i as f32 + 0.5) / 32.0, (j as f32 + 0.5) / 32.0]))
}

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
    let mirror = material(MAT_METAL, 0.8, 0.0, 0.0);
    let d = Vec3::new(1.0, 0.5, -2.0);
    let (ray, hit) = hit_at_origin(d, -d);
    for u in grid() {
        let s = scatter(&mirror, &ray, &hit, u);
        let expected = Vec3::new(d.x, d.y, -d.z).normalize();
        assert!(s.ok && (s.dir - expected).length() < 1e-6, "{:?}", s.dir);
        assert_eq!(s.weight, Vec3::splat(0.8));
    }
    // grazing incidence with full fuzz: every scattered direction is above the surface
    let fuzzy = material(MAT_METAL, 0.8, 1.0, 0.0);
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

#[test]
fn dielectric_refracts_by_snell_reflects_by_fresnel_and_conserves_energy() {
    let glass = material(MAT_DIELECTRIC, 1.0, 1.5, 0.0);
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

#[test]
fn total_internal_reflection_inside_glass_at_grazing_angles() {
    let glass = material(MAT_DIELECTRIC, 1.0, 1.5, 0.0);
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

#[test]
fn absorption_follows_beer_lambert_over_the_distance_inside() {
    let amber = material(MAT_DIELECTRIC, 1.0, 1.5, 0.5);
    // leaving the glass after 2 units inside: exp(-0.5 x 2)
    let (ray, hit) = hit_at_origin(Vec3::Z, Vec3::new(0.0, 0.0, -2.0));
    let s = scatter(&amber, &ray, &hit, [0.9, 0.5]);
    assert!(
        (s.weight - Vec3::splat((-1.0f32).exp()))
            .abs()
            .max_element()
            < 1e-6,
        "{:?}",
        s.weight
    );
    // entering: no absorption yet
    let (ray, hit) = hit_at_origin(-Vec3::Z, Vec3::new(0.0, 0.0, 2.0));
    assert_eq!(scatter(&amber, &ray, &hit, [0.9, 0.5]).weight, Vec3::ONE);
}

// ------------------------------------------------------------------ microfacet (GGX)

mod common;

use wgtrace::cpu::materials::{microfacet_eval, microfacet_pdf};
use wgtrace::scene::records::MAT_MICROFACET;

fn microfacet(kd: f32, ks: f32, roughness: f32, ior: f32) -> Material {
    Material {
        tag: MAT_MICROFACET,
        albedo: [kd, kd, kd, 0.0],
        params: [roughness, ior, 0.0, 0.0],
        extra: [ks, ks, ks, 0.0],
        ..Default::default()
    }
}

/// The outgoing (view) direction at `theta` degrees from the normal +Z, in the xz-plane, and
/// the ray and hit that see the surface from it.
fn view(theta: f32) -> (Vec3, Ray, Hit) {
    let t = theta.to_radians();
    let wo = Vec3::new(t.sin(), 0.0, t.cos());
    let (ray, hit) = hit_at_origin(-wo, wo);
    (wo, ray, hit)
}

#[test]
fn microfacet_is_reciprocal() {
    let mut rng = 3u32;
    for roughness in [0.05f32, 0.3, 1.0] {
        let m = microfacet(0.6, 0.9, roughness, 1.5);
        for _ in 0..2000 {
            let (a, b) = (common::random_unit(&mut rng), common::random_unit(&mut rng));
            let (wo, wi) = (
                Vec3::new(a.x, a.y, a.z.abs()),
                Vec3::new(b.x, b.y, b.z.abs()),
            );
            // f = eval / cos_i must be symmetric
            let f1 = microfacet_eval(&m, Vec3::Z, wo, wi) / wi.z;
            let f2 = microfacet_eval(&m, Vec3::Z, wi, wo) / wo.z;
            assert!(
                (f1 - f2).abs().max_element() <= 1e-4 * f1.max_element().max(1e-3),
                "{f1} vs {f2}"
            );
        }
    }
}

/// The red channel's directional albedo of `m` seen from `theta` degrees: the mean of
/// 40,000 sampler weights (absorbed ones 0) and its standard error; every weight must be
/// finite and not negative.
fn directional_albedo(m: &Material, theta: f32, seed: u32) -> (f64, f64) {
    let (_, ray, hit) = view(theta);
    let mut rng = seed;
    let n = 40_000;
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let u = [common::random_f32(&mut rng), common::random_f32(&mut rng)];
        let s = scatter(m, &ray, &hit, u);
        let w = if s.ok { s.weight.x as f64 } else { 0.0 };
        assert!(w.is_finite() && w >= 0.0);
        sum += w;
        sum2 += w * w;
    }
    let mean = sum / n as f64;
    (
        mean,
        ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt(),
    )
}

#[test]
fn white_microfacet_never_reflects_more_than_arrives() {
    // kd = ks = 1: the naive sum of the lobes would exceed 1; the Fresnel-weighted base must not
    let mut worst = 0.0f64;
    for ior in [1.5f32, 3.0] {
        for roughness in [0.0f32, 0.05, 0.2, 0.5, 1.0] {
            let m = microfacet(1.0, 1.0, roughness, ior);
            for theta in [0.0f32, 30.0, 60.0, 80.0, 89.0] {
                let (mean, sigma) = directional_albedo(&m, theta, 17);
                assert!(
                    mean <= 1.0 + 4.0 * sigma + 1e-6,
                    "ior {ior}, roughness {roughness}, {theta} deg: albedo {mean} +- {sigma}"
                );
                worst = worst.max(mean);
            }
        }
    }
    eprintln!("largest directional albedo of a white microfacet: {worst:.4}");
}

#[test]
fn roughness_zero_is_a_mirror_without_dividing_by_zero() {
    let m = microfacet(0.0, 1.0, 0.0, 1.5);
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

/// Chi-square test of the directions `m`'s sampler draws, seen from `theta` degrees,
/// against its pdf (`bsdf_pdf`), as pbrt-v4 and Mitsuba 3 test their BSDFs: the upper
/// hemisphere in 20 (cos theta) x 40 (phi) cells, expected counts by integrating the pdf
/// over each cell, plus a cell for the directions the sampler absorbs (under the
/// surface); cells expecting fewer than 5 are pooled.
fn assert_sampling_matches_pdf(m: &Material, theta: f32, label: &str) {
    const N: usize = 200_000;
    const NT: usize = 20;
    const NP: usize = 40;
    const SUB: usize = 10;
    let (_, ray, hit) = view(theta);
    let cell_of = |d: Vec3| {
        let t = ((d.z * NT as f32) as usize).min(NT - 1);
        let phi = d.y.atan2(d.x).rem_euclid(2.0 * std::f32::consts::PI);
        let p = ((phi / (2.0 * std::f32::consts::PI) * NP as f32) as usize).min(NP - 1);
        t * NP + p
    };
    let mut observed = vec![0f64; NT * NP + 1];
    let mut rng = 99u32;
    for _ in 0..N {
        let u = [common::random_f32(&mut rng), common::random_f32(&mut rng)];
        let s = scatter(m, &ray, &hit, u);
        let k = if s.ok { cell_of(s.dir) } else { NT * NP };
        observed[k] += 1.0;
    }
    // expected: midpoint rule on SUB x SUB points per cell (d omega = d cos d phi)
    let mut expected = vec![0f64; NT * NP + 1];
    let (dc, dp) = (1.0 / NT as f64, 2.0 * std::f64::consts::PI / NP as f64);
    for t in 0..NT {
        for p in 0..NP {
            let mut integral = 0.0f64;
            for i in 0..SUB {
                for j in 0..SUB {
                    let c = (t as f64 + (i as f64 + 0.5) / SUB as f64) * dc;
                    let phi = (p as f64 + (j as f64 + 0.5) / SUB as f64) * dp;
                    let s = (1.0 - c * c).max(0.0).sqrt();
                    let wi = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, c as f32);
                    integral += bsdf_pdf(m, &ray, &hit, wi) as f64;
                }
            }
            expected[t * NP + p] = integral * dc * dp / (SUB * SUB) as f64 * N as f64;
        }
    }
    let upper: f64 = expected[..NT * NP].iter().sum::<f64>() / N as f64;
    assert!(
        upper <= 1.0 + 2e-3,
        "{label}, {theta} deg: the pdf integrates to {upper} > 1"
    );
    expected[NT * NP] = (1.0 - upper).max(0.0) * N as f64;
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
        "{label}, {theta} deg: chi2 {chi2:.1} over {cells} cells, critical {critical:.1}"
    );
    eprintln!("{label}, {theta} deg: chi2 {chi2:.1} / critical {critical:.1} ({cells} cells), pdf integral {upper:.4}");
}

/// The microfacet's sampling against its pdf (`assert_sampling_matches_pdf`).
#[test]
fn microfacet_sampling_matches_its_pdf() {
    for (roughness, theta) in [
        (0.1f32, 0.0f32),
        (0.1, 60.0),
        (0.4, 30.0),
        (0.4, 75.0),
        (1.0, 45.0),
    ] {
        let m = microfacet(0.5, 1.0, roughness, 1.5);
        assert_sampling_matches_pdf(&m, theta, &format!("microfacet, roughness {roughness}"));
    }
}

/// The sampler's density over the whole sphere integrates to one: the specular lobe's
/// visible-normal density mapped through the reflection, G1(wo) D(h) / (4 cos_o) wherever
/// wo . h > 0 (including the directions under the surface, which the sampler draws and then
/// absorbs), mixed with the cosine lobe. microfacet_pdf is this density above the surface.
#[test]
fn microfacet_sampling_density_integrates_to_one_over_the_sphere() {
    use wgtrace::cpu::materials::{ggx_d, microfacet_spec_prob, smith_lambda};
    const NT: usize = 400;
    const NP: usize = 400;
    for (roughness, theta) in [(0.3f32, 0.0f32), (0.3, 60.0), (0.6, 45.0), (1.0, 80.0)] {
        let m = microfacet(0.5, 1.0, roughness, 1.5);
        let (wo, _, _) = view(theta);
        let p_s = microfacet_spec_prob(&m, wo.z) as f64;
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
                    upper += microfacet_pdf(&m, Vec3::Z, wo, wi) as f64 * cell;
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

// ------------------------------------------------- glTF metallic-roughness (`pbr`)

use wgtrace::cpu::materials::{bsdf_pdf, pbr_eval};
use wgtrace::scene::records::{ALPHA_SMOOTH, MAT_PBR};

/// The record `type = "pbr"` flattens to: alpha = roughness^2 (at least ALPHA_SMOOTH).
fn pbr(base: [f32; 3], metallic: f32, roughness: f32, ior: f32, specular: f32) -> Material {
    Material {
        tag: MAT_PBR,
        albedo: [base[0], base[1], base[2], 0.0],
        params: [
            (roughness * roughness).max(ALPHA_SMOOTH),
            ior,
            metallic,
            specular,
        ],
        extra: [1.0, 1.0, 1.0, 0.0],
        ..Default::default()
    }
}

/// f = eval / cos_i is symmetric in its two directions: both Fresnels are taken at v . h
/// and G2 is symmetric.
#[test]
fn pbr_is_reciprocal() {
    let mut rng = 5u32;
    for (metallic, roughness) in [(0.0f32, 0.2f32), (0.5, 0.5), (1.0, 0.8), (0.3, 1.0)] {
        let m = pbr([0.8, 0.5, 0.2], metallic, roughness, 1.5, 1.0);
        for _ in 0..2000 {
            let (a, b) = (common::random_unit(&mut rng), common::random_unit(&mut rng));
            let (wo, wi) = (
                Vec3::new(a.x, a.y, a.z.abs()),
                Vec3::new(b.x, b.y, b.z.abs()),
            );
            let f1 = pbr_eval(&m, Vec3::Z, wo, wi) / wi.z;
            let f2 = pbr_eval(&m, Vec3::Z, wi, wo) / wo.z;
            assert!(
                (f1 - f2).abs().max_element() <= 1e-4 * f1.max_element().max(1e-3),
                "metallic {metallic}, roughness {roughness}: {f1} vs {f2}"
            );
        }
    }
}

/// A white base never reflects more than arrives (directional albedo by the sampler's
/// weights, to 4 standard errors), at every view angle, metallic and roughness; without
/// its specular layer (specular = 0) the dielectric is exactly Lambertian: every weight is
/// 1, so the furnace is 1.
#[test]
fn white_pbr_never_reflects_more_than_arrives_and_its_lambertian_limit_is_exact() {
    let mut worst = 0.0f64;
    for metallic in [0.0f32, 0.5, 1.0] {
        for roughness in [0.0f32, 0.1, 0.3, 0.6, 1.0] {
            for ior in [1.5f32, 3.0] {
                let m = pbr([1.0; 3], metallic, roughness, ior, 1.0);
                for theta in [0.0f32, 30.0, 60.0, 80.0, 89.0] {
                    let (mean, sigma) = directional_albedo(&m, theta, 23);
                    assert!(
                        mean <= 1.0 + 4.0 * sigma + 1e-6,
                        "metallic {metallic}, roughness {roughness}, ior {ior}, {theta} deg: albedo {mean} +- {sigma}"
                    );
                    worst = worst.max(mean);
                }
            }
        }
    }
    eprintln!("largest directional albedo of a white pbr material: {worst:.4}");
    let lambert = pbr([1.0; 3], 0.0, 0.5, 1.5, 0.0);
    for theta in [0.0f32, 45.0, 85.0] {
        let (_, ray, hit) = view(theta);
        for u in grid() {
            let s = scatter(&lambert, &ray, &hit, u);
            assert!(s.ok, "{theta} deg: absorbed");
            assert!(
                (s.weight - Vec3::ONE).abs().max_element() < 1e-5,
                "{theta} deg: weight {}",
                s.weight
            );
        }
    }
}

/// The metallic-roughness material's sampling against its pdf (chi-square).
#[test]
fn pbr_sampling_matches_its_pdf() {
    for (metallic, roughness, theta) in [
        (0.0f32, 0.3f32, 0.0f32),
        (0.0, 0.5, 70.0),
        (1.0, 0.3, 40.0),
        (0.5, 0.7, 60.0),
        (1.0, 1.0, 20.0),
    ] {
        let m = pbr([0.9, 0.6, 0.3], metallic, roughness, 1.5, 1.0);
        assert_sampling_matches_pdf(
            &m,
            theta,
            &format!("pbr, metallic {metallic}, roughness {roughness}"),
        );
    }
}
