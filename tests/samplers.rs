//! Pixel samplers against their definitions (CPU; tests/gpu.rs renders each on both
//! backends): Hammersley's radical inverse is exact, jittered puts one sample in each
//! stratum (and every power-of-4 prefix in each coarser stratum), Sobol' points are
//! (0, 2)-sequences in their two dimensions, scrambled or not.

use wgtrace::cpu::bindings::Bindings;
use wgtrace::cpu::rng::u32_to_unit_float;
use wgtrace::cpu::samplers::{hammersley, jittered, sobol_dim1, sobol_owen_bits, DIM_PIXEL};
use wgtrace::scene::records::Params;
use wgtrace::FlatScene;

fn scene(spp: u32) -> FlatScene {
    let src =
        format!("[render]\nspp = {spp}\n[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n");
    wgtrace::load_scene_str(&src, std::path::Path::new("s.toml"), &Default::default()).unwrap()
}

fn params(s: &FlatScene) -> Params {
    s.params(0, s.full_band())
}

#[test]
fn radical_inverse_is_exact() {
    for i in (0u32..1 << 16).chain((0..1000).map(|k| k * 16_777 + 3)) {
        let exact: f64 = (0..24)
            .filter(|b| i >> b & 1 == 1)
            .map(|b| 0.5f64.powi(b + 1))
            .sum();
        assert_eq!(u32_to_unit_float(i.reverse_bits()) as f64, exact, "i = {i}");
    }
}

#[test]
fn hammersley_points_are_i_over_n_and_the_radical_inverse_rotated_per_pixel() {
    let s = scene(16);
    let b = Bindings::new(&s, params(&s));
    for pixel in [0u32, 77, 1000] {
        let first = hammersley(&b, pixel, 0);
        for i in 0..16u32 {
            let p = hammersley(&b, pixel, i);
            // undo the rotation (the point of sample 0 is the rotation itself)
            let x = (p[0] - first[0]).rem_euclid(1.0);
            let y = (p[1] - first[1]).rem_euclid(1.0);
            let ry = u32_to_unit_float(i.reverse_bits());
            assert!(
                (x - i as f32 / 16.0).abs() < 1e-6 || (x - i as f32 / 16.0).abs() > 1.0 - 1e-6,
                "x {x}"
            );
            assert!(
                (y - ry).abs() < 1e-6 || (y - ry).abs() > 1.0 - 1e-6,
                "y {y} vs {ry}"
            );
        }
    }
}

#[test]
fn jittered_puts_one_sample_in_each_stratum_and_prefixes_stay_stratified() {
    for (spp, k) in [(16u32, 2u32), (64, 3), (256, 4)] {
        let s = scene(spp);
        assert_eq!(params(&s).strata_log2, k);
        let b = Bindings::new(&s, params(&s));
        for pixel in [0u32, 5, 12345] {
            let pts: Vec<[f32; 2]> = (0..spp).map(|i| jittered(&b, pixel, i)).collect();
            // every power-of-4 prefix covers the 2^j x 2^j grid once per cell
            for j in 0..=k {
                let n = 1usize << (2 * j);
                let side = (1u32 << j) as f32;
                let mut seen = vec![false; n];
                for p in &pts[..n] {
                    assert!(p[0] >= 0.0 && p[0] < 1.0 && p[1] >= 0.0 && p[1] < 1.0);
                    let cell = (p[1] * side) as usize * (1 << j) + (p[0] * side) as usize;
                    assert!(
                        !seen[cell],
                        "spp {spp}, pixel {pixel}: two of the first {n} samples share a cell"
                    );
                    seen[cell] = true;
                }
            }
        }
    }
}

/// Whether the points (as 32-bit fractions) form a (0, m, 2)-net: each of the 2^m boxes of
/// every shape 2^-a x 2^-(m - a) holds exactly one point.
fn is_02_net(points: &[[u32; 2]], m: u32) -> bool {
    let cell = |v: u32, bits: u32| {
        if bits == 0 {
            0
        } else {
            (v >> (32 - bits)) as usize
        }
    };
    (0..=m).all(|a| {
        let mut count = vec![0u32; 1 << m];
        for p in points {
            count[(cell(p[0], a) << (m - a)) | cell(p[1], m - a)] += 1;
        }
        count.iter().all(|&c| c == 1)
    })
}

