// A group of consecutive samples per pixel per dispatch over one band of the image: for
// each, a camera ray, then one extend_path per ray until the path ends; each is added to
// the pixel's sums in index order, or dropped and counted when it is not finite.
#import shared/bindings
#import shared/intersect
#import shared/lights
#import shared/materials
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

// Next-event estimation at a hit: a direction toward a light, a shadow ray from just off
// the surface to just short of the sampled point, and the light's emission there (its own
// shading record: side, texture) times BSDF x cos, weighed against BSDF sampling by the
// power heuristic and divided by the light's pdf.
fn direct_light(mat: Material, ray: Ray, hit: Hit, u_light: f32, u: vec2<f32>, u_alpha: f32) -> vec3<f32> {
    // Every step runs whatever the earlier ones found, and one test at the end keeps the
    // contribution or not: llvmpipe runs both sides of each branch anyway, and its masked
    // early returns cost more (1.3% of the Cornell box's bounce loop). A value of a failed
    // step is never used; without a light, emitter_record reads a clamped record.
    let ls = sample_light(hit.p, u_light, u);
    let f = bsdf_eval(mat, ray, hit, ls.dir);
    var shadow = spawn_ray(hit, ls.dir);
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
        let lh = surface_at(Ray(hit.p, ls.dir), Candidate(ls.dist, e.primitive, ls.uv.x, ls.uv.y, NO_HIT));
#else
        let lh = surface_at(Ray(hit.p, ls.dir), Candidate(ls.dist, e.primitive, ls.uv.x, ls.uv.y));
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
    if (!lit || shadowed(shadow, t_max, u_alpha)) {
        return vec3<f32>(0.0);
    }
    let w = power_heuristic(ls.pdf, bsdf_pdf(mat, ray, hit, pdf_dir));
    return f * le * (w / ls.pdf);
}

#ifdef HAS_PUNCTUAL
// Next-event estimation toward a light without a surface, chosen among them in proportion
// to its power: a shadow ray to its position (or out of the scene, for a directional
// light), and f x intensity x the spot's falloff / d^2 (or f x irradiance) over the
// choice's probability. No MIS weight: no other strategy can find a point or a direction.
fn direct_punctual(mat: Material, ray: Ray, hit: Hit, u: f32, u_alpha: f32) -> vec3<f32> {
    let s = sample_punctual(hit.p, u);
    var shadow = spawn_ray(hit, s.dir);
    var t_max = FAR;
    if (s.positioned) {
        let w = s.position - shadow.origin;
        t_max = length(w);
        shadow.dir = w / t_max;
    }
    let f = bsdf_eval(mat, ray, hit, s.dir);
    let lit = s.prob > 0.0 && s.d2 > 0.0 && t_max > 0.0 && any(f != vec3<f32>(0.0)) && any(s.le != vec3<f32>(0.0));
    if (!lit || shadowed(shadow, t_max, u_alpha)) {
        return vec3<f32>(0.0);
    }
    return f * s.le / s.prob;
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
#ifdef HAS_AOVS
    return Path(camera, vec3<f32>(0.0), vec3<f32>(1.0), camera.origin, 0.0, true, 0u, vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), 0.0, false);
#else
    return Path(camera, vec3<f32>(0.0), vec3<f32>(1.0), camera.origin, 0.0, true, 0u);
#endif
}

