// Pixel samplers: the 2D points a sample uses for its position in the pixel, on the lens
// and for the first bounce's BSDF. random: independent points (rand_2d). jittered: strata
// of the pixel. hammersley: (i / N, radical inverse of i), rotated per pixel. sobol:
// Owen-scrambled Sobol' points (Burley, "Practical Hash-based Owen Scrambling", JCGT 2020).
// Later bounces always use rand_2d.
#import shared/bindings
#import shared/rng
#import shared/sampling
#import shared/types

// The dimension pairs drawn at each bounce (rand_2d's `dim`: DIM_PIXEL, DIM_LENS,
// DIM_BSDF, DIM_LIGHT, DIM_LIGHT_CHOICE, DIM_RR, DIM_PUNCTUAL, DIM_ALPHA, DIM_BLEND, and
// DIM_MEDIUM + k for the k-th stretch's free flight) come with the constants of
// types.wgsl.

// Second dimension of Sobol' (primitive polynomial x + 1): the XOR of the direction numbers
// v_k = v_{k-1} ^ (v_{k-1} >> 1), v_1 = 2^31, of the set bits of i. Bit a of i reaches
// bit 31 - m of the result when C(a, m) is odd, that is (Lucas) when m's bits are a
// subset of a's: so bit m before the reversal is the XOR of the bits of i at the
// supersets of m, five shift-and-mask steps. No loop: llvmpipe ran one per bit of the
// scrambled, full-width index, five times per bounce.
fn sobol_dim1(i: u32) -> u32 {
    var z = i;
    z ^= (z >> 1u) & 0x55555555u;
    z ^= (z >> 2u) & 0x33333333u;
    z ^= (z >> 4u) & 0x0f0f0f0fu;
    z ^= (z >> 8u) & 0x00ff00ffu;
    z ^= (z >> 16u) & 0x0000ffffu;
    return reverseBits(z);
}

// Laine and Karras's hash-based permutation: bit k of the result depends only on bits
// k and below of x (Burley 2020, the improved constants).
fn laine_karras(x_in: u32, seed: u32) -> u32 {
    var x = x_in + seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

// Nested uniform (Owen) scramble of a base-2 fraction held in the bits of x.
fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    return reverseBits(laine_karras(reverseBits(x), seed));
}

// Owen-scrambled, shuffled Sobol' point `sample` of pair `dim` in `pixel`: every power-of-2
// prefix of the samples is a (0, m, 2)-net.
fn sobol_owen(pixel: u32, sample: u32, dim: u32) -> vec2<f32> {
    let h = pcg4d(vec4<u32>(pixel, dim, params.seed, 0x5b0c2a3du));
    let index = nested_uniform_scramble(sample, h.x);
    let x = nested_uniform_scramble(reverseBits(index), h.y);
    let y = nested_uniform_scramble(sobol_dim1(index), h.z);
    return vec2<f32>(u32_to_unit_float(x), u32_to_unit_float(y));
}

// Jittered: the pixel as a 2^k x 2^k grid (4^k >= spp). Sample i takes the cell of the i-th
// point of the unscrambled (0, 2)-sequence, digitally shifted per pixel, so every
// power-of-4 prefix of the passes covers the pixel evenly and the first 4^k samples fill
// every cell once; within its cell a sample is uniform.
fn jittered(pixel: u32, sample: u32) -> vec2<f32> {
    let k = params.strata_log2;
    let j = rand_2d(pixel, sample, 0u, DIM_PIXEL, params.seed);
    if (k == 0u) {
        return j;
    }
    let shift = pcg4d(vec4<u32>(pixel, params.seed, 0x2c1b3c6du, 0u));
    let mask = (1u << k) - 1u;
    let cx = ((reverseBits(sample) >> (32u - k)) ^ shift.x) & mask;
    let cy = ((sobol_dim1(sample) >> (32u - k)) ^ shift.y) & mask;
    let side = f32(1u << k);
    return (vec2<f32>(f32(cx), f32(cy)) + j) / side;
}

// Hammersley: (i / N, base-2 radical inverse of i), N = spp, shifted modulo 1 by a random
// offset per pixel (Cranley-Patterson rotation) so neighbouring pixels decorrelate.
fn hammersley(pixel: u32, sample: u32) -> vec2<f32> {
    let p = vec2<f32>(f32(sample) / f32(params.spp), u32_to_unit_float(reverseBits(sample)));
    let s = p + rand_2d(pixel, 0u, 0u, DIM_PIXEL, params.seed ^ 0x68bc21ebu);
    return s - floor(s);
}

