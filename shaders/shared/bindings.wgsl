// Every resource of the trace pipeline, in one place. Binding order is the order of
// `gpu::render::BINDINGS` on the host.
#import shared/types

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> primitives: array<Primitive>;
@group(0) @binding(2) var<storage, read> materials: array<Material>;
@group(0) @binding(3) var<storage, read> emitters: array<Emitter>;
// Two vec4 per pixel of the tile being rendered (a band of whole rows with its own buffer,
// pixel i row-major within the band): [2i] = (sum r, sum g, sum b, samples), [2i + 1] =
// (sum r^2, g^2, b^2, samples dropped as not finite).
@group(0) @binding(4) var<storage, read_write> accum: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> bvh: array<BvhNode>;
// Transforms and triangle vertex attributes, indexed by Primitive.data.
@group(0) @binding(6) var<storage, read> shape_data: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read> textures: array<Texture>;
// Image texels (linear RGB) and the Perlin noise tables.
@group(0) @binding(8) var<storage, read> texels: array<vec4<f32>>;
