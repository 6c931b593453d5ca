// A group of consecutive samples per pixel per dispatch over one band of the image: for
// each, a camera ray, then one extend_path per ray until the path ends; each is added to
// the pixel's sums in index order, or dropped and counted when it is not finite.
#import shared/bindings
#import shared/path
#import shared/rng
#import shared/samplers
#import shared/types

// BVH_STACK_LANES invocations, a tile of 8 x 8 pixels (the dispatch's workgroups are
// tiles), in one dimension
@compute @workgroup_size(64, 1, 1)
fn main(
    @builtin(workgroup_id) tile: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
#ifdef HAS_LANE_STATS
    @builtin(subgroup_size) subgroup_size: u32,
#endif
) {
    let gid = vec2<u32>(tile.x * 8u + (lane & 7u), tile.y * 8u + (lane >> 3u));
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
