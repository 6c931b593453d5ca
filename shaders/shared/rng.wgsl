// Counter-based random numbers: a pure function of (pixel, sample, bounce, dimension, seed).
// No state lives in buffers; src/cpu/rng.rs computes the very same bits.

// pcg4d: Jarzynski and Olano, "Hash Functions for GPU Rendering", JCGT 2020.
fn pcg4d(key: vec4<u32>) -> vec4<u32> {
    var v = key * 1664525u + 1013904223u;
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    v ^= v >> vec4<u32>(16u);
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    return v;
}

// The top 24 bits of a u32 as a float in [0, 1): exact in f32 on every device.
fn u32_to_unit_float(x: u32) -> f32 {
    return f32(x >> 8u) * (1.0 / 16777216.0);
}

// Two uniform numbers in [0, 1) for dimension pair `dim` of bounce `bounce` of one sample.
fn rand_2d(pixel: u32, sample: u32, bounce: u32, dim: u32, seed: u32) -> vec2<f32> {
    let h = pcg4d(vec4<u32>(pixel, sample, (bounce << 8u) | (dim & 0xffu), seed));
    return vec2<f32>(u32_to_unit_float(h.x), u32_to_unit_float(h.y));
}
