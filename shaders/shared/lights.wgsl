// Lights: the background's radiance, choosing a light in proportion to its power, sampling
// a direction toward it, and the solid-angle pdf of a direction under light sampling.
// Every pdf includes the probability of choosing the light, exactly as the estimators use
// it. Area lights (triangles, disks, spheres) are sampled from their world-space records
// in `emitters`; the image background from a 2D distribution over its pixels.
#import shared/bindings
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
// asin(sin(outer - theta)), which keeps its relative precision at the cone's edge (an
// acos of cos_theta would not).
fn spot_falloff(cos_theta: f32, cos_outer: f32, cos_inner: f32, mode: f32) -> f32 {
    let ramp = clamp((cos_theta - cos_outer) / max(0.001, cos_inner - cos_outer), 0.0, 1.0);
    let sin_outer = sqrt(max(0.0, 1.0 - cos_outer * cos_outer));
    let sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
    let to_edge = asin(clamp(sin_outer * cos_theta - cos_outer * sin_theta, -1.0, 1.0));
    let linear = select(clamp(to_edge / max(1e-6, mode - 1.0), 0.0, 1.0), 1.0, cos_theta >= cos_inner);
    return select(ramp * ramp, select(0.0, linear, cos_theta > cos_outer), mode >= 1.0);
}

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

// Solid-angle pdf of a point x with unit normal n drawn uniformly from an area, seen from
// p: |x - p|^2 / (|cos| area); 0 when seen edge-on.
fn area_pdf(p: vec3<f32>, x: vec3<f32>, n: vec3<f32>, area: f32) -> f32 {
    let v = x - p;
    let d2 = dot(v, v);
    let c = abs(dot(n, v)) / sqrt(d2);
    if (!(d2 > 0.0) || !(c >= EDGE_ON_COS) || c * area <= d2 * 1e-30) {
        return 0.0;
    }
    return d2 / (c * area);
}

// Whether p is inside a sphere light for sampling: within radius x (1 + 1/1024), squared 1 + 1/512. On and just
// outside the surface (a point shaded on the light itself) the cone degenerates into a
// cap of nearly zero size whose directions rounding destroys; area sampling is exact there.
fn sphere_inside(p: vec3<f32>, center: vec3<f32>, r: f32) -> bool {
    let v = p - center;
    return dot(v, v) <= r * r * (1.0 + 1.0 / 512.0);
}

// 1 - cos(theta_max) of the cone a sphere of radius r subtends at squared distance dc2
// from its centre (sin^2 / 2 for small cones, where the subtraction would cancel).
fn sphere_cone(r: f32, dc2: f32) -> f32 {
    let sin2_max = r * r / dc2;
    if (sin2_max < 0.00068523) {
        return 0.5 * sin2_max;
    }
    return 1.0 - sqrt(max(0.0, 1.0 - sin2_max));
}

// A point on a sphere light seen from p: uniform in the cone of directions the sphere
// subtends (pbrt-v4's Sphere::Sample, small cones by the series), or uniform by area when
// p is inside (sphere_inside). Returns the point in .xyz, its solid-angle pdf in .w.
fn sample_sphere_light(center: vec3<f32>, r: f32, p: vec3<f32>, u: vec2<f32>) -> vec4<f32> {
    let oc = center - p;
    let dc2 = dot(oc, oc);
    if (sphere_inside(p, center, r)) {
        let n = sample_sphere(u);
        let x = center + r * n;
        return vec4<f32>(x, area_pdf(p, x, n, 4.0 * PI * r * r));
    }
    let sin2_max = r * r / dc2;
    let sin_max = sqrt(sin2_max);
    let cos_max = sqrt(max(0.0, 1.0 - sin2_max));
    var cos_t = (cos_max - 1.0) * u.x + 1.0;
    var sin2_t = 1.0 - cos_t * cos_t;
    if (sin2_max < 0.00068523) {
        sin2_t = sin2_max * u.x;
        cos_t = sqrt(1.0 - sin2_t);
    }
    let cos_a = sin2_t / sin_max + cos_t * sqrt(max(0.0, 1.0 - sin2_t / sin2_max));
    let sin_a = sqrt(max(0.0, 1.0 - cos_a * cos_a));
    let phi = 2.0 * PI * u.y;
    let wc = oc / sqrt(dc2);
    let tb = onb_tangents(wc);
    let n = -(sin_a * cos(phi) * tb[0] + sin_a * sin(phi) * tb[1] + cos_a * wc);
    return vec4<f32>(center + r * n, 1.0 / (2.0 * PI * sphere_cone(r, dc2)));
}

