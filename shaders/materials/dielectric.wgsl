// type = "dielectric": smooth glass (scene::materials::dielectric; CPU twin
// cpu/materials/dielectric.rs).
#import shared/bsdf
#import shared/types

// eta = eta_i / eta_t (1 / ior entering, ior leaving, the normal turned toward the
// incoming ray). Snell's law in vector form, t = eta d + (eta cos_i - cos_t) n; total
// internal reflection when eta^2 sin^2(theta_i) >= 1; otherwise reflection with the exact
// Fresnel probability (fresnel_dielectric; ior 1 is invisible). Weight = tint, times the
// Beer-Lambert transmittance exp(-absorption x distance) for a segment that ran inside.
// Deltas only.
fn dielectric_scatter(p: DielectricParams, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
    let entering = hit.front_face;
    let n = select(-hit.ns, hit.ns, entering);
    let eta = select(p.ior, 1.0 / p.ior, entering);
    let cos_i = clamp(-dot(ray.dir, n), 0.0, 1.0);
    let sin2_t = eta * eta * max(0.0, 1.0 - cos_i * cos_i);
    var weight = p.tint;
    if (!entering) {
        weight *= exp(-p.absorption * length(hit.p - ray.origin));
    }
    if (sin2_t >= 1.0) {
        return Scatter(true, reflect_dir(ray.dir, n), weight, 0.0, true);
    }
    let cos_t = sqrt(1.0 - sin2_t);
    if (u.x < fresnel_dielectric(cos_i, cos_t, eta)) {
        return Scatter(true, reflect_dir(ray.dir, n), weight, 0.0, true);
    }
    return Scatter(true, normalize(eta * ray.dir + (eta * cos_i - cos_t) * n), weight, 0.0, true);
}
