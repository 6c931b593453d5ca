//! The directional albedo of microfacet lobes, for multiple-scattering energy compensation
//! (Kulla and Conty 2017, "Revisiting Physically Based Shading at Imageworks"): a lobe of
//! alpha that reflects E(mu) of the light from direction cosine mu once loses 1 - E(mu)
//! to the light that bounces between microfacets; a diffuse-like lobe
//! F_ms (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg)) gives it back, reciprocally, so that
//! a white lobe (F = 1) reflects all the light that arrives, E_avg = 2 int E(mu) mu dmu.
//! F_ms = F_avg^2 E_avg / (1 - F_avg (1 - E_avg)) colours it by the lobe's Fresnel,
//! F_avg = 2 int F(mu) mu dmu.
//!
//! Tables, per [`Variant`] (distribution and masking), over `SIZE` roughnesses
//! sqrt(alpha) = i / (SIZE - 1) (rows) and `SIZE` cosines sqrt(mu) = j / (SIZE - 1)
//! (columns, closer together toward grazing, where the albedo turns fastest):
//! E1, the albedo with F = 1; E1's average by roughness; E5, the albedo with Schlick's
//! weight (1 - wo . h)^5 for F, so that a Schlick Fresnel's albedo is F0 E1 + (F90 - F0)
//! E5; E5's average. The averages are the exact integrals of the tables linear in mu
//! between columns, as the shaders read them, so that a compensated white lobe reflects
//! 1 up to the tables' own error. Integrated on load (f64, a stratified 64 x 64 grid of
//! normals: GGX's visible ones, Beckmann's by D(h) cos theta_h), once per process; the
//! flattener places them in `tables` (at `Params::ms_tables`), the CPU reads them here.
//!
//! Rough dielectrics (glass, plastic's coating) lose energy the same way, but what their
//! microfacets scatter again is reflected or transmitted: per [`DielectricVariant`],
//! tables of the total albedo E (reflection and transmission, in energy) over the same
//! roughnesses and cosines, for `IORS` index ratios from 1 to MS_IOR_MAX (`table_ior`,
//! closer together toward 1) and both sides of the boundary, their averages, and the
//! Fresnel average per index (shared/bsdf.wgsl's `ms_dielectric_lobe` has the lobes).
//! Integrated on load where a scene needs a variant (a stratified 32 x 32 grid of
//! normals, about 0.3 s for GGX and 0.65 s for Beckmann on two cores); against a 256 x
//! 256 grid their error is 0.0015 rms, 0.009 at worst; linear between indices, 0.01 at
//! worst from index 1.2 up (coarser below, where the inside's albedo turns within a
//! hundredth of an index).

use std::sync::OnceLock;

use rayon::prelude::*;

use crate::scene::records::{
    MS_BECKMANN_SEPARABLE, MS_DIELECTRIC_BECKMANN_CORRELATED, MS_DIELECTRIC_BECKMANN_SEPARABLE,
    MS_DIELECTRIC_GGX_CORRELATED, MS_DIELECTRIC_GGX_SEPARABLE, MS_GGX_CORRELATED, MS_GGX_SEPARABLE,
    MS_IORS, MS_IOR_MAX,
};

/// Rows and columns of each table.
pub const SIZE: usize = crate::scene::records::MS_TABLE_SIZE as usize;
/// Floats of one variant's block: E1, E1's averages, E5, E5's averages.
pub const BLOCK: usize = 2 * (SIZE * SIZE + SIZE);
/// Indices of refraction of the dielectric tables.
pub const IORS: usize = MS_IORS as usize;
/// Floats of one dielectric variant's block: per index of refraction, per side (the
/// lower index's, then the higher's), the total albedo E and its averages by roughness;
/// then the Fresnel average seen from the lower index, per index.
pub const DIELECTRIC_BLOCK: usize = IORS * 2 * (SIZE * SIZE + SIZE) + IORS;

/// The index of refraction of the dielectric tables' k-th: closer together toward 1,
/// where the albedo seen from inside turns fastest (at 1 nothing reflects totally, at
/// 1.01 grazing light already does).
pub fn table_ior(k: usize) -> f64 {
    let t = k as f64 / (IORS - 1) as f64;
    1.0 + (MS_IOR_MAX as f64 - 1.0) * t * t
}

