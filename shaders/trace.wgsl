// One sample per pixel per dispatch over one tile of the image: camera ray, then an
// iterative bounce loop; the result is added to the accumulation buffer, or dropped and
// counted when it is not finite.
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
    return Ray(params.cam_origin.xyz + lens_offset, normalize(target_offset - lens_offset));
}

// A ray leaving a hit in direction dir, from just off the surface on dir's side.
fn spawn_ray(hit: Hit, dir: vec3<f32>) -> Ray {
    return Ray(offset_ray(hit.p, select(-hit.ng, hit.ng, dot(dir, hit.ng) > 0.0), hit.err), dir);
}

// Next-event estimation at a hit: a direction toward a light, a shadow ray from just off
// the surface to just short of the sampled point, and the light's emission there (its own
// shading record: side, texture) times BSDF x cos, weighed against BSDF sampling by the
// power heuristic and divided by the light's pdf.
fn direct_light(mat: Material, ray: Ray, hit: Hit, u_light: f32, u: vec2<f32>) -> vec3<f32> {
    let ls = sample_light(hit.p, u_light, u);
    if (ls.light == NO_LIGHT) {
        return vec3<f32>(0.0);
    }
    let f = bsdf_eval(mat, ray, hit, ls.dir);
    if (all(f == vec3<f32>(0.0))) {
        return vec3<f32>(0.0);
    }
    var shadow = spawn_ray(hit, ls.dir);
    var t_max = FAR;
    var le: vec3<f32>;
    // the direction the MIS weight takes the material's pdf of: from the ray origin, as a
    // bounce ray toward the same point has it, so the two weights of a path add up to one
    // (from hit.p they differ by about offset / (distance x cos), 1e-3 on grazing chords)
    var pdf_dir = ls.dir;
    let e = emitters[ls.light];
    if (e.kind == LIGHT_ENVIRONMENT) {
        le = background_radiance(ls.dir);
    } else {
        let lh = surface_at(Ray(hit.p, ls.dir), Candidate(ls.dist, e.primitive, ls.uv.x, ls.uv.y));
        le = emitted(material_at(materials[lh.material], lh), lh);
        if (all(le == vec3<f32>(0.0))) {
            return vec3<f32>(0.0);
        }
        pdf_dir = normalize(lh.p - shadow.origin);
        let end = offset_ray(lh.p, select(-lh.ng, lh.ng, dot(ls.dir, lh.ng) < 0.0), lh.err);
        let v = end - shadow.origin;
        t_max = length(v);
        if (!(t_max > 0.0)) {
            return vec3<f32>(0.0);
        }
        shadow.dir = v / t_max;
    }
    if (intersect_scene(shadow, t_max).prim != NO_HIT) {
        return vec3<f32>(0.0);
    }
    let w = power_heuristic(ls.pdf, bsdf_pdf(mat, ray, hit, pdf_dir));
    return f * le * (w / ls.pdf);
}

