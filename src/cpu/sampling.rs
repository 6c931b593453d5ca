//! Mirrors `shaders/shared/sampling.wgsl`.

use glam::{BVec3, IVec3, Vec2, Vec3};

pub use std::f32::consts::PI;

/// Orthonormal basis around unit n, branchless (Duff et al., JCGT 2017).
#[inline]
pub fn onb_tangents(n: Vec3) -> [Vec3; 2] {
    let s = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    let t = Vec3::new(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    let bt = Vec3::new(b, s + n.y * n.y * a, -n.y);
    [t, bt]
}

/// Uniform point on the unit disk, polar mapping.
#[inline]
pub fn sample_disk(u: [f32; 2]) -> Vec2 {
    let r = u[0].sqrt();
    let phi = 2.0 * PI * u[1];
    Vec2::new(r * phi.cos(), r * phi.sin())
}

/// Uniform direction on the unit sphere.
#[inline]
pub fn sample_sphere(u: [f32; 2]) -> Vec3 {
    let z = 1.0 - 2.0 * u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Cosine-weighted direction about unit n (Malley's method): pdf = cos(theta) / pi.
#[inline]
pub fn sample_cosine_hemisphere(n: Vec3, u: [f32; 2]) -> Vec3 {
    let d = sample_disk(u);
    let z = (1.0 - u[0]).max(0.0).sqrt();
    let tb = onb_tangents(n);
    (d.x * tb[0] + d.y * tb[1] + z * n).normalize()
}

/// Ray origin just off a surface: leave the error box of half-size `err` around p (pbrt-v4),
/// then step 256 ulps, or 1/65536 near the origin (Ray Tracing Gems, chapter 6). n is unit
/// and points to the side the new ray leaves on.
#[inline]
pub fn offset_ray(p: Vec3, n: Vec3, err: f32) -> Vec3 {
    let an = n.abs();
    let q = p + n * (err * (an.x + an.y + an.z));
    let of_i = (4.0 * n).as_ivec3();
    let bits = IVec3::new(
        q.x.to_bits() as i32,
        q.y.to_bits() as i32,
        q.z.to_bits() as i32,
    );
    let neg = q.cmplt(Vec3::ZERO);
    let moved = bits + IVec3::select(neg, -of_i, of_i);
    let q_i = Vec3::new(
        f32::from_bits(moved.x as u32),
        f32::from_bits(moved.y as u32),
        f32::from_bits(moved.z as u32),
    );
    let q_f = q + (1.0 / 65536.0) * n;
    let near: BVec3 = q.abs().cmplt(Vec3::splat(1.0 / 32.0));
    Vec3::select(near, q_f, q_i)
}

/// Largest absolute coordinate.
#[inline]
pub fn max_abs(v: Vec3) -> f32 {
    let a = v.abs();
    a.x.max(a.y.max(a.z))
}

/// The error function (Abramowitz and Stegun 7.1.26).
#[allow(clippy::excessive_precision)]
pub fn erf_approx(x: f32) -> f32 {
    let a = x.abs();
    let t = 1.0 / (1.0 + 0.3275911 * a);
    let poly = t
        * (0.254829592
            + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    let v = 1.0 - poly * (-a * a).exp();
    if x >= 0.0 {
        v
    } else {
        -v
    }
}

/// The inverse error function on (-1, 1) (Giles 2010, single precision).
#[allow(clippy::excessive_precision)]
pub fn erfinv_approx(x: f32) -> f32 {
    let w = -((1.0 - x) * (1.0 + x)).max(1e-30).ln();
    let w1 = w - 2.5;
    let mut p1 = 2.81022636e-08;
    p1 = 3.43273939e-07 + p1 * w1;
    p1 = -3.5233877e-06 + p1 * w1;
    p1 = -4.39150654e-06 + p1 * w1;
    p1 = 0.00021858087 + p1 * w1;
    p1 = -0.00125372503 + p1 * w1;
    p1 = -0.00417768164 + p1 * w1;
    p1 = 0.246640727 + p1 * w1;
    p1 = 1.50140941 + p1 * w1;
    let w2 = w.sqrt() - 3.0;
    let mut p2 = -0.000200214257;
    p2 = 0.000100950558 + p2 * w2;
    p2 = 0.00134934322 + p2 * w2;
    p2 = -0.00367342844 + p2 * w2;
    p2 = 0.00573950773 + p2 * w2;
    p2 = -0.0076224613 + p2 * w2;
    p2 = 0.00943887047 + p2 * w2;
    p2 = 1.00167406 + p2 * w2;
    p2 = 2.83297682 + p2 * w2;
    (if w < 5.0 { p1 } else { p2 }) * x
}
