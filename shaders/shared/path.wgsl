// A camera path, one bounce at a time, in stages over a vertex: the next vertex along the
// path's ray (next_hit: the closest surface, passing through transparent ones; escape when
// there is none), what it emits toward the path (add_emission, weighed by MIS), next-event
// estimation at it (next_event: direct_light and direct_punctual), and the path continued
// from it (sample_bounce, then continue_path, the one place a path's state moves on).
// A vertex (Vertex) is asked through vertex_eval, vertex_pdf, vertex_spawn and
// vertex_nee, the questions a medium point will answer too.
#import shared/bindings
#import shared/intersect
#import shared/lights
#import shared/materials
#import shared/media
#import shared/rng
#import shared/samplers
#import shared/sampling
#import shared/textures
#import shared/types

// Camera ray through a point of pixel (x, y); pixel (0, 0) is the top-left, x grows along
// the camera's right vector. `jitter` is the position inside the pixel, `lens` in [0, 1)^2.
// The ray starts where it crosses the near clip plane, params.near_clip in front of the
// camera along its forward vector (Mitsuba's near_clip: ray.o + d near_clip / d.z).
fn camera_ray(x: u32, y: u32, jitter: vec2<f32>, lens: vec2<f32>) -> Ray {
    let s = (f32(x) + jitter.x) / f32(params.width);
    let t = (f32(y) + jitter.y) / f32(params.height);
    let right = params.cam_right.xyz;
    let up = params.cam_up.xyz;
    let forward = params.cam_forward.xyz;
    let target_offset = forward * params.cam_forward.w
        + right * ((2.0 * s - 1.0) * params.cam_right.w)
        + up * ((1.0 - 2.0 * t) * params.cam_up.w);
    // a pinhole (radius 0) draws the lens sample too: leaving it out made llvmpipe's
    // code for the rest of the shader 1.0x to 3.2x slower (docs/specialization.md)
    let d = sample_disk(lens) * params.cam_origin.w;
    let lens_offset = right * d.x + up * d.y;
    // an orthographic camera's rays leave the view rectangle along forward; chosen by
    // select, not a branch: an early return here made llvmpipe's code for the Cornell box
    // at 64 x 64 1.7x slower (0.616 s against 0.36 s for 256 spp)
    let ortho = params.orthographic != 0u;
    let origin = select(params.cam_origin.xyz + lens_offset, params.cam_origin.xyz + target_offset - forward * params.cam_forward.w, ortho);
    let dir = select(normalize(target_offset - lens_offset), forward, ortho);
    // from the near clip plane on (0: the camera itself)
    return Ray(origin + dir * (params.near_clip / dot(dir, forward)), dir);
}

// A ray leaving a hit in direction dir, from just off the surface on dir's side.
fn spawn_ray(hit: Hit, dir: vec3<f32>) -> Ray {
    return Ray(offset_ray(hit.p, select(-hit.ng, hit.ng, dot(dir, hit.ng) > 0.0), hit.err), dir);
}

// Whether anything opaque lies on a shadow ray before t_max. With alpha materials the
// surfaces on the way are found one after the other (closest hit) and passed through where
// transparent, u deciding for blended ones; without, the first hit found ends the search.
fn shadowed(ray: Ray, t_max: f32, u: f32) -> bool {
#ifdef HAS_ALPHA
    var r = ray;
    var t = t_max;
    for (var k = 0u; k < MAX_ALPHA_SKIPS; k++) {
        let cand = intersect_scene(r, t);
        if (cand.prim == NO_HIT) {
            return false;
        }
        let hit = surface_at(r, cand);
        if (!transparent_at(hit, alpha_u(u, k))) {
            return true;
        }
        // the rest of the segment, shortened by 2^-16 of itself (offset_ray's relative
        // step): the end stands a few ulps off the light's own surface, which the
        // rounding of the pass-through would otherwise reach on some rays (and not on
        // the CPU's), shadowing them
        let next = spawn_ray(hit, r.dir);
        t = (t - dot(next.origin - r.origin, r.dir)) * (1.0 - 1.0 / 65536.0);
        if (t <= 0.0) {
            return false;
        }
        r = next;
    }
    return true;
#else
    return occluded(ray, t_max);
#endif
}

