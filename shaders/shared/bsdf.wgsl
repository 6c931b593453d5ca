// What scattering returns, and the pieces several materials share: mirror directions,
// Fresnel, the GGX distribution, Smith's masking, the visible-normal sampler and the
// two-lobe mixture of a GGX and a cosine lobe.
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

// wi as scattering sends it. Where the hit's shading normal differs from its geometric
// one (an interpolated or mapped normal: HAS_SHADING_NORMALS), a direction its lobes send
// under the geometric surface (ng turned to the ray's side by `side`) is mirrored over
// it, as if the surface reflected it there, rather than lost: a smooth-shaded or
// normal-mapped surface keeps the energy its shading gives it (docs/robustness.md).
// bsdf_eval and bsdf_pdf count both directions that reach a direction. Elsewhere wi.
fn over_surface(wi: vec3<f32>, side: f32, hit: Hit) -> vec3<f32> {
#ifdef HAS_SHADING_NORMALS
    if (any(hit.ns != hit.ng) && side * dot(wi, hit.ng) < 0.0) {
        return mirrored(wi, hit);
    }
#endif
    return wi;
}

// The direction mirrored over the hit's geometric surface: of two directions that
// over_surface sends to the same place, the one from the other.
fn mirrored(wi: vec3<f32>, hit: Hit) -> vec3<f32> {
    return wi - 2.0 * dot(wi, hit.ng) * hit.ng;
}

// A direction wi drawn from a lobe with a density, weighted by BSDF x cos f over its pdf,
// sent over the surface (over_surface); absorbed when the pdf is not positive or the
// direction is under the geometric surface (ng turned to the ray's side).
fn density_sample(wi: vec3<f32>, f: vec3<f32>, pdf: f32, side: f32, hit: Hit) -> Scatter {
    let dir = over_surface(wi, side, hit);
    if (!(pdf > 0.0) || side * dot(dir, hit.ng) <= 0.0) {
        return absorbed();
    }
    return Scatter(true, dir, f / pdf, pdf, false);
}

// Mirror direction of d about the unit normal n: d - 2 (d . n) n.
fn reflect_dir(d: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return d - 2.0 * dot(d, n) * n;
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

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// ALPHA_SMOOTH (the shared constants): below this GGX alpha a specular lobe is a perfect
// mirror (a delta, as in pbrt-v4): eval and pdf leave it out and the sampler takes the
// mirror direction itself, so roughness 0 never divides by zero.

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