// Traces the path's next ray and adds what it finds; false when the path has ended.
// max_depth counts rays: 1 shows emitters and the background, 2 adds direct lighting, and
// so on. light_sampling picks how lights are found: by hitting them (bsdf); by a direction
// drawn half the time toward a light and weighted by the mixture pdf (mixture); or by
// next-event estimation at every vertex plus the material's direction, each weighted by
// the power heuristic so that emission is counted once (mis).
fn extend_path(path: ptr<function, Path>, pixel: u32, sample: u32) -> bool {
    // Russian roulette from ray rr_depth on: a path goes on with probability
    // min(1, max(throughput)), its throughput divided by that; unbiased, and a dim path
    // stops before its next ray
    if (params.rr_depth != 0u && (*path).depth >= params.rr_depth) {
        let survive = min(1.0, max((*path).throughput.x, max((*path).throughput.y, (*path).throughput.z)));
        if (rand_2d(pixel, sample, (*path).depth, DIM_RR, params.seed).x >= survive) {
            return false;
        }
        (*path).throughput /= survive;
    }
    var u_alpha = vec2<f32>(0.0);
    var cand: Candidate;
#ifdef HAS_ALPHA
    u_alpha = bounce_2d(pixel, sample, (*path).depth, DIM_ALPHA);
    // one call of the closest-hit search (llvmpipe inlines each call site whole)
    for (var k = 0u; k < MAX_ALPHA_SKIPS; k++) {
        cand = intersect_scene((*path).ray, FAR);
        // a surface transparent where the ray meets it is passed through: the ray goes on
        // from just beyond, its origin moved but its direction's pdf and the vertex it
        // left (prev_p) kept, and the bounce not counted; the last surface is kept whatever
        if (cand.prim != NO_HIT && k + 1u < MAX_ALPHA_SKIPS) {
            let h = surface_at((*path).ray, cand);
            if (transparent_at(h, alpha_u(u_alpha.x, k))) {
                (*path).ray = spawn_ray(h, (*path).ray.dir);
                continue;
            }
        }
        break;
    }
#else
    cand = intersect_scene((*path).ray, FAR);
#endif
#ifdef HAS_MIS
    let mis = params.light_sampling == LIGHT_SAMPLING_MIS && !(*path).prev_delta;
#endif
    if (cand.prim == NO_HIT) {
        var le = background_radiance((*path).ray.dir);
#ifdef HAS_AOVS
        // the background's radiance, clamped, is the albedo of a path that escapes
        if (!(*path).found) {
            (*path).albedo = clamp(le, vec3<f32>(0.0), vec3<f32>(1.0));
            (*path).found = true;
        }
#endif
#ifdef HAS_MIS
        if (mis && params.env_light != NO_LIGHT) {
            le *= power_heuristic((*path).prev_pdf, light_pdf(params.env_light, (*path).prev_p, (*path).prev_p, (*path).ray.dir));
        }
#endif
        if (params.hide_emitters != 0u && (*path).depth == 0u) {
            le = vec3<f32>(0.0);
        }
        (*path).radiance += (*path).throughput * le;
        return false;
    }
    let surface = surface_at((*path).ray, cand);
#ifdef HAS_BLEND
    // a blend's part, chosen here for all the vertex does
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
    var le = emitted(mat, hit);
#ifdef HAS_AOVS
    if ((*path).depth == 0u) {
        // prev_p is still the camera ray's origin (passing through alpha keeps it)
        (*path).distance = distance(hit.p, (*path).prev_p);
        (*path).position = hit.p;
    }
    if (!(*path).found) {
        // the shading normal facing the ray; an emitter's albedo is its emission, clamped
        (*path).normal = select(-hit.ns, hit.ns, dot(hit.ns, (*path).ray.dir) < 0.0);
        if (any(le > vec3<f32>(0.0))) {
            (*path).albedo = clamp(le, vec3<f32>(0.0), vec3<f32>(1.0));
            (*path).found = true;
        }
    }
#endif
#ifdef HAS_MIS
    let light = primitive_record(cand.prim).flags >> PRIM_LIGHT_SHIFT;
    if (mis && light != 0u && any(le > vec3<f32>(0.0))) {
        le *= power_heuristic((*path).prev_pdf, light_pdf(light - 1u, (*path).prev_p, hit.p, (*path).ray.dir));
    }
#endif
    if (params.hide_emitters != 0u && (*path).depth == 0u) {
        le = vec3<f32>(0.0);
    }
    (*path).radiance += (*path).throughput * le;
    if ((*path).depth + 1u >= params.max_depth) {
        return false;
    }
    let u = bounce_2d(pixel, sample, (*path).depth, DIM_BSDF);
#ifdef HAS_MIS
    if (params.light_sampling == LIGHT_SAMPLING_MIS && nee_applies(mat)) {
        let ul = bounce_2d(pixel, sample, (*path).depth, DIM_LIGHT);
        let uc = bounce_2d(pixel, sample, (*path).depth, DIM_LIGHT_CHOICE);
        (*path).radiance += (*path).throughput * direct_light(mat, (*path).ray, hit, uc.x, ul, u_alpha.y);
    }
#endif
#ifdef HAS_PUNCTUAL
    // the lights without a surface, under every strategy: only next-event estimation
    // finds them (the full shader holds this for scenes without any)
    if (params.num_punctual != 0u && nee_applies(mat)) {
        let up = bounce_2d(pixel, sample, (*path).depth, DIM_PUNCTUAL);
        (*path).radiance += (*path).throughput * direct_punctual(mat, (*path).ray, hit, up.x, u_alpha.y);
    }
#endif
#ifdef HAS_MIXTURE
    if (params.light_sampling == LIGHT_SAMPLING_MIXTURE && params.num_emitters != 0u && mixture_applies(mat)) {
        // one direction from the 50/50 mixture; the path goes on along it
        let uc = bounce_2d(pixel, sample, (*path).depth, DIM_LIGHT_CHOICE);
        var dir: vec3<f32>;
        if (uc.y < 0.5) {
            let ls = sample_light(hit.p, uc.x, bounce_2d(pixel, sample, (*path).depth, DIM_LIGHT));
            if (ls.light == NO_LIGHT) {
                return false;
            }
            dir = ls.dir;
        } else {
            let s = bsdf_scatter(mat, (*path).ray, hit, u);
            if (!s.ok) {
                return false;
            }
            dir = s.dir;
        }
        let f = bsdf_eval(mat, (*path).ray, hit, dir);
        let pdf = 0.5 * light_pdf_total(hit.p, dir) + 0.5 * bsdf_pdf(mat, (*path).ray, hit, dir);
        if (!(pdf > 0.0) || all(f == vec3<f32>(0.0))) {
            return false;
        }
#ifdef HAS_AOVS
        if (!(*path).found) {
            (*path).albedo = f / pdf;
            (*path).found = true;
        }
#endif
        (*path).throughput *= f / pdf;
        (*path).ray = spawn_ray(hit, dir);
        (*path).depth += 1u;
            return (*path).depth < params.max_depth;
    }
#endif
    let s = bsdf_scatter(mat, (*path).ray, hit, u);
    if (!s.ok) {
        return false;
    }
    (*path).throughput *= s.weight;
#ifdef HAS_AOVS
    // the albedo is the weight of the first bounce off a lobe with a density: f cos / pdf,
    // whose mean is the surface's directional albedo
    if (!(*path).found && !s.delta) {
        (*path).albedo = s.weight;
        (*path).found = true;
    }
#endif
    if (all((*path).throughput == vec3<f32>(0.0))) {
        // nothing further along this path can add to the pixel
        return false;
    }
    (*path).prev_p = hit.p;
    (*path).prev_pdf = scatter_pdf(mat, (*path).ray, hit, s);
    (*path).prev_delta = s.delta;
    (*path).ray = spawn_ray(hit, s.dir);
    (*path).depth += 1u;
    return (*path).depth < params.max_depth;
}