// A vertex of the path: a surface hit (its shading normal as the material bends it) and
// the material there, a blend's part already chosen; with media, or a point where the
// path scatters in a medium (`scatter`: hit.p is the point, mat unused).
struct Vertex {
    hit: Hit,
    mat: Material,
#ifdef HAS_MEDIA
    // the medium the path's ray arrived in, the media word of the surface's shape (0 at
    // a medium point), whether it is a medium point, and its medium's phase asymmetry
    medium: u32,
    media: u32,
    scatter: bool,
    g: f32,
#endif
}

// What the vertex scatters from the path's ray toward dir: BSDF x cos, or the phase
// function.
fn vertex_eval(v: Vertex, ray: Ray, dir: vec3<f32>) -> vec3<f32> {
#ifdef HAS_MEDIA
    if (v.scatter) {
        return vec3<f32>(hg_eval(dot(ray.dir, dir), v.g));
    }
#endif
    return bsdf_eval(v.mat, ray, v.hit, dir);
}

// The density with which the vertex's own sampling picks dir (for MIS).
fn vertex_pdf(v: Vertex, ray: Ray, dir: vec3<f32>) -> f32 {
#ifdef HAS_MEDIA
    if (v.scatter) {
        return hg_eval(dot(ray.dir, dir), v.g);
    }
#endif
    return bsdf_pdf(v.mat, ray, v.hit, dir);
}

// A ray leaving the vertex along dir (from a surface, just off it on dir's side).
fn vertex_spawn(v: Vertex, dir: vec3<f32>) -> Ray {
#ifdef HAS_MEDIA
    if (v.scatter) {
        return Ray(v.hit.p, dir);
    }
#endif
    return spawn_ray(v.hit, dir);
}

// Whether light sampling applies at the vertex (a lobe with a density; a medium point).
fn vertex_nee(v: Vertex) -> bool {
#ifdef HAS_MEDIA
    if (v.scatter) {
        return true;
    }
#endif
    return nee_applies(v.mat);
}

#ifdef HAS_MEDIA
// The medium a ray leaving the vertex along dir travels in.
fn vertex_medium(v: Vertex, dir: vec3<f32>) -> u32 {
    return medium_after(v.media, v.hit.ng, dir, v.medium);
}
#endif

