//! Mirrors `shaders/shared/samplers.wgsl`: the pixel samplers, bit for bit.

use super::bindings::Bindings;
use super::rng::{pcg4d, rand_2d, u32_to_unit_float};
use super::sampling::{erf_approx, erfinv_approx};
use crate::scene::records::{
    Params, FILTER_BOX, FILTER_TENT, SAMPLER_HAMMERSLEY, SAMPLER_JITTERED, SAMPLER_SOBOL,
};

pub use crate::scene::records::{
    DIM_ALPHA, DIM_BLEND, DIM_BSDF, DIM_LENS, DIM_LIGHT, DIM_LIGHT_CHOICE, DIM_PIXEL, DIM_PUNCTUAL,
    DIM_RR,
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

/// A sample's position in its pixel: the sampler's point, moved by the pixel filter
/// unless it is the box or the samples are splatted.
pub fn pixel_position(b: &Bindings, pixel: u32, sample: u32) -> [f32; 2] {
    let u = sample_2d(b, pixel, sample, DIM_PIXEL);
    if b.params.pixel_filter == FILTER_BOX || b.params.splat != 0 {
        return u;
    }
    let p = &b.params;
    let (x, y) = (pixel % p.width, pixel / p.width);
    [
        0.5 + filter_offset_on_image(p, u[0], x, p.width),
        0.5 + filter_offset_on_image(p, u[1], y, p.height),
    ]
}

/// The offset along one axis for pixel i of n, kept on the image when the filter says so
/// (samplers.wgsl's `filter_offset_on_image`).
pub fn filter_offset_on_image(p: &Params, u: f32, i: u32, n: u32) -> f32 {
    if p.filter_shape[3] == 0.0 {
        return filter_offset(p, u);
    }
    let a = -(i as f32 + 0.5);
    let b = n as f32 - i as f32 - 0.5;
    let (lo, hi) = (filter_cdf(p, a), filter_cdf(p, b));
    filter_offset(p, lo + u * (hi - lo)).clamp(a, b)
}

/// The filter's CDF along one axis (samplers.wgsl's `filter_cdf`).
#[allow(clippy::excessive_precision)]
pub fn filter_cdf(p: &Params, x: f32) -> f32 {
    let r = p.filter_shape[0];
    if p.filter_steps != 0 {
        return 0.5
            + wgsl_sign(x) * 0.5 * stepped_filter_integral(p, x.abs().min(r))
                / stepped_filter_integral(p, r);
    }
    let t = (x / r).clamp(-1.0, 1.0);
    if p.pixel_filter == FILTER_TENT {
        return if t < 0.0 {
            0.5 * (1.0 + t) * (1.0 + t)
        } else {
            1.0 - 0.5 * (1.0 - t) * (1.0 - t)
        };
    }
    let [_, s, b, _] = p.filter_shape;
    let k = std::f32::consts::FRAC_1_SQRT_2 / s;
    let c = 1.25331414 * s;
    let ax = x.abs().min(r);
    let g = c * erf_approx(ax * k) - b * ax;
    let total = c * erf_approx(r * k) - b * r;
    0.5 + wgsl_sign(x) * 0.5 * g / total
}

/// WGSL's sign: 0 at 0.
fn wgsl_sign(x: f32) -> f32 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// Filter importance sampling: a sample's offset from its pixel's centre along one axis,
/// the filter's inverse CDF at u (tent in closed form, Gaussian by
/// [`gaussian_filter_offset`]).
pub fn filter_offset(p: &Params, u: f32) -> f32 {
    let r = p.filter_shape[0];
    if p.filter_steps != 0 {
        let x = stepped_filter_offset(p, (2.0 * u - 1.0).abs());
        return if u >= 0.5 { x } else { -x };
    }
    if p.pixel_filter == FILTER_TENT {
        return if u < 0.5 {
            r * ((2.0 * u).sqrt() - 1.0)
        } else {
            r * (1.0 - (2.0 - 2.0 * u).sqrt())
        };
    }
    gaussian_filter_offset(p, u)
}

/// The Gaussian filter's offset at u: Newton's method inside a shrinking bracket on the
/// integral of g - g(r) from 0 (samplers.wgsl's `gaussian_filter_offset`).
#[allow(clippy::excessive_precision)]
pub fn gaussian_filter_offset(p: &Params, u: f32) -> f32 {
    let [r, s, b, _] = p.filter_shape;
    let k = std::f32::consts::FRAC_1_SQRT_2 / s;
    let c = 1.25331414 * s;
    let v = (2.0 * u - 1.0).abs();
    let edge = erf_approx(r * k);
    let goal = v * (c * edge - b * r);
    let (mut lo, mut hi) = (0.0f32, r);
    let mut x = (erfinv_approx(v * edge) / k).clamp(0.0, r);
    for _ in 0..6 {
        let e = c * erf_approx(x * k) - b * x - goal;
        if e <= 0.0 {
            lo = x;
        } else {
            hi = x;
        }
        let xk = x * k;
        let next = x - e / ((-xk * xk).exp() - b);
        x = if next >= lo && next <= hi {
            next
        } else {
            0.5 * (lo + hi)
        };
    }
    if u >= 0.5 {
        x
    } else {
        -x
    }
}

/// The filter's profile at x in [0, r) (samplers.wgsl's `filter_profile`).
pub fn filter_profile(p: &Params, x: f32) -> f32 {
    if p.pixel_filter == FILTER_TENT {
        return 1.0 - x / p.filter_shape[0];
    }
    let s = p.filter_shape[1];
    (-x * x / (2.0 * s * s)).exp() - p.filter_shape[2]
}

/// The stepped filter's integral from 0 to x in [0, r] (samplers.wgsl's
/// `stepped_filter_integral`).
pub fn stepped_filter_integral(p: &Params, x: f32) -> f32 {
    let h = p.filter_shape[0] / p.filter_steps as f32;
    let mut sum = 0.0;
    for k in 0..p.filter_steps {
        let lo = k as f32 * h;
        sum += filter_profile(p, lo) * (x - lo).clamp(0.0, h);
    }
    sum
}

/// The x in [0, r] where the stepped filter's integral from 0 is v times its whole
/// (samplers.wgsl's `stepped_filter_offset`).
pub fn stepped_filter_offset(p: &Params, v: f32) -> f32 {
    let r = p.filter_shape[0];
    let h = r / p.filter_steps as f32;
    let goal = v * stepped_filter_integral(p, r);
    let (mut below, mut x, mut found) = (0.0, r, false);
    for k in 0..p.filter_steps {
        let lo = k as f32 * h;
        let value = filter_profile(p, lo);
        if !found && below + value * h >= goal {
            x = lo + (goal - below) / value;
            found = true;
        }
        below += value * h;
    }
    x.min(r)
}

/// The weight of a splatted sample `d` pixels from a pixel's centre along one axis
/// (samplers.wgsl's `splat_weight`).
pub fn splat_weight(p: &Params, d: f32) -> f32 {
    let r = p.filter_shape[0];
    let mut x = d.abs();
    if x >= r {
        return 0.0;
    }
    if p.filter_steps != 0 {
        let h = r / p.filter_steps as f32;
        x = (x / h).floor() * h;
    }
    filter_profile(p, x)
}
