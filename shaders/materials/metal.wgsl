// type = "metal": a mirror perturbed by fuzz (scene::materials::metal; CPU twin
// cpu/materials/metal.rs).
#import shared/bsdf
#import shared/sampling
#import shared/types

// The mirror direction about the shading normal, perturbed by fuzz x a uniform unit
// vector; weight = albedo. A direction under the surface (the shading normal's horizon),
// or a perturbation that cancels the reflection, is absorbed; one that a shading normal
// tilts under the geometric surface only is sent over it (over_surface). A delta: its
// density has no closed form.
fn metal_scatter(p: MetalParams, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
    let side = select(-1.0, 1.0, hit.front_face);
    let v = reflect_dir(ray.dir, side * hit.ns) + p.fuzz * sample_sphere(u);
    let len = length(v);
    let dir = over_surface(v, side, hit);
    if (!(len > 0.0) || side * dot(v, hit.ns) <= 0.0 || side * dot(dir, hit.ng) <= 0.0) {
        return absorbed();
    }
    return Scatter(true, dir / len, p.albedo, 0.0, true);
}