// The 2D point of pair `dim` for sample `sample` of `pixel` at the first bounce.
fn sample_2d(pixel: u32, sample: u32, dim: u32) -> vec2<f32> {
    switch params.sampler {
#ifdef HAS_JITTERED
        case SAMPLER_JITTERED: {
            if (dim == DIM_PIXEL) {
                return jittered(pixel, sample);
            }
        }
#endif
#ifdef HAS_HAMMERSLEY
        case SAMPLER_HAMMERSLEY: {
            if (dim == DIM_PIXEL) {
                return hammersley(pixel, sample);
            }
        }
#endif
#ifdef HAS_SOBOL
        case SAMPLER_SOBOL: {
            return sobol_owen(pixel, sample, dim);
        }
#endif
        default: {}
    }
    return rand_2d(pixel, sample, 0u, dim, params.seed);
}

// The 2D point of pair `dim` at bounce `depth`: the sampler's at the first bounce.
fn bounce_2d(pixel: u32, sample: u32, depth: u32, dim: u32) -> vec2<f32> {
    if (depth == 0u) {
        return sample_2d(pixel, sample, dim);
    }
    return rand_2d(pixel, sample, depth, dim, params.seed);
}

// A sample's position in its pixel ([0, 1)^2 is the pixel's square): the sampler's point,
// moved by the pixel filter where the scene has one other than the box and does not
// splat.
fn pixel_position(pixel: u32, sample: u32) -> vec2<f32> {
    let u = sample_2d(pixel, sample, DIM_PIXEL);
#ifdef HAS_PIXEL_FILTER
#ifdef HAS_SPLAT
    // splatted samples lie uniformly in their pixel: the filter weighs them afterwards
    if (params.splat != 0u) {
        return u;
    }
#endif
    let x = pixel % params.width;
    let y = pixel / params.width;
    return vec2<f32>(
        0.5 + filter_offset_on_image(u.x, x, params.width),
        0.5 + filter_offset_on_image(u.y, y, params.height),
    );
#else
    return u;
#endif
}

#ifdef HAS_PIXEL_FILTER
// Filter importance sampling (Ernst et al. 2006): a sample's offset from its pixel's
// centre along one axis, drawn from the filter's profile by inverting its CDF at u, so
// every sample weighs 1 and the pixel stays the mean of its samples. The filters are
// separable (Mitsuba 3's and pbrt-v4's). Tent of radius r, 1 - |x| / r: inverted in
// closed form. Gaussian: g(x) = exp(-x^2 / (2 s^2)) less g(r), on [-r, r]
// (gaussian_filter_offset). Either as a step function (filter_steps): by walking its
// steps (stepped_filter_offset).
fn filter_offset(u: f32) -> f32 {
    let r = params.filter_shape.x;
    if (params.filter_steps != 0u) {
        let x = stepped_filter_offset(abs(2.0 * u - 1.0));
        return select(-x, x, u >= 0.5);
    }
    if (params.pixel_filter == FILTER_TENT) {
        return select(r * (1.0 - sqrt(2.0 - 2.0 * u)), r * (sqrt(2.0 * u) - 1.0), u < 0.5);
    }
    return gaussian_filter_offset(u);
}

// The offset along one axis for pixel i of n: with samples kept on the image
// (filter_shape.w = 1, Mitsuba's film without sample_border), drawn from the filter
// restricted to the image by moving u into the part of the filter's CDF over it (exact:
// the filters are separable and the image a rectangle); else from the whole filter.
fn filter_offset_on_image(u: f32, i: u32, n: u32) -> f32 {
    if (params.filter_shape.w == 0.0) {
        return filter_offset(u);
    }
    let a = -(f32(i) + 0.5);
    let b = f32(n) - f32(i) - 0.5;
    let lo = filter_cdf(a);
    let hi = filter_cdf(b);
    return clamp(filter_offset(lo + u * (hi - lo)), a, b);
}

