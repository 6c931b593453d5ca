// Materials: emission and scattering, dispatched by a switch on the material tag.
#import shared/sampling
#import shared/types

struct Scatter {
    // false: the path ends here (absorbed)
    ok: bool,
    dir: vec3<f32>,
    // BSDF * cos / pdf of the sampled direction
    weight: vec3<f32>,
    // the pdf of the sampled direction (what MIS weighs against light sampling)
    pdf: f32,
    // the direction came from a delta lobe (mirror, refraction; fuzzy metal too, whose pdf
    // has no closed form): no light sampling can produce it
    delta: bool,
}

// The path ends here.
fn absorbed() -> Scatter {
    return Scatter(false, vec3<f32>(0.0), vec3<f32>(0.0), 0.0, true);
}

// Radiance the surface emits toward the ray that hit it.
fn emitted(mat: Material, hit: Hit) -> vec3<f32> {
    if (hit.front_face || (mat.flags & MAT_FLAG_TWO_SIDED) != 0u) {
        return mat.emission.rgb;
    }
    return vec3<f32>(0.0);
}

// Lambertian: cosine-weighted about the shading normal on the side the ray came from, so
// either side of a surface scatters; weight = albedo exactly. A direction that an
// interpolated normal tilts under the geometric surface ends the path.
fn scatter_lambertian(mat: Material, hit: Hit, u: vec2<f32>) -> Scatter {
    let side = select(-1.0, 1.0, hit.front_face);
    let dir = sample_cosine_hemisphere(side * hit.ns, u);
    if (side * dot(dir, hit.ng) <= 0.0) {
        return absorbed();
    }
    return Scatter(true, dir, mat.albedo.rgb, dot(side * hit.ns, dir) / PI, false);
}

// Mirror direction of d about the unit normal n: d - 2 (d . n) n.
fn reflect_dir(d: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return d - 2.0 * dot(d, n) * n;
}

// Metal: the mirror direction about the shading normal, perturbed by fuzz x a uniform unit
// vector; weight = albedo. A direction under the geometric surface (or a perturbation that
// cancels the reflection) is absorbed.
fn scatter_metal(mat: Material, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
    let side = select(-1.0, 1.0, hit.front_face);
    let v = reflect_dir(ray.dir, side * hit.ns) + mat.params.x * sample_sphere(u);
    let len = length(v);
    if (!(len > 0.0) || side * dot(v, hit.ng) <= 0.0) {
        return absorbed();
    }
    return Scatter(true, v / len, mat.albedo.rgb, 0.0, true);
}

// Schlick's approximation of the Fresnel reflectance at cosine c between media of relative
// index eta: R0 + (1 - R0)(1 - c)^5, R0 = ((1 - eta) / (1 + eta))^2.
fn schlick(c: f32, eta: f32) -> f32 {
    let r = (1.0 - eta) / (1.0 + eta);
    let r0 = r * r;
    let m = 1.0 - c;
    return r0 + (1.0 - r0) * m * m * m * m * m;
}

// Fresnel reflectance of unpolarised light at a smooth dielectric boundary, exactly (the
// average of the s and p amplitudes squared), for cosines cos_i and cos_t on the two sides
// and eta = eta_i / eta_t. It is 0 at matched indices (eta = 1), where Schlick's
// approximation still reflects (1 - cos)^5 at grazing angles.
fn fresnel_dielectric(cos_i: f32, cos_t: f32, eta: f32) -> f32 {
    let r_pa = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let r_pe = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return 0.5 * (r_pa * r_pa + r_pe * r_pe);
}

