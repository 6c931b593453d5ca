//! Mirrors `shaders/shared/rng.wgsl`: counter-based random numbers, bit for bit.

/// pcg4d (Jarzynski and Olano, JCGT 2020), in wrapping u32 arithmetic like WGSL.
#[inline]
pub fn pcg4d(key: [u32; 4]) -> [u32; 4] {
    let mut v = key.map(|k| k.wrapping_mul(1664525).wrapping_add(1013904223));
    v[0] = v[0].wrapping_add(v[1].wrapping_mul(v[3]));
    v[1] = v[1].wrapping_add(v[2].wrapping_mul(v[0]));
    v[2] = v[2].wrapping_add(v[0].wrapping_mul(v[1]));
    v[3] = v[3].wrapping_add(v[1].wrapping_mul(v[2]));
    v = v.map(|x| x ^ (x >> 16));
    v[0] = v[0].wrapping_add(v[1].wrapping_mul(v[3]));
    v[1] = v[1].wrapping_add(v[2].wrapping_mul(v[0]));
    v[2] = v[2].wrapping_add(v[0].wrapping_mul(v[1]));
    v[3] = v[3].wrapping_add(v[1].wrapping_mul(v[2]));
    v
}

/// The top 24 bits of a u32 as a float in [0, 1).
#[inline]
pub fn u32_to_unit_float(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / 16777216.0)
}

/// Two uniform numbers in [0, 1) for dimension pair `dim` of bounce `bounce` of one sample.
#[inline]
pub fn rand_2d(pixel: u32, sample: u32, bounce: u32, dim: u32, seed: u32) -> [f32; 2] {
    let h = pcg4d([pixel, sample, (bounce << 8) | (dim & 0xff), seed]);
    [u32_to_unit_float(h[0]), u32_to_unit_float(h[1])]
}