// The filter's CDF along one axis at offset x: the tent's in closed form; the Gaussian's
// from the integral of g - g(r) from 0, by symmetry.
fn filter_cdf(x: f32) -> f32 {
    let r = params.filter_shape.x;
    if (params.filter_steps != 0u) {
        return 0.5 + sign(x) * 0.5 * stepped_filter_integral(min(abs(x), r)) / stepped_filter_integral(r);
    }
    let t = clamp(x / r, -1.0, 1.0);
    if (params.pixel_filter == FILTER_TENT) {
        return select(1.0 - 0.5 * (1.0 - t) * (1.0 - t), 0.5 * (1.0 + t) * (1.0 + t), t < 0.0);
    }
    let s = params.filter_shape.y;
    let b = params.filter_shape.z;
    let k = 0.70710678 / s;
    let c = 1.25331414 * s;
    let ax = min(abs(x), r);
    let g = c * erf_approx(ax * k) - b * ax;
    let total = c * erf_approx(r * k) - b * r;
    return 0.5 + sign(x) * 0.5 * g / total;
}

// The Gaussian filter's offset at u: by symmetry the x in [0, r] where the integral of
// g - g(r) from 0, s sqrt(pi / 2) erf(x / (s sqrt 2)) - g(r) x, is |2u - 1| times its
// integral up to r; found by Newton's method kept inside a shrinking bracket (a step
// that leaves it bisects), from the untruncated Gaussian's quantile.
fn gaussian_filter_offset(u: f32) -> f32 {
    let r = params.filter_shape.x;
    let s = params.filter_shape.y;
    let b = params.filter_shape.z;
    let k = 0.70710678 / s;
    let c = 1.25331414 * s;
    let v = abs(2.0 * u - 1.0);
    let edge = erf_approx(r * k);
    let goal = v * (c * edge - b * r);
    var lo = 0.0;
    var hi = r;
    var x = clamp(erfinv_approx(v * edge) / k, 0.0, r);
    for (var i = 0u; i < 6u; i++) {
        let e = c * erf_approx(x * k) - b * x - goal;
        lo = select(lo, x, e <= 0.0);
        hi = select(x, hi, e <= 0.0);
        let xk = x * k;
        let next = x - e / (exp(-xk * xk) - b);
        x = select(0.5 * (lo + hi), next, next >= lo && next <= hi);
    }
    return select(-x, x, u >= 0.5);
}

// The filter's profile at x in [0, r): the tent's 1 - x / r, the Gaussian's g(x) - g(r).
fn filter_profile(x: f32) -> f32 {
    if (params.pixel_filter == FILTER_TENT) {
        return 1.0 - x / params.filter_shape.x;
    }
    let s = params.filter_shape.y;
    return exp(-x * x / (2.0 * s * s)) - params.filter_shape.z;
}

// The stepped filter (filter_steps = n, Mitsuba 3's film's table): step k, |x| in
// [k h, (k + 1) h) with h = r / n, keeps the profile's value at k h. Its integral from 0
// to x in [0, r].
fn stepped_filter_integral(x: f32) -> f32 {
    let h = params.filter_shape.x / f32(params.filter_steps);
    var sum = 0.0;
    for (var k = 0u; k < params.filter_steps; k++) {
        let lo = f32(k) * h;
        sum += filter_profile(lo) * clamp(x - lo, 0.0, h);
    }
    return sum;
}

// The x in [0, r] where the stepped filter's integral from 0 is v times its integral up
// to r: the step it falls in, found by walking the steps, then linear within it.
fn stepped_filter_offset(v: f32) -> f32 {
    let r = params.filter_shape.x;
    let h = r / f32(params.filter_steps);
    let goal = v * stepped_filter_integral(r);
    var below = 0.0;
    var x = r;
    var found = false;
    for (var k = 0u; k < params.filter_steps; k++) {
        let lo = f32(k) * h;
        let value = filter_profile(lo);
        if (!found && below + value * h >= goal) {
            x = lo + (goal - below) / value;
            found = true;
        }
        below += value * h;
    }
    return min(x, r);
}
#endif

#ifdef HAS_SPLAT
// The weight a splatted sample d pixels from a pixel's centre along one axis has in that
// pixel (splat reconstruction): the filter's profile at |d| (the stepped filter's at the
// start of |d|'s step), 0 from the radius on, as Mitsuba 3's film weighs a sample.
fn splat_weight(d: f32) -> f32 {
    let r = params.filter_shape.x;
    var x = abs(d);
    if (x >= r) {
        return 0.0;
    }
    if (params.filter_steps != 0u) {
        let h = r / f32(params.filter_steps);
        x = floor(x / h) * h;
    }
    return filter_profile(x);
}
#endif
