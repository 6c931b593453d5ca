// type = "plastic": a dielectric coating, smooth or GGX/Beckmann rough, over a Lambertian
// base (scene::materials::plastic, which gives the formulas; CPU twin
// cpu/materials/plastic.rs).
#import shared/bindings
#import shared/bsdf
#import shared/sampling
#import shared/types

// The coating's exact Fresnel reflectance seen from outside at cosine c.
fn plastic_fresnel(c: f32, ior: f32) -> f32 {
    let eta = 1.0 / ior;
    let sin2_t = eta * eta * max(0.0, 1.0 - c * c);
    return select(fresnel_dielectric(c, sqrt(max(0.0, 1.0 - sin2_t)), eta), 1.0, sin2_t >= 1.0);
}

// The fraction of light at cosine c that the coating lets through: 1 - F when smooth,
// else its table (PLASTIC_TABLE_SIZE cosines from 0 to 1 in tables[p.table...]), linearly
// interpolated; a compensated coating also lets through its share b of what its
// microfacets lose, b (1 - E(c)) (shared/bsdf.wgsl's rough dielectrics).
fn plastic_transmittance(p: PlasticParams, c: f32) -> f32 {
    if (p.alpha < ALPHA_SMOOTH) {
        return 1.0 - plastic_fresnel(c, p.ior);
    }
    let x = clamp(c, 0.0, 1.0) * f32(PLASTIC_TABLE_SIZE - 1u);
    let i = min(u32(x), PLASTIC_TABLE_SIZE - 2u);
    let j = i + 1u;
    let a = tables[p.table + (i >> 2u)][i & 3u];
    let b = tables[p.table + (j >> 2u)][j & 3u];
    var t = mix(a, b, x - f32(i));
#ifdef HAS_ENERGY_COMPENSATION
    if (plastic_compensated(p)) {
        let v = plastic_ms_variant(p);
        let split = ms_dielectric_split(v, p.ior, p.alpha);
        t += split.x * max(1.0 - ms_dielectric_albedo(v, p.ior, 0u, c, p.alpha), 0.0);
    }
#endif
    return t;
}

// The base's albedo as the coating's inner reflections leave it: over 1 - R_int, or
// 1 - albedo R_int when nonlinear; a compensated coating's R_int also holds the share
// 1 - b' of what it loses inside on average, (1 - b') (1 - E'_avg).
fn plastic_diffuse(p: PlasticParams) -> vec3<f32> {
    var internal = p.internal;
#ifdef HAS_ENERGY_COMPENSATION
    if (plastic_compensated(p)) {
        let split = ms_dielectric_split(plastic_ms_variant(p), p.ior, p.alpha);
        internal += (1.0 - split.y) * split.w;
    }
#endif
    let r = select(vec3<f32>(internal), p.diffuse * internal, p.nonlinear > 0.5);
    return p.diffuse / (vec3<f32>(1.0) - r);
}

#ifdef HAS_ENERGY_COMPENSATION
// Whether the coating gives back what its microfacets lose to multiple scattering:
// rough, of ior above 1, with MAT_FLAG_ENERGY.
fn plastic_compensated(p: PlasticParams) -> bool {
    return (p.flags & MAT_FLAG_ENERGY) != 0u && p.alpha >= ALPHA_SMOOTH && p.ior > 1.0;
}

// The dielectric tables' variant of the coating (separable masking).
fn plastic_ms_variant(p: PlasticParams) -> u32 {
    return select(MS_DIELECTRIC_GGX_SEPARABLE, MS_DIELECTRIC_BECKMANN_SEPARABLE, p.beckmann > 0.5);
}
#endif

// The probability of sampling the coating seen at cos_o: its reflected share weighed by
// spec_weight against the base's, as Mitsuba's plastics choose.
fn plastic_spec_prob(p: PlasticParams, cos_o: f32) -> f32 {
    let t = plastic_transmittance(p, cos_o);
    let s = (1.0 - t) * p.spec_weight;
    let d = t * (1.0 - p.spec_weight);
    return select(s / (s + d), 0.0, s + d <= 0.0);
}