// 8 x 8 = BVH_STACK_LANES invocations
@compute @workgroup_size(8, 8, 1)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
#ifdef HAS_LANE_STATS
    @builtin(subgroup_size) subgroup_size: u32,
#endif
) {
    stack_lane = lane;
#ifdef HAS_LANE_STATS
    lane_subgroup_size = subgroup_size;
#endif
    if (gid.x >= params.band_width || gid.y >= params.band_height) {
        return;
    }
    let x = params.band_x + gid.x;
    let y = params.band_y + gid.y;
    let pixel = y * params.width + x;
    // samples sample_index .. sample_index + sample_count, one after the other: a lane
    // whose path ends starts its next sample at once, so the 8 lanes of a SIMD batch stay
    // busy (llvmpipe runs a loop until its last lane is done). Each sample is added to the
    // pixel's sums in index order, as one sample per dispatch would add it, but the sums
    // are read and written once. A sample that is not finite (or whose square is not) is
    // dropped and counted in the otherwise unused .w of the squares.
    // The bound accumulation buffer holds the pixels of the band of rows from accum_y.
    let slot = (y - params.accum_y) * params.band_width + gid.x;
#ifdef HAS_AOVS
    let at = ACCUM_ENTRIES_AOVS * slot;
    var albedo_depth = accum[at + 2u];
    var normal = accum[at + 3u];
    var position = accum[at + 4u];
#else
    let at = ACCUM_ENTRIES * slot;
#endif
    var sum = accum[at];
    var sum2 = accum[at + 1u];
#ifdef HAS_EMISSION
    var sample = params.sample_index;
    let end = sample + params.sample_count;
    var jitter = pixel_position(pixel, sample);
    var path = start_path(camera_ray(x, y, jitter, sample_2d(pixel, sample, DIM_LENS)));
    loop {
#ifdef HAS_LANE_STATS
        count_lanes(0u);
#endif
        if (params.max_depth == 0u || !extend_path(&path, pixel, sample)) {
            let c = path.radiance;
            let finite = all_finite(c) && all_finite(c * c);
#ifdef HAS_SPLAT
            // a splatted sample waits in the sample buffer for the gather pass; only a
            // dropped one is counted here, in its own pixel
            if (params.splat != 0u) {
                samples[splat_slot(pixel, sample)] = splat_record(c, finite, jitter);
                sum2.w += select(1.0, 0.0, finite);
#ifdef HAS_LANE_STATS
                // the lane statistics count samples here; their gather adds nothing
                sum.w += select(0.0, 1.0, finite);
#endif
            } else {
#endif
            if (finite) {
                sum += vec4<f32>(c, 1.0);
                sum2 += vec4<f32>(c * c, 0.0);
            } else {
                sum2.w += 1.0;
            }
#ifdef HAS_SPLAT
            }
#endif
#ifdef HAS_AOVS
            // every sample's AOVs, those of a colour dropped as not finite too; a splat
            // render counts them in normal's .w (its colour sums hold weights)
            albedo_depth += vec4<f32>(select(vec3<f32>(0.0), path.albedo, all_finite(path.albedo)), path.distance);
            normal += vec4<f32>(path.normal, f32(params.splat));
            position += vec4<f32>(path.position, 0.0);
#endif
            sample++;
            if (sample >= end) {
                break;
            }
            jitter = pixel_position(pixel, sample);
            path = start_path(camera_ray(x, y, jitter, sample_2d(pixel, sample, DIM_LENS)));
        }
    }
#else
    // nothing in the scene emits, so no path can carry light: no ray is traced
#ifdef HAS_SPLAT
    if (params.splat != 0u) {
        for (var s = params.sample_index; s < params.sample_index + params.sample_count; s++) {
            samples[splat_slot(pixel, s)] = splat_record(vec3<f32>(0.0), true, pixel_position(pixel, s));
        }
    } else {
        sum.w += f32(params.sample_count);
    }
#else
    sum.w += f32(params.sample_count);
#endif
#endif
#ifdef HAS_LANE_STATS
    // the lane statistics instead of light (the counts of samples stay)
    sum = vec4<f32>(accum[at].xyz + lane_steps, sum.w);
    sum2 = vec4<f32>(accum[at + 1u].xyz + lane_shares, sum2.w);
#endif
    accum[at] = sum;
    accum[at + 1u] = sum2;
#ifdef HAS_AOVS
    accum[at + 2u] = albedo_depth;
    accum[at + 3u] = normal;
    accum[at + 4u] = position;
#endif
}

