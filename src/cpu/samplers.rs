//! Mirrors `shaders/shared/samplers.wgsl`: the pixel samplers, bit for bit.

use super::bindings::Bindings;
use super::rng::{pcg4d, rand_2d, u32_to_unit_float};
use crate::scene::records::{SAMPLER_HAMMERSLEY, SAMPLER_JITTERED, SAMPLER_SOBOL};

pub use crate::scene::records::{
    DIM_ALPHA, DIM_BSDF, DIM_LENS, DIM_LIGHT, DIM_LIGHT_CHOICE, DIM_PIXEL, DIM_PUNCTUAL, DIM_RR,
};

/// Second dimension of Sobol' (primitive polynomial x + 1): the XOR of the direction
/// numbers of the set bits of i, as five shift-and-mask steps (see samplers.wgsl).
pub fn sobol_dim1(i: u32) -> u32 {
    let mut z = i;
    z ^= (z >> 1) & 0x5555_5555;
    z ^= (z >> 2) & 0x3333_3333;
    z ^= (z >> 4) & 0x0f0f_0f0f;
    z ^= (z >> 8) & 0x00ff_00ff;
    z ^= (z >> 16) & 0x0000_ffff;
    z.reverse_bits()
}

/// Laine and Karras's hash-based permutation (Burley 2020's constants).
pub fn laine_karras(x_in: u32, seed: u32) -> u32 {
    let mut x = x_in.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// Nested uniform (Owen) scramble of a base-2 fraction held in the bits of x.
pub fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    laine_karras(x.reverse_bits(), seed).reverse_bits()
}

/// Owen-scrambled, shuffled Sobol' point as u32 fractions (for tests of the net property).
pub fn sobol_owen_bits(pixel: u32, sample: u32, dim: u32, seed: u32) -> [u32; 2] {
    let h = pcg4d([pixel, dim, seed, 0x5b0c_2a3d]);
    let index = nested_uniform_scramble(sample, h[0]);
    [
        nested_uniform_scramble(index.reverse_bits(), h[1]),
        nested_uniform_scramble(sobol_dim1(index), h[2]),
    ]
}

/// Owen-scrambled, shuffled Sobol' point `sample` of pair `dim` in `pixel`.
pub fn sobol_owen(b: &Bindings, pixel: u32, sample: u32, dim: u32) -> [f32; 2] {
    let [x, y] = sobol_owen_bits(pixel, sample, dim, b.params.seed);
    [u32_to_unit_float(x), u32_to_unit_float(y)]
}

/// Jittered: the cell of the i-th (0, 2)-sequence point, digitally shifted per pixel, and a
/// uniform point inside it.
pub fn jittered(b: &Bindings, pixel: u32, sample: u32) -> [f32; 2] {
    let k = b.params.strata_log2;
    let j = rand_2d(pixel, sample, 0, DIM_PIXEL, b.params.seed);
    if k == 0 {
        return j;
    }
    let shift = pcg4d([pixel, b.params.seed, 0x2c1b_3c6d, 0]);
    let mask = (1u32 << k) - 1;
    let cx = ((sample.reverse_bits() >> (32 - k)) ^ shift[0]) & mask;
    let cy = ((sobol_dim1(sample) >> (32 - k)) ^ shift[1]) & mask;
    let side = (1u32 << k) as f32;
    [(cx as f32 + j[0]) / side, (cy as f32 + j[1]) / side]
}

/// Hammersley: (i / N, radical inverse of i), Cranley-Patterson rotated per pixel.
pub fn hammersley(b: &Bindings, pixel: u32, sample: u32) -> [f32; 2] {
    let p = [
        sample as f32 / b.params.spp as f32,
        u32_to_unit_float(sample.reverse_bits()),
    ];
    let r = rand_2d(pixel, 0, 0, DIM_PIXEL, b.params.seed ^ 0x68bc_21eb);
    let s = [p[0] + r[0], p[1] + r[1]];
    [s[0] - s[0].floor(), s[1] - s[1].floor()]
}

/// The 2D point of pair `dim` for sample `sample` of `pixel` at the first bounce.
pub fn sample_2d(b: &Bindings, pixel: u32, sample: u32, dim: u32) -> [f32; 2] {
    match b.params.sampler {
        SAMPLER_JITTERED if dim == DIM_PIXEL => return jittered(b, pixel, sample),
        SAMPLER_HAMMERSLEY if dim == DIM_PIXEL => return hammersley(b, pixel, sample),
        SAMPLER_SOBOL => return sobol_owen(b, pixel, sample, dim),
        _ => {}
    }
    rand_2d(pixel, sample, 0, dim, b.params.seed)
}

/// The 2D point of pair `dim` at bounce `depth`: the sampler's at the first bounce.
pub fn bounce_2d(b: &Bindings, pixel: u32, sample: u32, depth: u32, dim: u32) -> [f32; 2] {
    if depth == 0 {
        return sample_2d(b, pixel, sample, dim);
    }
    rand_2d(pixel, sample, depth, dim, b.params.seed)
}
