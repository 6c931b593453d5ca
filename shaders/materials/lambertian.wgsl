// type = "lambertian": the ideal diffuse reflector (scene::materials::lambertian; CPU twin
// cpu/materials/lambertian.rs). LambertianParams and lambertian_params() are written from
// its view.
#import shared/bsdf
#import shared/sampling
#import shared/types

// Cosine-weighted about the shading normal on the side the ray came from, so either side
// of a surface scatters; weight = albedo exactly. A direction that a shading normal tilts
// under the geometric surface is sent over it (over_surface); its pdf is the drawn one's.
fn lambertian_scatter(p: LambertianParams, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
    let side = select(-1.0, 1.0, hit.front_face);
    let drawn = sample_cosine_hemisphere(side * hit.ns, u);
    let dir = over_surface(drawn, side, hit);
    if (side * dot(dir, hit.ng) <= 0.0) {
        return absorbed();
    }
    return Scatter(true, dir, p.albedo, dot(side * hit.ns, drawn) / PI, false);
}

// albedo / pi x cos.
fn lambertian_eval(p: LambertianParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    return p.albedo * (max(0.0, dot(n, wi)) / PI);
}

fn lambertian_pdf(p: LambertianParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    return max(0.0, dot(n, wi)) / PI;
}
