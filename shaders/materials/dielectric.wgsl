// type = "dielectric": glass, smooth or rough (scene::materials::dielectric; CPU twin
// cpu/materials/dielectric.rs).
#import shared/bsdf
#import shared/sampling
#import shared/types

// eta = eta_i / eta_t (1 / ior entering, ior leaving, the normal turned toward the
// incoming ray). Snell's law in vector form, t = eta d + (eta cos_i - cos_t) n; total
// internal reflection when eta^2 sin^2(theta_i) >= 1; otherwise reflection with the exact
// Fresnel probability (fresnel_dielectric; ior 1 is invisible). Weight = specular for a
// reflection, tint for a refraction (absorption inside is a medium: media.wgsl).
// Deltas when smooth; a rough one (an alpha at least ALPHA_SMOOTH) scatters by
// dielectric_rough_scatter.
fn dielectric_scatter(p: DielectricParams, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
    let entering = hit.front_face;
    let n = select(-hit.ns, hit.ns, entering);
    let eta = select(p.ior, 1.0 / p.ior, entering);
#ifdef HAS_ROUGH_DIELECTRIC
    if (max(p.alpha, p.alpha_v) >= ALPHA_SMOOTH) {
        return dielectric_rough_scatter(p, ray, hit, n, eta, u);
    }
#endif
    let cos_i = clamp(-dot(ray.dir, n), 0.0, 1.0);
    let sin2_t = eta * eta * max(0.0, 1.0 - cos_i * cos_i);
    if (sin2_t >= 1.0) {
        return Scatter(true, reflect_dir(ray.dir, n), p.specular, 0.0, true);
    }
    let cos_t = sqrt(1.0 - sin2_t);
    if (u.x < fresnel_dielectric(cos_i, cos_t, eta)) {
        return Scatter(true, reflect_dir(ray.dir, n), p.specular, 0.0, true);
    }
    return Scatter(true, normalize(eta * ray.dir + (eta * cos_i - cos_t) * n), p.tint, 0.0, true);
}

#ifdef HAS_ROUGH_DIELECTRIC
// Compiled for scenes with rough glass only (llvmpipe runs an untaken branch under a
// mask, and smooth glass would pay for it).

// The exact Fresnel reflectance at cosine c > 0 on the side of relative index eta
// (1 under total internal reflection).
fn dielectric_fresnel(c: f32, eta: f32) -> f32 {
    let sin2_t = eta * eta * max(0.0, 1.0 - c * c);
    if (sin2_t >= 1.0) {
        return 1.0;
    }
    return fresnel_dielectric(c, sqrt(1.0 - sin2_t), eta);
}

// The probability of sampling reflection off a rough dielectric seen at cos_o: the
// Fresnel reflectance of the mean surface, kept in [0.1, 0.9]. It depends on wo only, so
// the pdf of the two lobes together is exact.
fn dielectric_reflect_prob(cos_o: f32, eta: f32) -> f32 {
    return clamp(dielectric_fresnel(cos_o, eta), 0.1, 0.9);
}

// The microfacet normal of wo and wi about n (wo's side, eta = eta_o / eta_i of the two
// sides): the half vector of a reflection, the generalized one eta wo + wi of a
// refraction (Walter et al. 2007), on n's side; zero when none is.
fn dielectric_half(n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, eta: f32) -> vec3<f32> {
    let reflected = dot(n, wi) > 0.0;
    var h = select(eta * wo + wi, wo + wi, reflected);
    let len = length(h);
    if (len == 0.0) {
        return vec3<f32>(0.0);
    }
    h = h / len;
    return select(-h, h, dot(h, n) > 0.0);
}

// Rough glass's microfacets: GGX or Beckmann, alpha along the tangent and the bitangent
// (in the frame tangent_frame makes of n and the hit's tangent).
fn dielectric_microfacet(p: DielectricParams) -> Microfacet {
    return Microfacet(p.alpha, p.alpha_v, p.beckmann > 0.5);
}

