//! Mirrors `shaders/shared/media.wgsl`: medium records, the medium after a surface, the
//! Henyey-Greenstein phase function, free flights (closed form, spectral MIS over the
//! colour channels) and the transmittance of shadow rays.

use glam::Vec3;

use super::bindings::Bindings;
use super::intersect::{intersect_scene, surface_at};
use super::materials::{alpha_u, transparent_at};
use super::sampling::{offset_ray, onb_tangents};
use super::types::{Hit, Ray, FAR, NO_HIT};
use crate::scene::records::{MAX_ALPHA_SKIPS, MEDIA_SIDE, MEDIUM_ENTRIES, NO_MEDIUM, PI};

/// A medium's record (media.wgsl's `Medium`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Medium {
    pub sigma_t: Vec3,
    /// The Henyey-Greenstein asymmetry.
    pub g: f32,
    pub albedo: Vec3,
}

/// Medium i of the tables.
pub fn medium_record(b: &Bindings, i: u32) -> Medium {
    let at = (b.params.media + i * MEDIUM_ENTRIES) as usize;
    let (a, c) = (b.tables[at], b.tables[at + 1]);
    Medium {
        sigma_t: Vec3::new(a[0], a[1], a[2]),
        g: a[3],
        albedo: Vec3::new(c[0], c[1], c[2]),
    }
}

/// The medium a ray is in once it leaves a surface whose shape holds `media` along dir:
/// the interior against the outward normal, else the exterior; `current` without media.
pub fn medium_after(media: u32, ng: Vec3, dir: Vec3, current: u32) -> u32 {
    if media == 0 {
        return current;
    }
    let side = if dir.dot(ng) < 0.0 {
        media % MEDIA_SIDE
    } else {
        media / MEDIA_SIDE
    };
    if side == 0 {
        NO_MEDIUM
    } else {
        side - 1
    }
}

/// The media word of the shape a hit is on.
pub fn media_at(b: &Bindings, hit: &Hit) -> u32 {
    let i = (b.params.material_media * 4 + hit.material) as usize;
    b.tables[i >> 2][i & 3] as u32
}

/// The Henyey-Greenstein phase function of the cosine between the direction of travel
/// and the scattered one; its own pdf.
pub fn hg_eval(cos_theta: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos_theta;
    (1.0 - g * g) / (4.0 * PI * denom * denom.sqrt())
}

/// A direction scattered from travel direction d by the Henyey-Greenstein phase function.
pub fn hg_sample(d: Vec3, g: f32, u: [f32; 2]) -> Vec3 {
    let mut cos_theta = 1.0 - 2.0 * u[0];
    if g.abs() >= 1e-3 {
        let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u[0]);
        cos_theta = (1.0 + g * g - s * s) / (2.0 * g);
    }
    let cos_theta = cos_theta.clamp(-1.0, 1.0);
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    let t = onb_tangents(d);
    (cos_theta * d + sin_theta * (phi.cos() * t[0] + phi.sin() * t[1])).normalize()
}

/// A free flight's outcome (media.wgsl's `Flight`): the distance of a scattering event
/// (negative: none before t_max) and what the throughput takes.
#[derive(Clone, Copy, Debug)]
pub struct Flight {
    pub t: f32,
    pub weight: Vec3,
}

/// A free flight through m up to t_max: the channel by u[0], the distance by u[1].
pub fn free_flight(m: &Medium, t_max: f32, u: [f32; 2]) -> Flight {
    let c = ((u[0] * 3.0) as u32).min(2) as usize;
    let sigma = m.sigma_t[c];
    let mut t = FAR;
    if sigma > 0.0 {
        t = -(1.0 - u[1]).ln() / sigma;
    }
    if t < t_max {
        let tr = (-m.sigma_t * t).exp();
        let pdf = (tr * m.sigma_t).dot(Vec3::splat(1.0 / 3.0));
        let weight = if pdf > 0.0 {
            tr * m.sigma_t * m.albedo / pdf
        } else {
            Vec3::ZERO
        };
        return Flight { t, weight };
    }
    let tr = (-m.sigma_t * t_max).exp();
    let p = tr.dot(Vec3::splat(1.0 / 3.0));
    Flight {
        t: -1.0,
        weight: if p > 0.0 { tr / p } else { Vec3::ZERO },
    }
}

/// What reaches the end of a shadow ray (unit direction, to t_max) that starts in
/// `medium`: the media's transmittance over their stretches, transparent surfaces passed
/// through (media changing where a shape holds them), 0 at an opaque one.
pub fn transmittance(b: &Bindings, ray: &Ray, t_max: f32, u: f32, medium: u32) -> Vec3 {
    let mut r = *ray;
    let mut t = t_max;
    let mut m = medium;
    let mut tr = Vec3::ONE;
    // each pass-through stops 2^-16 of the whole ray shorter: the end stands a few ulps
    // off the light's own surface, which the rounding of a pass-through (of the ray's
    // length, not the rest's) would otherwise reach on some rays and not on others
    let margin = t_max / 65536.0;
    for k in 0..MAX_ALPHA_SKIPS {
        let cand = intersect_scene(b, &r, t);
        let stretch = if cand.prim != NO_HIT { cand.t } else { t };
        if m != NO_MEDIUM {
            tr *= (-medium_record(b, m).sigma_t * stretch).exp();
        }
        if cand.prim == NO_HIT {
            return tr;
        }
        let hit = surface_at(b, &r, &cand);
        if !b.has_alpha || !transparent_at(b, &hit, alpha_u(u, k)) {
            return Vec3::ZERO;
        }
        m = medium_after(media_at(b, &hit), hit.ng, r.dir, m);
        let side = if r.dir.dot(hit.ng) > 0.0 {
            hit.ng
        } else {
            -hit.ng
        };
        let next = Ray {
            origin: offset_ray(hit.p, side, hit.err),
            dir: r.dir,
        };
        t = t - (next.origin - r.origin).dot(r.dir) - margin;
        if t <= 0.0 {
            return tr;
        }
        r = next;
    }
    Vec3::ZERO
}
