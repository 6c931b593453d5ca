// type = "conductor": a metal by its complex index of refraction, smooth or GGX/Beckmann
// rough, isotropic or not (scene::materials::conductor; CPU twin
// cpu/materials/conductor.rs).
#import shared/bsdf
#import shared/sampling
#import shared/types

// Its microfacet distribution.
fn conductor_microfacet(p: ConductorParams) -> Microfacet {
    return Microfacet(p.alpha_u, p.alpha_v, p.beckmann > 0.5);
}

// BSDF x cos for unit wo and wi about the unit normal n on wo's side: specular x
// F(wo . h) D(h) G1(wo) G1(wi) / (4 cos_o), in the frame of the tangent (the normal's
// own where there is none); 0 when smooth (the mirror is a delta).
fn conductor_eval(p: ConductorParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let cos_o = dot(n, wo);
    let cos_i = dot(n, wi);
    if (cos_o <= 0.0 || cos_i <= 0.0 || max(p.alpha_u, p.alpha_v) < ALPHA_SMOOTH) {
        return vec3<f32>(0.0);
    }
    let m = conductor_microfacet(p);
    let tb = tangent_frame(n, p.tangent);
    let lo = vec3<f32>(dot(wo, tb[0]), dot(wo, tb[1]), cos_o);
    let li = vec3<f32>(dot(wi, tb[0]), dot(wi, tb[1]), cos_i);
    let h = normalize(lo + li);
    let g = mf_g1(m, lo, h) * mf_g1(m, li, h);
    return p.specular * fresnel_conductor(dot(lo, h), p.eta, p.k) * (mf_d(m, h) * g / (4.0 * cos_o));
}

// The pdf of conductor_scatter's directions: the visible normal's density through the
// reflection, D(h) G1(wo) / (4 cos_o).
fn conductor_pdf(p: ConductorParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    let cos_o = dot(n, wo);
    let cos_i = dot(n, wi);
    if (cos_o <= 0.0 || cos_i <= 0.0 || max(p.alpha_u, p.alpha_v) < ALPHA_SMOOTH) {
        return 0.0;
    }
    let m = conductor_microfacet(p);
    let tb = tangent_frame(n, p.tangent);
    let lo = vec3<f32>(dot(wo, tb[0]), dot(wo, tb[1]), cos_o);
    let li = vec3<f32>(dot(wi, tb[0]), dot(wi, tb[1]), cos_i);
    let h = normalize(lo + li);
    return mf_pdf_visible(m, lo, h) / (4.0 * dot(lo, h));
}

// The mirror direction (smooth: weight specular x F(cos_o), a delta), or the mirror
// direction about a visible normal seen from wo (weight eval / pdf). A direction under
// the geometric surface is absorbed.
fn conductor_scatter(p: ConductorParams, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
    let side = select(-1.0, 1.0, hit.front_face);
    let n = side * hit.ns;
    let wo = -ray.dir;
    let cos_o = dot(n, wo);
    if (cos_o <= 0.0) {
        return absorbed();
    }
    if (max(p.alpha_u, p.alpha_v) < ALPHA_SMOOTH) {
        return mirror_scatter(ray, hit, side, n, p.specular * fresnel_conductor(cos_o, p.eta, p.k));
    }
    let tb = tangent_frame(n, p.tangent);
    let lo = vec3<f32>(dot(wo, tb[0]), dot(wo, tb[1]), cos_o);
    let h_l = mf_sample_visible(conductor_microfacet(p), lo, u);
    let h = h_l.x * tb[0] + h_l.y * tb[1] + h_l.z * n;
    let wi = normalize(2.0 * dot(wo, h) * h - wo);
    return density_sample(wi, conductor_eval(p, n, wo, wi), conductor_pdf(p, n, wo, wi), side, hit);
}
