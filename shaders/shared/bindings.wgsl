// Every resource of the trace pipeline, in one place. Binding order is the order of
// `gpu::render::BINDINGS` on the host. A read-only record array that fits in 64 KiB is a
// uniform buffer when its UNIFORM_* define is set (`shader::UNIFORM_DEFINES`): llvmpipe
// loads a storage buffer one lane and one component at a time, a uniform buffer with one
// gather. The fixed lengths are 65536 bytes / the record's size (a test checks them).
#import shared/types
#ifdef SCENE_CODE
// records written into this scene's shader as constants (gpu::shader::scene_shader)
#import generated/scene
#endif

@group(0) @binding(0) var<uniform> params: Params;
#ifdef UNIFORM_PRIMITIVES
@group(0) @binding(1) var<uniform> primitives: array<Primitive, 1024>;
#else
@group(0) @binding(1) var<storage, read> primitives: array<Primitive>;
#endif
#ifdef UNIFORM_MATERIALS
@group(0) @binding(2) var<uniform> materials: array<Material, 682>;
#else
@group(0) @binding(2) var<storage, read> materials: array<Material>;
#endif
#ifdef UNIFORM_EMITTERS
@group(0) @binding(3) var<uniform> emitters: array<Emitter, 819>;
#else
@group(0) @binding(3) var<storage, read> emitters: array<Emitter>;
#endif
// Two vec4 per pixel of the tile being rendered (a band of whole rows with its own buffer,
// pixel i row-major within the band): [2i] = (sum r, sum g, sum b, samples), [2i + 1] =
// (sum r^2, g^2, b^2, samples dropped as not finite).
@group(0) @binding(4) var<storage, read_write> accum: array<vec4<f32>>;
#ifdef UNIFORM_BVH
@group(0) @binding(5) var<uniform> bvh: array<BvhNode, 2048>;
#else
@group(0) @binding(5) var<storage, read> bvh: array<BvhNode>;
#endif
// Transforms and triangle vertex attributes, indexed by Primitive.data.
#ifdef UNIFORM_SHAPE_DATA
@group(0) @binding(6) var<uniform> shape_data: array<vec4<f32>, 4096>;
#else
@group(0) @binding(6) var<storage, read> shape_data: array<vec4<f32>>;
#endif
#ifdef UNIFORM_TEXTURES
@group(0) @binding(7) var<uniform> textures: array<Texture, 819>;
#else
@group(0) @binding(7) var<storage, read> textures: array<Texture>;
#endif
// Image texels (linear RGB) and the Perlin noise tables.
@group(0) @binding(8) var<storage, read> texels: array<vec4<f32>>;

// Primitive, material and light i: from their buffers, or, for a scene of few of them,
// from constants written into its shader (BAKED_PRIMITIVES, BAKED_MATERIALS,
// BAKED_EMITTERS): llvmpipe gathers a record from a buffer one lane and one component at
// a time.
#ifndef BAKED_PRIMITIVES
fn primitive_record(i: u32) -> Primitive {
    return primitives[i];
}
#endif
#ifndef BAKED_MATERIALS
fn material_record(i: u32) -> Material {
    return materials[i];
}
#endif
#ifndef BAKED_EMITTERS
fn emitter_record(i: u32) -> Emitter {
    return emitters[i];
}
#endif
