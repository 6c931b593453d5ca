// type = "principled": the Disney principled BSDF as Mitsuba 3 defines it
// (scene::materials::principled, which gives the formulas; CPU twin
// cpu/materials/principled.rs).
#import shared/bindings
#import shared/bsdf
#import shared/sampling
#import shared/textures
#import shared/types

// The scalars' textures (two 16-bit indices a word, 0xffff none): each replaces its
// scalar by its luminance, in [0, 1]. One look-up in a loop, so that the texture code is
// compiled once.
fn principled_textures(p: PrincipledParams, hit: Hit) -> PrincipledParams {
    var q = p;
    var words = array<u32, 5>(p.textures0, p.textures1, p.textures2, p.textures3, p.textures4);
    var s = array<f32, 10>(p.roughness, p.anisotropic, p.metallic, p.spec_trans, p.spec_tint, p.sheen, p.sheen_tint, p.flatness, p.clearcoat, p.clearcoat_gloss);
    for (var i = 0u; i < 10u; i++) {
        let t = (words[i >> 1u] >> (16u * (i & 1u))) & 0xffffu;
        if (t != 0xffffu) {
            s[i] = clamp(luminance(texture_at(t, hit)), 0.0, 1.0);
        }
    }
    q.roughness = s[0];
    q.anisotropic = s[1];
    q.metallic = s[2];
    q.spec_trans = s[3] * p.transmits;
    q.spec_tint = s[4];
    q.sheen = s[5];
    q.sheen_tint = s[6];
    q.flatness = s[7];
    q.clearcoat = s[8];
    q.clearcoat_gloss = s[9];
    return q;
}

// Schlick's weight (1 - c)^5.
fn principled_schlick_weight(c: f32) -> f32 {
    let m = clamp(1.0 - c, 0.0, 1.0);
    return m * m * m * m * m;
}

// Schlick's Fresnel of reflectance r0 at the microfacet cosine c seen from outside,
// relative index eta: of c itself, or where eta < 1 of the refracted cosine (1 beyond
// total internal reflection).
fn principled_schlick(r0: vec3<f32>, c: f32, eta: f32) -> vec3<f32> {
    var w = principled_schlick_weight(abs(c));
    if (eta <= 1.0) {
        let cos2_t = 1.0 - (1.0 - c * c) / (eta * eta);
        w = principled_schlick_weight(sqrt(max(0.0, cos2_t)));
    }
    return r0 + (vec3<f32>(1.0) - r0) * w;
}

// The exact dielectric Fresnel reflectance at cosine c > 0 toward a side of relative
// index e (eta_t / eta_i; 1 under total internal reflection).
fn principled_fresnel(c: f32, e: f32) -> f32 {
    let eta = 1.0 / e;
    let sin2_t = eta * eta * max(0.0, 1.0 - c * c);
    return select(fresnel_dielectric(c, sqrt(max(0.0, 1.0 - sin2_t)), eta), 1.0, sin2_t >= 1.0);
}

// base_color's hue: over its luminance (white where it is black).
fn principled_tint(base: vec3<f32>) -> vec3<f32> {
    let lum = luminance(base);
    return select(vec3<f32>(1.0), base / lum, lum > 0.0);
}

// The main lobes' GGX: alpha = max(0.001, roughness^2), stretched by anisotropic.
fn principled_microfacet(p: PrincipledParams) -> Microfacet {
    let r2 = p.roughness * p.roughness;
    let aspect = sqrt(1.0 - 0.9 * p.anisotropic);
    return Microfacet(max(0.001, r2 / aspect), max(0.001, r2 * aspect), false);
}

// The clearcoat's GTR1 alpha.
fn principled_coat_alpha(p: PrincipledParams) -> f32 {
    return mix(0.1, 0.001, p.clearcoat_gloss);
}

// GTR1's density of normals at cosine c (projected: integrates to 1 against c).
fn principled_gtr1(c: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let d = (a2 - 1.0) / (PI * log(a2) * (1.0 + (a2 - 1.0) * c * c));
    return select(0.0, d, c > 0.0 && d * c > 1e-20);
}

// Whether wo sees the inside of a transmitting one (its back side); one that does not
// transmit is seen from outside on both sides.
fn principled_outside(p: PrincipledParams) -> bool {
    return p.back_face < 0.5 || p.transmits < 0.5;
}