// Next-event estimation at a vertex: a direction toward a light, a shadow ray from just off
// the surface to just short of the sampled point, and the light's emission there (its own
// shading record: side, texture) times BSDF x cos, weighed against BSDF sampling by the
// power heuristic and divided by the light's pdf.
fn direct_light(v: Vertex, ray: Ray, u_light: f32, u: vec2<f32>, u_alpha: f32) -> vec3<f32> {
    // Every step runs whatever the earlier ones found, and one test at the end keeps the
    // contribution or not: llvmpipe runs both sides of each branch anyway, and its masked
    // early returns cost more (1.3% of the Cornell box's bounce loop). A value of a failed
    // step is never used; without a light, emitter_record reads a clamped record.
    let ls = sample_light(v.hit.p, u_light, u);
    let f = vertex_eval(v, ray, ls.dir);
    var shadow = vertex_spawn(v, ls.dir);
    var t_max = FAR;
    var le: vec3<f32>;
    // the direction the MIS weight takes the material's pdf of: from the ray origin, as a
    // bounce ray toward the same point has it, so the two weights of a path add up to one
    // (from hit.p they differ by about offset / (distance x cos), 1e-3 on grazing chords)
    var pdf_dir = ls.dir;
    let e = emitter_record(ls.light);
    if (e.kind == LIGHT_ENVIRONMENT) {
        le = background_radiance(ls.dir);
    } else {
#ifdef HAS_INSTANCES
        let lh = surface_at(Ray(v.hit.p, ls.dir), Candidate(ls.dist, e.primitive, ls.uv.x, ls.uv.y, NO_HIT));
#else
        let lh = surface_at(Ray(v.hit.p, ls.dir), Candidate(ls.dist, e.primitive, ls.uv.x, ls.uv.y));
#endif
        le = emitted(material_at(material_record(lh.material), lh), lh);
#ifdef HAS_ALPHA
        // a light point where the emitter is cut out or passed through emits nothing
        // there, as a bounce ray finds it
        if (transparent_at(lh, alpha_u(u_alpha, MAX_ALPHA_SKIPS))) {
            le = vec3<f32>(0.0);
        }
#endif
        pdf_dir = normalize(lh.p - shadow.origin);
        let end = offset_ray(lh.p, select(-lh.ng, lh.ng, dot(ls.dir, lh.ng) < 0.0), lh.err);
        let v = end - shadow.origin;
        t_max = length(v);
        shadow.dir = v / t_max;
    }
    let lit = ls.light != NO_LIGHT && any(f != vec3<f32>(0.0)) && any(le != vec3<f32>(0.0)) && t_max > 0.0;
#ifdef HAS_MEDIA
    var tr = vec3<f32>(0.0);
    if (lit) {
        tr = transmittance(shadow, t_max, u_alpha, vertex_medium(v, ls.dir), u);
    }
    if (all(tr == vec3<f32>(0.0))) {
        return vec3<f32>(0.0);
    }
    let w = power_heuristic(ls.pdf, vertex_pdf(v, ray, pdf_dir));
    return f * tr * le * (w / ls.pdf);
#else
    if (!lit || shadowed(shadow, t_max, u_alpha)) {
        return vec3<f32>(0.0);
    }
    let w = power_heuristic(ls.pdf, vertex_pdf(v, ray, pdf_dir));
    return f * le * (w / ls.pdf);
#endif
}

#ifdef HAS_PUNCTUAL
// Next-event estimation toward a light without a surface, chosen among them in proportion
// to its power: a shadow ray to its position (or out of the scene, for a directional
// light), and f x intensity x the spot's falloff / d^2 (or f x irradiance) over the
// choice's probability. No MIS weight: no other strategy can find a point or a direction.
fn direct_punctual(v: Vertex, ray: Ray, u: f32, u_alpha: f32) -> vec3<f32> {
    let s = sample_punctual(v.hit.p, u);
    var shadow = vertex_spawn(v, s.dir);
    var t_max = FAR;
    if (s.positioned) {
        let w = s.position - shadow.origin;
        t_max = length(w);
        shadow.dir = w / t_max;
    }
    let f = vertex_eval(v, ray, s.dir);
    let lit = s.prob > 0.0 && s.d2 > 0.0 && t_max > 0.0 && any(f != vec3<f32>(0.0)) && any(s.le != vec3<f32>(0.0));
#ifdef HAS_MEDIA
    var tr = vec3<f32>(0.0);
    if (lit) {
        tr = transmittance(shadow, t_max, u_alpha, vertex_medium(v, s.dir), vec2<f32>(u, 0.5));
    }
    if (all(tr == vec3<f32>(0.0))) {
        return vec3<f32>(0.0);
    }
    return f * tr * s.le / s.prob;
#else
    if (!lit || shadowed(shadow, t_max, u_alpha)) {
        return vec3<f32>(0.0);
    }
    return f * s.le / s.prob;
#endif
}
#endif

