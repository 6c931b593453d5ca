// Lights: the background's radiance, choosing a light in proportion to its power, sampling
// a direction toward it, and the solid-angle pdf of a direction under light sampling.
// Every pdf includes the probability of choosing the light, exactly as the estimators use
// it. Lights with a surface are sampled from their world-space records in `emitters`, by
// their primitive type's functions (shape_light_sample, shape_light_pdf and
// shape_light_distance, the dispatch gpu::codegen::primitives writes); the image
// background from a 2D distribution over its pixels.
#import shared/bindings
#import shared/geometry
#import shared/intersect
#import shared/sampling
#import shared/textures
#import shared/types

// EDGE_ON_COS (types.wgsl's constants): below this cosine between a light's normal and
// the direction to it, the light is seen edge-on: pdf 0 and no sample, never an unbounded
// weight.

// The image background's frame: a world direction turned by minus the rotation about +y.
fn env_local(d: vec3<f32>) -> vec3<f32> {
    let c = params.env.x;
    let s = params.env.y;
    return vec3<f32>(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
}

// Equirectangular coordinates of a direction: (u, t), u = 0.5 + atan2(x, -z) / (2 pi) in
// the rotated frame (so -z is the middle of the image), t = theta / pi from straight up
// (image row 0) to straight down.
fn env_coords(d: vec3<f32>) -> vec2<f32> {
    let l = env_local(d);
    let sin_theta = sqrt(max(0.0, (1.0 - l.y) * (1.0 + l.y)));
    return vec2<f32>(0.5 + env_atan2(l.x, -l.z) * (0.5 / PI), env_atan2(sin_theta, l.y) / PI);
}

// atan2(y, x) from only correctly rounded operations, so that both backends find the same
// texel of the image background for a direction (a texel edge is where its density jumps):
// atan on [0, 1] as Abramowitz and Stegun's polynomial 4.4.49 (error below 2e-8), then the
// octant's reflection.
fn env_atan2(y: f32, x: f32) -> f32 {
    let ax = abs(x);
    let ay = abs(y);
    let hi = max(ax, ay);
    let r = select(min(ax, ay) / hi, 0.0, hi == 0.0);
    let r2 = r * r;
    var a = 0.0028662257;
    a = a * r2 - 0.0161657367;
    a = a * r2 + 0.0429096138;
    a = a * r2 - 0.0752896400;
    a = a * r2 + 0.1065626393;
    a = a * r2 - 0.1420889944;
    a = a * r2 + 0.1999355085;
    a = a * r2 - 0.3333314528;
    a = (a * r2 + 1.0) * r;
    a = select(a, 0.5 * PI - a, ay > ax);
    a = select(a, PI - a, x < 0.0);
    return select(a, -a, y < 0.0);
}

// The direction of equirectangular coordinates (u, t), inverse of env_coords.
fn env_direction(ut: vec2<f32>) -> vec3<f32> {
    let theta = PI * ut.y;
    let phi = 2.0 * PI * (ut.x - 0.5);
    let st = sin(theta);
    let l = vec3<f32>(st * sin(phi), cos(theta), -st * cos(phi));
    let c = params.env.x;
    let s = params.env.y;
    return vec3<f32>(c * l.x + s * l.z, l.y, -s * l.x + c * l.z);
}

// Radiance of a ray that leaves the scene in unit direction d: the constant, the vertical
// gradient bottom + (top - bottom) (d.y + 1) / 2, or the image times its strength.
fn background_radiance(d: vec3<f32>) -> vec3<f32> {
    switch params.background_kind {
        case BACKGROUND_GRADIENT: {
            return mix(params.background.rgb, params.background_top.rgb, 0.5 * (d.y + 1.0));
        }
#ifdef HAS_ENV_MAP
        case BACKGROUND_IMAGE: {
            let ut = env_coords(d);
            let st = vec2<f32>(ut.x, 1.0 - ut.y);
            return texture_value(params.env_texture, vec4<f32>(st, st), d) * params.env.z;
        }
#endif
        default: {}
    }
    return params.background.rgb;
}

// Scalar i of the image background's distribution (four to a tables entry).
fn env_cdf_at(i: u32) -> f32 {
    return tables[params.env_cdf + (i >> 2u)][i & 3u];
}

// A point drawn from a piecewise-constant density over n equal intervals, given by its
// CDF (n + 1 values from scalar `base`): x in [0, 1), the density at x, the interval.
struct CdfSample {
    x: f32,
    pdf: f32,
    i: u32,
}

// Inverts the CDF: the interval i with cdf[i] <= u < cdf[i + 1] (binary search; intervals
// of zero probability are never chosen) and u's place inside it.
fn sample_cdf(base: u32, n: u32, u: f32) -> CdfSample {
    var lo = 0u;
    var hi = n;
    while (hi - lo > 1u) {
        let mid = (lo + hi) / 2u;
        if (env_cdf_at(base + mid) <= u) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let c0 = env_cdf_at(base + lo);
    let c1 = env_cdf_at(base + lo + 1u);
    let du = clamp((u - c0) / (c1 - c0), 0.0, 1.0);
    return CdfSample(min((f32(lo) + du) / f32(n), 0.99999994), (c1 - c0) * f32(n), lo);
}

// Solid-angle pdf of direction d under the image background's distribution:
// p(u, t) / (2 pi^2 sin theta).
fn env_pdf(d: vec3<f32>) -> f32 {
    let tex = textures[params.env_texture];
    let ut = env_coords(d);
    let sin_theta = sqrt(max(0.0, 1.0 - d.y * d.y));
    if (sin_theta <= 0.0) {
        return 0.0;
    }
    let row = min(u32(ut.y * f32(tex.height)), tex.height - 1u);
    let col = min(u32(ut.x * f32(tex.width)), tex.width - 1u);
    let p_row = (env_cdf_at(row + 1u) - env_cdf_at(row)) * f32(tex.height);
    let base = tex.height + 1u + row * (tex.width + 1u);
    let p_col = (env_cdf_at(base + col + 1u) - env_cdf_at(base + col)) * f32(tex.width);
    return p_row * p_col / (2.0 * PI * PI * sin_theta);
}

// The emitter among first ..= last whose CDF interval holds u: the first with u < cdf.
fn search_cdf(first: u32, last: u32, u: f32) -> u32 {
    var lo = first;
    var hi = last;
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        if (u < emitter_record(mid).cdf) {
            hi = mid;
        } else {
            lo = mid + 1u;
        }
    }
    return lo;
}

// The index of the light whose CDF interval holds u.
fn choose_light(u: f32) -> u32 {
#ifdef BAKED_EMITTERS
    // a few lights written into the shader (gpu::codegen::baked_emitters)
    return choose_light_baked(u);
#else
    return search_cdf(0u, params.num_emitters - 1u, u);
#endif
}

#ifdef HAS_PUNCTUAL
// The light without a surface whose CDF interval holds u: emitters num_emitters ..
// num_emitters + num_punctual, whose cdf runs over them alone.
fn choose_punctual(u: f32) -> u32 {
    return search_cdf(params.num_emitters, params.num_emitters + params.num_punctual - 1u, u);
}

// A spot's falloff at cos_theta from its axis: 1 within the inner cone, 0 beyond the
// outer, and between them KHR_lights_punctual's ramp, the square of a linear ramp in the
// cosine, or where `mode` (the record's c.w) is 1 + the cones' difference in radians,
// Mitsuba 3's, linear in the angle: (outer - theta) / (outer - inner), the numerator as
// atan2 of the sine and cosine of outer - theta, which keeps its relative precision at
// the cone's edge (an acos of cos_theta would not; llvmpipe's asin is 2e-4 off at 0.5).
fn spot_falloff(cos_theta: f32, cos_outer: f32, cos_inner: f32, mode: f32) -> f32 {
    let ramp = clamp((cos_theta - cos_outer) / max(0.001, cos_inner - cos_outer), 0.0, 1.0);
    let sin_outer = sqrt(max(0.0, 1.0 - cos_outer * cos_outer));
    let sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
    let to_edge = atan2(sin_outer * cos_theta - cos_outer * sin_theta, cos_outer * cos_theta + sin_outer * sin_theta);
    let linear = select(clamp(to_edge / max(1e-6, mode - 1.0), 0.0, 1.0), 1.0, cos_theta >= cos_inner);
    return select(ramp * ramp, select(0.0, linear, cos_theta > cos_outer), mode >= 1.0);
}

#ifdef HAS_TEXTURES
// A textured spot's colour toward w (from the light to the point p, any length, within
// its outer cone): its texture at uv = (1 + (w . r, w . u) / (w . f)) / 2, v up, for the
// axis f (the record's c.xyz), the up vector over the tangent of the outer angle u (d.xyz)
// and r = f x u: the outer cone's square spans the image (Mitsuba 3's spot).
fn spot_texture(e: Emitter, w: vec3<f32>, p: vec3<f32>) -> vec3<f32> {
    let f = e.c.xyz;
    let u = e.d.xyz;
    let uv = 0.5 + 0.5 * vec2<f32>(dot(w, cross(f, u)), dot(w, u)) / dot(w, f);
    return texture_value(e.texture, vec4<f32>(uv, uv), p);
}
#endif

#ifdef HAS_PROJECTOR
// A projector's intensity toward w (from the light to the point p, any length) over its
// colour: pi x its irradiance texture at the frustum's uv, over cos^3 of the angle from
// its axis, so that a plane facing it at distance 1 along the axis receives pi x the
// texture (Mitsuba 3's projector); 0 outside the frustum. The record holds the right and
// up vectors over the tangents of the half angles: uv = (1 + (w . r, w . u) / (w . f)) / 2,
// v up, for the axis f = u x r.
fn projector_falloff(e: Emitter, w: vec3<f32>, p: vec3<f32>) -> vec3<f32> {
    let r = vec3<f32>(e.a.w, e.b.w, e.c.w);
    let u = e.c.xyz;
    let z = dot(w, normalize(cross(u, r)));
    let st = vec2<f32>(dot(w, r), dot(w, u)) / z;
    if (!(z > 0.0 && abs(st.x) <= 1.0 && abs(st.y) <= 1.0)) {
        return vec3<f32>(0.0);
    }
    var irradiance = vec3<f32>(1.0);
#ifdef HAS_TEXTURES
    if (e.texture != NO_TEXTURE) {
        let uv = 0.5 + 0.5 * st;
        irradiance = texture_value(e.texture, vec4<f32>(uv, uv), p);
    }
#endif
    let c = z / length(w);
    return irradiance * (PI / (c * c * c));
}
#endif

// A light without a surface, seen from a point.
struct PunctualSample {
    // the light (index in emitters)
    light: u32,
    // unit direction toward it
    dir: vec3<f32>,
    // what it sends along dir: intensity x a spot's falloff / d^2, or a directional
    // light's irradiance
    le: vec3<f32>,
    // squared distance to it (1 for a directional light)
    d2: f32,
    // the probability it was chosen with
    prob: f32,
    // where it is, when it is somewhere (a directional light is not)
    position: vec3<f32>,
    positioned: bool,
}

// The light without a surface chosen by u (in proportion to its power), seen from p.
fn sample_punctual(p: vec3<f32>, u: f32) -> PunctualSample {
    let i = choose_punctual(u);
    let e = emitter_record(i);
    let positioned = e.kind != LIGHT_DIRECTIONAL;
    var dir = e.a.xyz;
    var le = e.b.xyz;
    var d2 = 1.0;
    if (positioned) {
        let v = e.a.xyz - p;
        d2 = dot(v, v);
        dir = v / sqrt(d2);
        var falloff = 1.0;
        if (e.kind == LIGHT_SPOT) {
            falloff = spot_falloff(-dot(dir, e.c.xyz), e.a.w, e.b.w, e.c.w);
#ifdef HAS_TEXTURES
            if (e.texture != NO_TEXTURE && falloff > 0.0) {
                le *= spot_texture(e, -v, p);
            }
#endif
        }
#ifdef HAS_PROJECTOR
        if (e.kind == LIGHT_PROJECTOR) {
            le *= projector_falloff(e, -v, p);
        }
#endif
        le *= falloff / d2;
    }
    return PunctualSample(i, dir, le, d2, e.prob, e.a.xyz, positioned);
}
#endif

// A direction toward a light from a reference point.
struct LightSample {
    // the light (index in emitters), NO_LIGHT when there is no sample
    light: u32,
    // unit direction from the reference point
    dir: vec3<f32>,
    // distance to the sampled point (FAR for the environment)
    dist: f32,
    // solid-angle pdf, the choice of the light included
    pdf: f32,
    // the hit candidate's (u, v) on the light: barycentrics of a triangle's v1 and v2
    uv: vec2<f32>,
}

// Solid-angle pdf that light `i` is sampled toward x (a point on it, in direction d from
// p), the choice of the light included.
fn light_pdf(i: u32, p: vec3<f32>, x: vec3<f32>, d: vec3<f32>) -> f32 {
    let e = emitter_record(i);
#ifdef HAS_ENV_MAP
    if (e.kind == LIGHT_ENVIRONMENT) {
        return e.prob * env_pdf(d);
    }
#endif
    let pdf = shape_light_pdf(e, p, x);
    return e.prob * pdf;
}

// Samples a direction toward a light from p: the light by u_light (in proportion to
// power), the point on it by u: by its type's NAME_light_sample (a triangle or a disk by
// area, a sphere in the cone it subtends), the image background from its 2D
// distribution.
fn sample_light(p: vec3<f32>, u_light: f32, u: vec2<f32>) -> LightSample {
    var ls = LightSample(NO_LIGHT, vec3<f32>(0.0, 0.0, 1.0), FAR, 0.0, vec2<f32>(0.0));
    if (params.num_emitters == 0u) {
        return ls;
    }
    let i = choose_light(u_light);
    let e = emitter_record(i);
#ifdef HAS_ENV_MAP
    if (e.kind == LIGHT_ENVIRONMENT) {
        let tex = textures[params.env_texture];
        let row = sample_cdf(0u, tex.height, u.y);
        let col = sample_cdf(tex.height + 1u + row.i * (tex.width + 1u), tex.width, u.x);
        let sin_theta = sin(PI * row.x);
        if (sin_theta > 0.0) {
            ls.dir = env_direction(vec2<f32>(col.x, row.x));
            ls.pdf = e.prob * row.pdf * col.pdf / (2.0 * PI * PI * sin_theta);
            ls.light = select(NO_LIGHT, i, ls.pdf > 0.0);
        }
        return ls;
    }
#endif
    let lp = shape_light_sample(e, p, u);
    let x = lp.x;
    let pdf = lp.pdf;
    ls.uv = lp.uv;
    let v = x - p;
    let dist = length(v);
    if (pdf > 0.0 && dist > 0.0) {
        ls.light = i;
        ls.dir = v / dist;
        ls.dist = dist;
        ls.pdf = e.prob * pdf;
    }
    return ls;
}

// Solid-angle pdf of direction d from p under light sampling as a whole: the sum over
// lights of choice x density, each light's surface found along the ray whatever lies in
// between (what the 50/50 mixture divides by). Costs one test per light.
fn light_pdf_total(p: vec3<f32>, d: vec3<f32>) -> f32 {
    var total = 0.0;
    for (var i = 0u; i < params.num_emitters; i++) {
        let e = emitter_record(i);
#ifdef HAS_ENV_MAP
        // the image background is along every ray, at no distance
        let t = select(shape_light_distance(e, p, d), 0.0, e.kind == LIGHT_ENVIRONMENT);
#else
        let t = shape_light_distance(e, p, d);
#endif
        if (t < FAR) {
            total += light_pdf(i, p, p + t * d, d);
        }
    }
    return total;
}

// The power heuristic (beta = 2) weight of a strategy with pdf a against one with pdf b,
// a^2 / (a^2 + b^2), by ratios so that no square overflows.
fn power_heuristic(a: f32, b: f32) -> f32 {
    if (!(a > 0.0)) {
        return 0.0;
    }
    if (a >= b) {
        let r = b / a;
        return 1.0 / (1.0 + r * r);
    }
    let r = a / b;
    return r * r / (1.0 + r * r);
}
