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

// The probability of sampling the energy compensation's lobe seen at cos_o (0 without
// it), and the lobe x cos_i: Kulla and Conty's, of the tables of the distribution with
// separable masking, at the geometric mean of an anisotropic alpha.
fn conductor_ms_prob(p: ConductorParams, cos_o: f32) -> f32 {
#ifdef HAS_ENERGY_COMPENSATION
    if ((p.flags & MAT_FLAG_ENERGY) != 0u) {
        return ms_loss(select(MS_GGX_SEPARABLE, MS_BECKMANN_SEPARABLE, p.beckmann > 0.5), ms_alpha(p.alpha_u, p.alpha_v), cos_o);
    }
#endif
    return 0.0;
}

#ifdef HAS_ENERGY_COMPENSATION
fn conductor_ms(p: ConductorParams, cos_o: f32, cos_i: f32) -> vec3<f32> {
    if ((p.flags & MAT_FLAG_ENERGY) == 0u) {
        return vec3<f32>(0.0);
    }
    let variant = select(MS_GGX_SEPARABLE, MS_BECKMANN_SEPARABLE, p.beckmann > 0.5);
    return ms_lobe(variant, ms_alpha(p.alpha_u, p.alpha_v), cos_o, cos_i, p.specular * p.fresnel_avg);
}
#endif

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
    var f = p.specular * fresnel_conductor(dot(lo, h), p.eta, p.k) * (mf_d(m, h) * g / (4.0 * cos_o));
#ifdef HAS_ENERGY_COMPENSATION
    f += conductor_ms(p, cos_o, cos_i);
#endif
    return f;
}

// The pdf of conductor_scatter's directions: the visible normal's density through the
// reflection, D(h) G1(wo) / (4 cos_o) (and with energy compensation, the cosine lobe's by
// conductor_ms_prob).
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
    let pdf = mf_pdf_visible(m, lo, h) / (4.0 * dot(lo, h));
#ifdef HAS_ENERGY_COMPENSATION
    let p_ms = conductor_ms_prob(p, cos_o);
    return (1.0 - p_ms) * pdf + p_ms * cos_i / PI;
#else
    return pdf;
#endif
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
#ifdef HAS_ENERGY_COMPENSATION
    // the compensation's cosine lobe with conductor_ms_prob, u.x reused
    let p_ms = conductor_ms_prob(p, cos_o);
    if (u.x < p_ms) {
        let wc = sample_cosine_hemisphere(n, vec2<f32>(u.x / p_ms, u.y));
        return density_sample(wc, conductor_eval(p, n, wo, wc), conductor_pdf(p, n, wo, wc), side, hit);
    }
    let h_l = mf_sample_visible(conductor_microfacet(p), lo, vec2<f32>((u.x - p_ms) / (1.0 - p_ms), u.y));
#else
    let h_l = mf_sample_visible(conductor_microfacet(p), lo, u);
#endif
    let h = h_l.x * tb[0] + h_l.y * tb[1] + h_l.z * n;
    let wi = normalize(2.0 * dot(wo, h) * h - wo);
    return density_sample(wi, conductor_eval(p, n, wo, wi), conductor_pdf(p, n, wo, wi), side, hit);
}