/// A lobe's distribution and masking-shadowing: each has its own tables.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    /// GGX with Smith's height-correlated G2 (pbr, microfacet).
    GgxCorrelated = MS_GGX_CORRELATED as isize,
    /// GGX with Smith's separable G1(wo) G1(wi) (conductor, principled).
    GgxSeparable = MS_GGX_SEPARABLE as isize,
    /// Beckmann with the separable G1(wo) G1(wi) (conductor).
    BeckmannSeparable = MS_BECKMANN_SEPARABLE as isize,
}

impl Variant {
    pub const ALL: [Variant; 3] = [
        Variant::GgxCorrelated,
        Variant::GgxSeparable,
        Variant::BeckmannSeparable,
    ];

    /// The first float of its block.
    pub fn offset(self) -> usize {
        self as usize * BLOCK
    }
}

/// A rough dielectric's distribution and masking-shadowing: each has its own dielectric
/// tables.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DielectricVariant {
    /// GGX with the height-correlated G2 (dielectric).
    GgxCorrelated = MS_DIELECTRIC_GGX_CORRELATED as isize,
    /// Beckmann with the height-correlated G2 (dielectric).
    BeckmannCorrelated = MS_DIELECTRIC_BECKMANN_CORRELATED as isize,
    /// GGX with the separable G1(wo) G1(wi) (plastic).
    GgxSeparable = MS_DIELECTRIC_GGX_SEPARABLE as isize,
    /// Beckmann with the separable G1(wo) G1(wi) (plastic).
    BeckmannSeparable = MS_DIELECTRIC_BECKMANN_SEPARABLE as isize,
}

impl DielectricVariant {
    pub const ALL: [DielectricVariant; 4] = [
        DielectricVariant::GgxCorrelated,
        DielectricVariant::BeckmannCorrelated,
        DielectricVariant::GgxSeparable,
        DielectricVariant::BeckmannSeparable,
    ];

    fn beckmann(self) -> bool {
        matches!(
            self,
            DielectricVariant::BeckmannCorrelated | DielectricVariant::BeckmannSeparable
        )
    }

    fn correlated(self) -> bool {
        matches!(
            self,
            DielectricVariant::GgxCorrelated | DielectricVariant::BeckmannCorrelated
        )
    }

    /// The first float of its block in the whole tables (after the reflecting ones').
    pub fn offset(self) -> usize {
        3 * BLOCK + self as usize * DIELECTRIC_BLOCK
    }
}

/// Smith's Lambda at cosine c for isotropic alpha.
fn lambda(beckmann: bool, c: f64, alpha: f64) -> f64 {
    lambda_with(beckmann, c, alpha, erf)
}

/// `lambda` with `erf_approx` (five times faster: enough for the dielectric tables' 32 x
/// 32 strata).
fn lambda_fast(beckmann: bool, c: f64, alpha: f64) -> f64 {
    lambda_with(beckmann, c, alpha, erf_approx)
}