// (probability of the diffuse lobe, of the clearcoat, of transmission given the main
// specular lobes) for wo at cos_o, relative index e: the lobes' weights as Mitsuba
// normalizes them, the transmission by the mean surface's Fresnel (kept in [0.1, 0.9],
// depending on wo only, so that the pdf is exact).
fn principled_probs(p: PrincipledParams, outside: bool, cos_o: f32, e: f32) -> vec3<f32> {
    let bsdf = (1.0 - p.metallic) * p.spec_trans;
    let t = select(0.0, clamp(1.0 - principled_fresnel(cos_o, e), 0.1, 0.9), bsdf > 0.0);
    if (!outside) {
        return vec3<f32>(0.0, 0.0, t);
    }
    let brdf = (1.0 - p.metallic) * (1.0 - p.spec_trans);
    let coat = 0.25 * p.clearcoat;
    let total = 1.0 + coat + brdf;
    return vec3<f32>(brdf / total, coat / total, bsdf * t);
}

// The probability of sampling the energy compensation's lobe (by the cosine) seen from
// outside at cos_o; 0 without it.
fn principled_ms_prob(p: PrincipledParams, outside: bool, cos_o: f32) -> f32 {
#ifdef HAS_ENERGY_COMPENSATION
    if (outside && (p.flags & MAT_FLAG_ENERGY) != 0u) {
        let m = principled_microfacet(p);
        return ms_loss(MS_GGX_SEPARABLE, ms_alpha(m.alpha_u, m.alpha_v), cos_o);
    }
#endif
    return 0.0;
}

#ifdef HAS_ENERGY_COMPENSATION
// The compensation lobe x cos_i of the main reflection, coloured by its Fresnel's
// average: the dielectric's exact one, Schlick's of the metal and of the tint.
fn principled_ms(p: PrincipledParams, cos_o: f32, cos_i: f32) -> vec3<f32> {
    let m = principled_microfacet(p);
    let r = (p.eta - 1.0) / (p.eta + 1.0);
    let r0 = principled_tint(p.base_color) * (r * r);
    let f_avg = vec3<f32>((1.0 - p.metallic) * (1.0 - p.spec_tint) * p.fresnel_avg)
        + p.metallic * (p.base_color + (vec3<f32>(1.0) - p.base_color) / 21.0)
        + (1.0 - p.metallic) * p.spec_tint * (r0 + (vec3<f32>(1.0) - r0) / 21.0);
    return ms_lobe(MS_GGX_SEPARABLE, ms_alpha(m.alpha_u, m.alpha_v), cos_o, cos_i, f_avg);
}
#endif

// wo and wi in the frame of the tangent about n, and the microfacet normal that joins
// them on wo's side: the half vector of a reflection, lo + e li of a refraction.
fn principled_local(p: PrincipledParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, e: f32) -> array<vec3<f32>, 3> {
    let tb = tangent_frame(n, p.tangent);
    let lo = vec3<f32>(dot(wo, tb[0]), dot(wo, tb[1]), dot(wo, n));
    let li = vec3<f32>(dot(wi, tb[0]), dot(wi, tb[1]), dot(wi, n));
    var h = select(lo + e * li, lo + li, li.z > 0.0);
    let len = length(h);
    h = select(vec3<f32>(0.0, 0.0, 1.0), h / len, len > 0.0);
    return array<vec3<f32>, 3>(lo, li, select(-h, h, h.z >= 0.0));
}

