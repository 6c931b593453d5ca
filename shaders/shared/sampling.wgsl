// Sampling primitives: orthonormal bases, disks, hemispheres, ray origin offsets.
#import shared/types

// PI (types.wgsl's constants) is the f32 nearest to pi, std::f32::consts::PI on the CPU.

// Orthonormal basis around unit n, branchless (Duff et al., JCGT 2017).
// Returns (tangent, bitangent); with n they form a right-handed frame.
fn onb_tangents(n: vec3<f32>) -> array<vec3<f32>, 2> {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    let t = vec3<f32>(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    let bt = vec3<f32>(b, s + n.y * n.y * a, -n.y);
    return array<vec3<f32>, 2>(t, bt);
}

// Uniform point on the unit disk, polar mapping.
fn sample_disk(u: vec2<f32>) -> vec2<f32> {
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    return vec2<f32>(r * cos(phi), r * sin(phi));
}

// Uniform direction on the unit sphere.
fn sample_sphere(u: vec2<f32>) -> vec3<f32> {
    let z = 1.0 - 2.0 * u.x;
    let r = sqrt(max(0.0, 1.0 - z * z));
    let phi = 2.0 * PI * u.y;
    return vec3<f32>(r * cos(phi), r * sin(phi), z);
}

// Cosine-weighted direction about unit n (Malley's method): pdf = cos(theta) / pi.
fn sample_cosine_hemisphere(n: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let d = sample_disk(u);
    let z = sqrt(max(0.0, 1.0 - u.x));
    let tb = onb_tangents(n);
    return normalize(d.x * tb[0] + d.y * tb[1] + z * n);
}

// Ray origin just off a surface. First leave the box of half-size `err` around p that
// holds the true surface point (pbrt-v4's OffsetRayOrigin, with a scalar error bound),
// then step 256 ulps of each coordinate, or a fixed 1/65536 near the origin (Waechter and
// Binder, Ray Tracing Gems, chapter 6), which also covers the rounding of that addition.
// n must be unit length and point to the side the new ray leaves on.
fn offset_ray(p: vec3<f32>, n: vec3<f32>, err: f32) -> vec3<f32> {
    let an = abs(n);
    let q = p + n * (err * (an.x + an.y + an.z));
    let of_i = vec3<i32>(4.0 * n);
    let q_i = bitcast<vec3<f32>>(bitcast<vec3<i32>>(q) + select(of_i, -of_i, q < vec3<f32>(0.0)));
    let q_f = q + (1.0 / 65536.0) * n;
    return select(q_i, q_f, abs(q) < vec3<f32>(1.0 / 32.0));
}

// Largest absolute coordinate.
fn max_abs(v: vec3<f32>) -> f32 {
    let a = abs(v);
    return max(a.x, max(a.y, a.z));
}

#ifdef HAS_ERF
// The error function and its inverse, compiled for the scenes that need them (Beckmann
// microfacets, the Gaussian pixel filter: HAS_ERF).

// The error function, by Abramowitz and Stegun's 7.1.26 (absolute error under 1.5e-7).
fn erf_approx(x: f32) -> f32 {
    let a = abs(x);
    let t = 1.0 / (1.0 + 0.3275911 * a);
    let poly = t * (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    let v = 1.0 - poly * exp(-a * a);
    return select(-v, v, x >= 0.0);
}

// The inverse error function on (-1, 1), by Giles's single-precision approximation (2010).
fn erfinv_approx(x: f32) -> f32 {
    let w = -log(max((1.0 - x) * (1.0 + x), 1e-30));
    let w1 = w - 2.5;
    var p1 = 2.81022636e-08;
    p1 = 3.43273939e-07 + p1 * w1;
    p1 = -3.5233877e-06 + p1 * w1;
    p1 = -4.39150654e-06 + p1 * w1;
    p1 = 0.00021858087 + p1 * w1;
    p1 = -0.00125372503 + p1 * w1;
    p1 = -0.00417768164 + p1 * w1;
    p1 = 0.246640727 + p1 * w1;
    p1 = 1.50140941 + p1 * w1;
    let w2 = sqrt(w) - 3.0;
    var p2 = -0.000200214257;
    p2 = 0.000100950558 + p2 * w2;
    p2 = 0.00134934322 + p2 * w2;
    p2 = -0.00367342844 + p2 * w2;
    p2 = 0.00573950773 + p2 * w2;
    p2 = -0.0076224613 + p2 * w2;
    p2 = 0.00943887047 + p2 * w2;
    p2 = 1.00167406 + p2 * w2;
    p2 = 2.83297682 + p2 * w2;
    return select(p2, p1, w < 5.0) * x;
}
#endif
