// type = "microfacet": Cook-Torrance, a GGX lobe over a Lambertian base
// (scene::materials::microfacet; CPU twin cpu/materials/microfacet.rs).
#import shared/bsdf
#import shared/types

// Probability of sampling the specular lobe: its share by Fresnel at the view angle and the
// lobes' colours, kept in [0.1, 0.9] when both lobes reflect. It depends on wo only, so
// the mixture's pdf is exact.
// With energy compensation the cosine lobe samples the compensation's lobe too, weighted
// by what the GGX lobe loses.
fn microfacet_spec_prob(p: MicrofacetParams, cos_o: f32) -> f32 {
    let f = schlick(cos_o, p.ior);
    var wd = luminance(p.diffuse) * (1.0 - f);
#ifdef HAS_ENERGY_COMPENSATION
    if ((p.flags & MAT_FLAG_ENERGY) != 0u && p.alpha >= ALPHA_SMOOTH) {
        wd += luminance(p.specular) * ms_loss(MS_GGX_CORRELATED, p.alpha, cos_o);
    }
#endif
    return lobe_prob(luminance(p.specular) * f, wd);
}

// Cook-Torrance BSDF x cos(theta_i), for unit wo and wi about the unit normal n on wo's side:
// ks D G2 F / (4 cos_o) + kd (1 - F(cos_i)) (1 - F(cos_o)) cos_i / pi. G2 is Smith's
// height-correlated masking-shadowing, F Schlick's from the ior. With energy
// compensation, Kulla and Conty's lobe for the GGX lobe's multiple scattering, and the
// base weighted by what the compensated lobe leaves of both directions (ms_under)
// instead of by the Fresnel of both. The diffuse base gets the
// light the Fresnel of both directions lets through, which keeps the sum reciprocal and
// within energy conservation (the white furnace test checks it). The mirror lobe, when
// smooth, is a delta and left out.
fn microfacet_eval(p: MicrofacetParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let cos_o = dot(n, wo);
    let cos_i = dot(n, wi);
    if (cos_o <= 0.0 || cos_i <= 0.0) {
        return vec3<f32>(0.0);
    }
    let alpha = p.alpha;
    let ior = p.ior;
    let diff = (1.0 - schlick(cos_i, ior)) * (1.0 - schlick(cos_o, ior)) * cos_i / PI;
    if (alpha < ALPHA_SMOOTH) {
        return p.diffuse * diff;
    }
    let h = normalize(wo + wi);
    let spec = ggx_d(dot(n, h), alpha) * smith_g2(cos_o, cos_i, alpha) * schlick(dot(wi, h), ior) / (4.0 * cos_o);
#ifdef HAS_ENERGY_COMPENSATION
    // compensated: the lobe's multiple scattering, and the base under what the whole
    // lobe reflects (ks times Schlick's from F0 to 1)
    if ((p.flags & MAT_FLAG_ENERGY) != 0u) {
        let r = (1.0 - ior) / (1.0 + ior);
        let f0 = p.specular * (r * r);
        let under = ms_under(MS_GGX_CORRELATED, alpha, cos_o, cos_i, f0, p.specular);
        let ms = ms_lobe(MS_GGX_CORRELATED, alpha, cos_o, cos_i, f0 + (p.specular - f0) / 21.0);
        return p.specular * spec + ms + p.diffuse * under * (cos_i / PI);
    }
#endif
    return p.specular * spec + p.diffuse * diff;
}

// The pdf of microfacet_scatter's directions.
fn microfacet_pdf(p: MicrofacetParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    return ggx_lobes_pdf(microfacet_spec_prob(p, dot(n, wo)), p.alpha, n, wo, wi);
}

// The specular lobe (a visible normal, then the mirror direction about it; the mirror
// direction itself when smooth) or the diffuse one (cosine), chosen by
// microfacet_spec_prob with u.x reused; weight = eval / pdf of the whole mixture. A
// direction under the geometric surface is absorbed.
fn microfacet_scatter(p: MicrofacetParams, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
    let side = select(-1.0, 1.0, hit.front_face);
    let n = side * hit.ns;
    let wo = -ray.dir;
    let cos_o = dot(n, wo);
    if (cos_o <= 0.0) {
        return absorbed();
    }
    let p_s = microfacet_spec_prob(p, cos_o);
    let is_smooth = p.alpha < ALPHA_SMOOTH;
    if (is_smooth && u.x < p_s) {
        // the mirror lobe: weight = ks F(cos_o) / p_s
        let wi = over_surface(reflect_dir(ray.dir, n), side, hit);
        if (side * dot(wi, hit.ng) <= 0.0) {
            return absorbed();
        }
        return Scatter(true, wi, p.specular * (schlick(cos_o, p.ior) / p_s), 0.0, true);
    }
    let wi = sample_ggx_lobes(p_s, p.alpha, n, wo, u);
    return density_sample(wi, microfacet_eval(p, n, wo, wi), microfacet_pdf(p, n, wo, wi), side, hit);
}