// BSDF x |cos_i| for unit wo and wi about the unit normal n on wo's side (the module's
// formulas).
fn principled_eval(p: PrincipledParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let cos_o = dot(n, wo);
    let cos_i = dot(n, wi);
    let outside = principled_outside(p);
    let e = select(1.0 / p.eta, p.eta, outside);
    let bsdf = (1.0 - p.metallic) * p.spec_trans;
    let brdf = (1.0 - p.metallic) * (1.0 - p.spec_trans);
    if (cos_o <= 0.0 || cos_i == 0.0 || (cos_i < 0.0 && !(bsdf > 0.0))) {
        return vec3<f32>(0.0);
    }
    let l = principled_local(p, n, wo, wi, e);
    let h = l[2];
    let oh = dot(l[0], h);
    let ih = dot(l[1], h);
    let m = principled_microfacet(p);
    let f = principled_fresnel(max(oh, 0.0), e);
    let dg = mf_d(m, h) * mf_g1(m, l[0], h) * mf_g1(m, l[1], h);
    if (cos_i < 0.0) {
        if (oh <= 0.0 || ih >= 0.0 || f >= 1.0) {
            return vec3<f32>(0.0);
        }
        let denom = oh + e * ih;
        return sqrt(p.base_color) * (bsdf * (1.0 - f) * dg * abs(oh * ih) / (cos_o * denom * denom));
    }
    if (oh <= 0.0 || ih <= 0.0) {
        return vec3<f32>(0.0);
    }
    if (!outside) {
        return vec3<f32>(bsdf * f * dg / (4.0 * cos_o));
    }
    var value = vec3<f32>(0.0);
    if (f > 0.0) {
        let tint = principled_tint(p.base_color);
        let r = (p.eta - 1.0) / (p.eta + 1.0);
        let fp = vec3<f32>((1.0 - p.metallic) * (1.0 - p.spec_tint) * f)
            + p.metallic * principled_schlick(p.base_color, oh, p.eta)
            + (1.0 - p.metallic) * p.spec_tint * principled_schlick(tint * (r * r), oh, p.eta);
        value = fp * (dg / (4.0 * cos_o));
    }
    if (p.clearcoat > 0.0) {
        let coat = Microfacet(0.25, 0.25, false);
        let g = mf_g1(coat, l[0], h) * mf_g1(coat, l[1], h);
        let fc = principled_schlick(vec3<f32>(0.04), oh, p.eta).x;
        value += vec3<f32>(0.25 * p.clearcoat * fc * principled_gtr1(h.z, principled_coat_alpha(p)) * g * cos_i);
    }
    if (brdf > 0.0) {
        let fo = principled_schlick_weight(cos_i);
        let fi = principled_schlick_weight(cos_o);
        let f_diff = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo);
        let rr = 2.0 * p.roughness * ih * ih;
        let f_retro = rr * (fo + fi + fo * fi * (rr - 1.0));
        let fss = mix(1.0, 0.5 * rr, fo) * mix(1.0, 0.5 * rr, fi);
        let f_ss = 1.25 * (fss * (1.0 / (cos_o + cos_i) - 0.5) + 0.5);
        value += p.base_color * (brdf * cos_i / PI * mix(f_diff + f_retro, f_ss, p.flatness));
        if (p.sheen > 0.0) {
            let sheen = mix(vec3<f32>(1.0), principled_tint(p.base_color), p.sheen_tint);
            value += sheen * (p.sheen * (1.0 - p.metallic) * principled_schlick_weight(ih) * cos_i);
        }
    }
#ifdef HAS_ENERGY_COMPENSATION
    if ((p.flags & MAT_FLAG_ENERGY) != 0u) {
        value += principled_ms(p, cos_o, cos_i);
    }
#endif
    return value;
}

// The pdf of principled_scatter's directions: the compensation's cosine lobe by
// principled_ms_prob, the others' (principled_lobes_pdf) with the rest.
fn principled_pdf(p: PrincipledParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    let pdf = principled_lobes_pdf(p, n, wo, wi);
#ifdef HAS_ENERGY_COMPENSATION
    let p_ms = principled_ms_prob(p, principled_outside(p), dot(n, wo));
    return (1.0 - p_ms) * pdf + p_ms * max(dot(n, wi), 0.0) / PI;
#else
    return pdf;
#endif
}

// The pdf of the lobes but the compensation's: the cosine lobe, GTR1's normals and the
// visible normals of the main lobes through the reflection (1 / (4 wo . h)) or the
// refraction (e^2 |wi . h| / (wo . h + e wi . h)^2), by principled_probs.
fn principled_lobes_pdf(p: PrincipledParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    let cos_o = dot(n, wo);
    let cos_i = dot(n, wi);
    let outside = principled_outside(p);
    let e = select(1.0 / p.eta, p.eta, outside);
    if (cos_o <= 0.0 || cos_i == 0.0) {
        return 0.0;
    }
    let probs = principled_probs(p, outside, cos_o, e);
    let spec = 1.0 - probs.x - probs.y;
    let l = principled_local(p, n, wo, wi, e);
    let h = l[2];
    let oh = dot(l[0], h);
    let ih = dot(l[1], h);
    let visible = mf_pdf_visible(principled_microfacet(p), l[0], h);
    if (cos_i < 0.0) {
        if (oh <= 0.0 || ih >= 0.0) {
            return 0.0;
        }
        let denom = oh + e * ih;
        return spec * probs.z * visible * e * e * abs(ih) / (denom * denom);
    }
    if (oh <= 0.0 || ih <= 0.0) {
        return 0.0;
    }
    // a refraction chosen at a microfacet that reflects totally reflects
    let tir = (1.0 - oh * oh) >= e * e;
    let reflect = select(1.0 - probs.z, 1.0, tir);
    let coat = probs.y * principled_gtr1(h.z, principled_coat_alpha(p)) * h.z;
    return (spec * reflect * visible + coat) / (4.0 * oh) + probs.x * cos_i / PI;
}