/// The closed form of Sobol's second dimension equals its definition: the XOR of the
/// direction numbers v_1 = 2^31, v_k = v_(k-1) ^ (v_(k-1) >> 1) of the set bits.
#[test]
fn sobol_second_dimension_matches_its_direction_numbers() {
    let by_definition = |i: u32| {
        let (mut v, mut r) = (0x8000_0000u32, 0u32);
        for k in 0..32 {
            if i >> k & 1 != 0 {
                r ^= v;
            }
            v ^= v >> 1;
        }
        r
    };
    let mut x = 0x9e37_79b9u32;
    let mut inputs: Vec<u32> = (0..4096).chain([u32::MAX, 1 << 31]).collect();
    for _ in 0..100_000 {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        inputs.push(x);
    }
    for i in inputs {
        assert_eq!(sobol_dim1(i), by_definition(i), "index {i:#x}");
    }
}

#[test]
fn sobol_points_are_02_sequences_scrambled_or_not() {
    let plain: Vec<[u32; 2]> = (0u32..1024)
        .map(|i| [i.reverse_bits(), sobol_dim1(i)])
        .collect();
    for m in 0..=10 {
        assert!(is_02_net(&plain[..1 << m], m), "unscrambled, first 2^{m}");
    }
    for pixel in [0u32, 1, 999, 123_456] {
        for dim in [DIM_PIXEL, 1, 2] {
            let pts: Vec<[u32; 2]> = (0u32..1024)
                .map(|i| sobol_owen_bits(pixel, i, dim, 7))
                .collect();
            for m in 0..=10 {
                assert!(
                    is_02_net(&pts[..1 << m], m),
                    "pixel {pixel}, dim {dim}, first 2^{m}"
                );
            }
        }
    }
    // scrambling decorrelates pixels: their first points differ
    assert_ne!(sobol_owen_bits(0, 0, 0, 7), sobol_owen_bits(1, 0, 0, 7));
}

/// With samples kept on the image (`sample_border = false`, Mitsuba's film), a border
/// pixel draws from its filter restricted to the image: the tent of radius 1 at pixel 0
/// of 8 gives offsets in [-0.5, 1] only, with the restricted profile's mean, 1/12 over
/// 7/8 = 0.095238 (for u spread evenly over [0, 1)); an inner pixel keeps the whole
/// filter (mean 0); and the Gaussian of radius 2 at the last pixel of 4 stays at or under
/// +0.5, its mean that of the half profile truncated at 0.5.
#[test]
fn filters_kept_on_the_image_sample_the_restricted_profile() {
    use wgtrace::cpu::samplers::filter_offset_on_image;
    use wgtrace::scene::format::{FilterKind, PixelFilter};
    use wgtrace::scene::records::{FILTER_GAUSSIAN, FILTER_TENT};
    let s = scene(1);
    let mut p = params(&s);
    let n = 100_000;
    let offsets = |p: &Params, i: u32, of: u32| -> Vec<f64> {
        (0..n)
            .map(|k| filter_offset_on_image(p, (k as f32 + 0.5) / n as f32, i, of) as f64)
            .collect()
    };
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    p.pixel_filter = FILTER_TENT;
    p.filter_shape = PixelFilter {
        kind: FilterKind::Tent,
        radius: 1.0,
        stddev: 0.0,
        inside: true,
        steps: 0,
        splat: false,
    }
    .shape();
    let edge = offsets(&p, 0, 8);
    assert!(edge.iter().all(|&x| (-0.5..=1.0).contains(&x)));
    assert!((mean(&edge) - 0.095238).abs() < 1e-3, "{}", mean(&edge));
    let inner = offsets(&p, 4, 8);
    assert!(mean(&inner).abs() < 1e-3 && inner.iter().any(|&x| x < -0.9));
    p.pixel_filter = FILTER_GAUSSIAN;
    p.filter_shape = PixelFilter {
        kind: FilterKind::Gaussian,
        radius: 2.0,
        stddev: 0.5,
        inside: true,
        steps: 0,
        splat: false,
    }
    .shape();
    let last = offsets(&p, 3, 4);
    assert!(last.iter().all(|&x| (-2.0..=0.5).contains(&x)));
    // the truncated profile's mean, by Simpson's rule in f64
    let g = |x: f64| (-x * x / 0.5).exp() - (-8.0f64).exp();
    let (a, b, m) = (-2.0f64, 0.5f64, 20_000);
    let h = (b - a) / m as f64;
    let simpson = |f: &dyn Fn(f64) -> f64| {
        (0..=m)
            .map(|k| {
                let w = if k == 0 || k == m {
                    1.0
                } else if k % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                w * f(a + k as f64 * h)
            })
            .sum::<f64>()
            * h
            / 3.0
    };
    let want = simpson(&|x| x * g(x)) / simpson(&|x| g(x));
    assert!(
        (mean(&last) - want).abs() < 2e-3,
        "{} against {want}",
        mean(&last)
    );
}