// A camera path being traced: the ray to follow next, the radiance gathered so far, the
// throughput, and the previous vertex for the MIS weight of an emitter the ray hits (its
// point, the pdf of the ray's direction, and whether that came from a delta lobe, weight
// 1). depth counts the rays traced so far.
struct Path {
    ray: Ray,
    radiance: vec3<f32>,
    throughput: vec3<f32>,
    prev_p: vec3<f32>,
    prev_pdf: f32,
    prev_delta: bool,
    depth: u32,
#ifdef HAS_MEDIA
    // the medium the ray travels in (NO_MEDIUM: none)
    medium: u32,
#endif
#ifdef HAS_AOVS
    // the sample's AOVs: albedo and normal of the first vertex whose bounce is not a
    // delta lobe's (found once it is known), distance and point of the first hit
    albedo: vec3<f32>,
    normal: vec3<f32>,
    position: vec3<f32>,
    distance: f32,
    found: bool,
#endif
}

fn start_path(camera: Ray) -> Path {
    var path: Path;
    path.ray = camera;
    path.radiance = vec3<f32>(0.0);
    path.throughput = vec3<f32>(1.0);
    path.prev_p = camera.origin;
    path.prev_pdf = 0.0;
    path.prev_delta = true;
    path.depth = 0u;
#ifdef HAS_MEDIA
    path.medium = params.camera_medium;
#endif
#ifdef HAS_AOVS
    path.albedo = vec3<f32>(0.0);
    path.normal = vec3<f32>(0.0);
    path.position = vec3<f32>(0.0);
    path.distance = 0.0;
    path.found = false;
#endif
    return path;
}

// Russian roulette from ray rr_depth on: a path goes on with probability
// min(1, max(throughput)), its throughput divided by that; unbiased, and a dim path stops
// before its next ray. False when the path stops.
fn survives_roulette(path: ptr<function, Path>, pixel: u32, sample: u32) -> bool {
    if (params.rr_depth != 0u && (*path).depth >= params.rr_depth) {
        let survive = min(1.0, max((*path).throughput.x, max((*path).throughput.y, (*path).throughput.z)));
        if (rand_2d(pixel, sample, (*path).depth, DIM_RR, params.seed).x >= survive) {
            return false;
        }
        (*path).throughput /= survive;
    }
    return true;
}

// The next vertex along the path's ray: the closest surface (NO_HIT: none), or with media
// the point of a free flight's scattering event (MEDIUM_HIT, flies). With alpha
// materials, a surface transparent where the ray meets it is passed through (u decides for
// blended ones): the ray goes on from just beyond, its origin moved but its direction's
// pdf and the vertex it left (prev_p) kept, and the bounce not counted; the last surface
// is kept whatever.
fn next_hit(path: ptr<function, Path>, u: f32, pixel: u32, sample: u32) -> Candidate {
    var cand: Candidate;
#ifdef HAS_ALPHA
    // one call of the closest-hit search (llvmpipe inlines each call site whole)
    for (var k = 0u; k < MAX_ALPHA_SKIPS; k++) {
        cand = intersect_scene((*path).ray, FAR);
#ifdef HAS_MEDIA
        if (flies(path, &cand, pixel, sample, k)) {
            break;
        }
#endif
        if (cand.prim != NO_HIT && k + 1u < MAX_ALPHA_SKIPS) {
            let h = surface_at((*path).ray, cand);
            if (transparent_at(h, alpha_u(u, k))) {
#ifdef HAS_MEDIA
                (*path).medium = medium_after(media_at(h), h.ng, (*path).ray.dir, (*path).medium);
#endif
                (*path).ray = spawn_ray(h, (*path).ray.dir);
                continue;
            }
        }
        break;
    }
#else
    cand = intersect_scene((*path).ray, FAR);
#ifdef HAS_MEDIA
    flies(path, &cand, pixel, sample, 0u);
#endif
#endif
    return cand;
}

#ifdef HAS_MEDIA
// The free flight through the path's medium up to the surface cand found (the k-th
// stretch of this bounce's ray): true when the path scatters before it, cand then
// MEDIUM_HIT at the event's distance; the throughput takes the flight's weight.
fn flies(path: ptr<function, Path>, cand: ptr<function, Candidate>, pixel: u32, sample: u32, k: u32) -> bool {
    if ((*path).medium == NO_MEDIUM) {
        return false;
    }
    let t_max = select(FAR, (*cand).t, (*cand).prim != NO_HIT);
    let u = bounce_2d(pixel, sample, (*path).depth, DIM_MEDIUM + k);
    let flight = medium_flight(medium_record((*path).medium), (*path).ray, t_max, u, k);
    (*path).throughput *= flight.weight;
    if (flight.t >= 0.0) {
        (*cand).prim = MEDIUM_HIT;
        (*cand).t = flight.t;
        return true;
    }
    return false;
}