// Radiance along one camera path. max_depth counts rays: 1 shows emitters and the
// background, 2 adds direct lighting, and so on. light_sampling picks how lights are
// found: by hitting them (bsdf); by a direction drawn half the time toward a light and
// weighted by the mixture pdf (mixture); or by next-event estimation at every vertex plus
// the material's direction, each weighted by the power heuristic so that emission is
// counted once (mis).
fn trace_path(pixel: u32, sample: u32, camera: Ray) -> vec3<f32> {
    var ray = camera;
    var radiance = vec3<f32>(0.0);
    var throughput = vec3<f32>(1.0);
    // the previous vertex, for the MIS weight of an emitter the ray hits: its point, the
    // pdf of the ray's direction, and whether that came from a delta lobe (weight 1)
    var prev_p = camera.origin;
    var prev_pdf = 0.0;
    var prev_delta = true;
    for (var depth = 0u; depth < params.max_depth; depth++) {
        // Russian roulette from ray rr_depth on: a path goes on with probability
        // min(1, max(throughput)), its throughput divided by that; unbiased, and a dim path
        // stops before its next ray
        if (params.rr_depth != 0u && depth >= params.rr_depth) {
            let survive = min(1.0, max(throughput.x, max(throughput.y, throughput.z)));
            if (rand_2d(pixel, sample, depth, DIM_RR, params.seed).x >= survive) {
                break;
            }
            throughput /= survive;
        }
        let cand = intersect_scene(ray, FAR);
#ifdef HAS_MIS
        let mis = params.light_sampling == LIGHT_SAMPLING_MIS && !prev_delta;
#endif
        if (cand.prim == NO_HIT) {
            var le = background_radiance(ray.dir);
#ifdef HAS_MIS
            if (mis && params.env_light != NO_LIGHT) {
                le *= power_heuristic(prev_pdf, light_pdf(params.env_light, prev_p, prev_p, ray.dir));
            }
#endif
            radiance += throughput * le;
            break;
        }
        let hit = surface_at(ray, cand);
        let mat = material_at(materials[hit.material], hit);
        var le = emitted(mat, hit);
#ifdef HAS_MIS
        let light = primitives[cand.prim].flags >> PRIM_LIGHT_SHIFT;
        if (mis && light != 0u && any(le > vec3<f32>(0.0))) {
            le *= power_heuristic(prev_pdf, light_pdf(light - 1u, prev_p, hit.p, ray.dir));
        }
#endif
        radiance += throughput * le;
        if (depth + 1u >= params.max_depth) {
            break;
        }
        let u = bounce_2d(pixel, sample, depth, DIM_BSDF);
#ifdef HAS_MIS
        if (params.light_sampling == LIGHT_SAMPLING_MIS && nee_applies(mat)) {
            let ul = bounce_2d(pixel, sample, depth, DIM_LIGHT);
            let uc = bounce_2d(pixel, sample, depth, DIM_LIGHT_CHOICE);
            radiance += throughput * direct_light(mat, ray, hit, uc.x, ul);
        }
#endif
#ifdef HAS_MIXTURE
        if (params.light_sampling == LIGHT_SAMPLING_MIXTURE && mixture_applies(mat)) {
            // one direction from the 50/50 mixture; the path goes on along it
            let uc = bounce_2d(pixel, sample, depth, DIM_LIGHT_CHOICE);
            var dir: vec3<f32>;
            if (uc.y < 0.5) {
                let ls = sample_light(hit.p, uc.x, bounce_2d(pixel, sample, depth, DIM_LIGHT));
                if (ls.light == NO_LIGHT) {
                    break;
                }
                dir = ls.dir;
            } else {
                let s = scatter(mat, ray, hit, u);
                if (!s.ok) {
                    break;
                }
                dir = s.dir;
            }
            let f = bsdf_eval(mat, ray, hit, dir);
            let pdf = 0.5 * light_pdf_total(hit.p, dir) + 0.5 * bsdf_pdf(mat, ray, hit, dir);
            if (!(pdf > 0.0) || all(f == vec3<f32>(0.0))) {
                break;
            }
            throughput *= f / pdf;
            ray = spawn_ray(hit, dir);
            continue;
        }
#endif
        let s = scatter(mat, ray, hit, u);
        if (!s.ok) {
            break;
        }
        throughput *= s.weight;
        if (all(throughput == vec3<f32>(0.0))) {
            // nothing further along this path can add to the pixel
            break;
        }
        prev_p = hit.p;
        prev_pdf = s.pdf;
        prev_delta = s.delta;
        ray = spawn_ray(hit, s.dir);
    }
    return radiance;
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= params.tile_width || gid.y >= params.tile_height) {
        return;
    }
    let x = params.tile_x + gid.x;
    let y = params.tile_y + gid.y;
    let pixel = y * params.width + x;
    let sample = params.sample_index;
    let jitter = sample_2d(pixel, sample, DIM_PIXEL);
    let lens = sample_2d(pixel, sample, DIM_LENS);
#ifdef HAS_EMISSION
    let c = trace_path(pixel, sample, camera_ray(x, y, jitter, lens));
#else
    // nothing in the scene emits, so no path can carry light: no ray is traced
    let c = vec3<f32>(0.0);
#endif
    // the bound accumulation buffer holds the pixels of the band of rows from accum_y
    let slot = (y - params.accum_y) * params.tile_width + gid.x;
    if (all_finite(c) && all_finite(c * c)) {
        accum[2u * slot] += vec4<f32>(c, 1.0);
        accum[2u * slot + 1u] += vec4<f32>(c * c, 0.0);
    } else {
        // dropped, and counted in the otherwise unused .w of the squares
        accum[2u * slot + 1u].w += 1.0;
    }
}

// Whether every component is a finite number, judged by its bits (an exponent of all ones
// is an infinity or a NaN): WGSL promises neither at run time, nor a way to test for them.
fn all_finite(v: vec3<f32>) -> bool {
    let e = bitcast<vec3<u32>>(v) & vec3<u32>(0x7f800000u);
    return all(e != vec3<u32>(0x7f800000u));
}
