// Participating media (HAS_MEDIA): the medium records, which medium a ray is in after it
// crosses a surface, the Henyey-Greenstein phase function, free flights and the
// transmittance of shadow rays. A homogeneous medium's free flight is drawn in closed
// form by the extinction of one colour channel chosen uniformly, and weighed by the mean
// of the three channels' densities (spectral MIS, the one-sample balance heuristic over
// the channels), so chromatic extinction never weighs a path by an unbounded ratio.
#import shared/bindings
#import shared/intersect
#import shared/materials
#import shared/sampling
#import shared/types

#ifdef HAS_MEDIA
struct Medium {
    sigma_t: vec3<f32>,
    // the Henyey-Greenstein asymmetry
    g: f32,
    albedo: vec3<f32>,
}

// Medium i of the tables (params.media, MEDIUM_ENTRIES each).
fn medium_record(i: u32) -> Medium {
    let at = params.media + i * MEDIUM_ENTRIES;
    let a = tables[at];
    let b = tables[at + 1u];
    return Medium(a.xyz, a.w, b.xyz);
}

// The medium a ray is in once it leaves a surface whose shape holds `media` (its media
// word: interior + 1 + MEDIA_SIDE x (exterior + 1)) along dir: the interior when dir goes
// against the outward normal ng, else the exterior; `current` when the shape holds none.
fn medium_after(media: u32, ng: vec3<f32>, dir: vec3<f32>, current: u32) -> u32 {
    if (media == 0u) {
        return current;
    }
    let side = select(media / MEDIA_SIDE, media % MEDIA_SIDE, dot(dir, ng) < 0.0);
    return select(side - 1u, NO_MEDIUM, side == 0u);
}

// The media word of the shape a hit is on (its material record's).
fn media_at(hit: Hit) -> u32 {
    let i = params.material_media * 4u + hit.material;
    return u32(tables[i >> 2u][i & 3u]);
}

// The Henyey-Greenstein phase function for the cosine between the direction of travel
// and the scattered direction (g > 0 scatters forward); it is its own pdf.
fn hg_eval(cos_theta: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos_theta;
    return (1.0 - g * g) / (4.0 * PI * denom * sqrt(denom));
}

// A direction scattered from travel direction d by the Henyey-Greenstein phase function
// (the inverse of its cumulative distribution in cos theta).
fn hg_sample(d: vec3<f32>, g: f32, u: vec2<f32>) -> vec3<f32> {
    var cos_theta = 1.0 - 2.0 * u.x;
    if (abs(g) >= 1e-3) {
        let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u.x);
        cos_theta = (1.0 + g * g - s * s) / (2.0 * g);
    }
    cos_theta = clamp(cos_theta, -1.0, 1.0);
    let sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
    let phi = 2.0 * PI * u.y;
    let t = onb_tangents(d);
    return normalize(cos_theta * d + sin_theta * (cos(phi) * t[0] + sin(phi) * t[1]));
}

// A free flight through medium m from t = 0 along a unit direction, up to t_max (the next
// surface, FAR without one): u.x picks the channel whose extinction draws the distance,
// u.y the distance. Returns the distance of a scattering event before t_max, or a negative
// number when the flight reaches t_max; `weight` times what the path's throughput takes
// (Tr sigma_s / pdf for an event, Tr / P(no event) else, each pdf the channels' mean).
struct Flight {
    t: f32,
    weight: vec3<f32>,
}

fn free_flight(m: Medium, t_max: f32, u: vec2<f32>) -> Flight {
    let c = min(u32(u.x * 3.0), 2u);
    let sigma = m.sigma_t[c];
    var t = FAR;
    if (sigma > 0.0) {
        t = -log(1.0 - u.y) / sigma;
    }
    if (t < t_max) {
        let tr = exp(-m.sigma_t * t);
        let pdf = dot(tr * m.sigma_t, vec3<f32>(1.0 / 3.0));
        return Flight(t, select(vec3<f32>(0.0), tr * m.sigma_t * m.albedo / pdf, pdf > 0.0));
    }
    let tr = exp(-m.sigma_t * t_max);
    let p = dot(tr, vec3<f32>(1.0 / 3.0));
    return Flight(-1.0, select(vec3<f32>(0.0), tr / p, p > 0.0));
}

// What reaches the end of a shadow ray of unit direction from its origin to t_max, which
// starts in `medium`: each medium's transmittance exp(-sigma_t d) over the stretch it
// holds, surfaces transparent where the ray meets them passed through (u deciding for
// blended ones; crossing a shape with media changes the medium), 0 at an opaque one.
fn transmittance(ray: Ray, t_max: f32, u: f32, medium: u32) -> vec3<f32> {
    var r = ray;
    var t = t_max;
    var m = medium;
    var tr = vec3<f32>(1.0);
    // each pass-through stops 2^-16 of the whole ray shorter: the end stands a few ulps
    // off the light's own surface, which the rounding of a pass-through (of the ray's
    // length, not the rest's) would otherwise reach on some rays and not on others
    let margin = t_max / 65536.0;
    for (var k = 0u; k < MAX_ALPHA_SKIPS; k++) {
        let cand = intersect_scene(r, t);
        let stretch = select(t, cand.t, cand.prim != NO_HIT);
        if (m != NO_MEDIUM) {
            tr *= exp(-medium_record(m).sigma_t * stretch);
        }
        if (cand.prim == NO_HIT) {
            return tr;
        }
        let hit = surface_at(r, cand);
#ifdef HAS_ALPHA
        if (!transparent_at(hit, alpha_u(u, k))) {
            return vec3<f32>(0.0);
        }
#else
        return vec3<f32>(0.0);
#endif
        m = medium_after(media_at(hit), hit.ng, r.dir, m);
        let next = Ray(offset_ray(hit.p, select(-hit.ng, hit.ng, dot(r.dir, hit.ng) > 0.0), hit.err), r.dir);
        t = t - dot(next.origin - r.origin, r.dir) - margin;
        if (t <= 0.0) {
            return tr;
        }
        r = next;
    }
    return vec3<f32>(0.0);
}
#endif