#ifdef HAS_AOVS
// The AOVs of a medium vertex that comes first: its distance and point, the normal facing
// the ray (a medium has none), the medium's single-scattering albedo.
fn medium_aovs(path: ptr<function, Path>, v: Vertex) {
    if ((*path).depth == 0u) {
        (*path).distance = distance(v.hit.p, (*path).prev_p);
        (*path).position = v.hit.p;
    }
    if (!(*path).found) {
        (*path).normal = -(*path).ray.dir;
        (*path).albedo = medium_albedo(medium_record(v.medium), v.hit.p);
        (*path).found = true;
    }
}
#endif

// The vertex where the path scatters in its medium, at distance t along its ray.
fn medium_vertex(path: ptr<function, Path>, t: f32) -> Vertex {
    var v: Vertex;
    v.hit.p = (*path).ray.origin + t * (*path).ray.dir;
    v.medium = (*path).medium;
    v.media = 0u;
    v.scatter = true;
    v.g = medium_record((*path).medium).g;
    return v;
}
#endif

// Whether an emitter the path's ray finds is weighed against light sampling: under MIS,
// after a bounce that light sampling could have made (not a delta lobe's).
fn weighs_emission(path: ptr<function, Path>) -> bool {
    return params.light_sampling == LIGHT_SAMPLING_MIS && !(*path).prev_delta;
}

// The path's ray leaves the scene: the background's radiance, weighed by MIS against
// sampling the environment light; the path ends.
fn escape(path: ptr<function, Path>) {
    var le = background_radiance((*path).ray.dir);
#ifdef HAS_AOVS
    // the background's radiance, clamped, is the albedo of a path that escapes
    if (!(*path).found) {
        (*path).albedo = clamp(le, vec3<f32>(0.0), vec3<f32>(1.0));
        (*path).found = true;
    }
#endif
#ifdef HAS_MIS
    if (weighs_emission(path) && params.env_light != NO_LIGHT) {
        le *= power_heuristic((*path).prev_pdf, light_pdf(params.env_light, (*path).prev_p, (*path).prev_p, (*path).ray.dir));
    }
#endif
    if (params.hide_emitters != 0u && (*path).depth == 0u) {
        le = vec3<f32>(0.0);
    }
    (*path).radiance += (*path).throughput * le;
}

// The vertex at a surface the path's ray found: its shading record, a blend's part chosen
// (for all the vertex does), the material there, its normal map and shading normal.
fn surface_vertex(path: ptr<function, Path>, cand: Candidate, pixel: u32, sample: u32) -> Vertex {
    let surface = surface_at((*path).ray, cand);
#ifdef HAS_BLEND
    let record = blend_choice(surface.material, surface, bounce_2d(pixel, sample, (*path).depth, DIM_BLEND).x);
#else
    let record = material_record(surface.material);
#endif
    let mat = material_at(record, surface);
#ifdef HAS_NORMAL_MAP
    let mapped = normal_mapped(mat, surface);
#else
    let mapped = surface;
#endif
#ifdef HAS_SHADING_NORMALS
    let hit = bent_normal(mat, mapped, (*path).ray);
#else
    let hit = mapped;
#endif
#ifdef HAS_MEDIA
    return Vertex(hit, mat, (*path).medium, media_at(surface), false, 0.0);
#else
    return Vertex(hit, mat);
#endif
}

