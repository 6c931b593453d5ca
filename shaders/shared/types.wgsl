// Records shared with the host. Each struct mirrors one `#[repr(C)]` struct in
// src/scene/records.rs; tests/shaders.rs checks sizes and offsets against naga's layout.
// vec3 never appears in a storage struct (16-byte alignment): positions are vec4 with .w used
// for a scalar or left as padding.

// The constants both languages read (tags, flags, sampler and light kinds, NO_HIT, FAR,
// the random-number dimensions, PI, ...) are declared once, in src/scene/records.rs, and
// written into every shader from there (gpu::codegen::constants):
#import generated/constants

// In object space when PRIM_FLAG_TRANSFORM is set. Storage: each type names its places in
// its view (NAMEParams, written from scene::primitives).
struct Primitive {
    tag: u32,
    material: u32,
    flags: u32,
    // first shape_data entry of the transform or of the vertex attributes
    data: u32,
    a: vec4<f32>,
    b: vec4<f32>,
    c: vec4<f32>,
}

// A node of the compressed 8-wide BVH (scene::records::BvhNode has the layout): the
// quantization grid's origin, its steps' exponent bytes and imask (top byte), the first
// child node, the first primitive of the leaf children, a meta byte per child, and each
// child's planes as bytes of the grid (q0: lo.x, lo.y; q1: lo.z, hi.x; q2: hi.y, hi.z;
// two words each, children 0-3 then 4-7).
struct BvhNode {
    origin: vec3<f32>,
    scale: u32,
    child: u32,
    prim: u32,
    meta0: u32,
    meta1: u32,
    q0: vec4<u32>,
    q1: vec4<u32>,
    q2: vec4<u32>,
}

// Storage: each material names its places in its view (NAMEParams, written from
// scene::materials), what every material has in SurfaceParams. The record's own rules: a
// texture in tex_color replaces color.rgb (clamped to 1), in tex_color2 color2.rgb, in
// tex_emission emission.rgb; tex_data0 to tex_data5 and tex_normal2 are the material's
// own (its texture hook may write normal2, a second shading normal at the hit; with
// MAT_FLAG_ANISOTROPIC material_at writes the hit's tangent there instead); table is the
// first tables entry of a table the material reads.
struct Material {
    tag: u32,
    flags: u32,
    tex_color: u32,
    tex_emission: u32,
    color: vec4<f32>,
    emission: vec4<f32>,
    scalars: vec4<f32>,
    color2: vec4<f32>,
    tex_color2: u32,
    tex_data0: u32,
    tex_normal: u32,
    tex_data1: u32,
    color3: vec4<f32>,
    scalars2: vec4<f32>,
    normal2: vec4<f32>,
    tex_data2: u32,
    tex_data3: u32,
    tex_data4: u32,
    tex_data5: u32,
    tex_normal2: u32,
    table: u32,
    // the opacity mask's texture, with MAT_FLAG_OPACITY_TEXTURE
    tex_opacity: u32,
    pad1: u32,
}

// Constant: color0 | checker: cells of textures even / odd (color0 / color1 where
// NO_TEXTURE), params.x cells per unit | image: width x height texels of texel bank `bank`,
// page `layer`, from page texel (x, y), row 0 at the top, read from uv set uv_set | noise:
// color0 x Perlin noise of params.x x p, its tables at tables[offset].
struct Texture {
    tag: u32,
    flags: u32,
    even: u32,
    odd: u32,
    width: u32,
    height: u32,
    bank: u32,
    layer: u32,
    x: u32,
    y: u32,
    uv_set: u32,
    offset: u32,
    color0: vec4<f32>,
    color1: vec4<f32>,
    params: vec4<f32>,
}

// One light: an emissive primitive with its world-space geometry, or the environment
// (primitive = NO_HIT). Chosen with probability prob by inverting the running sum cdf.
// triangle: vertices a, b, c | disk: a = (center, radius), b = unit normal
// sphere: a = (center, radius)
// A light with a surface: kind = its primitive's tag, a, b, c = its primitive's places in
// world space.
struct Emitter {
    primitive: u32,
    kind: u32,
    prob: f32,
    cdf: f32,
    a: vec4<f32>,
    b: vec4<f32>,
    c: vec4<f32>,
    area: f32,
    power: f32,
    // a projector's irradiance texture or a spot's texture
    texture: u32,
    pad1: u32,
    // a textured spot's up vector over the tangent of its outer angle
    d: vec4<f32>,
}