// Whether rough glass is other than isotropic GGX (Beckmann, or anisotropic): compiled
// for scenes that have such glass (HAS_GLASS_MICROFACETS), isotropic GGX keeps its own
// shorter code.
fn dielectric_general(p: DielectricParams) -> bool {
    return p.beckmann > 0.5 || p.alpha != p.alpha_v;
}

// Rough glass toward wi, for unit wo and wi about the unit normal n on wo's side,
// eta = eta_o / eta_i: (BSDF x |cos(theta_i)|, the pdf of dielectric_rough_scatter's
// directions), computed together since the scatter needs both.
// BSDF (microfacets D, Smith's height-correlated G2 = 1 / (1 + Lambda(wo) + Lambda(wi)),
// exact Fresnel F at wo . h): reflection F D G2 / (4 cos_o);
// refraction (Walter et al. 2007, for radiance: times eta^2, the 1 / eta_t^2 scaling of
// radiance across the boundary) eta^2 (1 - F) D G2 |wi . h| |wo . h| /
// ((wi . h + eta wo . h)^2 cos_o).
// pdf: a visible normal's density G1(wo) D(h) (wo . h) / cos_o, mapped through the
// reflection (1 / (4 wo . h)) with probability dielectric_reflect_prob (1 where h
// reflects totally: a refraction chosen there reflects instead), or through the
// refraction (|wi . h| / (wi . h + eta wo . h)^2) with the rest.
fn dielectric_rough_lobes(p: DielectricParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, eta: f32) -> vec2<f32> {
    let cos_o = dot(n, wo);
    let cos_i = dot(n, wi);
    let h = dielectric_half(n, wo, wi, eta);
    let oh = dot(wo, h);
    let ih = dot(wi, h);
    // a microfacet seen from both sides as the two directions need
    if (cos_o <= 0.0 || cos_i == 0.0 || oh <= 0.0 || ih * cos_i <= 0.0) {
        return vec2<f32>(0.0);
    }
    let alpha = p.alpha;
    var d = ggx_d(dot(n, h), alpha);
    var g2 = smith_g2(cos_o, abs(cos_i), alpha);
    var visible = d / ((1.0 + smith_lambda(cos_o, alpha)) * cos_o);
#ifdef HAS_GLASS_MICROFACETS
    if (dielectric_general(p)) {
        let m = dielectric_microfacet(p);
        let tb = tangent_frame(n, p.tangent);
        let lh = vec3<f32>(dot(h, tb[0]), dot(h, tb[1]), dot(h, n));
        let g_o = mf_g1(m, vec3<f32>(dot(wo, tb[0]), dot(wo, tb[1]), cos_o), lh);
        let g_i = mf_g1(m, vec3<f32>(dot(wi, tb[0]), dot(wi, tb[1]), cos_i), lh);
        d = mf_d(m, lh);
        // 1 / (1 + Lambda(wo) + Lambda(wi)), Lambda = 1 / G1 - 1
        g2 = select(0.0, g_o * g_i / (g_o + g_i - g_o * g_i), g_o * g_i > 0.0);
        visible = d * g_o / cos_o;
    }
#endif
    let f = dielectric_fresnel(oh, eta);
    let p_r = dielectric_reflect_prob(cos_o, eta);
    if (cos_i > 0.0) {
        let tir = eta * eta * (1.0 - oh * oh) >= 1.0;
        return vec2<f32>(f * d * g2 / (4.0 * cos_o), select(p_r, 1.0, tir) * visible / 4.0);
    }
    let denom = ih + eta * oh;
    let jacobian = abs(ih) * oh / (denom * denom);
    return vec2<f32>(eta * eta * (1.0 - f) * d * g2 * jacobian / cos_o, (1.0 - p_r) * visible * jacobian);
}