// What the vertex emits toward the path, weighed by MIS against light sampling when prim
// is a light; the AOVs of a first hit.
fn add_emission(path: ptr<function, Path>, v: Vertex, prim: u32) {
    var le = emitted(v.mat, v.hit);
#ifdef HAS_AOVS
    if ((*path).depth == 0u) {
        // prev_p is still the camera ray's origin (passing through alpha keeps it)
        (*path).distance = distance(v.hit.p, (*path).prev_p);
        (*path).position = v.hit.p;
    }
    if (!(*path).found) {
        // the shading normal facing the ray; an emitter's albedo is its emission, clamped
        (*path).normal = select(-v.hit.ns, v.hit.ns, dot(v.hit.ns, (*path).ray.dir) < 0.0);
        if (any(le > vec3<f32>(0.0))) {
            (*path).albedo = clamp(le, vec3<f32>(0.0), vec3<f32>(1.0));
            (*path).found = true;
        }
    }
#endif
#ifdef HAS_MIS
    let light = primitive_record(prim).flags >> PRIM_LIGHT_SHIFT;
    if (weighs_emission(path) && light != 0u && any(le > vec3<f32>(0.0))) {
        le *= power_heuristic((*path).prev_pdf, light_pdf(light - 1u, (*path).prev_p, v.hit.p, (*path).ray.dir));
    }
#endif
    if (params.hide_emitters != 0u && (*path).depth == 0u) {
        le = vec3<f32>(0.0);
    }
    (*path).radiance += (*path).throughput * le;
}

// Next-event estimation at the vertex: a light with a surface or the background under MIS,
// and the lights without a surface under every strategy (only next-event estimation finds
// them; the full shader holds this for scenes without any).
fn next_event(path: ptr<function, Path>, v: Vertex, pixel: u32, sample: u32, u_alpha: f32) {
#ifdef HAS_MIS
    if (params.light_sampling == LIGHT_SAMPLING_MIS && vertex_nee(v)) {
        let ul = bounce_2d(pixel, sample, (*path).depth, DIM_LIGHT);
        let uc = bounce_2d(pixel, sample, (*path).depth, DIM_LIGHT_CHOICE);
        (*path).radiance += (*path).throughput * direct_light(v, (*path).ray, uc.x, ul, u_alpha);
    }
#endif
#ifdef HAS_PUNCTUAL
    if (params.num_punctual != 0u && vertex_nee(v)) {
        let up = bounce_2d(pixel, sample, (*path).depth, DIM_PUNCTUAL);
        (*path).radiance += (*path).throughput * direct_punctual(v, (*path).ray, up.x, u_alpha);
    }
#endif
}

// A direction the path goes on in from a vertex: its weight (f x cos / pdf), the pdf
// (what MIS weighs an emitter the next ray finds by), whether it came from a delta lobe;
// ok false: the path ends.
struct Bounce {
    ok: bool,
    dir: vec3<f32>,
    weight: vec3<f32>,
    pdf: f32,
    delta: bool,
}

fn no_bounce() -> Bounce {
    return Bounce(false, vec3<f32>(0.0), vec3<f32>(0.0), 0.0, false);
}

