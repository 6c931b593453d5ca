// Kernels for tests. `main`: one ray per invocation through the closest-hit search,
// surface_at and the shadow-ray search, reporting everything the CPU reference computes for
// the same ray.
// `textures_main`: one texture look-up per invocation. Group 0 is the scene, as in
// trace.wgsl; group 1 holds each kernel's inputs and results.
#import shared/bindings
#import shared/intersect
#import shared/textures
#import shared/types

struct KernelRay {
    origin: vec4<f32>,
    dir: vec4<f32>,
}

struct KernelHit {
    t: f32,
    prim: u32,
    front_face: u32,
    // occluded(ray, FAR) in bit 0, occluded(ray, 0.999 t) in bit 1
    occluded: u32,
    // hit point, .w = error bound
    p: vec4<f32>,
    ng: vec4<f32>,
    ns: vec4<f32>,
    // uv in .xy, the candidate's (u, v) in .zw
    uv: vec4<f32>,
}

@group(1) @binding(0) var<storage, read> rays: array<KernelRay>;
@group(1) @binding(1) var<storage, read_write> hits: array<KernelHit>;

// BVH_STACK_LANES invocations
@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    stack_lane = lane;
    let i = gid.x;
    if (i >= arrayLength(&rays)) {
        return;
    }
    let ray = Ray(rays[i].origin.xyz, rays[i].dir.xyz);
    let cand = intersect_scene(ray, FAR);
    let occ = select(0u, 1u, occluded(ray, FAR)) | select(0u, 2u, occluded(ray, 0.999 * cand.t));
    var out = KernelHit(cand.t, cand.prim, 0u, occ, vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    if (cand.prim != NO_HIT) {
        let h = surface_at(ray, cand);
        out.front_face = select(0u, 1u, h.front_face);
        out.p = vec4<f32>(h.p, h.err);
        out.ng = vec4<f32>(h.ng, 0.0);
        out.ns = vec4<f32>(h.ns, 0.0);
        out.uv = vec4<f32>(h.uv, cand.u, cand.v);
    }
    hits[i] = out;
}

// Texture look-ups for tests: texture `index` at (uv, p), one per invocation.
struct TextureLookup {
    // uv in .xy, texture index in .z (as a float)
    uv: vec4<f32>,
    p: vec4<f32>,
}


@group(1) @binding(2) var<storage, read> lookups: array<TextureLookup>;
@group(1) @binding(3) var<storage, read_write> colors: array<vec4<f32>>;

@compute @workgroup_size(64, 1, 1)
fn textures_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= arrayLength(&lookups)) {
        return;
    }
    let l = lookups[i];
    colors[i] = vec4<f32>(texture_value(u32(l.uv.z), l.uv.xy, l.p.xyz), 0.0);
}
