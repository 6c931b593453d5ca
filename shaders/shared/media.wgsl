// Participating media (HAS_MEDIA): the medium records, which medium a ray is in after it
// crosses a surface, the Henyey-Greenstein phase function, free flights and the
// transmittance of shadow rays. A homogeneous medium's free flight is drawn in closed
// form by the extinction of one colour channel chosen uniformly, and weighed by the mean
// of the three channels' densities (spectral MIS, the one-sample balance heuristic over
// the channels), so chromatic extinction never weighs a path by an unbounded ratio.
// A heterogeneous medium (HAS_GRID_MEDIA) scales its extinction by a density grid:
// free flights by delta tracking and shadow rays by ratio tracking, both against the
// majorants of coarse cells the ray steps through.
#import shared/bindings
#import shared/intersect
#import shared/materials
#import shared/rng
#import shared/sampling
#import shared/types

#ifdef HAS_MEDIA
struct Medium {
    sigma_t: vec3<f32>,
    // the Henyey-Greenstein asymmetry
    g: f32,
    albedo: vec3<f32>,
    // the tables entry of its density grid's header (GRID_ENTRIES), 0: homogeneous
    grid: u32,
}

// Medium i of the tables (params.media, MEDIUM_ENTRIES each).
fn medium_record(i: u32) -> Medium {
    let at = params.media + i * MEDIUM_ENTRIES;
    let a = tables[at];
    let b = tables[at + 1u];
    return Medium(a.xyz, a.w, b.xyz, bitcast<u32>(b.w));
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
    if (all(m.albedo == vec3<f32>(0.0))) {
        // nothing scatters: the transmittance itself (a glass's absorption)
        return Flight(-1.0, exp(-m.sigma_t * t_max));
    }
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

#ifdef HAS_GRID_MEDIA
// A density grid (its header at tables entry h): the affine map from the scene into the
// unit cube the grid fills (three rows), the voxel counts and the first value (a float
// index into the tables, x fastest), the same for the majorants of its cells of
// MAJORANT_CELL voxels a side, its channels, and the header of its albedo grid (0: none).
struct Grid {
    to_unit: array<vec4<f32>, 3>,
    res: vec3<u32>,
    data: u32,
    cells: vec3<u32>,
    majorants: u32,
    // values per voxel: 1, or 3 for a density per colour channel
    channels: u32,
    albedo: u32,
}

fn grid_record(h: u32) -> Grid {
    let r = tables[h + 3u];
    let c = tables[h + 4u];
    return Grid(array<vec4<f32>, 3>(tables[h], tables[h + 1u], tables[h + 2u]), bitcast<vec3<u32>>(r.xyz), bitcast<u32>(r.w), bitcast<vec3<u32>>(c.xyz), bitcast<u32>(c.w), bitcast<u32>(tables[h + 5u].x), bitcast<u32>(tables[h + 5u].w));
}

fn table_float(i: u32) -> f32 {
    return tables[i >> 2u][i & 3u];
}

// Channel c of the grid's values (`channels` a voxel) at p in its unit cube: trilinear
// between voxel centres ((i + 0.5) / res), clamped at the faces.
fn grid_value(g: Grid, p: vec3<f32>, channels: u32, c: u32) -> f32 {
    let x = p * vec3<f32>(g.res) - 0.5;
    let f = floor(x);
    let w = x - f;
    let top = vec3<i32>(g.res) - 1;
    let i0 = vec3<u32>(clamp(vec3<i32>(f), vec3<i32>(0), top));
    let i1 = vec3<u32>(clamp(vec3<i32>(f) + 1, vec3<i32>(0), top));
    let row = g.res.x;
    let slice = g.res.x * g.res.y;
    var d = 0.0;
    for (var k = 0u; k < 8u; k++) {
        let v = select(i0, i1, (vec3<u32>(k) & vec3<u32>(1u, 2u, 4u)) != vec3<u32>(0u));
        let wk = select(1.0 - w, w, (vec3<u32>(k) & vec3<u32>(1u, 2u, 4u)) != vec3<u32>(0u));
        d += wk.x * wk.y * wk.z * table_float(g.data + (v.x + v.y * row + v.z * slice) * channels + c);
    }
    return d;
}

// The density grid's density at p in its unit cube, per colour channel.
fn grid_density(g: Grid, p: vec3<f32>) -> vec3<f32> {
    if (g.channels == 3u) {
        return vec3<f32>(grid_value(g, p, 3u, 0u), grid_value(g, p, 3u, 1u), grid_value(g, p, 3u, 2u));
    }
    return vec3<f32>(grid_value(g, p, 1u, 0u));
}

// The single-scattering albedo of heterogeneous medium m at p (in the scene): its albedo
// grid's there, else its own.
fn grid_albedo(m: Medium, g: Grid, p: vec3<f32>) -> vec3<f32> {
    if (g.albedo == 0u) {
        return m.albedo;
    }
    let a = grid_record(g.albedo);
    let q = grid_point(a, p);
    return vec3<f32>(grid_value(a, q, 3u, 0u), grid_value(a, q, 3u, 1u), grid_value(a, q, 3u, 2u));
}

fn grid_point(g: Grid, p: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(g.to_unit[0].xyz, p) + g.to_unit[0].w, dot(g.to_unit[1].xyz, p) + g.to_unit[1].w, dot(g.to_unit[2].xyz, p) + g.to_unit[2].w);
}