/// The error function by Abramowitz and Stegun's 7.1.26 (error under 1.5e-7).
pub fn erf_approx(x: f64) -> f64 {
    let a = x.abs();
    let t = 1.0 / (1.0 + 0.3275911 * a);
    let poly = t
        * (0.254829592
            + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    (1.0 - poly * (-a * a).exp()).copysign(x)
}

fn lambda_with(beckmann: bool, c: f64, alpha: f64, erf: impl Fn(f64) -> f64) -> f64 {
    let c = c.abs().min(1.0);
    let tan2 = (1.0 - c * c).max(0.0) / (c * c);
    if tan2 == 0.0 {
        return 0.0;
    }
    if beckmann {
        let a = 1.0 / (alpha * tan2.sqrt());
        let erf = erf(a);
        (0.5 * (erf - 1.0) + (-a * a).exp() / (a * std::f64::consts::PI.sqrt() * 2.0)).max(0.0)
    } else {
        0.5 * ((1.0 + alpha * alpha * tan2).sqrt() - 1.0)
    }
}

/// The error function (Abramowitz and Stegun 7.1.26 is too coarse for a table: this is
/// its series and continued fraction, to 1e-14).
fn erf(x: f64) -> f64 {
    if x < 0.0 {
        return -erf(-x);
    }
    if x < 3.0 {
        // the Maclaurin series
        let mut sum = x;
        let mut term = x;
        let x2 = x * x;
        for n in 1..200 {
            term *= -x2 / n as f64;
            let add = term / (2 * n + 1) as f64;
            sum += add;
            if add.abs() < 1e-17 {
                break;
            }
        }
        sum * 2.0 / std::f64::consts::PI.sqrt()
    } else {
        // erfc's continued fraction (Lentz)
        let mut f = x;
        let mut c = x;
        let mut d = 0.0;
        for n in 1..200 {
            let a = n as f64 * 0.5;
            d = x + a * d;
            d = 1.0 / d;
            c = x + a / c;
            let delta = c * d;
            f *= delta;
            if (delta - 1.0).abs() < 1e-16 {
                break;
            }
        }
        1.0 - (-x * x).exp() / (f * std::f64::consts::PI.sqrt())
    }
}

/// (E1, E5) of a lobe seen at cosine mu with alpha: a stratified 64 x 64 grid of
/// normals drawn by the visible normals (Heitz 2018) for GGX, whose weight G2 / G1(wo) is
/// at most 1 even at grazing views, and by D(h) cos theta_h for Beckmann.
fn albedo(variant: Variant, mu: f64, alpha: f64) -> (f64, f64) {
    if alpha < 1e-6 {
        // a mirror
        let w = (1.0 - mu).powi(5);
        return (1.0, w);
    }
    let beckmann = variant == Variant::BeckmannSeparable;
    let wo = [(1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu];
    const N: usize = 64;
    let (mut e1, mut e5) = (0.0, 0.0);
    let lo = lambda(beckmann, mu, alpha);
    for a in 0..N {
        for b in 0..N {
            let u = [(a as f64 + 0.5) / N as f64, (b as f64 + 0.5) / N as f64];
            let (h, visible) = if beckmann {
                (sample_normal(alpha, u), false)
            } else {
                (sample_visible(wo, alpha, u), true)
            };
            let oh = wo[0] * h[0] + wo[2] * h[2];
            if oh <= 0.0 {
                continue;
            }
            let wi_z = 2.0 * oh * h[2] - wo[2];
            if wi_z <= 0.0 {
                continue;
            }
            let li = lambda(beckmann, wi_z, alpha);
            let g2 = match variant {
                Variant::GgxCorrelated => 1.0 / (1.0 + lo + li),
                _ => 1.0 / ((1.0 + lo) * (1.0 + li)),
            };
            // f cos_i / pdf: D G2 / (4 mu) over G1(wo) D oh / (4 mu oh) for visible normals,
            // over D cos_h / (4 oh) for normals
            let w = if visible {
                g2 * (1.0 + lo)
            } else {
                g2 * oh / (mu * h[2])
            };
            e1 += w;
            e5 += w * (1.0 - oh).powi(5);
        }
    }
    let n = (N * N) as f64;
    (e1 / n, e5 / n)
}

/// The total albedos, reflection and transmission in energy (the radiance's eta^2
/// across the boundary left out), of a rough dielectric boundary seen at cosine mu with
/// alpha from the sides of relative indices `etas` (eta = eta_o / eta_i): each of a
/// stratified n x n grid of normals h (drawn as `albedo` draws them, the same for every
/// eta) reflects F(wo . h) and transmits 1 - F, each weighted by the masking-shadowing of
/// its direction. What one lacks of 1 is what the microfacets' multiple scattering
/// would send on.
fn dielectric_albedos(
    variant: DielectricVariant,
    mu: f64,
    alpha: f64,
    etas: &[f64],
    n: usize,
) -> Vec<f64> {
    if alpha < 1e-6 {
        return vec![1.0; etas.len()];
    }
    let beckmann = variant.beckmann();
    let wo = [(1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu];
    let lo = lambda_fast(beckmann, mu, alpha);
    let g2 = |li: f64| {
        if variant.correlated() {
            1.0 / (1.0 + lo + li)
        } else {
            1.0 / ((1.0 + lo) * (1.0 + li))
        }
    };
    let mut sums = vec![0.0; etas.len()];
    for a in 0..n {
        for b in 0..n {
            let u = [(a as f64 + 0.5) / n as f64, (b as f64 + 0.5) / n as f64];
            let h = if beckmann {
                sample_normal(alpha, u)
            } else {
                sample_visible(wo, alpha, u)
            };
            let oh = wo[0] * h[0] + wo[2] * h[2];
            if oh <= 0.0 {
                continue;
            }
            // f cos_i / pdf without F and G2 (as in `albedo`)
            let w = if beckmann { oh / (mu * h[2]) } else { 1.0 + lo };
            let wr_z = 2.0 * oh * h[2] - wo[2];
            let reflected = if wr_z > 0.0 {
                w * g2(lambda_fast(beckmann, wr_z, alpha))
            } else {
                0.0
            };
            for (sum, &eta) in sums.iter_mut().zip(etas) {
                let sin2_t = eta * eta * (1.0 - oh * oh);
                if sin2_t >= 1.0 {
                    *sum += reflected;
                    continue;
                }
                let ct = (1.0 - sin2_t).sqrt();
                let rs = (oh - eta * ct) / (oh + eta * ct);
                let rp = (eta * oh - ct) / (eta * oh + ct);
                let f = 0.5 * (rs * rs + rp * rp);
                *sum += f * reflected;
                let wt_z = -eta * wo[2] + (eta * oh - ct) * h[2];
                if wt_z < 0.0 {
                    *sum += w * (1.0 - f) * g2(lambda_fast(beckmann, wt_z, alpha));
                }
            }
        }
    }
    sums.iter().map(|s| s / (n * n) as f64).collect()
}

/// A Beckmann normal drawn by D(h) cos theta_h.
fn sample_normal(alpha: f64, u: [f64; 2]) -> [f64; 3] {
    let tan2 = -alpha * alpha * (1.0 - u[0]).ln();
    let cos_h = 1.0 / (1.0 + tan2).sqrt();
    let sin_h = (1.0 - cos_h * cos_h).max(0.0).sqrt();
    let phi = u[1] * std::f64::consts::TAU;
    [sin_h * phi.cos(), sin_h * phi.sin(), cos_h]
}

/// A visible normal of isotropic GGX seen from wo (Heitz 2018), in f64.
fn sample_visible(wo: [f64; 3], alpha: f64, u: [f64; 2]) -> [f64; 3] {
    let v = [alpha * wo[0], alpha * wo[1], wo[2]];
    let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let v = [v[0] / len, v[1] / len, v[2] / len];
    let lensq = v[0] * v[0] + v[1] * v[1];
    let t1 = if lensq > 0.0 {
        let l = lensq.sqrt();
        [-v[1] / l, v[0] / l, 0.0]
    } else {
        [1.0, 0.0, 0.0]
    };
    let t2 = [
        v[1] * t1[2] - v[2] * t1[1],
        v[2] * t1[0] - v[0] * t1[2],
        v[0] * t1[1] - v[1] * t1[0],
    ];
    let r = u[0].sqrt();
    let phi = std::f64::consts::TAU * u[1];
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + v[2]);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let p3 = (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    let n: [f64; 3] = std::array::from_fn(|i| p1 * t1[i] + p2 * t2[i] + p3 * v[i]);
    let h = [alpha * n[0], alpha * n[1], n[2].max(0.0)];
    let l = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
    [h[0] / l, h[1] / l, h[2] / l]
}

/// 2 int E(mu) mu dmu for E linear in sqrt(mu) between the columns, exactly: with s =
/// sqrt(mu), int 4 s^3 E ds.
fn average(row: &[f32]) -> f32 {
    let d = 1.0 / (SIZE - 1) as f64;
    let mut sum = 0.0;
    for j in 0..SIZE - 1 {
        let (s0, s1) = (j as f64 * d, (j + 1) as f64 * d);
        let (e0, e1) = (row[j] as f64, row[j + 1] as f64);
        // E = a + b s on the segment
        let b = (e1 - e0) / d;
        let a = e0 - b * s0;
        sum += a * (s1.powi(4) - s0.powi(4)) + 4.0 * b * (s1.powi(5) - s0.powi(5)) / 5.0;
    }
    sum as f32
}

/// Every variant's block, in [`Variant`] order (computed once).
pub fn tables() -> &'static [f32] {
    static TABLES: OnceLock<Vec<f32>> = OnceLock::new();
    TABLES.get_or_init(|| {
        let mut out = Vec::with_capacity(3 * BLOCK);
        for v in Variant::ALL {
            let rows: Vec<(Vec<f32>, Vec<f32>)> = (0..SIZE)
                .into_par_iter()
                .map(|i| {
                    let r = i as f64 / (SIZE - 1) as f64;
                    (0..SIZE)
                        .map(|j| {
                            let s = j as f64 / (SIZE - 1) as f64;
                            let mu = (s * s).max(1e-4);
                            let (e1, e5) = albedo(v, mu, r * r);
                            (e1.min(1.0) as f32, e5.min(1.0) as f32)
                        })
                        .unzip()
                })
                .collect();
            for (e1, _) in &rows {
                out.extend_from_slice(e1);
            }
            out.extend(rows.iter().map(|(e1, _)| average(e1)));
            for (_, e5) in &rows {
                out.extend_from_slice(e5);
            }
            out.extend(rows.iter().map(|(_, e5)| average(e5)));
        }
        out
    })
}

/// The tables as `tables` entries (four floats each; BLOCK is a multiple of 4).
/// The tables as `tables` entries (four floats each; BLOCK and DIELECTRIC_BLOCK are
/// multiples of 4): the reflecting variants', then each dielectric variant's, computed
/// where `dielectric` says a material reads it (zeros elsewhere, which nothing reads).
pub fn table_entries(dielectric: [bool; 4]) -> Vec<[f32; 4]> {
    let zeros = vec![0.0; DIELECTRIC_BLOCK];
    let mut all = tables().to_vec();
    for v in DielectricVariant::ALL {
        all.extend_from_slice(if dielectric[v as usize] {
            dielectric_block(v)
        } else {
            &zeros
        });
    }
    all.chunks(4).map(|c| [c[0], c[1], c[2], c[3]]).collect()
}

/// F_avg = 2 int F(mu) mu dmu of a conductor's exact Fresnel per channel, for the
/// compensation's colour (f64, 256 midpoints).
pub fn conductor_average(eta: [f32; 3], k: [f32; 3]) -> [f32; 3] {
    let n = 256;
    std::array::from_fn(|c| {
        let (e, k) = (eta[c] as f64, k[c] as f64);
        let mut sum = 0.0;
        for i in 0..n {
            let mu = (i as f64 + 0.5) / n as f64;
            sum += 2.0 * mu * fresnel_conductor(mu, e, k) / n as f64;
        }
        sum as f32
    })
}

/// The exact Fresnel reflectance of a conductor eta + i k at cosine c.
fn fresnel_conductor(c: f64, eta: f64, k: f64) -> f64 {
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let t1 = eta * eta - k * k - s2;
    let a2b2 = (t1 * t1 + 4.0 * eta * eta * k * k).max(0.0).sqrt();
    let a = (0.5 * (a2b2 + t1)).max(0.0).sqrt();
    let t2 = a2b2 + c2;
    let t3 = 2.0 * c * a;
    let r_s = (t2 - t3) / (t2 + t3);
    let t4 = a2b2 * c2 + s2 * s2;
    let t5 = t3 * s2;
    let r_p = r_s * (t4 - t5) / (t4 + t5);
    0.5 * (r_s + r_p)
}

/// F_avg = 2 int F(mu) mu dmu of the exact dielectric Fresnel of relative index eta seen
/// from outside (f64, 256 midpoints).
pub fn dielectric_average(eta: f32) -> f32 {
    let n = 256;
    let eta = eta as f64;
    let mut sum = 0.0;
    for i in 0..n {
        let c = (i as f64 + 0.5) / n as f64;
        let s2 = (1.0 - c * c) / (eta * eta);
        let f = if s2 >= 1.0 {
            1.0
        } else {
            let t = (1.0 - s2).sqrt();
            let rs = (c - eta * t) / (c + eta * t);
            let rp = (eta * c - t) / (eta * c + t);
            0.5 * (rs * rs + rp * rp)
        };
        sum += 2.0 * c * f / n as f64;
    }
    sum as f32
}

/// A dielectric variant's block (computed on first use, once per process).
pub fn dielectric_block(variant: DielectricVariant) -> &'static [f32] {
    static BLOCKS: [OnceLock<Vec<f32>>; 4] = [
        OnceLock::new(),
        OnceLock::new(),
        OnceLock::new(),
        OnceLock::new(),
    ];
    BLOCKS[variant as usize].get_or_init(|| {
        // every (ior, side)'s eta, for each (alpha, mu) at once
        let etas: Vec<f64> = (0..IORS)
            .flat_map(|k| [1.0 / table_ior(k), table_ior(k)])
            .collect();
        let cells: Vec<Vec<f64>> = (0..SIZE * SIZE)
            .into_par_iter()
            .map(|c| {
                let r = (c / SIZE) as f64 / (SIZE - 1) as f64;
                let s = (c % SIZE) as f64 / (SIZE - 1) as f64;
                dielectric_albedos(variant, (s * s).max(1e-4), r * r, &etas, 32)
            })
            .collect();
        let mut out = Vec::with_capacity(DIELECTRIC_BLOCK);
        for e in 0..etas.len() {
            let table: Vec<f32> = cells.iter().map(|c| c[e].min(1.0) as f32).collect();
            out.extend_from_slice(&table);
            out.extend(table.chunks(SIZE).map(average));
        }
        out.extend((0..IORS).map(|k| dielectric_average(table_ior(k) as f32)));
        debug_assert_eq!(out.len(), DIELECTRIC_BLOCK);
        out
    })
}