// Whether every component is a finite number, judged by its bits (an exponent of all ones
// is an infinity or a NaN): WGSL promises neither at run time, nor a way to test for them.
fn all_finite(v: vec3<f32>) -> bool {
    let e = bitcast<vec3<u32>>(v) & vec3<u32>(0x7f800000u);
    return all(e != vec3<u32>(0x7f800000u));
}

#ifdef HAS_SPLAT
// Splat reconstruction. `main` writes each sample of its dispatch into `samples` (sample s
// of pixel i at (s - sample_index) x width x height + i) instead of adding it to its pixel;
// then `gather` adds to each pixel every sample its filter reaches, weighted.

fn splat_slot(pixel: u32, sample: u32) -> u32 {
    return (sample - params.sample_index) * params.width * params.height + pixel;
}

// A sample as the sample buffer holds it: its colour's bits (SPLAT_DROPPED in .x when not
// finite) and its position in the pixel as two 16-bit fixed-point numbers in .w, x in the
// low half: floor(65536 p), exact on every backend (pack2x16unorm's rounding of ties is
// the driver's).
fn splat_record(c: vec3<f32>, finite: bool, jitter: vec2<f32>) -> vec4<u32> {
    let bits = select(vec3<u32>(SPLAT_DROPPED, 0u, 0u), bitcast<vec3<u32>>(c), finite);
    let q = min(vec2<u32>(jitter * 65536.0), vec2<u32>(65535u));
    return vec4<u32>(bits, q.x | (q.y << 16u));
}