// Per-dispatch constants: camera, image, pass and band.
struct Params {
    // camera position, .w = lens radius
    cam_origin: vec4<f32>,
    // unit right vector, .w = half width of the focus plane
    cam_right: vec4<f32>,
    // unit up vector, .w = half height of the focus plane
    cam_up: vec4<f32>,
    // unit forward vector, .w = focus distance
    cam_forward: vec4<f32>,
    // radiance of rays that leave the scene (the bottom of a gradient), .w unused
    background: vec4<f32>,
    // the top of a vertical gradient
    background_top: vec4<f32>,
    // image background: (cos, sin) of its rotation about +y, strength
    env: vec4<f32>,
    width: u32,
    height: u32,
    max_depth: u32,
    seed: u32,
    sample_index: u32,
    num_primitives: u32,
    num_emitters: u32,
    band_x: u32,
    band_y: u32,
    band_width: u32,
    band_height: u32,
    // primitives 0 .. num_unbounded (planes) are tested on every ray, the rest via the BVH
    num_unbounded: u32,
    // 1: traverse the BVH, 0: test every primitive
    use_bvh: u32,
    // SAMPLER_* for the first bounce's 2D points
    sampler: u32,
    // jittered: the pixel is a 2^strata_log2 x 2^strata_log2 grid
    strata_log2: u32,
    // samples per pixel of the whole render (hammersley's N)
    spp: u32,
    // LIGHT_SAMPLING_*
    light_sampling: u32,
    // BACKGROUND_*
    background_kind: u32,
    // image background: its texture, the first tables entry of its distribution, and its
    // index in the light list (or NO_LIGHT)
    env_texture: u32,
    env_cdf: u32,
    env_light: u32,
    // image row of the bound accumulation buffer's first pixel (the band it holds)
    accum_y: u32,
    // Russian roulette decides whether rays from this one on are traced (0: never)
    rr_depth: u32,
    // samples sample_index .. sample_index + sample_count are traced by this dispatch
    sample_count: u32,
    // lights without a surface: emitters num_emitters .. num_emitters + num_punctual
    num_punctual: u32,
    // 1: an orthographic camera (parallel rays along cam_forward), 0: a perspective one
    orthographic: u32,
    // FILTER_*: the pixel filter a sample's position in the pixel follows
    pixel_filter: u32,
    // the first tables entry of the microfacet albedo tables (energy compensation)
    ms_tables: u32,
    // 1: camera rays see no emitter and no background
    hide_emitters: u32,
    // camera rays start this far in front of the camera (along cam_forward); 0: none
    near_clip: f32,
    // the tent or Gaussian as a step function of this many steps over [0, radius]; 0: itself
    filter_steps: u32,
    // 1: samples lie uniformly in their pixels and the gather pass splats them over the
    // pixels the filter reaches; 0: drawn from the filter
    splat: u32,
    // the first tables entry of the media (MEDIUM_ENTRIES each), and the medium camera
    // rays start in (NO_MEDIUM: none)
    media: u32,
    camera_medium: u32,
    // the first tables entry of the material records' media words (MEDIA_SIDE)
    material_media: u32,
    pad0: u32,
    // the filter's radius (pixels), a Gaussian's standard deviation, its value at the
    // radius (subtracted), and 1 when samples stay on the image
    filter_shape: vec4<f32>,
}

struct Ray {
    origin: vec3<f32>,
    dir: vec3<f32>,
}

// A hit in a primitive's own space (each type's NAME_surface).
struct Surface {
    p: vec3<f32>,
    ng: vec3<f32>,
    ns: vec3<f32>,
    uv: vec2<f32>,
    err: f32,
    tangent: vec4<f32>,
    // a triangle's second uv set (PRIM_FLAG_UV1) and vertex colour (PRIM_FLAG_COLORS)
    uv1: vec2<f32>,
    color: vec4<f32>,
}

// A point sampled on a light with a surface (each such type's NAME_light_sample): the
// point, its solid-angle pdf seen from where it was sampled (0: none), and its (u, v) as
// a hit's candidate would have them.
struct LightPoint {
    x: vec3<f32>,
    pdf: f32,
    uv: vec2<f32>,
}

// What the closest-hit search reports: distance, primitive, and the primitive's own
// parameters of the hit: barycentrics of v1 and v2 for triangles, the slab axis for boxes,
// the part (0 side, 1 base cap, 2 top cap) for cylinders. With instances, also the
// instance the primitive was hit through (NO_HIT: none; prim is then its group's), t along
// the ray the search was given.
struct Candidate {
    t: f32,
    prim: u32,
    u: f32,
    v: f32,
#ifdef HAS_INSTANCES
    inst: u32,
#endif
}

// The shading record of the closest hit.
struct Hit {
    // hit point, computed from the primitive (not origin + t * dir)
    p: vec3<f32>,
    // geometric normal on the front side (outward for closed shapes, right-hand rule for
    // triangles, the given normal for planes and disks)
    ng: vec3<f32>,
    // shading normal, on the same side as ng (interpolated vertex normals, else ng; then
    // as a normal or bump map turns it: normal_mapped)
    ns: vec3<f32>,
    // the shading normal before a normal or bump map turned it
    unmapped: vec3<f32>,
    // surface coordinates for textures: uv set 0 in .xy, set 1 in .zw (set 0's where the
    // surface has one set)
    uv: vec4<f32>,
    // true when the ray arrives on the front side
    front_face: bool,
    material: u32,
    // bound on the absolute error of each coordinate of p, from the primitive's magnitude
    err: f32,
    // interpolated vertex tangent (xyz, not unit) and bitangent sign (w) of a triangle
    // with tangents (HAS_NORMAL_MAP), else zero
    tangent: vec4<f32>,
    // interpolated vertex colour (linear rgb, alpha) of a triangle with vertex colours
    // (HAS_VERTEX_COLORS), else 1
    color: vec4<f32>,
#ifdef HAS_BUMP
    // the derivatives of p along the surface's first uv set (surface_uv_derivatives), for
    // bump maps
    dpdu: vec3<f32>,
    dpdv: vec3<f32>,
#endif
}
