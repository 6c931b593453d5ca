//! Spectra to RGB as Mitsuba 3's RGB variants turn them into colours when they load a scene
//! file, and the named indices of refraction its dielectrics accept.

use super::cie::{CIE_MAX, CIE_MIN, CIE_XYZ_D65, XYZ_TO_SRGB, Y_NORMALIZATION};
use super::parse::Spectrum;

/// Where a spectrum is used decides how Mitsuba's RGB mode converts it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Use {
    /// A reflectance or transmittance: weighted by D65, clamped to [0, 1].
    Reflectance,
    /// A value that may exceed 1 (an index of refraction, a scale): weighted by D65,
    /// clamped at 0 only.
    Unbounded,
    /// An emitter's radiance or intensity: not weighted by D65, clamped at 0 only; a
    /// constant becomes that constant times the sRGB colour of a flat spectrum (what the
    /// spectral variants would show).
    Emission,
}

/// The RGB colour of a spectrum.
pub fn to_rgb(s: &Spectrum, use_: Use) -> [f64; 3] {
    match s {
        Spectrum::Uniform(v) if use_ == Use::Emission => {
            let white = xyz_to_srgb([1.0; 3]);
            white.map(|c| c * v)
        }
        Spectrum::Uniform(v) => [*v; 3],
        Spectrum::Samples(pairs) => samples_to_rgb(pairs, use_),
    }
}

fn xyz_to_srgb(xyz: [f64; 3]) -> [f64; 3] {
    XYZ_TO_SRGB.map(|row| row[0] * xyz[0] + row[1] * xyz[1] + row[2] * xyz[2])
}

/// The CIE table (x, y, z, D65) at a wavelength, linear between its 5 nm samples.
fn cie_at(w: f64) -> [f64; 4] {
    let t = (w - CIE_MIN) / 5.0;
    let i = (t.max(0.0) as usize).min(CIE_XYZ_D65.len() - 2);
    let f = t - i as f64;
    let (a, b) = (CIE_XYZ_D65[i], CIE_XYZ_D65[i + 1]);
    [0, 1, 2, 3].map(|k| a[k] * (1.0 - f) + b[k] * f)
}

/// Mitsuba's integral: 1000 wavelengths evenly over the CIE range, the spectrum linear
/// between its samples and zero outside them.
fn samples_to_rgb(pairs: &[(f64, f64)], use_: Use) -> [f64; 3] {
    const STEPS: usize = 1000;
    let d65 = use_ != Use::Emission;
    let mut xyz = [0.0; 3];
    let (first, last) = (pairs[0].0, pairs[pairs.len() - 1].0);
    if pairs.len() >= 2 {
        for i in 0..STEPS {
            let w = CIE_MIN + (i as f64 / (STEPS - 1) as f64) * (CIE_MAX - CIE_MIN);
            if w < first || w > last {
                continue;
            }
            let k = pairs[..pairs.len() - 1]
                .iter()
                .rposition(|p| p.0 <= w)
                .unwrap_or(0);
            let ((w0, v0), (w1, v1)) = (pairs[k], pairs[k + 1]);
            let v = ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1);
            let c = cie_at(w);
            let weight = v * if d65 { c[3] } else { 1.0 };
            for (x, ck) in xyz.iter_mut().zip(c) {
                *x += ck * weight;
            }
        }
    }
    let scale = (CIE_MAX - CIE_MIN) / STEPS as f64 * Y_NORMALIZATION;
    let rgb = xyz_to_srgb(xyz.map(|x| x * scale));
    match use_ {
        Use::Reflectance => rgb.map(|c| c.clamp(0.0, 1.0)),
        Use::Unbounded | Use::Emission => rgb.map(|c| c.max(0.0)),
    }
}

/// The indices of refraction Mitsuba 3 accepts by name (its dielectrics' `int_ior` and
/// `ext_ior`), at 589 nm.
pub const NAMED_IORS: &[(&str, f64)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// A named index of refraction (any case).
pub fn named_ior(name: &str) -> Option<f64> {
    let name = name.to_ascii_lowercase();
    NAMED_IORS.iter().find(|(n, _)| *n == name).map(|(_, v)| *v)
}
