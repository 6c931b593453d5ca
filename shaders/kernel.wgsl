// Kernels for tests. `main`: one ray per invocation through the closest-hit search,
// surface_at and the shadow-ray search, reporting everything the CPU reference computes for
// the same ray.
// `textures_main`: one texture look-up per invocation.
// `materials_main`: one material at one hit per invocation, asked what the integrator asks.
// `lights_main`: lights sampled from one point per invocation, with their pdfs.
// `paths_main`: one camera path per invocation, its state after each extend_path.
// Group 0 is the scene, as in trace.wgsl; group 1 holds each kernel's inputs and results.
#import shared/bindings
#import shared/intersect
#import shared/lights
#import shared/materials
#import shared/path
#import shared/samplers
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
    // the second uv set in .xy
    uv1: vec4<f32>,
    color: vec4<f32>,
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
    var out = KernelHit(cand.t, cand.prim, 0u, occ, vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    if (cand.prim != NO_HIT) {
        let h = surface_at(ray, cand);
        out.front_face = select(0u, 1u, h.front_face);
        out.p = vec4<f32>(h.p, h.err);
        out.ng = vec4<f32>(h.ng, 0.0);
        out.ns = vec4<f32>(h.ns, 0.0);
        out.uv = vec4<f32>(h.uv.xy, cand.u, cand.v);
#ifdef HAS_INSTANCES
        // the instance hit through, plus 1 (0: none)
        out.uv1 = vec4<f32>(h.uv.zw, f32(cand.inst + 1u), 0.0);
#else
        out.uv1 = vec4<f32>(h.uv.zw, 0.0, 0.0);
#endif
        out.color = h.color;
    }
    hits[i] = out;
}

// Texture look-ups for tests: texture `index` at (uv, p), one per invocation.
struct TextureLookup {
    // uv sets 0 (.xy) and 1 (.zw)
    uv: vec4<f32>,
    // the point in .xyz, the texture index in .w (as a float)
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
    colors[i] = vec4<f32>(texture_value(u32(l.p.w), l.uv, l.p.xyz), 0.0);
}

struct MaterialQuery {
    material: u32,
    front_face: u32,
    pad0: u32,
    pad1: u32,
    origin: vec4<f32>,
    dir: vec4<f32>,
    p: vec4<f32>,
    ng: vec4<f32>,
    ns: vec4<f32>,
    // the shading normal before a normal map turned it to ns
    unmapped: vec4<f32>,
    // the hit's uv in .xy, the sample in .zw
    uv: vec4<f32>,
    wi: vec4<f32>,
    // the hit's second uv set in .xy
    uv1: vec4<f32>,
    color: vec4<f32>,
}

struct MaterialReply {
    // bit 0: scatter's ok, bit 1: its delta, bit 2: nee_applies, bit 3: mixture_applies
    flags: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
    // scatter's direction, its pdf in .w
    dir: vec4<f32>,
    weight: vec4<f32>,
    // bsdf_eval toward wi, bsdf_pdf toward it in .w
    eval: vec4<f32>,
    emitted: vec4<f32>,
}

@group(1) @binding(4) var<storage, read> material_queries: array<MaterialQuery>;
@group(1) @binding(5) var<storage, read_write> material_replies: array<MaterialReply>;

// The material of each query at its hit (its textures looked up), asked what the
// integrator asks of it.
@compute @workgroup_size(64, 1, 1)
fn materials_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= arrayLength(&material_queries)) {
        return;
    }
    let q = material_queries[i];
    let ray = Ray(q.origin.xyz, q.dir.xyz);
#ifdef HAS_BUMP
    let hit = Hit(q.p.xyz, q.ng.xyz, q.ns.xyz, q.unmapped.xyz, vec4<f32>(q.uv.xy, q.uv1.xy), q.front_face != 0u, q.material, 0.0, vec4<f32>(0.0), q.color, vec3<f32>(0.0), vec3<f32>(0.0));
#else
    let hit = Hit(q.p.xyz, q.ng.xyz, q.ns.xyz, q.unmapped.xyz, vec4<f32>(q.uv.xy, q.uv1.xy), q.front_face != 0u, q.material, 0.0, vec4<f32>(0.0), q.color);
#endif
    let mat = material_at(material_record(q.material), hit);
    let s = bsdf_scatter(mat, ray, hit, q.uv.zw);
    var flags = select(0u, 1u, s.ok) | select(0u, 2u, s.delta);
    flags |= select(0u, 4u, nee_applies(mat)) | select(0u, 8u, mixture_applies(mat));
    let f = bsdf_eval(mat, ray, hit, q.wi.xyz);
    let pdf = bsdf_pdf(mat, ray, hit, q.wi.xyz);
    material_replies[i] = MaterialReply(flags, 0u, 0u, 0u, vec4<f32>(s.dir, s.pdf), vec4<f32>(s.weight, 0.0), vec4<f32>(f, pdf), vec4<f32>(emitted(mat, hit), 0.0));
}