fn grid_vector(g: Grid, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(g.to_unit[0].xyz, v), dot(g.to_unit[1].xyz, v), dot(g.to_unit[2].xyz, v));
}

// The next uniform number of a tracking's own stream (a PCG generator, O'Neill 2014).
fn tracking_rand(state: ptr<function, u32>) -> f32 {
    *state = *state * 747796405u + 2891336453u;
    let s = *state;
    let word = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
    return u32_to_unit_float((word >> 22u) ^ word);
}

// Tracking through heterogeneous medium m along a unit ray from t = 0 to t_max, its
// stream seeded by `seed`. Tentative collisions come at the rate of the majorant of the
// cell the ray is in (the cells stepped through in order, the optical depth to the next
// collision carried across them); where the grid holds nothing there are none.
// scatters (delta tracking with null collisions, a path's free flight): at a collision
// of density sigma_t, the path scatters with probability mean(sigma_s) / majorant,
// weighed by sigma_s / mean(sigma_s), else goes on weighed by (majorant - sigma_t) /
// (majorant - mean(sigma_s)), so absorption and chromatic extinction are in the weights.
// Else (ratio tracking, a shadow ray): never scatters, each collision weighs by
// (majorant - sigma_t) / majorant; the weight then is the transmittance's estimate.
// At most MAX_TRACKING_STEPS cells and collisions; a flight cut off there ends.
fn track(m: Medium, ray: Ray, t_max: f32, seed: u32, scatters: bool) -> Flight {
    let g = grid_record(m.grid);
    // the ray in cell units, its parameter still the scene's distance
    let k = vec3<f32>(g.res) / f32(MAJORANT_CELL);
    let o = grid_point(g, ray.origin) * k;
    let d = grid_vector(g, ray.dir) * k;
    let inv = 1.0 / d;
    let a = (vec3<f32>(0.0) - o) * inv;
    let b = (k - o) * inv;
    let lo = select(min(a, b), vec3<f32>(-FAR), d == vec3<f32>(0.0));
    let hi = select(max(a, b), vec3<f32>(FAR), d == vec3<f32>(0.0));
    var t = max(max(lo.x, lo.y), max(lo.z, 0.0));
    let t_end = min(min(hi.x, hi.y), min(hi.z, t_max));
    var weight = vec3<f32>(1.0);
    // parallel to a face and outside its slab: the ray misses the grid
    let misses = any((d == vec3<f32>(0.0)) & ((o < vec3<f32>(0.0)) | (o > k)));
    if (!(t < t_end) || misses) {
        return Flight(-1.0, weight);
    }
    let top = vec3<i32>(g.cells) - 1;
    var cell = clamp(vec3<i32>(floor(o + t * d)), vec3<i32>(0), top);
    let step = select(vec3<i32>(-1), vec3<i32>(1), d >= vec3<f32>(0.0));
    let edge = vec3<f32>(cell + select(vec3<i32>(0), vec3<i32>(1), d >= vec3<f32>(0.0)));
    var t_next = select((edge - o) * inv, vec3<f32>(FAR), d == vec3<f32>(0.0));
    let dt = select(abs(inv), vec3<f32>(FAR), d == vec3<f32>(0.0));
    let sigma_max = max(m.sigma_t.x, max(m.sigma_t.y, m.sigma_t.z));
    var state = seed;
    var tau = -log(1.0 - tracking_rand(&state));
    for (var i = 0u; i < MAX_TRACKING_STEPS; i++) {
        let c = vec3<u32>(cell);
        let mu = sigma_max * table_float(g.majorants + c.x + c.y * g.cells.x + c.z * g.cells.x * g.cells.y);
        let t_exit = min(min(min(t_next.x, t_next.y), t_next.z), t_end);
        let depth = mu * (t_exit - t);
        if (tau >= depth) {
            // no collision in this cell: on into the next
            tau -= depth;
            t = t_exit;
            if (t >= t_end) {
                return Flight(-1.0, weight);
            }
            let axis = select(select(2u, 1u, t_next.y <= t_next.z), 0u, t_next.x <= t_next.y && t_next.x <= t_next.z);
            cell[axis] += step[axis];
            t_next[axis] += dt[axis];
            if (any(cell < vec3<i32>(0)) || any(cell > top)) {
                return Flight(-1.0, weight);
            }
            continue;
        }
        t += tau / mu;
        tau = -log(1.0 - tracking_rand(&state));
        let x = ray.origin + t * ray.dir;
        let sigma_t = grid_density(g, grid_point(g, x)) * m.sigma_t;
        if (scatters) {
            let sigma_s = sigma_t * grid_albedo(m, g, x);
            let mean_s = dot(sigma_s, vec3<f32>(1.0 / 3.0));
            if (tracking_rand(&state) * mu < mean_s) {
                return Flight(t, weight * sigma_s / mean_s);
            }
            weight = select(vec3<f32>(0.0), weight * max(vec3<f32>(mu) - sigma_t, vec3<f32>(0.0)) / (mu - mean_s), mu > mean_s);
        } else {
            weight *= max(vec3<f32>(mu) - sigma_t, vec3<f32>(0.0)) / mu;
        }
        if (all(weight == vec3<f32>(0.0))) {
            return Flight(-1.0, weight);
        }
    }
    return Flight(-1.0, vec3<f32>(0.0));
}

