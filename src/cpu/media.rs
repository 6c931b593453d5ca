//! Mirrors `shaders/shared/media.wgsl`: medium records, the medium after a surface, the
//! Henyey-Greenstein phase function, free flights (closed form, spectral MIS over the
//! colour channels; delta tracking through a density grid) and the transmittance of
//! shadow rays (ratio tracking through a grid).

use glam::Vec3;

use super::bindings::Bindings;
use super::intersect::{intersect_scene, surface_at};
use super::materials::{alpha_u, transparent_at};
use super::rng::{pcg4d, u32_to_unit_float};
use super::sampling::{offset_ray, onb_tangents};
use super::types::{Hit, Ray, FAR, NO_HIT};
use crate::scene::records::{
    MAJORANT_CELL, MAX_ALPHA_SKIPS, MAX_TRACKING_STEPS, MEDIA_SIDE, MEDIUM_ENTRIES, NO_MEDIUM, PI,
};

/// A medium's record (media.wgsl's `Medium`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Medium {
    pub sigma_t: Vec3,
    /// The Henyey-Greenstein asymmetry.
    pub g: f32,
    pub albedo: Vec3,
    /// The tables entry of its density grid's header, 0: homogeneous.
    pub grid: u32,
}

/// Medium i of the tables.
pub fn medium_record(b: &Bindings, i: u32) -> Medium {
    let at = (b.params.media + i * MEDIUM_ENTRIES) as usize;
    let (a, c) = (b.tables[at], b.tables[at + 1]);
    Medium {
        sigma_t: Vec3::new(a[0], a[1], a[2]),
        g: a[3],
        albedo: Vec3::new(c[0], c[1], c[2]),
        grid: c[3].to_bits(),
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
    if m.albedo == Vec3::ZERO {
        // nothing scatters: the transmittance itself (a glass's absorption)
        return Flight {
            t: -1.0,
            weight: (-m.sigma_t * t_max).exp(),
        };
    }
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

/// A density grid's header (media.wgsl's `Grid`).
#[derive(Clone, Copy, Debug)]
pub struct Grid {
    pub to_unit: [[f32; 4]; 3],
    pub res: [u32; 3],
    pub data: u32,
    pub cells: [u32; 3],
    pub majorants: u32,
    /// Values per voxel: 1, or 3 for a density per colour channel.
    pub channels: u32,
    pub albedo: u32,
}

/// The grid whose header is at tables entry h.
pub fn grid_record(b: &Bindings, h: u32) -> Grid {
    let h = h as usize;
    let (r, c) = (b.tables[h + 3], b.tables[h + 4]);
    Grid {
        to_unit: [b.tables[h], b.tables[h + 1], b.tables[h + 2]],
        res: [r[0].to_bits(), r[1].to_bits(), r[2].to_bits()],
        data: r[3].to_bits(),
        cells: [c[0].to_bits(), c[1].to_bits(), c[2].to_bits()],
        majorants: c[3].to_bits(),
        channels: b.tables[h + 5][0].to_bits(),
        albedo: b.tables[h + 5][3].to_bits(),
    }
}

fn table_float(b: &Bindings, i: u32) -> f32 {
    b.tables[(i >> 2) as usize][(i & 3) as usize]
}

/// Channel c of the grid's values (`channels` a voxel) at p in its unit cube: trilinear
/// between voxel centres, clamped.
pub fn grid_value(b: &Bindings, g: &Grid, p: Vec3, channels: u32, c: u32) -> f32 {
    let res = Vec3::new(g.res[0] as f32, g.res[1] as f32, g.res[2] as f32);
    let x = p * res - 0.5;
    let f = x.floor();
    let w = x - f;
    let fi = [f.x as i32, f.y as i32, f.z as i32];
    let top = g.res.map(|r| r as i32 - 1);
    let i0: [u32; 3] = std::array::from_fn(|a| fi[a].clamp(0, top[a]) as u32);
    let i1: [u32; 3] = std::array::from_fn(|a| (fi[a] + 1).clamp(0, top[a]) as u32);
    let (row, slice) = (g.res[0], g.res[0] * g.res[1]);
    let mut d = 0.0;
    for k in 0..8u32 {
        let hi = [k & 1 != 0, k & 2 != 0, k & 4 != 0];
        let v: [u32; 3] = std::array::from_fn(|a| if hi[a] { i1[a] } else { i0[a] });
        let wk: [f32; 3] = std::array::from_fn(|a| if hi[a] { w[a] } else { 1.0 - w[a] });
        let i = (v[0] + v[1] * row + v[2] * slice) * channels + c;
        d += wk[0] * wk[1] * wk[2] * table_float(b, g.data + i);
    }
    d
}

/// The density grid's density at p in its unit cube, per colour channel.
pub fn grid_density(b: &Bindings, g: &Grid, p: Vec3) -> Vec3 {
    if g.channels == 3 {
        return Vec3::new(
            grid_value(b, g, p, 3, 0),
            grid_value(b, g, p, 3, 1),
            grid_value(b, g, p, 3, 2),
        );
    }
    Vec3::splat(grid_value(b, g, p, 1, 0))
}

/// The single-scattering albedo of heterogeneous medium m at p: its albedo grid's there,
/// else its own.
pub fn grid_albedo(b: &Bindings, m: &Medium, g: &Grid, p: Vec3) -> Vec3 {
    if g.albedo == 0 {
        return m.albedo;
    }
    let a = grid_record(b, g.albedo);
    let q = grid_point(&a, p);
    Vec3::new(
        grid_value(b, &a, q, 3, 0),
        grid_value(b, &a, q, 3, 1),
        grid_value(b, &a, q, 3, 2),
    )
}

/// The single-scattering albedo of medium m at p.
pub fn medium_albedo(b: &Bindings, m: &Medium, p: Vec3) -> Vec3 {
    if m.grid != 0 {
        return grid_albedo(b, m, &grid_record(b, m.grid), p);
    }
    m.albedo
}

fn grid_point(g: &Grid, p: Vec3) -> Vec3 {
    let r = |i: usize| Vec3::new(g.to_unit[i][0], g.to_unit[i][1], g.to_unit[i][2]);
    Vec3::new(
        r(0).dot(p) + g.to_unit[0][3],
        r(1).dot(p) + g.to_unit[1][3],
        r(2).dot(p) + g.to_unit[2][3],
    )
}

fn grid_vector(g: &Grid, v: Vec3) -> Vec3 {
    let r = |i: usize| Vec3::new(g.to_unit[i][0], g.to_unit[i][1], g.to_unit[i][2]);
    Vec3::new(r(0).dot(v), r(1).dot(v), r(2).dot(v))
}

/// The next uniform number of a tracking's own stream (PCG).
pub fn tracking_rand(state: &mut u32) -> f32 {
    *state = state.wrapping_mul(747796405).wrapping_add(2891336453);
    let s = *state;
    let word = ((s >> ((s >> 28) + 4)) ^ s).wrapping_mul(277803737);
    u32_to_unit_float((word >> 22) ^ word)
}

/// Delta tracking (scatters) or ratio tracking through heterogeneous medium m along a
/// unit ray from 0 to t_max, against the majorants of the cells it steps through.
pub fn track(b: &Bindings, m: &Medium, ray: &Ray, t_max: f32, seed: u32, scatters: bool) -> Flight {
    let g = grid_record(b, m.grid);
    let k = Vec3::new(g.res[0] as f32, g.res[1] as f32, g.res[2] as f32) / MAJORANT_CELL as f32;
    let o = grid_point(&g, ray.origin) * k;
    let d = grid_vector(&g, ray.dir) * k;
    let inv = Vec3::ONE / d;
    let a = (Vec3::ZERO - o) * inv;
    let bb = (k - o) * inv;
    let flat = d.cmpeq(Vec3::ZERO);
    let lo = Vec3::select(flat, Vec3::splat(-FAR), a.min(bb));
    let hi = Vec3::select(flat, Vec3::splat(FAR), a.max(bb));
    let mut t = lo.x.max(lo.y).max(lo.z.max(0.0));
    let t_end = hi.x.min(hi.y).min(hi.z.min(t_max));
    let mut weight = Vec3::ONE;
    let misses = (0..3).any(|i| d[i] == 0.0 && (o[i] < 0.0 || o[i] > k[i]));
    // (t_end may be NaN for a degenerate ray: that misses too)
    if t.partial_cmp(&t_end) != Some(std::cmp::Ordering::Less) || misses {
        return Flight { t: -1.0, weight };
    }
    let top = g.cells.map(|c| c as i32 - 1);
    let p0 = (o + t * d).floor();
    let mut cell: [i32; 3] = std::array::from_fn(|i| (p0[i] as i32).clamp(0, top[i]));
    let step: [i32; 3] = std::array::from_fn(|i| if d[i] >= 0.0 { 1 } else { -1 });
    let mut t_next = Vec3::ZERO;
    let mut dt = Vec3::ZERO;
    for i in 0..3 {
        let edge = (cell[i] + i32::from(d[i] >= 0.0)) as f32;
        t_next[i] = if flat.test(i) {
            FAR
        } else {
            (edge - o[i]) * inv[i]
        };
        dt[i] = if flat.test(i) { FAR } else { inv[i].abs() };
    }
    let sigma_max = m.sigma_t.max_element();
    let mut state = seed;
    let mut tau = -(1.0 - tracking_rand(&mut state)).ln();
    for _ in 0..MAX_TRACKING_STEPS {
        let c = cell.map(|x| x as u32);
        let mu = sigma_max
            * table_float(
                b,
                g.majorants + c[0] + c[1] * g.cells[0] + c[2] * g.cells[0] * g.cells[1],
            );
        let t_exit = t_next.x.min(t_next.y).min(t_next.z).min(t_end);
        let depth = mu * (t_exit - t);
        if tau >= depth {
            tau -= depth;
            t = t_exit;
            if t >= t_end {
                return Flight { t: -1.0, weight };
            }
            let axis = if t_next.x <= t_next.y && t_next.x <= t_next.z {
                0
            } else if t_next.y <= t_next.z {
                1
            } else {
                2
            };
            cell[axis] += step[axis];
            t_next[axis] += dt[axis];
            if (0..3).any(|i| cell[i] < 0 || cell[i] > top[i]) {
                return Flight { t: -1.0, weight };
            }
            continue;
        }
        t += tau / mu;
        tau = -(1.0 - tracking_rand(&mut state)).ln();
        let x = ray.origin + t * ray.dir;
        let sigma_t = grid_density(b, &g, grid_point(&g, x)) * m.sigma_t;
        if scatters {
            let sigma_s = sigma_t * grid_albedo(b, m, &g, x);
            let mean_s = sigma_s.dot(Vec3::splat(1.0 / 3.0));
            if tracking_rand(&mut state) * mu < mean_s {
                return Flight {
                    t,
                    weight: weight * sigma_s / mean_s,
                };
            }
            weight = if mu > mean_s {
                weight * (Vec3::splat(mu) - sigma_t).max(Vec3::ZERO) / (mu - mean_s)
            } else {
                Vec3::ZERO
            };
        } else {
            weight *= (Vec3::splat(mu) - sigma_t).max(Vec3::ZERO) / mu;
        }
        if weight == Vec3::ZERO {
            return Flight { t: -1.0, weight };
        }
    }
    Flight {
        t: -1.0,
        weight: Vec3::ZERO,
    }
}

/// The seed of a tracking's stream from two uniform numbers and a counter.
pub fn tracking_seed(u: [f32; 2], k: u32) -> u32 {
    pcg4d([u[0].to_bits(), u[1].to_bits(), k, 0x6d65_6469])[0]
}

/// A free flight through m along `ray` up to t_max, drawn from u (in a grid, from the
/// stream it seeds).
pub fn medium_flight(
    b: &Bindings,
    m: &Medium,
    ray: &Ray,
    t_max: f32,
    u: [f32; 2],
    k: u32,
) -> Flight {
    if m.grid != 0 {
        return track(b, m, ray, t_max, tracking_seed(u, k), true);
    }
    free_flight(m, t_max, u)
}

/// The transmittance of m along `ray` from 0 to t (ratio tracking in a grid, its stream
/// seeded by the shadow ray's own sample us and the stretch k).
pub fn medium_transmittance(
    b: &Bindings,
    m: &Medium,
    ray: &Ray,
    t: f32,
    us: [f32; 2],
    k: u32,
) -> Vec3 {
    if m.grid != 0 {
        return track(b, m, ray, t, tracking_seed(us, k), false).weight;
    }
    (-m.sigma_t * t).exp()
}

/// What reaches the end of a shadow ray (unit direction, to t_max) that starts in
/// `medium`: the media's transmittance over their stretches, transparent surfaces passed
/// through (media changing where a shape holds them), 0 at an opaque one; us, the sample
/// of the light the ray goes to, seeds ratio tracking through grids.
pub fn transmittance(
    b: &Bindings,
    ray: &Ray,
    t_max: f32,
    u: f32,
    medium: u32,
    us: [f32; 2],
) -> Vec3 {
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
            tr *= medium_transmittance(b, &medium_record(b, m), &r, stretch, us, k);
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
