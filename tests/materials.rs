//! Materials on the CPU reference, against physics: mirror reflection, Snell's law, Schlick's
//! Fresnel, total internal reflection, absorption, and fuzz that never scatters under the
//! surface. (tests/gpu.rs renders white furnaces of every material on both backends.)

use glam::{Vec2, Vec3};
use wgtrace::cpu::materials::{scatter, schlick};
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

#[test]
fn dielectric_refracts_by_snell_reflects_by_schlick_and_conserves_energy() {
    let glass = material(MAT_DIELECTRIC, 1.0, 1.5, 0.0);
    for angle in [0.0f32, 20.0, 45.0, 70.0, 89.0] {
        let t = angle.to_radians();
        let d = Vec3::new(t.sin(), 0.0, -t.cos());
        let (ray, hit) = hit_at_origin(d, -d);
        let f = schlick(t.cos(), 1.0 / 1.5);
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
        // the reflected share is Schlick's F, up to the 1/32 grid of u
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