// The seed of a tracking's stream from two uniform numbers and a counter.
fn tracking_seed(u: vec2<f32>, k: u32) -> u32 {
    return pcg4d(vec4<u32>(bitcast<vec2<u32>>(u), k, 0x6d656469u)).x;
}
#endif

// The single-scattering albedo of medium m at p.
fn medium_albedo(m: Medium, p: vec3<f32>) -> vec3<f32> {
#ifdef HAS_GRID_MEDIA
    if (m.grid != 0u) {
        return grid_albedo(m, grid_record(m.grid), p);
    }
#endif
    return m.albedo;
}

// A free flight through medium m along `ray` up to t_max, drawn from u (and, in a grid,
// the stream it seeds; k counts the stretches of one bounce).
fn medium_flight(m: Medium, ray: Ray, t_max: f32, u: vec2<f32>, k: u32) -> Flight {
#ifdef HAS_GRID_MEDIA
    if (m.grid != 0u) {
        return track(m, ray, t_max, tracking_seed(u, k), true);
    }
#endif
    return free_flight(m, t_max, u);
}

// The transmittance of medium m along `ray` from 0 to t (an estimate by ratio tracking in
// a grid, its stream seeded by the shadow ray's own sample us and the stretch k).
fn medium_transmittance(m: Medium, ray: Ray, t: f32, us: vec2<f32>, k: u32) -> vec3<f32> {
#ifdef HAS_GRID_MEDIA
    if (m.grid != 0u) {
        return track(m, ray, t, tracking_seed(us, k), false).weight;
    }
#endif
    return exp(-m.sigma_t * t);
}

// What reaches the end of a shadow ray of unit direction from its origin to t_max, which
// starts in `medium`: each medium's transmittance exp(-sigma_t d) over the stretch it
// holds, surfaces transparent where the ray meets them passed through (u deciding for
// blended ones; crossing a shape with media changes the medium), 0 at an opaque one. us,
// the sample of the light the ray goes to, seeds ratio tracking through grids.
fn transmittance(ray: Ray, t_max: f32, u: f32, medium: u32, us: vec2<f32>) -> vec3<f32> {
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
            tr *= medium_transmittance(medium_record(m), r, stretch, us, k);
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