// The position in its pixel a splat_record holds: the middle of its 1/65536 step.
fn splat_position(packed: u32) -> vec2<f32> {
    return (vec2<f32>(f32(packed & 0xffffu), f32(packed >> 16u)) + 0.5) / 65536.0;
}

// 8 x 8 invocations, one per pixel of the band: the samples of the dispatch `main` just
// made (sample_index .. sample_index + sample_count) that the pixel's filter reaches, each
// weighed by splat_weight along x times along y and added in sample order, then row by
// row and column by column: (sum w L, sum w) and (sum w L^2, dropped).
@compute @workgroup_size(8, 8, 1)
fn gather(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= params.band_width || gid.y >= params.band_height) {
        return;
    }
#ifdef HAS_LANE_STATS
    // the sums hold the lane statistics
    return;
#endif
    let x = params.band_x + gid.x;
    let y = params.band_y + gid.y;
    let slot = (y - params.accum_y) * params.band_width + gid.x;
#ifdef HAS_AOVS
    let at = ACCUM_ENTRIES_AOVS * slot;
#else
    let at = ACCUM_ENTRIES * slot;
#endif
    var sum = accum[at];
    var sum2 = accum[at + 1u];
    // the pixels whose samples can lie within the radius of this one's centre
    let reach = i32(ceil(params.filter_shape.x - 0.5));
    let pixels = params.width * params.height;
    for (var s = 0u; s < params.sample_count; s++) {
        for (var dy = -reach; dy <= reach; dy++) {
            let yy = i32(y) + dy;
            if (yy < 0 || yy >= i32(params.height)) {
                continue;
            }
            for (var dx = -reach; dx <= reach; dx++) {
                let xx = i32(x) + dx;
                if (xx < 0 || xx >= i32(params.width)) {
                    continue;
                }
                let r = samples[s * pixels + u32(yy) * params.width + u32(xx)];
                if (r.x == SPLAT_DROPPED) {
                    continue;
                }
                let at_pos = splat_position(r.w);
                let w = splat_weight(0.5 - at_pos.x - f32(dx)) * splat_weight(0.5 - at_pos.y - f32(dy));
                let c = bitcast<vec3<f32>>(r.xyz);
                sum += vec4<f32>(w * c, w);
                sum2 += vec4<f32>(w * c * c, 0.0);
            }
        }
    }
    accum[at] = sum;
    accum[at + 1u] = sum2;
}
#endif
