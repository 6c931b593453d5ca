// Every resource of the trace pipeline. The declarations are generated from one table in
// src/gpu/bindings.rs (`Slot`): binding numbers, names, record types, and whether a
// read-only record array is a storage buffer, or, where it fits in 64 KiB, a uniform
// buffer (llvmpipe loads a storage buffer one lane and one component at a time, a uniform
// buffer with one gather), as the scene's plan places it (gpu::plan):
//   params      the per-dispatch constants (Params)
//   primitives, materials, emitters, bvh, shape_data (transforms and triangle vertex
//               attributes, indexed by Primitive.data), textures: the scene's records
//   accum       two vec4 per pixel of the band being rendered (pixel i row-major within
//               the band): [2i] = (sum r, sum g, sum b, samples), [2i + 1] = (sum r^2,
//               g^2, b^2, samples dropped as not finite)
//   tables      the Perlin noise tables and the image background's distribution
//   texels0..7  the image texel banks: 2D array textures (8-bit, half or float texels),
//               read through texel_load(bank, layer, x, y), generated for the scene's
//               banks (src/scene/texels.rs)
#import shared/types
// Records written into this scene's shader as constants (empty for most scenes).
#import generated/scene
#import generated/bindings

// Primitive, material, light and BVH node i are read through primitive_record(i),
// material_record(i), emitter_record(i) and bvh_node(i), written with the declarations
// for where the plan keeps them: a buffer, a texture (read with textureLoad), or, for a
// scene of few of them, constants of its shader (BAKED_PRIMITIVES, BAKED_MATERIALS,
// BAKED_EMITTERS; the scene code defines those functions then): llvmpipe gathers a record
// from a storage buffer one lane and one component at a time.
