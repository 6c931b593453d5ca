// One sample per pixel per dispatch over one tile of the image: camera ray, then an
// iterative bounce loop; the result is added to the accumulation buffer.
#import shared/bindings
#import shared/intersect
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
    let d = sample_disk(lens) * params.cam_origin.w;
    let lens_offset = right * d.x + up * d.y;
    return Ray(params.cam_origin.xyz + lens_offset, normalize(target_offset - lens_offset));
}

// Radiance of a ray that leaves the scene in unit direction d: the constant background, or
// the vertical gradient bottom + (top - bottom) (d.y + 1) / 2.
fn background_radiance(d: vec3<f32>) -> vec3<f32> {
    if (params.background_top.w > 0.5) {
        return mix(params.background.rgb, params.background_top.rgb, 0.5 * (d.y + 1.0));
    }
    return params.background.rgb;
}

// Radiance along one camera path. max_depth counts rays: 1 shows emitters and the
// background, 2 adds direct lighting, and so on.
fn trace_path(pixel: u32, sample: u32, camera: Ray) -> vec3<f32> {
    var ray = camera;
    var radiance = vec3<f32>(0.0);
    var throughput = vec3<f32>(1.0);
    for (var depth = 0u; depth < params.max_depth; depth++) {
        let cand = intersect_scene(ray);
        if (cand.prim == NO_HIT) {
            radiance += throughput * background_radiance(ray.dir);
            break;
        }
        let hit = surface_at(ray, cand);
        let mat = material_at(materials[hit.material], hit);
        radiance += throughput * emitted(mat, hit);
        if (depth + 1u >= params.max_depth) {
            break;
        }
        let u = bounce_2d(pixel, sample, depth, DIM_BSDF);
        let s = scatter(mat, ray, hit, u);
        if (!s.ok) {
            break;
        }
        throughput *= s.weight;
        let side = select(-hit.ng, hit.ng, dot(s.dir, hit.ng) > 0.0);
        ray = Ray(offset_ray(hit.p, side, hit.err), s.dir);
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
    let c = trace_path(pixel, sample, camera_ray(x, y, jitter, lens));
    accum[2u * pixel] += vec4<f32>(c, 1.0);
    accum[2u * pixel + 1u] += vec4<f32>(c * c, 0.0);
}