// Rough glass's lobes x |cos(theta_i)| toward wi and the pdf of dielectric_rough_scatter's
// directions: dielectric_rough_lobes, and with energy compensation its lobe
// (dielectric_ms_lobes) beside them.
fn dielectric_lobes(p: DielectricParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, eta: f32) -> vec2<f32> {
    let lobes = dielectric_rough_lobes(p, n, wo, wi, eta);
#ifdef HAS_ENERGY_COMPENSATION
    if (dielectric_compensated(p)) {
        let ms = dielectric_ms_lobes(p, n, wo, wi, eta);
        return vec2<f32>(lobes.x + ms.x, mix(lobes.y, ms.y, dielectric_ms_probs(p, dot(n, wo), eta).x));
    }
#endif
    return lobes;
}

#ifdef HAS_ENERGY_COMPENSATION
// Whether rough glass gives back what its microfacets lose to multiple scattering
// (MAT_FLAG_ENERGY).
fn dielectric_compensated(p: DielectricParams) -> bool {
    return (p.flags & MAT_FLAG_ENERGY) != 0u;
}

// The dielectric tables' variant of rough glass (height-correlated masking).
fn dielectric_ms_variant(p: DielectricParams) -> u32 {
    return select(MS_DIELECTRIC_GGX_CORRELATED, MS_DIELECTRIC_BECKMANN_CORRELATED, p.beckmann > 0.5);
}

// (the probability of sampling the compensation seen at cos_o, what it transmits of it)
// with eta = eta_o / eta_i: what the side loses, 1 - E(cos_o) (at most 0.9), and the
// side's b (ms_dielectric_split).
fn dielectric_ms_probs(p: DielectricParams, cos_o: f32, eta: f32) -> vec2<f32> {
    let v = dielectric_ms_variant(p);
    let ior = max(eta, 1.0 / eta);
    let side = select(1u, 0u, eta < 1.0);
    let alpha = ms_alpha(p.alpha, p.alpha_v);
    let loss = clamp(1.0 - ms_dielectric_albedo(v, ior, side, cos_o, alpha), 0.0, 0.9);
    let split = ms_dielectric_split(v, ior, alpha);
    return vec2<f32>(loss, select(split.x, split.y, side == 1u));
}

// The compensation x |cos(theta_i)| for radiance (ms_dielectric_lobe, times eta^2 where
// it transmits) and the density of its sampling: a cosine lobe on wo's side with 1 - b,
// on the other with b.
fn dielectric_ms_lobes(p: DielectricParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, eta: f32) -> vec2<f32> {
    let cos_o = dot(n, wo);
    let cos_i = dot(n, wi);
    let side = select(1u, 0u, eta < 1.0);
    let f = ms_dielectric_lobe(dielectric_ms_variant(p), max(eta, 1.0 / eta), ms_alpha(p.alpha, p.alpha_v), side, cos_o, cos_i);
    let b = dielectric_ms_probs(p, cos_o, eta).y;
    let transmits = cos_i < 0.0;
    return vec2<f32>(f * select(1.0, eta * eta, transmits), select(1.0 - b, b, transmits) * abs(cos_i) / PI);
}
#endif