/// The largest |F(x) - u| of the pixel filter's offsets x (`filter_offset`) for 4096 u
/// spread over [0, 1), F the filter's CDF from -r; every offset within the radius r.
fn inverse_cdf_error(p: &Params, r: f64, cdf: impl Fn(f64) -> f64, label: &str) -> f64 {
    (0..4096)
        .map(|i| {
            let u = (i as f32 + 0.5) / 4096.0;
            let x = wgtrace::cpu::samplers::filter_offset(p, u) as f64;
            assert!(x.abs() <= r, "{label}: offset {x} outside the radius");
            (cdf(x) - u as f64).abs()
        })
        .fold(0.0, f64::max)
}

/// The pixel filters' samplers invert their CDFs: for u across [0, 1), the offset x the
/// sampler returns has F(x) = u, where F is the filter's profile integrated from -radius
/// in f64 (Simpson's rule, not the sampler's erf) and normalized; so the offsets follow
/// the profile exactly, and every sample may weigh 1. Tent (Mitsuba's radius 1,
/// pbrt-v4's 2) and Gaussian (Mitsuba's radius 4 deviations, pbrt-v4's 1.5, a wide one).
#[test]
fn pixel_filters_sample_their_profiles_by_the_inverse_cdf() {
    use wgtrace::scene::format::{FilterKind, PixelFilter};
    use wgtrace::scene::records::{FILTER_GAUSSIAN, FILTER_TENT};
    let filters = [
        (FilterKind::Tent, FILTER_TENT, 1.0f32, 0.0f32),
        (FilterKind::Tent, FILTER_TENT, 2.0, 0.0),
        (FilterKind::Gaussian, FILTER_GAUSSIAN, 2.0, 0.5),
        (FilterKind::Gaussian, FILTER_GAUSSIAN, 1.5, 0.5),
        (FilterKind::Gaussian, FILTER_GAUSSIAN, 3.0, 1.5),
    ];
    for (kind, tag, radius, stddev) in filters {
        let filter = PixelFilter {
            kind,
            radius,
            stddev,
            inside: false,
            steps: 0,
            splat: false,
        };
        let s = scene(1);
        let mut p = params(&s);
        p.pixel_filter = tag;
        p.filter_shape = filter.shape();
        let (r, sd) = (radius as f64, stddev as f64);
        let profile = |x: f64| match kind {
            FilterKind::Tent => (1.0 - x.abs() / r).max(0.0),
            _ => {
                let g = |t: f64| (-t * t / (2.0 * sd * sd)).exp();
                (g(x) - g(r)).max(0.0)
            }
        };
        let integral = |a: f64, b: f64| {
            let n = 2000;
            let h = (b - a) / n as f64;
            (0..=n)
                .map(|i| {
                    let w = if i == 0 || i == n {
                        1.0
                    } else if i % 2 == 1 {
                        4.0
                    } else {
                        2.0
                    };
                    w * profile(a + i as f64 * h)
                })
                .sum::<f64>()
                * h
                / 3.0
        };
        let total = integral(-r, r);
        let label = format!("{kind:?} {radius}");
        let worst = inverse_cdf_error(&p, r, |x| integral(-r, x) / total, &label);
        assert!(
            worst < 2e-4,
            "{kind:?} radius {radius} stddev {stddev}: F(offset) is {worst} from u"
        );
    }
}