// The diffuse lobe (cosine), the clearcoat (a GTR1 normal) or the main lobes (a visible
// normal, then reflection or refraction through it) by principled_probs, u.x reused;
// weight eval / pdf. A reflection under the surface or a refraction over it is absorbed,
// and a direction on the wrong side of the geometric surface (one that does not
// transmit sends it over the surface first, as every reflector).
fn principled_scatter(p: PrincipledParams, ray: Ray, hit: Hit, u0: vec2<f32>) -> Scatter {
    var q = p;
    q.back_face = select(1.0, 0.0, hit.front_face);
    let side = select(-1.0, 1.0, hit.front_face);
    let n = side * hit.ns;
    let wo = -ray.dir;
    let cos_o = dot(n, wo);
    if (cos_o <= 0.0) {
        return absorbed();
    }
    let outside = principled_outside(q);
    let e = select(1.0 / q.eta, q.eta, outside);
    let probs = principled_probs(q, outside, cos_o, e);
    let tb = tangent_frame(n, q.tangent);
    var wi = vec3<f32>(0.0);
    var refracted = false;
    var u = u0;
#ifdef HAS_ENERGY_COMPENSATION
    // the compensation's cosine lobe with principled_ms_prob, u.x reused
    let p_ms = principled_ms_prob(q, outside, cos_o);
    let chose_ms = u.x < p_ms;
    u.x = select((u.x - p_ms) / (1.0 - p_ms), u.x / p_ms, chose_ms);
    if (chose_ms) {
        wi = sample_cosine_hemisphere(n, u);
    } else {
#endif
    if (u.x < probs.x) {
        wi = sample_cosine_hemisphere(n, vec2<f32>(u.x / probs.x, u.y));
    } else if (u.x < probs.x + probs.y) {
        let a2 = principled_coat_alpha(q) * principled_coat_alpha(q);
        let cos2 = (1.0 - pow(a2, 1.0 - u.y)) / (1.0 - a2);
        let sin_t = sqrt(max(0.0, 1.0 - cos2));
        let phi = 2.0 * PI * (u.x - probs.x) / probs.y;
        let h = sin_t * cos(phi) * tb[0] + sin_t * sin(phi) * tb[1] + sqrt(max(0.0, cos2)) * n;
        wi = normalize(2.0 * dot(wo, h) * h - wo);
    } else {
        let x = (u.x - probs.x - probs.y) / (1.0 - probs.x - probs.y);
        let refracts = x < probs.z;
        let xh = select((x - probs.z) / (1.0 - probs.z), x / probs.z, refracts);
        let lo = vec3<f32>(dot(wo, tb[0]), dot(wo, tb[1]), cos_o);
        let h_l = mf_sample_visible(principled_microfacet(q), lo, vec2<f32>(min(xh, 0.99999994), u.y));
        let h = h_l.x * tb[0] + h_l.y * tb[1] + h_l.z * n;
        let oh = dot(wo, h);
        let eta = 1.0 / e;
        let sin2_t = eta * eta * max(0.0, 1.0 - oh * oh);
        if (refracts && sin2_t < 1.0) {
            refracted = true;
            wi = normalize(-eta * wo + (eta * oh - sqrt(1.0 - sin2_t)) * h);
        } else {
            wi = normalize(2.0 * oh * h - wo);
        }
    }
#ifdef HAS_ENERGY_COMPENSATION
    }
#endif
    let f = principled_eval(q, n, wo, wi);
    let pdf = principled_pdf(q, n, wo, wi);
    if (q.transmits < 0.5) {
        return density_sample(wi, f, pdf, side, hit);
    }
    // a reflection under the surface, or a refraction over it, is not what the lobe
    // that drew it weighs (its pdf is the other lobes')
    let over = dot(wi, n) > 0.0;
    if (!(pdf > 0.0) || over == refracted || (side * dot(wi, hit.ng) > 0.0) != over) {
        return absorbed();
    }
    return Scatter(true, wi, f / pdf, pdf, false);
}