// The bounce from a vertex: one direction from the 50/50 mixture of light and material
// sampling, weighed by the mixture pdf (mixture, at a material without a delta lobe), or
// the material's own.
fn sample_bounce(path: ptr<function, Path>, v: Vertex, pixel: u32, sample: u32) -> Bounce {
    let u = bounce_2d(pixel, sample, (*path).depth, DIM_BSDF);
#ifdef HAS_MEDIA
    if (v.scatter) {
        // the phase function's own sample: weight 1
        let dir = hg_sample((*path).ray.dir, v.g, u);
        return Bounce(true, dir, vec3<f32>(1.0), hg_eval(dot((*path).ray.dir, dir), v.g), false);
    }
#endif
#ifdef HAS_MIXTURE
    if (params.light_sampling == LIGHT_SAMPLING_MIXTURE && params.num_emitters != 0u && mixture_applies(v.mat)) {
        let uc = bounce_2d(pixel, sample, (*path).depth, DIM_LIGHT_CHOICE);
        var dir: vec3<f32>;
        if (uc.y < 0.5) {
            let ls = sample_light(v.hit.p, uc.x, bounce_2d(pixel, sample, (*path).depth, DIM_LIGHT));
            if (ls.light == NO_LIGHT) {
                return no_bounce();
            }
            dir = ls.dir;
        } else {
            let s = bsdf_scatter(v.mat, (*path).ray, v.hit, u);
            if (!s.ok) {
                return no_bounce();
            }
            dir = s.dir;
        }
        let f = vertex_eval(v, (*path).ray, dir);
        let pdf = 0.5 * light_pdf_total(v.hit.p, dir) + 0.5 * vertex_pdf(v, (*path).ray, dir);
        if (!(pdf > 0.0) || all(f == vec3<f32>(0.0))) {
            return no_bounce();
        }
        return Bounce(true, dir, f / pdf, pdf, false);
    }
#endif
    let s = bsdf_scatter(v.mat, (*path).ray, v.hit, u);
    return Bounce(s.ok, s.dir, s.weight, scatter_pdf(v.mat, (*path).ray, v.hit, s), s.delta);
}

// The path goes on from the vertex along the bounce: its throughput, the first albedo
// (the weight of the first bounce off a lobe with a density: f cos / pdf, whose mean is
// the directional albedo), the vertex MIS remembers, the next ray. False when it ends.
fn continue_path(path: ptr<function, Path>, v: Vertex, b: Bounce) -> bool {
    if (!b.ok) {
        return false;
    }
    (*path).throughput *= b.weight;
#ifdef HAS_AOVS
    if (!(*path).found && !b.delta) {
        (*path).albedo = b.weight;
        (*path).found = true;
    }
#endif
    if (all((*path).throughput == vec3<f32>(0.0))) {
        // nothing further along this path can add to the pixel
        return false;
    }
    (*path).prev_p = v.hit.p;
    (*path).prev_pdf = b.pdf;
    (*path).prev_delta = b.delta;
#ifdef HAS_MEDIA
    (*path).medium = vertex_medium(v, b.dir);
#endif
    (*path).ray = vertex_spawn(v, b.dir);
    (*path).depth += 1u;
    return (*path).depth < params.max_depth;
}

// Traces the path's next ray and adds what it finds; false when the path has ended.
// max_depth counts rays: 1 shows emitters and the background, 2 adds direct lighting, and
// so on. light_sampling picks how lights are found: by hitting them (bsdf); by a direction
// drawn half the time toward a light and weighted by the mixture pdf (mixture); or by
// next-event estimation at every vertex plus the material's direction, each weighted by
// the power heuristic so that emission is counted once (mis).
fn extend_path(path: ptr<function, Path>, pixel: u32, sample: u32) -> bool {
    if (!survives_roulette(path, pixel, sample)) {
        return false;
    }
    var u_alpha = vec2<f32>(0.0);
#ifdef HAS_ALPHA
    u_alpha = bounce_2d(pixel, sample, (*path).depth, DIM_ALPHA);
#endif
    let cand = next_hit(path, u_alpha.x, pixel, sample);
    if (cand.prim == NO_HIT) {
        escape(path);
        return false;
    }
#ifdef HAS_MEDIA
    var v: Vertex;
    if (cand.prim == MEDIUM_HIT) {
        v = medium_vertex(path, cand.t);
#ifdef HAS_AOVS
        medium_aovs(path, v);
#endif
    } else {
        v = surface_vertex(path, cand, pixel, sample);
        add_emission(path, v, cand.prim);
    }
#else
    let v = surface_vertex(path, cand, pixel, sample);
    add_emission(path, v, cand.prim);
#endif
    if ((*path).depth + 1u >= params.max_depth) {
        return false;
    }
    next_event(path, v, pixel, sample, u_alpha.y);
    return continue_path(path, v, sample_bounce(path, v, pixel, sample));
}