/// The stepped filters (`filter_steps`, Mitsuba's film's table of 31 steps) are sampled
/// by their own inverse CDF: the profile is the filter's value at each step's inner end,
/// k r / n for |x| in [k r / n, (k + 1) r / n), integrated exactly in f64 (a sum of
/// rectangles); for u across [0, 1), F(offset) = u to 1e-5. Their CDF (which keeps
/// samples on the image) is that F too, and a pixel at the image's last column draws no
/// offset past its edge. The last step of Mitsuba's Gaussian holds 2.06 times the share
/// of the samples that the exact Gaussian puts in the last 1/31 of its radius: the
/// difference the table makes.
#[test]
fn stepped_filters_sample_their_steps_by_the_inverse_cdf() {
    use wgtrace::cpu::samplers::{filter_cdf, filter_offset_on_image};
    use wgtrace::scene::format::{FilterKind, PixelFilter};
    use wgtrace::scene::records::{FILTER_GAUSSIAN, FILTER_TENT};
    for (kind, tag, radius, stddev, steps) in [
        (FilterKind::Tent, FILTER_TENT, 1.0f32, 0.0f32, 31u32),
        (FilterKind::Gaussian, FILTER_GAUSSIAN, 2.0, 0.5, 31),
        (FilterKind::Gaussian, FILTER_GAUSSIAN, 1.5, 0.5, 4),
    ] {
        let filter = PixelFilter {
            kind,
            radius,
            stddev,
            inside: false,
            steps,
            splat: false,
        };
        let s = scene(1);
        let mut p = params(&s);
        p.pixel_filter = tag;
        p.filter_shape = filter.shape();
        p.filter_steps = steps;
        let (r, sd, n) = (radius as f64, stddev as f64, steps as usize);
        let h = r / n as f64;
        let value = |k: usize| {
            let x = k as f64 * h;
            match kind {
                FilterKind::Tent => 1.0 - x / r,
                _ => (-x * x / (2.0 * sd * sd)).exp() - (-r * r / (2.0 * sd * sd)).exp(),
            }
        };
        // the stepped profile's integral from 0 to a in [0, r]
        let half = |a: f64| {
            (0..n)
                .map(|k| value(k) * (a - k as f64 * h).clamp(0.0, h))
                .sum::<f64>()
        };
        let cdf = |x: f64| 0.5 + x.signum() * 0.5 * half(x.abs().min(r)) / half(r);
        let mut worst = inverse_cdf_error(&p, r, cdf, &format!("{kind:?} {steps}"));
        for i in 0..4096 {
            let at = (i as f64 / 4096.0 - 0.5) * 2.0 * r;
            worst = worst.max((filter_cdf(&p, at as f32) as f64 - cdf(at)).abs());
        }
        assert!(
            worst < 1e-5,
            "{kind:?} steps {steps}: F(offset) is {worst} from u"
        );
        p.filter_shape[3] = 1.0;
        let last = (0..4096)
            .map(|i| filter_offset_on_image(&p, (i as f32 + 0.5) / 4096.0, 7, 8))
            .fold(f32::MIN, f32::max);
        assert!(
            last <= 0.5,
            "{kind:?} {steps}: an offset {last} past the image"
        );
    }
    // Mitsuba's Gaussian: the last step's share against the exact Gaussian's there
    let g = |x: f64| (-2.0 * x * x).exp() - (-8.0f64).exp();
    let h = 2.0 / 31.0;
    let stepped = g(30.0 * h) * h / (0..31).map(|k| g(k as f64 * h) * h).sum::<f64>();
    let m = 10_000;
    let exact = (0..m)
        .map(|i| g(30.0 * h + (i as f64 + 0.5) * h / m as f64) * h / m as f64)
        .sum::<f64>()
        / (0..m * 31)
            .map(|i| g((i as f64 + 0.5) * h / m as f64) * h / m as f64)
            .sum::<f64>();
    assert!((stepped / exact - 2.06).abs() < 0.01, "{}", stepped / exact);
}
