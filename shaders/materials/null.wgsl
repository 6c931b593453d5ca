// type = "null": a boundary with no surface (scene::materials::null; CPU twin
// cpu/materials/null.rs). Its opacity is 0, so the alpha loop passes rays through it; a
// ray that meets it after the loop's last pass-through goes straight on.
#import shared/bsdf
#import shared/types

// Straight on, weight 1, a delta.
fn null_scatter(p: NullParams, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
    return Scatter(true, ray.dir, vec3<f32>(1.0), 0.0, true);
}