struct LightQuery {
    // the point lights are sampled from; .w chooses the light
    p: vec4<f32>,
    // .xy: the point on the light, .z: the light without a surface
    u: vec4<f32>,
    // a direction from p
    d: vec4<f32>,
}

struct LightReply {
    light: u32,
    punctual: u32,
    pad0: u32,
    pad1: u32,
    // sample_light's direction, its distance in .w
    dir: vec4<f32>,
    // sample_light's pdf, light_pdf of the point it sampled, light_pdf_total of d
    pdf: vec4<f32>,
    uv: vec4<f32>,
    background: vec4<f32>,
    // sample_punctual's direction (squared distance in .w) and radiance (probability)
    punctual_dir: vec4<f32>,
    punctual_le: vec4<f32>,
}

@group(1) @binding(6) var<storage, read> light_queries: array<LightQuery>;
@group(1) @binding(7) var<storage, read_write> light_replies: array<LightReply>;

// Lights sampled from each query's point, the pdfs of what they sampled and of the
// query's direction, the background along it, and a light without a surface.
@compute @workgroup_size(64, 1, 1)
fn lights_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= arrayLength(&light_queries)) {
        return;
    }
    let q = light_queries[i];
    var r = LightReply(NO_LIGHT, NO_LIGHT, 0u, 0u, vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    let ls = sample_light(q.p.xyz, q.p.w, q.u.xy);
    r.light = ls.light;
    r.dir = vec4<f32>(ls.dir, ls.dist);
    r.uv = vec4<f32>(ls.uv, 0.0, 0.0);
    var sampled = 0.0;
    if (ls.light != NO_LIGHT) {
        sampled = light_pdf(ls.light, q.p.xyz, q.p.xyz + ls.dist * ls.dir, ls.dir);
    }
    r.pdf = vec4<f32>(ls.pdf, sampled, light_pdf_total(q.p.xyz, q.d.xyz), 0.0);
    r.background = vec4<f32>(background_radiance(q.d.xyz), 0.0);
#ifdef HAS_PUNCTUAL
    if (params.num_punctual != 0u) {
        let s = sample_punctual(q.p.xyz, q.u.z);
        r.punctual = s.light;
        r.punctual_dir = vec4<f32>(s.dir, s.d2);
        r.punctual_le = vec4<f32>(s.le, s.prob);
    }
#endif
    light_replies[i] = r;
}

struct PathQuery {
    x: u32,
    y: u32,
    sample: u32,
    pad0: u32,
}

struct PathStep {
    // the ray's origin, the path's depth in .w
    origin: vec4<f32>,
    // the ray's direction, 1 in .w while the path goes on
    dir: vec4<f32>,
    // .w: the extend_path calls the state follows
    throughput: vec4<f32>,
    radiance: vec4<f32>,
}

@group(1) @binding(8) var<storage, read> path_queries: array<PathQuery>;
@group(1) @binding(9) var<storage, read_write> path_steps: array<PathStep>;

fn path_step(path: Path, going: bool, calls: u32) -> PathStep {
    return PathStep(vec4<f32>(path.ray.origin, f32(path.depth)), vec4<f32>(path.ray.dir, select(0.0, 1.0, going)), vec4<f32>(path.throughput, f32(calls)), vec4<f32>(path.radiance, 0.0));
}

// Each query's camera path as the render's main traces it (the same camera ray, the same
// extend_path), its state at the start and after each extend_path: PATH_STEPS slots, the
// last one the final state however long the path was, the slots after a shorter path's
// end zero.
@compute @workgroup_size(64, 1, 1)
fn paths_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    stack_lane = lane;
    let i = gid.x;
    if (i >= arrayLength(&path_queries)) {
        return;
    }
    let q = path_queries[i];
    let pixel = q.y * params.width + q.x;
    var path = start_path(camera_ray(q.x, q.y, pixel_position(pixel, q.sample), sample_2d(pixel, q.sample, DIM_LENS)));
    let at = i * PATH_STEPS;
    for (var k = 0u; k < PATH_STEPS; k++) {
        path_steps[at + k] = PathStep(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    }
    var going = params.max_depth != 0u;
    path_steps[at] = path_step(path, going, 0u);
    var calls = 0u;
    while (going) {
        going = extend_path(&path, pixel, q.sample);
        calls++;
        path_steps[at + min(calls, PATH_STEPS - 1u)] = path_step(path, going, calls);
    }
}