// BSDF x cos: the base, diffuse T(cos_o) T(cos_i) cos_i / (pi ior^2), plus a rough
// coating's specular F(wo . h) D(h) G1(wo) G1(wi) / (4 cos_o) (a smooth one's mirror is a
// delta, left out), and a compensated coating's reflected share of its microfacets'
// multiple scattering (ms_dielectric_lobe), tinted as the specular. (Its sampling needs
// nothing new: the base's cosine lobe covers it.)
fn plastic_eval(p: PlasticParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let cos_o = dot(n, wo);
    let cos_i = dot(n, wi);
    if (cos_o <= 0.0 || cos_i <= 0.0) {
        return vec3<f32>(0.0);
    }
    let base = plastic_diffuse(p) * (plastic_transmittance(p, cos_o) * plastic_transmittance(p, cos_i) * cos_i / (PI * p.ior * p.ior));
    if (p.alpha < ALPHA_SMOOTH) {
        return base;
    }
    let m = Microfacet(p.alpha, p.alpha, p.beckmann > 0.5);
    let tb = onb_tangents(n);
    let lo = vec3<f32>(dot(wo, tb[0]), dot(wo, tb[1]), cos_o);
    let li = vec3<f32>(dot(wi, tb[0]), dot(wi, tb[1]), cos_i);
    let h = normalize(lo + li);
    let g = mf_g1(m, lo, h) * mf_g1(m, li, h);
    var spec = plastic_fresnel(dot(lo, h), p.ior) * mf_d(m, h) * g / (4.0 * cos_o);
#ifdef HAS_ENERGY_COMPENSATION
    if (plastic_compensated(p)) {
        spec += ms_dielectric_lobe(plastic_ms_variant(p), p.ior, p.alpha, 0u, cos_o, cos_i);
    }
#endif
    return p.specular * spec + base;
}

// The pdf of plastic_scatter's directions: the coating's visible normals through the
// reflection, D(h) G1(wo) / (4 cos_o), with plastic_spec_prob (when rough), else the
// cosine lobe.
fn plastic_pdf(p: PlasticParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    let cos_o = dot(n, wo);
    let cos_i = dot(n, wi);
    if (cos_o <= 0.0 || cos_i <= 0.0) {
        return 0.0;
    }
    let p_s = plastic_spec_prob(p, cos_o);
    let diff = (1.0 - p_s) * cos_i / PI;
    if (p.alpha < ALPHA_SMOOTH) {
        return diff;
    }
    let m = Microfacet(p.alpha, p.alpha, p.beckmann > 0.5);
    let tb = onb_tangents(n);
    let lo = vec3<f32>(dot(wo, tb[0]), dot(wo, tb[1]), cos_o);
    let li = vec3<f32>(dot(wi, tb[0]), dot(wi, tb[1]), cos_i);
    let h = normalize(lo + li);
    return p_s * mf_pdf_visible(m, lo, h) / (4.0 * dot(lo, h)) + diff;
}

// The coating (its mirror when smooth, weight specular F(cos_o) / p_s, a delta; else the
// mirror direction about a visible normal) with probability plastic_spec_prob, u.x
// reused, or the base (cosine); weight eval / pdf. A direction under the geometric
// surface is absorbed.
fn plastic_scatter(p: PlasticParams, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
    let side = select(-1.0, 1.0, hit.front_face);
    let n = side * hit.ns;
    let wo = -ray.dir;
    let cos_o = dot(n, wo);
    if (cos_o <= 0.0) {
        return absorbed();
    }
    let p_s = plastic_spec_prob(p, cos_o);
    let is_smooth = p.alpha < ALPHA_SMOOTH;
    if (is_smooth && u.x < p_s) {
        return mirror_scatter(ray, hit, side, n, p.specular * (plastic_fresnel(cos_o, p.ior) / p_s));
    }
    var wi = vec3<f32>(0.0);
    if (u.x < p_s) {
        let tb = onb_tangents(n);
        let lo = vec3<f32>(dot(wo, tb[0]), dot(wo, tb[1]), cos_o);
        let h_l = mf_sample_visible(Microfacet(p.alpha, p.alpha, p.beckmann > 0.5), lo, vec2<f32>(u.x / p_s, u.y));
        let h = h_l.x * tb[0] + h_l.y * tb[1] + h_l.z * n;
        wi = normalize(2.0 * dot(wo, h) * h - wo);
    } else {
        wi = sample_cosine_hemisphere(n, vec2<f32>((u.x - p_s) / (1.0 - p_s), u.y));
    }
    return density_sample(wi, plastic_eval(p, n, wo, wi), plastic_pdf(p, n, wo, wi), side, hit);
}