// Solid-angle pdf that light `i` is sampled toward x (a point on it, in direction d from
// p), the choice of the light included.
fn light_pdf(i: u32, p: vec3<f32>, x: vec3<f32>, d: vec3<f32>) -> f32 {
    let e = emitter_record(i);
    var pdf = 0.0;
    switch e.kind {
#ifdef HAS_TRIANGLE
        case LIGHT_TRIANGLE: {
            let n = normalize(cross(e.b.xyz - e.a.xyz, e.c.xyz - e.a.xyz));
            pdf = area_pdf(p, x, n, e.area);
        }
#endif
#ifdef HAS_DISK
        case LIGHT_DISK: {
            pdf = area_pdf(p, x, e.b.xyz, e.area);
        }
#endif
#ifdef HAS_SPHERE
        case LIGHT_SPHERE: {
            if (sphere_inside(p, e.a.xyz, e.a.w)) {
                pdf = area_pdf(p, x, normalize(x - e.a.xyz), e.area);
            } else {
                pdf = 1.0 / (2.0 * PI * sphere_cone(e.a.w, dot(e.a.xyz - p, e.a.xyz - p)));
            }
        }
#endif
#ifdef HAS_ENV_MAP
        case LIGHT_ENVIRONMENT: {
            pdf = env_pdf(d);
        }
#endif
        default: {}
    }
    return e.prob * pdf;
}

// Samples a direction toward a light from p: the light by u_light (in proportion to
// power), the point on it by u. Triangles: u = 1 - sqrt(xi1), v = xi2 sqrt(xi1) weigh
// vertices a and b; disks: rho = R sqrt(xi1), theta = 2 pi xi2 in the disk's plane;
// spheres: the cone they subtend; the image background: its 2D distribution.
fn sample_light(p: vec3<f32>, u_light: f32, u: vec2<f32>) -> LightSample {
    var ls = LightSample(NO_LIGHT, vec3<f32>(0.0, 0.0, 1.0), FAR, 0.0, vec2<f32>(0.0));
    if (params.num_emitters == 0u) {
        return ls;
    }
    let i = choose_light(u_light);
    let e = emitter_record(i);
    var x = vec3<f32>(0.0);
    var pdf = 0.0;
    switch e.kind {
#ifdef HAS_TRIANGLE
        case LIGHT_TRIANGLE: {
            let su = sqrt(u.x);
            let wa = 1.0 - su;
            let wb = u.y * su;
            x = wa * e.a.xyz + wb * e.b.xyz + (1.0 - wa - wb) * e.c.xyz;
            let n = normalize(cross(e.b.xyz - e.a.xyz, e.c.xyz - e.a.xyz));
            pdf = area_pdf(p, x, n, e.area);
            ls.uv = vec2<f32>(wb, 1.0 - wa - wb);
        }
#endif
#ifdef HAS_DISK
        case LIGHT_DISK: {
            let d = sample_disk(u) * e.a.w;
            let tb = onb_tangents(e.b.xyz);
            x = e.a.xyz + d.x * tb[0] + d.y * tb[1];
            pdf = area_pdf(p, x, e.b.xyz, e.area);
        }
#endif
#ifdef HAS_SPHERE
        case LIGHT_SPHERE: {
            let s = sample_sphere_light(e.a.xyz, e.a.w, p, u);
            x = s.xyz;
            pdf = s.w;
        }
#endif
#ifdef HAS_ENV_MAP
        case LIGHT_ENVIRONMENT: {
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
        default: {}
    }
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
    let ray = Ray(p, d);
    var total = 0.0;
    for (var i = 0u; i < params.num_emitters; i++) {
        let e = emitter_record(i);
        var t = FAR;
        switch e.kind {
#ifdef HAS_TRIANGLE
            case LIGHT_TRIANGLE: {
                t = intersect_triangle(e.a.xyz, e.b.xyz, e.c.xyz, ray, FAR).x;
            }
#endif
#ifdef HAS_DISK
            case LIGHT_DISK: {
                t = intersect_disk(e.a.xyz, e.b.xyz, e.a.w, ray, FAR);
            }
#endif
#ifdef HAS_SPHERE
            case LIGHT_SPHERE: {
                if (sphere_inside(p, e.a.xyz, e.a.w)) {
                    // inside: the far root (the way out)
                    let oc = p - e.a.xyz;
                    let b = dot(oc, d);
                    let c = dot(oc, oc) - e.a.w * e.a.w;
                    t = -b + sqrt(max(0.0, b * b - c));
                    if (!(t > 0.0)) {
                        t = FAR;
                    }
                } else {
                    t = intersect_sphere(e.a.xyz, e.a.w, ray, FAR);
                }
            }
#endif
#ifdef HAS_ENV_MAP
            case LIGHT_ENVIRONMENT: {
                t = 0.0;
            }
#endif
            default: {}
        }
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