// Dielectric: eta = eta_i / eta_t (1 / ior entering, ior leaving, the normal turned toward
// the incoming ray). Snell's law in vector form, t = eta d + (eta cos_i - cos_t) n; total
// internal reflection when eta^2 sin^2(theta_i) >= 1; otherwise reflection with the exact
// Fresnel probability (fresnel_dielectric; ior 1 is invisible). Weight = tint, times the
// Beer-Lambert transmittance exp(-absorption x distance) for a segment that ran inside.
fn scatter_dielectric(mat: Material, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
    let entering = hit.front_face;
    let n = select(-hit.ns, hit.ns, entering);
    let eta = select(mat.params.x, 1.0 / mat.params.x, entering);
    let cos_i = clamp(-dot(ray.dir, n), 0.0, 1.0);
    let sin2_t = eta * eta * max(0.0, 1.0 - cos_i * cos_i);
    var weight = mat.albedo.rgb;
    if (!entering) {
        weight *= exp(-mat.extra.rgb * length(hit.p - ray.origin));
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

// ALPHA_SMOOTH (types.wgsl's constants): below this GGX alpha the specular lobe is a
// perfect mirror (a delta, as in pbrt-v4): eval and pdf leave it out and
// scatter_microfacet samples the mirror direction itself, so roughness 0 never divides by
// zero.

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// GGX (Trowbridge-Reitz) normal distribution at cos(theta_h) = c.
fn ggx_d(c: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let k = c * c * (a2 - 1.0) + 1.0;
    return a2 / (PI * k * k);
}

// Smith's Lambda for GGX at cos(theta) = c > 0: (sqrt(1 + alpha^2 tan^2) - 1) / 2, written
// without tan so that grazing directions stay finite.
fn smith_lambda(c: f32, alpha: f32) -> f32 {
    let c2 = c * c;
    return 0.5 * (sqrt(c2 + alpha * alpha * (1.0 - c2)) / c - 1.0);
}

// Smith's height-correlated masking-shadowing G2 = 1 / (1 + Lambda(cos_o) + Lambda(cos_i)).
fn smith_g2(cos_o: f32, cos_i: f32, alpha: f32) -> f32 {
    return 1.0 / (1.0 + smith_lambda(cos_o, alpha) + smith_lambda(cos_i, alpha));
}

// A visible normal of GGX seen from wo (local frame, z = the normal), sampled as in Heitz,
// "Sampling the GGX Distribution of Visible Normals" (JCGT 2018).
fn sample_ggx_vndf(wo: vec3<f32>, alpha: f32, u: vec2<f32>) -> vec3<f32> {
    let vh = normalize(vec3<f32>(alpha * wo.x, alpha * wo.y, wo.z));
    let len2 = vh.x * vh.x + vh.y * vh.y;
    var t1 = vec3<f32>(1.0, 0.0, 0.0);
    if (len2 > 0.0) {
        t1 = vec3<f32>(-vh.y, vh.x, 0.0) / sqrt(len2);
    }
    let t2 = cross(vh, t1);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    let p1 = r * cos(phi);
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * sqrt(max(0.0, 1.0 - p1 * p1)) + s * r * sin(phi);
    let nh = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
    return normalize(vec3<f32>(alpha * nh.x, alpha * nh.y, max(0.0, nh.z)));
}

// Probability of sampling the specular lobe: its share by Fresnel at the view angle and the
// lobes' colours, kept in [0.1, 0.9] when both lobes reflect. It depends on wo only, so
// the mixture's pdf is exact.
fn microfacet_spec_prob(mat: Material, cos_o: f32) -> f32 {
    let f = schlick(cos_o, mat.params.y);
    return lobe_prob(luminance(mat.extra.rgb) * f, luminance(mat.albedo.rgb) * (1.0 - f));
}

// The probability of the specular lobe of weight ws beside the diffuse one of weight wd:
// its share, kept in [0.1, 0.9] when both reflect.
fn lobe_prob(ws: f32, wd: f32) -> f32 {
    if (ws <= 0.0) {
        return 0.0;
    }
    if (wd <= 0.0) {
        return 1.0;
    }
    return clamp(ws / (ws + wd), 0.1, 0.9);
}

// Cook-Torrance BSDF x cos(theta_i), for unit wo and wi about the unit normal n on wo's side:
// ks D G2 F / (4 cos_o) + kd (1 - F(cos_i)) (1 - F(cos_o)) cos_i / pi. G2 is Smith's
// height-correlated masking-shadowing, F Schlick's from the ior. The diffuse base gets the
// light the Fresnel of both directions lets through, which keeps the sum reciprocal and
// within energy conservation (the white furnace test checks it).
fn microfacet_eval(mat: Material, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let cos_o = dot(n, wo);
    let cos_i = dot(n, wi);
    if (cos_o <= 0.0 || cos_i <= 0.0) {
        return vec3<f32>(0.0);
    }
    let alpha = mat.params.x;
    let ior = mat.params.y;
    let diff = (1.0 - schlick(cos_i, ior)) * (1.0 - schlick(cos_o, ior)) * cos_i / PI;
    if (alpha < ALPHA_SMOOTH) {
        return mat.albedo.rgb * diff;
    }
    let h = normalize(wo + wi);
    let spec = ggx_d(dot(n, h), alpha) * smith_g2(cos_o, cos_i, alpha) * schlick(dot(wi, h), ior) / (4.0 * cos_o);
    return mat.extra.rgb * spec + mat.albedo.rgb * diff;
}

// The pdf of scatter_microfacet's directions.
fn microfacet_pdf(mat: Material, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    return ggx_lobes_pdf(microfacet_spec_prob(mat, dot(n, wo)), mat.params.x, n, wo, wi);
}

// The pdf of sample_ggx_lobes's directions: the visible-normal pdf mapped through the
// reflection, G1(wo) D(h) / (4 cos_o), with probability p_s, else the cosine pdf (the
// specular lobe left out below ALPHA_SMOOTH, where it is a delta).
fn ggx_lobes_pdf(p_s: f32, alpha: f32, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    let cos_o = dot(n, wo);
    let cos_i = dot(n, wi);
    if (cos_o <= 0.0 || cos_i <= 0.0) {
        return 0.0;
    }
    let diff = (1.0 - p_s) * cos_i / PI;
    if (alpha < ALPHA_SMOOTH) {
        return diff;
    }
    let h = normalize(wo + wi);
    let spec = ggx_d(dot(n, h), alpha) / ((1.0 + smith_lambda(cos_o, alpha)) * 4.0 * cos_o);
    return p_s * spec + diff;
}

// Microfacet: the specular lobe (a visible normal, then the mirror direction about it; the
// mirror direction itself when smooth) or the diffuse one (cosine), chosen by
// microfacet_spec_prob with u.x reused; weight = eval / pdf of the whole mixture. A
// direction under the geometric surface is absorbed.
fn scatter_microfacet(mat: Material, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
    let side = select(-1.0, 1.0, hit.front_face);
    let n = side * hit.ns;
    let wo = -ray.dir;
    let cos_o = dot(n, wo);
    if (cos_o <= 0.0) {
        return absorbed();
    }
    let p_s = microfacet_spec_prob(mat, cos_o);
    let is_smooth = mat.params.x < ALPHA_SMOOTH;
    if (is_smooth && u.x < p_s) {
        // the mirror lobe: weight = ks F(cos_o) / p_s
        let wi = reflect_dir(ray.dir, n);
        if (side * dot(wi, hit.ng) <= 0.0) {
            return absorbed();
        }
        return Scatter(true, wi, mat.extra.rgb * (schlick(cos_o, mat.params.y) / p_s), 0.0, true);
    }
    let wi = sample_ggx_lobes(p_s, mat.params.x, n, wo, u);
    let pdf = microfacet_pdf(mat, n, wo, wi);
    if (!(pdf > 0.0) || side * dot(wi, hit.ng) <= 0.0) {
        return absorbed();
    }
    return Scatter(true, wi, microfacet_eval(mat, n, wo, wi) / pdf, pdf, false);
}

// A direction from a GGX lobe of roughness alpha (a visible normal seen from wo, then the
// mirror direction about it) with probability p_s, else from the cosine lobe; u.x chooses
// and is reused.
fn sample_ggx_lobes(p_s: f32, alpha: f32, n: vec3<f32>, wo: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    if (u.x < p_s) {
        let tb = onb_tangents(n);
        let local = vec3<f32>(dot(wo, tb[0]), dot(wo, tb[1]), dot(n, wo));
        let h_l = sample_ggx_vndf(local, alpha, vec2<f32>(u.x / p_s, u.y));
        let h = h_l.x * tb[0] + h_l.y * tb[1] + h_l.z * n;
        return normalize(2.0 * dot(wo, h) * h - wo);
    }
    return sample_cosine_hemisphere(n, vec2<f32>((u.x - p_s) / (1.0 - p_s), u.y));
}

#ifdef HAS_PBR
// glTF's metallic-roughness material (glTF 2.0's Appendix B, with KHR_materials_ior and
// KHR_materials_specular): albedo = base colour; params = (alpha = roughness^2, at least
// ALPHA_SMOOTH, ior, metallic, specular); extra = specular colour.
// Fresnel-Schlick of the dielectric layer at cos c (v . h):
// F0 = min(((ior - 1) / (ior + 1))^2 specular colour, 1) specular, F90 = specular.
fn pbr_dielectric_fresnel(mat: Material, c: f32) -> vec3<f32> {
    let r = (mat.params.y - 1.0) / (mat.params.y + 1.0);
    let f0 = min(vec3<f32>(r * r) * mat.extra.rgb, vec3<f32>(1.0)) * mat.params.w;
    let m = 1.0 - clamp(c, 0.0, 1.0);
    return f0 + (vec3<f32>(mat.params.w) - f0) * (m * m * m * m * m);
}

// Fresnel-Schlick of the metal: F0 = the base colour, F90 = 1.
fn pbr_metal_fresnel(mat: Material, c: f32) -> vec3<f32> {
    let m = 1.0 - clamp(c, 0.0, 1.0);
    return mat.albedo.rgb + (vec3<f32>(1.0) - mat.albedo.rgb) * (m * m * m * m * m);
}

// BSDF x cos(theta_i), for unit wo and wi about the unit normal n on wo's side:
// mix((1 - F_d(cos_i)) (1 - F_d(cos_o)) base / pi cos_i + F_d(v . h) S, F_m(v . h) S,
// metallic), S = D V cos_i = D G2 / (4 cos_o) the GGX lobe with Smith's height-correlated
// G2 (h the half vector). Appendix B weighs the base by 1 - F_d(v . h) instead, which
// reflects up to 1.026 of a white furnace near roughness 0 (seen at 60 degrees); the
// base here gets what the Fresnel of both directions lets through, as the microfacet
// material's does: reciprocal and within energy conservation (tests/materials.rs).
fn pbr_eval(mat: Material, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let cos_o = dot(n, wo);
    let cos_i = dot(n, wi);
    if (cos_o <= 0.0 || cos_i <= 0.0) {
        return vec3<f32>(0.0);
    }
    let alpha = mat.params.x;
    let h = normalize(wo + wi);
    let vh = dot(wo, h);
    let spec = ggx_d(dot(n, h), alpha) * smith_g2(cos_o, cos_i, alpha) / (4.0 * cos_o);
    let through = (vec3<f32>(1.0) - pbr_dielectric_fresnel(mat, cos_i)) * (vec3<f32>(1.0) - pbr_dielectric_fresnel(mat, cos_o));
    let dielectric = through * mat.albedo.rgb * (cos_i / PI) + pbr_dielectric_fresnel(mat, vh) * spec;
    let metallic = mat.params.z;
    return dielectric * (1.0 - metallic) + pbr_metal_fresnel(mat, vh) * spec * metallic;
}

// Probability of sampling the GGX lobe: its share at the view angle (both Fresnels at
// cos_o, the diffuse lobe's colour), kept in [0.1, 0.9] when both lobes reflect.
fn pbr_spec_prob(mat: Material, cos_o: f32) -> f32 {
    let fd = pbr_dielectric_fresnel(mat, cos_o);
    let metallic = mat.params.z;
    let ws = luminance(fd * (1.0 - metallic) + pbr_metal_fresnel(mat, cos_o) * metallic);
    let wd = (1.0 - mat.params.z) * luminance((vec3<f32>(1.0) - fd) * mat.albedo.rgb);
    return lobe_prob(ws, wd);
}

fn pbr_pdf(mat: Material, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    return ggx_lobes_pdf(pbr_spec_prob(mat, dot(n, wo)), mat.params.x, n, wo, wi);
}

// The metallic-roughness material: the GGX lobe or the cosine one, chosen by
// pbr_spec_prob; weight = eval / pdf of the mixture. A direction under the geometric
// surface is absorbed.
fn scatter_pbr(mat: Material, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
    let side = select(-1.0, 1.0, hit.front_face);
    let n = side * hit.ns;
    let wo = -ray.dir;
    let cos_o = dot(n, wo);
    if (cos_o <= 0.0) {
        return absorbed();
    }
    let wi = sample_ggx_lobes(pbr_spec_prob(mat, cos_o), mat.params.x, n, wo, u);
    let pdf = pbr_pdf(mat, n, wo, wi);
    if (!(pdf > 0.0) || side * dot(wi, hit.ng) <= 0.0) {
        return absorbed();
    }
    return Scatter(true, wi, pbr_eval(mat, n, wo, wi) / pdf, pdf, false);
}
#endif

fn scatter(mat: Material, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
    switch mat.tag {
#ifdef HAS_LAMBERTIAN
        case MAT_LAMBERTIAN: {
            return scatter_lambertian(mat, hit, u);
        }
#endif
#ifdef HAS_METAL
        case MAT_METAL: {
            return scatter_metal(mat, ray, hit, u);
        }
#endif
#ifdef HAS_DIELECTRIC
        case MAT_DIELECTRIC: {
            return scatter_dielectric(mat, ray, hit, u);
        }
#endif
#ifdef HAS_MICROFACET
        case MAT_MICROFACET: {
            return scatter_microfacet(mat, ray, hit, u);
        }
#endif
#ifdef HAS_PBR
        case MAT_PBR: {
            return scatter_pbr(mat, ray, hit, u);
        }
#endif
        default: {
            // emissive and unknown materials absorb
            return absorbed();
        }
    }
}

// BSDF x cos toward wi for the materials light sampling serves (0 for the others): what
// scatter's weight is the ratio of, and 0 under the geometric surface, where scatter
// absorbs. The microfacet's mirror lobe when smooth is a delta and is left out.
fn bsdf_eval(mat: Material, ray: Ray, hit: Hit, wi: vec3<f32>) -> vec3<f32> {
    let side = select(-1.0, 1.0, hit.front_face);
    if (side * dot(wi, hit.ng) <= 0.0) {
        return vec3<f32>(0.0);
    }
    let n = side * hit.ns;
    switch mat.tag {
#ifdef HAS_LAMBERTIAN
        case MAT_LAMBERTIAN: {
            return mat.albedo.rgb * (max(0.0, dot(n, wi)) / PI);
        }
#endif
#ifdef HAS_MICROFACET
        case MAT_MICROFACET: {
            return microfacet_eval(mat, n, -ray.dir, wi);
        }
#endif
#ifdef HAS_PBR
        case MAT_PBR: {
            return pbr_eval(mat, n, -ray.dir, wi);
        }
#endif
        default: {
            return vec3<f32>(0.0);
        }
    }
}

// The density with which scatter draws wi (before it absorbs directions under the
// geometric surface), for the materials light sampling serves.
fn bsdf_pdf(mat: Material, ray: Ray, hit: Hit, wi: vec3<f32>) -> f32 {
    let n = select(-hit.ns, hit.ns, hit.front_face);
    switch mat.tag {
#ifdef HAS_LAMBERTIAN
        case MAT_LAMBERTIAN: {
            return max(0.0, dot(n, wi)) / PI;
        }
#endif
#ifdef HAS_MICROFACET
        case MAT_MICROFACET: {
            return microfacet_pdf(mat, n, -ray.dir, wi);
        }
#endif
#ifdef HAS_PBR
        case MAT_PBR: {
            return pbr_pdf(mat, n, -ray.dir, wi);
        }
#endif
        default: {
            return 0.0;
        }
    }
}

// Whether next-event estimation applies at a surface: it has a lobe that is not a delta.
fn nee_applies(mat: Material) -> bool {
    return mat.tag == MAT_LAMBERTIAN || mat.tag == MAT_MICROFACET || mat.tag == MAT_PBR;
}

// Whether the 50/50 mixture samples lights at a surface: as nee_applies, less the smooth
// microfacet, whose mirror lobe the mixture's pdf cannot hold.
fn mixture_applies(mat: Material) -> bool {
    return mat.tag == MAT_LAMBERTIAN || mat.tag == MAT_PBR || (mat.tag == MAT_MICROFACET && mat.params.x >= ALPHA_SMOOTH);
}