// Rough glass: a visible normal h seen from wo (Heitz 2018), then the mirror direction
// about it (with probability dielectric_reflect_prob, u.x reused) or the refraction
// through it (the mirror direction where h reflects totally); with energy compensation,
// first its lobe with dielectric_ms_probs (a cosine direction, mirrored through the
// surface where it transmits). Weight = BSDF x cos / pdf (dielectric_lobes) times
// specular (reflected) or tint (transmitted). A direction on the wrong side of the
// geometric surface is absorbed. It has a density, which next-event estimation weighs
// (dielectric_eval, dielectric_pdf).
fn dielectric_rough_scatter(p: DielectricParams, ray: Ray, hit: Hit, n: vec3<f32>, eta: f32, u0: vec2<f32>) -> Scatter {
    let wo = -ray.dir;
    let cos_o = dot(n, wo);
    if (cos_o <= 0.0) {
        return absorbed();
    }
    var u = u0;
    var wi = vec3<f32>(0.0);
    var is_reflection = true;
    var sampled = false;
#ifdef HAS_ENERGY_COMPENSATION
    if (dielectric_compensated(p)) {
        let ms = dielectric_ms_probs(p, cos_o, eta);
        if (u.x < ms.x) {
            let v = u.x / ms.x;
            is_reflection = v >= ms.y;
            let w = select(v / ms.y, (v - ms.y) / (1.0 - ms.y), is_reflection);
            wi = sample_cosine_hemisphere(n, vec2<f32>(w, u.y));
            if (!is_reflection) {
                wi = wi - 2.0 * dot(wi, n) * n;
            }
            sampled = true;
        } else {
            u.x = (u.x - ms.x) / (1.0 - ms.x);
        }
    }
#endif
    if (!sampled) {
        let p_r = dielectric_reflect_prob(cos_o, eta);
        let chose_reflection = u.x < p_r;
        let uh = vec2<f32>(select((u.x - p_r) / (1.0 - p_r), u.x / p_r, chose_reflection), u.y);
        var tb = onb_tangents(n);
        var h_l = sample_ggx_vndf(vec3<f32>(dot(wo, tb[0]), dot(wo, tb[1]), cos_o), p.alpha, uh);
#ifdef HAS_GLASS_MICROFACETS
        if (dielectric_general(p)) {
            tb = tangent_frame(n, p.tangent);
            h_l = mf_sample_visible(dielectric_microfacet(p), vec3<f32>(dot(wo, tb[0]), dot(wo, tb[1]), cos_o), uh);
        }
#endif
        let h = h_l.x * tb[0] + h_l.y * tb[1] + h_l.z * n;
        let oh = dot(wo, h);
        let sin2_t = eta * eta * max(0.0, 1.0 - oh * oh);
        let cos_t = sqrt(max(0.0, 1.0 - sin2_t));
        is_reflection = chose_reflection || sin2_t >= 1.0;
        wi = select(normalize(-eta * wo + (eta * oh - cos_t) * h), normalize(2.0 * oh * h - wo), is_reflection);
    }
    let side = select(-1.0, 1.0, hit.front_face);
    let above = side * dot(wi, hit.ng) > 0.0;
    let lobes = dielectric_lobes(p, n, wo, wi, eta);
    if (!(lobes.y > 0.0) || above != is_reflection) {
        return absorbed();
    }
    let delta = !dielectric_has_density(p);
    let weight = select(p.tint, p.specular, is_reflection);
    return Scatter(true, wi, weight * (lobes.x / lobes.y), select(lobes.y, 0.0, delta), delta);
}

// Whether the glass has a density that light sampling weighs: rough
// (scene::materials::dielectric::has_density).
fn dielectric_has_density(p: DielectricParams) -> bool {
    return max(p.alpha, p.alpha_v) >= ALPHA_SMOOTH;
}

// eta = eta_o / eta_i at a hit: 1 / ior from outside (the front face), ior from inside.
fn dielectric_eta(p: DielectricParams) -> f32 {
    return select(1.0 / p.ior, p.ior, p.back_face > 0.0);
}
#endif

// Rough glass: specular (reflected) or tint (transmitted) x BSDF x
// |cos(theta_i)| toward wi (dielectric_lobes), n on wo's side; 0 for smooth glass's
// deltas.
fn dielectric_eval(p: DielectricParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
#ifdef HAS_ROUGH_DIELECTRIC
    if (dielectric_has_density(p)) {
        return select(p.tint, p.specular, dot(n, wi) > 0.0) * dielectric_lobes(p, n, wo, wi, dielectric_eta(p)).x;
    }
#endif
    return vec3<f32>(0.0);
}

// The density of dielectric_rough_scatter's directions where it has one (as
// dielectric_eval), else 0.
fn dielectric_pdf(p: DielectricParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
#ifdef HAS_ROUGH_DIELECTRIC
    if (dielectric_has_density(p)) {
        return dielectric_lobes(p, n, wo, wi, dielectric_eta(p)).y;
    }
#endif
    return 0.0;
}
