// type = "thin_dielectric": a window of zero thickness (scene::materials::thin_dielectric;
// CPU twin cpu/materials/thin_dielectric.rs).
#import shared/bsdf
#import shared/types

// The reflectance of the sheet seen at cosine c: the exact Fresnel reflectance R of its
// ior with the reflections between its faces summed, R + T^2 R / (1 - R^2), T = 1 - R.
fn thin_dielectric_reflectance(c: f32, ior: f32) -> f32 {
    let eta = 1.0 / ior;
    let sin2_t = eta * eta * max(0.0, 1.0 - c * c);
    var r = 1.0;
    if (sin2_t < 1.0) {
        r = fresnel_dielectric(c, sqrt(1.0 - sin2_t), eta);
    }
    let t = 1.0 - r;
    return select(1.0, r + t * t * r / (1.0 - r * r), r < 1.0);
}

// Reflection about the shading normal with probability thin_dielectric_reflectance
// (weight specular), else straight through (weight tint); both deltas. A reflection a
// shading normal sends under the geometric surface is sent over it.
fn thin_dielectric_scatter(p: ThinDielectricParams, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
    let side = select(-1.0, 1.0, hit.front_face);
    let n = side * hit.ns;
    let c = clamp(-dot(ray.dir, n), 0.0, 1.0);
    if (u.x < thin_dielectric_reflectance(c, p.ior)) {
        return mirror_scatter(ray, hit, side, n, p.specular);
    }
    return Scatter(true, ray.dir, p.tint, 0.0, true);
}
