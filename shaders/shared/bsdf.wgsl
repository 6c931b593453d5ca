// What scattering returns, and the pieces several materials share: mirror directions,
// Fresnel, the GGX distribution, Smith's masking, the visible-normal sampler and the
// two-lobe mixture of a GGX and a cosine lobe.
#import shared/bindings
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

// A delta lobe's mirror reflection of the ray about n (the shading normal on its side,
// `side` that of the geometric one), weighted `weight`: sent over the surface where a
// shading normal tilts it under (over_surface), absorbed where it still is under.
fn mirror_scatter(ray: Ray, hit: Hit, side: f32, n: vec3<f32>, weight: vec3<f32>) -> Scatter {
    let wi = over_surface(reflect_dir(ray.dir, n), side, hit);
    if (side * dot(wi, hit.ng) <= 0.0) {
        return absorbed();
    }
    return Scatter(true, wi, weight, 0.0, true);
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
    return sample_ggx_vndf_aniso(wo, alpha, alpha, u);
}

// The same for roughness alpha_u along x and alpha_v along y: the sampler in the
// configuration stretched by them.
fn sample_ggx_vndf_aniso(wo: vec3<f32>, alpha_u: f32, alpha_v: f32, u: vec2<f32>) -> vec3<f32> {
    let vh = normalize(vec3<f32>(alpha_u * wo.x, alpha_v * wo.y, wo.z));
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
    return normalize(vec3<f32>(alpha_u * nh.x, alpha_v * nh.y, max(0.0, nh.z)));
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

// The exact Fresnel reflectance of unpolarised light off a conductor of complex relative
// index eta + i k (per channel) at cosine c in [0, 1]: the average of the s and p
// reflectances, written with a^2 + b^2 = |(eta + i k)^2 - sin^2| and a its real root's
// real part (Born and Wolf). eta = 0, k = 1 reflects everything; where a ratio is 0 / 0
// (eta = k = 0, a channel a measured table clamps, seen head-on) its limit, 1.
fn fresnel_conductor(c: f32, eta: vec3<f32>, k: vec3<f32>) -> vec3<f32> {
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let t1 = eta * eta - k * k - vec3<f32>(s2);
    let a2b2 = sqrt(max(t1 * t1 + 4.0 * eta * eta * k * k, vec3<f32>(0.0)));
    let a = sqrt(max(0.5 * (a2b2 + t1), vec3<f32>(0.0)));
    let t2 = a2b2 + vec3<f32>(c2);
    let t3 = 2.0 * c * a;
    let d_s = t2 + t3;
    let r_s = select(vec3<f32>(1.0), (t2 - t3) / max(d_s, vec3<f32>(1e-30)), d_s > vec3<f32>(0.0));
    let t4 = a2b2 * c2 + vec3<f32>(s2 * s2);
    let t5 = t3 * s2;
    let d_p = t4 + t5;
    let r_p = r_s * select(vec3<f32>(1.0), (t4 - t5) / max(d_p, vec3<f32>(1e-30)), d_p > vec3<f32>(0.0));
    return 0.5 * (r_s + r_p);
}

// A microfacet distribution as Mitsuba 3 and pbrt define them: GGX or Beckmann
// (beckmann), roughness alpha_u along the frame's tangent (x) and alpha_v along its
// bitangent (y). Its functions take directions in that local frame, z the normal.
struct Microfacet {
    alpha_u: f32,
    alpha_v: f32,
    beckmann: bool,
}

// Its density of normals D(h) (projected: integrates to 1 against h.z).
fn mf_d(m: Microfacet, h: vec3<f32>) -> f32 {
    // kept off 0: a normal in the horizon has no density, and no 0 / 0 computes it
    let c2 = max(h.z * h.z, 1e-12);
    let e = (h.x * h.x) / (m.alpha_u * m.alpha_u) + (h.y * h.y) / (m.alpha_v * m.alpha_v);
    let norm = PI * m.alpha_u * m.alpha_v;
    let k = e + c2;
    var d = 1.0 / (norm * k * k);
#ifdef HAS_BECKMANN
    if (m.beckmann) {
        d = exp(-e / c2) / (norm * c2 * c2);
    }
#endif
    return select(0.0, d, h.z > 0.0 && d * h.z > 1e-20);
}

// Smith's masking of direction v by normals about h, G1(v, h) = 1 / (1 + Lambda(v)),
// exact for both: Beckmann's Lambda = (erf(a) - 1) / 2 + e^(-a^2) / (2 a sqrt(pi)),
// a = 1 / (alpha tan), which the visible-normal sampler's CDF assumes (Walter et al.'s
// rational fit, which Mitsuba 3 uses, is up to ~1% off at grazing angles and leaves the
// sampler's pdf short of 1); 0 where v sees h's back.
fn mf_g1(m: Microfacet, v: vec3<f32>, h: vec3<f32>) -> f32 {
    let xy = (m.alpha_u * v.x) * (m.alpha_u * v.x) + (m.alpha_v * v.y) * (m.alpha_v * v.y);
    let tan2 = xy / (v.z * v.z);
    var g = 2.0 / (1.0 + sqrt(1.0 + tan2));
#ifdef HAS_BECKMANN
    if (m.beckmann) {
        let a = inverseSqrt(tan2);
        let lambda = 0.5 * (erf_approx(a) - 1.0) + 0.2820947918 * exp(-a * a) / a;
        g = 1.0 / (1.0 + max(lambda, 0.0));
    }
#endif
    g = select(g, 1.0, xy == 0.0);
    return select(0.0, g, dot(v, h) * v.z > 0.0);
}

#ifdef HAS_BECKMANN
// Beckmann's pieces, compiled for scenes that have it (HAS_BECKMANN): llvmpipe runs an
// untaken branch under a mask, and a GGX-only scene would pay for the search.

// The state of the Newton-bisection search of beckmann_slope_x: the guess b (in erf's
// domain) and the bracket [lo, hi] the root is in.
struct BeckmannSearch {
    b: f32,
    lo: f32,
    hi: f32,
}

// One step of the search for the erf-domain b whose CDF of visible slopes,
// norm (1 + b + tan e^(-erfinv(b)^2) / sqrt(pi)), equals x: a Newton step kept in the
// bracket by bisection.
fn beckmann_step(s: BeckmannSearch, x: f32, tan_i: f32, norm: f32) -> BeckmannSearch {
    var r = s;
    if (!(r.b >= r.lo && r.b <= r.hi)) {
        r.b = 0.5 * (r.lo + r.hi);
    }
    let e = erfinv_approx(r.b);
    let value = norm * (1.0 + r.b + 0.5641895835 * tan_i * exp(-e * e)) - x;
    let derivative = norm * (1.0 - e * tan_i);
    if (value > 0.0) {
        r.hi = r.b;
    } else {
        r.lo = r.b;
    }
    // the Newton step where it stays in the bracket, else the bracket's middle (no
    // division by a zero derivative)
    let ok = derivative != 0.0;
    let next = r.b - value / select(1.0, derivative, ok);
    r.b = select(0.5 * (r.lo + r.hi), next, ok && next >= r.lo && next <= r.hi);
    return r;
}

// A slope of Beckmann's unit-roughness visible normals seen at cos_i (Jakob's
// inversion, 2014, of the CDF of Heitz and d'Eon's sampler): x by a fitted first guess
// and six Newton-bisection steps (written out: no loop), y by the inverse error function.
fn beckmann_slope(cos_i: f32, u: vec2<f32>) -> vec2<f32> {
    let sin_i = sqrt(max(0.0, 1.0 - cos_i * cos_i));
    let tan_i = sin_i / cos_i;
    let cot_i = cos_i / max(sin_i, 1e-7);
    let x = max(u.x, 1e-6);
    let hi = erf_approx(cot_i);
    let theta = acos(clamp(cos_i, -1.0, 1.0));
    let fit = 1.0 + theta * (-0.876 + theta * (0.4265 - 0.0594 * theta));
    let norm = 1.0 / (1.0 + hi + 0.5641895835 * tan_i * exp(-cot_i * cot_i));
    var s = BeckmannSearch(hi - (1.0 + hi) * pow(1.0 - x, fit), -1.0, hi);
    s = beckmann_step(s, x, tan_i, norm);
    s = beckmann_step(s, x, tan_i, norm);
    s = beckmann_step(s, x, tan_i, norm);
    s = beckmann_step(s, x, tan_i, norm);
    s = beckmann_step(s, x, tan_i, norm);
    s = beckmann_step(s, x, tan_i, norm);
    let b = select(0.5 * (s.lo + s.hi), s.b, s.b >= s.lo && s.b <= s.hi);
    let slope = vec2<f32>(erfinv_approx(clamp(b, -0.9999999, 0.9999999)), erfinv_approx(2.0 * max(u.y, 1e-6) - 1.0));
    // at normal incidence, the distribution of all slopes
    let r = sqrt(-log(max(1.0 - u.x, 1e-30)));
    let phi = 2.0 * PI * u.y;
    return select(slope, r * vec2<f32>(cos(phi), sin(phi)), cos_i > 0.99999);
}
#endif

// A visible normal of the distribution seen from wo (local, wo.z > 0): GGX's by Heitz's
// sampler (JCGT 2018) in the stretched configuration; Beckmann's by a slope of the
// unit-roughness distribution (beckmann_slope) rotated to wo's azimuth and stretched.
fn mf_sample_visible(m: Microfacet, wo: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
#ifdef HAS_BECKMANN
    if (m.beckmann) {
        let vh = normalize(vec3<f32>(m.alpha_u * wo.x, m.alpha_v * wo.y, wo.z));
        let len = length(vh.xy);
        let cs = select(vec2<f32>(1.0, 0.0), vh.xy / len, len > 0.0);
        let s = beckmann_slope(vh.z, u);
        let slope = vec2<f32>(cs.x * s.x - cs.y * s.y, cs.y * s.x + cs.x * s.y) * vec2<f32>(m.alpha_u, m.alpha_v);
        return normalize(vec3<f32>(-slope.x, -slope.y, 1.0));
    }
#endif
    return sample_ggx_vndf_aniso(wo, m.alpha_u, m.alpha_v, u);
}

// The density of mf_sample_visible's normals: G1(wo, h) max(0, wo . h) D(h) / wo.z.
fn mf_pdf_visible(m: Microfacet, wo: vec3<f32>, h: vec3<f32>) -> f32 {
    return mf_g1(m, wo, h) * max(0.0, dot(wo, h)) * mf_d(m, h) / wo.z;
}

// A frame about the unit normal n whose first axis follows `tangent` (made orthogonal
// to n): (t, b), b = n x t. Where the tangent is zero or along n (a hit without
// tangents), the first axis is +y x n, around the world's up axis (a sphere's lines of
// latitude: continuous but at the poles, where onb_tangents(n) serves), not
// onb_tangents's, which turns over where n.z changes sign.
fn tangent_frame(n: vec3<f32>, tangent: vec3<f32>) -> array<vec3<f32>, 2> {
    let t = tangent - n * dot(n, tangent);
    let len = length(t);
    if (len > 1e-6) {
        let tu = t / len;
        return array<vec3<f32>, 2>(tu, cross(n, tu));
    }
    let around = vec3<f32>(n.z, 0.0, -n.x);
    let l = length(around);
    if (l > 1e-3) {
        let tu = around / l;
        return array<vec3<f32>, 2>(tu, cross(n, tu));
    }
    return onb_tangents(n);
}

#ifdef HAS_ENERGY_COMPENSATION
// Multiple-scattering energy compensation (Kulla and Conty 2017): the lobe
// F_ms (1 - E(cos_o)) (1 - E(cos_i)) / (pi (1 - E_avg)) that gives a microfacet lobe back
// what it loses between its microfacets (scene::microfacet_albedo has the formulas and the
// tables' layout). Compiled for scenes with a compensated material only.

// Float i of the albedo tables (from params.ms_tables).
fn ms_float(i: u32) -> f32 {
    let j = params.ms_tables * 4u + i;
    return tables[j >> 2u][j & 3u];
}

// The first float of a variant's (MS_GGX_CORRELATED, ...) table t: 0 E1 (F = 1), 1 E5
// (Schlick's weight (1 - wo . h)^5 for F).
fn ms_offset(variant: u32, t: u32) -> u32 {
    let block = MS_TABLE_SIZE * MS_TABLE_SIZE + MS_TABLE_SIZE;
    return (2u * variant + t) * block;
}

// The isotropic alpha whose tables stand for an anisotropic lobe's: the mean of the two
// (a white lobe of alphas 0.16 and 1 compensated at their geometric mean reflects 0.74 of
// a white furnace head-on, at their root mean square 1.03).
fn ms_alpha(alpha_u: f32, alpha_v: f32) -> f32 {
    return 0.5 * (alpha_u + alpha_v);
}

// A table's albedo at cosine c and alpha, bilinear in sqrt(c) and sqrt(alpha).
fn ms_albedo(offset: u32, c: f32, alpha: f32) -> f32 {
    let last = f32(MS_TABLE_SIZE - 1u);
    let x = sqrt(clamp(c, 0.0, 1.0)) * last;
    let y = sqrt(clamp(alpha, 0.0, 1.0)) * last;
    let x0 = min(u32(x), MS_TABLE_SIZE - 2u);
    let y0 = min(u32(y), MS_TABLE_SIZE - 2u);
    let i = offset + y0 * MS_TABLE_SIZE + x0;
    let j = i + MS_TABLE_SIZE;
    let fx = x - f32(x0);
    return mix(mix(ms_float(i), ms_float(i + 1u), fx), mix(ms_float(j), ms_float(j + 1u), fx), y - f32(y0));
}

// A table's average 2 int E(mu) mu dmu at alpha.
fn ms_average(offset: u32, alpha: f32) -> f32 {
    let last = f32(MS_TABLE_SIZE - 1u);
    let y = sqrt(clamp(alpha, 0.0, 1.0)) * last;
    let y0 = min(u32(y), MS_TABLE_SIZE - 2u);
    let i = offset + MS_TABLE_SIZE * MS_TABLE_SIZE + y0;
    return mix(ms_float(i), ms_float(i + 1u), y - f32(y0));
}

// The compensation's colour F_ms = F_avg^2 E_avg / (1 - F_avg (1 - E_avg)) of a lobe
// whose Fresnel averages f_avg.
fn ms_fresnel(f_avg: vec3<f32>, e_avg: f32) -> vec3<f32> {
    return f_avg * f_avg * e_avg / (vec3<f32>(1.0) - f_avg * (1.0 - e_avg));
}

// The compensation lobe x cos_i of a lobe of `variant` and alpha whose Fresnel averages
// f_avg; 0 where the lobe loses nothing (a mirror).
fn ms_lobe(variant: u32, alpha: f32, cos_o: f32, cos_i: f32, f_avg: vec3<f32>) -> vec3<f32> {
    let o = ms_offset(variant, 0u);
    let e_avg = ms_average(o, alpha);
    if (cos_o <= 0.0 || cos_i <= 0.0 || e_avg >= 1.0) {
        return vec3<f32>(0.0);
    }
    let k = (1.0 - ms_albedo(o, cos_o, alpha)) * (1.0 - ms_albedo(o, cos_i, alpha)) / (PI * (1.0 - e_avg));
    return ms_fresnel(f_avg, e_avg) * (k * cos_i);
}

// What a white lobe of `variant` and alpha loses seen at cos_o, 1 - E1(cos_o): the
// probability with which a material samples its compensation lobe (by the cosine).
fn ms_loss(variant: u32, alpha: f32, cos_o: f32) -> f32 {
    return clamp(1.0 - ms_albedo(ms_offset(variant, 0u), cos_o, alpha), 0.0, 0.9);
}

// The directional albedo at cosine c of a lobe of `variant` and alpha with Schlick's
// Fresnel from f0 to f90, alone: f0 E1 + (f90 - f0) E5.
fn ms_schlick_single(variant: u32, alpha: f32, c: f32, f0: vec3<f32>, f90: vec3<f32>) -> vec3<f32> {
    return f0 * ms_albedo(ms_offset(variant, 0u), c, alpha) + (f90 - f0) * ms_albedo(ms_offset(variant, 1u), c, alpha);
}

// ms_schlick_single averaged over cosines (2 int E mu dmu).
fn ms_schlick_single_average(variant: u32, alpha: f32, f0: vec3<f32>, f90: vec3<f32>) -> vec3<f32> {
    return f0 * ms_average(ms_offset(variant, 0u), alpha) + (f90 - f0) * ms_average(ms_offset(variant, 1u), alpha);
}

// The directional albedo at cosine c of a lobe of `variant` and alpha with Schlick's
// Fresnel from f0 to f90, its compensation lobe included: f0 E1 + (f90 - f0) E5 + F_ms
// (1 - E1).
fn ms_schlick_albedo(variant: u32, alpha: f32, c: f32, f0: vec3<f32>, f90: vec3<f32>) -> vec3<f32> {
    let o1 = ms_offset(variant, 0u);
    let e1 = ms_albedo(o1, c, alpha);
    let f_ms = ms_fresnel(f0 + (f90 - f0) / 21.0, ms_average(o1, alpha));
    return ms_schlick_single(variant, alpha, c, f0, f90) + f_ms * (1.0 - e1);
}

// ms_schlick_albedo averaged over cosines (2 int E mu dmu).
fn ms_schlick_average(variant: u32, alpha: f32, f0: vec3<f32>, f90: vec3<f32>) -> vec3<f32> {
    let e1 = ms_average(ms_offset(variant, 0u), alpha);
    let f_ms = ms_fresnel(f0 + (f90 - f0) / 21.0, e1);
    return ms_schlick_single_average(variant, alpha, f0, f90) + f_ms * (1.0 - e1);
}

// Kulla and Conty's albedo scaling of a layer under a lobe whose albedo is a_o toward wo
// and a_i toward wi and avg on average: (1 - a_o) (1 - a_i) / (1 - avg), reciprocal, and
// a white layer under a lobe reflects all that the lobe does not.
fn ms_scaling(a_o: vec3<f32>, a_i: vec3<f32>, avg: vec3<f32>) -> vec3<f32> {
    let v = (vec3<f32>(1.0) - a_o) * (vec3<f32>(1.0) - a_i) / (vec3<f32>(1.0) - avg);
    return select(v, vec3<f32>(0.0), avg >= vec3<f32>(1.0));
}

// The share of a layer under a compensated Schlick lobe between wo and wi: what the lobe
// (and its compensation) leaves of both directions (ms_scaling of ms_schlick_albedo).
fn ms_under(variant: u32, alpha: f32, cos_o: f32, cos_i: f32, f0: vec3<f32>, f90: vec3<f32>) -> vec3<f32> {
    let avg = ms_schlick_average(variant, alpha, f0, f90);
    return ms_scaling(ms_schlick_albedo(variant, alpha, cos_o, f0, f90), ms_schlick_albedo(variant, alpha, cos_i, f0, f90), avg);
}

// ----- rough dielectrics (after the reflecting variants: scene::microfacet_albedo's
// dielectric tables). A dielectric boundary's multiple scattering sends what a side loses,
// 1 - E(cos_o) of E its total albedo in energy (reflection and transmission), both ways:
// a diffuse-like reflection (1 - b) (1 - E(cos_o)) (1 - E(cos_i)) / (pi (1 - E_avg)) on
// the same side, and a transmission b (1 - E(cos_o)) (1 - E'(cos_i)) / (pi (1 - E'_avg))
// into the other (E' its tables), so that every direction of either side keeps all its
// energy. b = 1 - F_avg seen from the lower index, and seen from the higher its
// reciprocal b (1 - E_avg) / (ior^2 (1 - E'_avg)) (what radiance's reciprocity across
// the boundary asks), the lower side's lowered where that would pass 1.

// Where an index ratio ior >= 1 lands on the tables' axis (indices 1 + (max - 1) t^2):
// (the lower table, the fraction toward the next).
fn ms_ior_position(ior: f32) -> vec2<f32> {
    let t = sqrt(clamp((ior - 1.0) / (MS_IOR_MAX - 1.0), 0.0, 1.0)) * f32(MS_IORS - 1u);
    let k = min(floor(t), f32(MS_IORS - 2u));
    return vec2<f32>(k, t - k);
}

// The first float of a dielectric variant's (MS_DIELECTRIC_GGX_CORRELATED, ...) table of
// index k and side (0: the lower index's, 1: the higher's); side 2 of the last index is
// the Fresnel averages.
fn ms_dielectric_offset(variant: u32, k: u32, side: u32) -> u32 {
    let block = MS_TABLE_SIZE * MS_TABLE_SIZE + MS_TABLE_SIZE;
    return 6u * block + variant * (MS_IORS * 2u * block + MS_IORS) + (2u * k + side) * block;
}

// The total albedo at cosine c and alpha seen from `side` of a boundary of index ratio
// ior >= 1 (linear between the tables' indices).
fn ms_dielectric_albedo(variant: u32, ior: f32, side: u32, c: f32, alpha: f32) -> f32 {
    let t = ms_ior_position(ior);
    let k = u32(t.x);
    let a = ms_albedo(ms_dielectric_offset(variant, k, side), c, alpha);
    return mix(a, ms_albedo(ms_dielectric_offset(variant, k + 1u, side), c, alpha), t.y);
}

// (the shares b transmitted from the lower index's side and from the higher's, what the
// two sides lose on average, 1 - E_avg and 1 - E'_avg), for index ratio ior >= 1.
fn ms_dielectric_split(variant: u32, ior: f32, alpha: f32) -> vec4<f32> {
    let t = ms_ior_position(ior);
    let k = u32(t.x);
    let l_low = 1.0 - mix(ms_average(ms_dielectric_offset(variant, k, 0u), alpha), ms_average(ms_dielectric_offset(variant, k + 1u, 0u), alpha), t.y);
    let l_high = 1.0 - mix(ms_average(ms_dielectric_offset(variant, k, 1u), alpha), ms_average(ms_dielectric_offset(variant, k + 1u, 1u), alpha), t.y);
    let f = ms_dielectric_offset(variant, MS_IORS, 0u) + k;
    let ior2 = ior * ior;
    var b_low = 1.0 - mix(ms_float(f), ms_float(f + 1u), t.y);
    if (l_low > 0.0) {
        b_low = min(b_low, ior2 * l_high / l_low);
    }
    let b_high = select(0.0, b_low * l_low / (ior2 * l_high), l_high > 0.0);
    return vec4<f32>(b_low, b_high, max(l_low, 0.0), max(l_high, 0.0));
}

// The compensation x |cos_i| in energy (a transmission's radiance factor eta^2 left to
// the caller) between wo at cos_o > 0 on `side` of a boundary of index ratio ior >= 1
// and wi at cos_i (negative: transmitted to the other side).
fn ms_dielectric_lobe(variant: u32, ior: f32, alpha: f32, side: u32, cos_o: f32, cos_i: f32) -> f32 {
    let s = ms_dielectric_split(variant, ior, alpha);
    let side_i = select(1u - side, side, cos_i > 0.0);
    let avg = select(s.z, s.w, side_i == 1u);
    if (cos_o <= 0.0 || cos_i == 0.0 || avg <= 0.0) {
        return 0.0;
    }
    let b = select(s.x, s.y, side == 1u);
    let share = select(b, 1.0 - b, cos_i > 0.0);
    let loss_o = max(1.0 - ms_dielectric_albedo(variant, ior, side, cos_o, alpha), 0.0);
    let loss_i = max(1.0 - ms_dielectric_albedo(variant, ior, side_i, abs(cos_i), alpha), 0.0);
    return share * loss_o * loss_i / (PI * avg) * abs(cos_i);
}
#endif
