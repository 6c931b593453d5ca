//! Mirrors `shaders/shared/lights.wgsl`: the background, choosing and sampling lights, and
//! light-sampling pdfs.

use glam::{Vec2, Vec3, Vec4};

use super::bindings::Bindings;
use super::primitives::{shape_light_distance, shape_light_pdf, shape_light_sample};
use super::sampling::PI;
use super::textures::texture_value;
use super::types::{xyz, FAR};
use crate::scene::records::{
    Emitter, BACKGROUND_GRADIENT, BACKGROUND_IMAGE, LIGHT_DIRECTIONAL, LIGHT_ENVIRONMENT,
    LIGHT_PROJECTOR, LIGHT_SPOT, NO_LIGHT, NO_TEXTURE,
};

pub use crate::scene::records::EDGE_ON_COS;

/// The image background's frame: a world direction turned by minus the rotation.
pub fn env_local(b: &Bindings, d: Vec3) -> Vec3 {
    let (c, s) = (b.params.env[0], b.params.env[1]);
    Vec3::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z)
}

/// Equirectangular coordinates (u, t) of a direction; t = theta / pi from straight up.
pub fn env_coords(b: &Bindings, d: Vec3) -> Vec2 {
    let l = env_local(b, d);
    let sin_theta = (0.0f32).max((1.0 - l.y) * (1.0 + l.y)).sqrt();
    Vec2::new(
        0.5 + env_atan2(l.x, -l.z) * (0.5 / PI),
        env_atan2(sin_theta, l.y) / PI,
    )
}

/// atan2(y, x) from only correctly rounded operations, as the shader computes it (both
/// backends find the same texel of the image background): Abramowitz and Stegun's
/// polynomial 4.4.49 for atan on [0, 1] (error below 2e-8), then the octant's reflection.
// the coefficients as published and as the shader writes them (rounded to f32 alike)
#[allow(clippy::excessive_precision)]
pub fn env_atan2(y: f32, x: f32) -> f32 {
    let (ax, ay) = (x.abs(), y.abs());
    let hi = ax.max(ay);
    let r = if hi == 0.0 { 0.0 } else { ax.min(ay) / hi };
    let r2 = r * r;
    let mut a = 0.0028662257f32;
    for c in [
        -0.0161657367,
        0.0429096138,
        -0.0752896400,
        0.1065626393,
        -0.1420889944,
        0.1999355085,
        -0.3333314528,
    ] {
        a = a * r2 + c;
    }
    a = (a * r2 + 1.0) * r;
    if ay > ax {
        a = 0.5 * PI - a;
    }
    if x < 0.0 {
        a = PI - a;
    }
    if y < 0.0 {
        -a
    } else {
        a
    }
}

/// The direction of equirectangular coordinates (u, t).
pub fn env_direction(b: &Bindings, ut: Vec2) -> Vec3 {
    let theta = PI * ut.y;
    let phi = 2.0 * PI * (ut.x - 0.5);
    let st = theta.sin();
    let l = Vec3::new(st * phi.sin(), theta.cos(), -st * phi.cos());
    let (c, s) = (b.params.env[0], b.params.env[1]);
    Vec3::new(c * l.x + s * l.z, l.y, -s * l.x + c * l.z)
}

/// Radiance of a ray leaving the scene: the constant, the gradient, or the image.
pub fn background_radiance(b: &Bindings, d: Vec3) -> Vec3 {
    let p = &b.params;
    match p.background_kind {
        BACKGROUND_GRADIENT => xyz(p.background).lerp(xyz(p.background_top), 0.5 * (d.y + 1.0)),
        BACKGROUND_IMAGE => {
            let ut = env_coords(b, d);
            let st = Vec4::new(ut.x, 1.0 - ut.y, ut.x, 1.0 - ut.y);
            texture_value(b, p.env_texture, st, d) * p.env[2]
        }
        _ => xyz(p.background),
    }
}

/// Scalar i of the image background's distribution.
pub fn env_cdf_at(b: &Bindings, i: u32) -> f32 {
    b.tables[(b.params.env_cdf + (i >> 2)) as usize][(i & 3) as usize]
}

/// A point drawn from a piecewise-constant density: x, the density at x, the interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CdfSample {
    pub x: f32,
    pub pdf: f32,
    pub i: u32,
}

/// Inverts the CDF of n intervals stored from scalar `base`.
pub fn sample_cdf(b: &Bindings, base: u32, n: u32, u: f32) -> CdfSample {
    let (mut lo, mut hi) = (0u32, n);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if env_cdf_at(b, base + mid) <= u {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let c0 = env_cdf_at(b, base + lo);
    let c1 = env_cdf_at(b, base + lo + 1);
    let du = ((u - c0) / (c1 - c0)).clamp(0.0, 1.0);
    CdfSample {
        x: ((lo as f32 + du) / n as f32).min(0.999_999_94),
        pdf: (c1 - c0) * n as f32,
        i: lo,
    }
}

/// Solid-angle pdf of direction d under the image background's distribution.
pub fn env_pdf(b: &Bindings, d: Vec3) -> f32 {
    let tex = &b.textures[b.params.env_texture as usize];
    let ut = env_coords(b, d);
    let sin_theta = (1.0 - d.y * d.y).max(0.0).sqrt();
    if sin_theta <= 0.0 {
        return 0.0;
    }
    let row = ((ut.y * tex.height as f32) as u32).min(tex.height - 1);
    let col = ((ut.x * tex.width as f32) as u32).min(tex.width - 1);
    let p_row = (env_cdf_at(b, row + 1) - env_cdf_at(b, row)) * tex.height as f32;
    let base = tex.height + 1 + row * (tex.width + 1);
    let p_col = (env_cdf_at(b, base + col + 1) - env_cdf_at(b, base + col)) * tex.width as f32;
    p_row * p_col / (2.0 * PI * PI * sin_theta)
}

/// The emitter among first ..= last whose CDF interval holds u: the first with u < cdf.
pub fn search_cdf(b: &Bindings, first: u32, last: u32, u: f32) -> u32 {
    let (mut lo, mut hi) = (first, last);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if u < b.emitters[mid as usize].cdf {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    lo
}

/// The index of the light whose CDF interval holds u.
pub fn choose_light(b: &Bindings, u: f32) -> u32 {
    search_cdf(b, 0, b.params.num_emitters - 1, u)
}

/// The light without a surface whose CDF interval holds u (emitters num_emitters ..
/// num_emitters + num_punctual, whose cdf runs over them alone).
pub fn choose_punctual(b: &Bindings, u: f32) -> u32 {
    let p = &b.params;
    search_cdf(b, p.num_emitters, p.num_emitters + p.num_punctual - 1, u)
}

/// A spot's falloff at cos_theta from its axis: 1 within the inner cone, 0 beyond the
/// outer, and between them KHR_lights_punctual's ramp (the square of a linear ramp in the
/// cosine) or, where `mode` is 1 + the cones' difference in radians, Mitsuba 3's (linear
/// in the angle; lights.wgsl's `spot_falloff` says how).
pub fn spot_falloff(cos_theta: f32, cos_outer: f32, cos_inner: f32, mode: f32) -> f32 {
    let ramp = ((cos_theta - cos_outer) / (cos_inner - cos_outer).max(0.001)).clamp(0.0, 1.0);
    if mode < 1.0 {
        return ramp * ramp;
    }
    let sin_outer = (1.0 - cos_outer * cos_outer).max(0.0).sqrt();
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let to_edge = (sin_outer * cos_theta - cos_outer * sin_theta)
        .atan2(cos_outer * cos_theta + sin_outer * sin_theta);
    let linear = if cos_theta >= cos_inner {
        1.0
    } else {
        (to_edge / (mode - 1.0).max(1e-6)).clamp(0.0, 1.0)
    };
    if cos_theta > cos_outer {
        linear
    } else {
        0.0
    }
}

/// A light without a surface seen from a point (lights.wgsl's `PunctualSample`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PunctualSample {
    pub light: u32,
    /// Unit direction toward it.
    pub dir: Vec3,
    /// Intensity x a spot's falloff / d^2, or a directional light's irradiance.
    pub le: Vec3,
    /// Squared distance to it (1 for a directional light).
    pub d2: f32,
    /// The probability it was chosen with.
    pub prob: f32,
    /// Where it is, when it is somewhere (a directional light is not).
    pub position: Vec3,
    pub positioned: bool,
}

/// A textured spot's colour toward w (lights.wgsl's `spot_texture`): its texture at
/// uv = (1 + (w . r, w . u) / (w . f)) / 2 for the axis f, the up vector over the tangent
/// of the outer angle u (the record's `d`) and r = f x u.
pub fn spot_texture(b: &Bindings, e: &Emitter, w: Vec3, p: Vec3) -> Vec3 {
    let f = xyz(e.c);
    let u = xyz(e.d);
    let uv = 0.5 + 0.5 * Vec2::new(w.dot(f.cross(u)), w.dot(u)) / w.dot(f);
    texture_value(b, e.texture, Vec4::new(uv.x, uv.y, uv.x, uv.y), p)
}

/// A projector's intensity toward w over its colour: pi x its texture at the frustum's uv
/// over cos^3 of the angle from its axis, 0 outside (lights.wgsl's `projector_falloff`).
pub fn projector_falloff(b: &Bindings, e: &Emitter, w: Vec3, p: Vec3) -> Vec3 {
    let r = Vec3::new(e.a[3], e.b[3], e.c[3]);
    let u = xyz(e.c);
    let z = w.dot(u.cross(r).normalize());
    let st = Vec2::new(w.dot(r), w.dot(u)) / z;
    // written as in WGSL, so a NaN takes the same branch on both backends
    if !(z > 0.0 && st.x.abs() <= 1.0 && st.y.abs() <= 1.0) {
        return Vec3::ZERO;
    }
    let mut irradiance = Vec3::ONE;
    if e.texture != NO_TEXTURE {
        let uv = 0.5 + 0.5 * st;
        irradiance = texture_value(b, e.texture, Vec4::new(uv.x, uv.y, uv.x, uv.y), p);
    }
    let c = z / w.length();
    irradiance * (PI / (c * c * c))
}

/// The light without a surface chosen by u (in proportion to its power), seen from p.
pub fn sample_punctual(b: &Bindings, p: Vec3, u: f32) -> PunctualSample {
    let light = choose_punctual(b, u);
    let e = &b.emitters[light as usize];
    let positioned = e.kind != LIGHT_DIRECTIONAL;
    let mut dir = xyz(e.a);
    let mut le = xyz(e.b);
    let mut d2 = 1.0;
    if positioned {
        let v = xyz(e.a) - p;
        d2 = v.dot(v);
        dir = v / d2.sqrt();
        let mut falloff = 1.0;
        if e.kind == LIGHT_SPOT {
            falloff = spot_falloff(-dir.dot(xyz(e.c)), e.a[3], e.b[3], e.c[3]);
            if e.texture != NO_TEXTURE && falloff > 0.0 {
                le *= spot_texture(b, e, -v, p);
            }
        }
        if e.kind == LIGHT_PROJECTOR {
            le *= projector_falloff(b, e, -v, p);
        }
        le *= falloff / d2;
    }
    PunctualSample {
        light,
        dir,
        le,
        d2,
        prob: e.prob,
        position: xyz(e.a),
        positioned,
    }
}

/// A direction toward a light from a reference point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightSample {
    /// The light, `NO_LIGHT` when there is no sample.
    pub light: u32,
    pub dir: Vec3,
    /// Distance to the sampled point (FAR for the environment).
    pub dist: f32,
    /// Solid-angle pdf, the choice of the light included.
    pub pdf: f32,
    /// The candidate's (u, v) on the light.
    pub uv: Vec2,
}

/// Solid-angle pdf that light i is sampled toward x (direction d from p), choice included.
pub fn light_pdf(b: &Bindings, i: u32, p: Vec3, x: Vec3, d: Vec3) -> f32 {
    let e = &b.emitters[i as usize];
    if e.kind == LIGHT_ENVIRONMENT {
        return e.prob * env_pdf(b, d);
    }
    let pdf = shape_light_pdf(e, p, x);
    e.prob * pdf
}

/// Samples a direction toward a light from p: the light by u_light, the point by u.
pub fn sample_light(b: &Bindings, p: Vec3, u_light: f32, u: [f32; 2]) -> LightSample {
    let mut ls = LightSample {
        light: NO_LIGHT,
        dir: Vec3::Z,
        dist: FAR,
        pdf: 0.0,
        uv: Vec2::ZERO,
    };
    if b.params.num_emitters == 0 {
        return ls;
    }
    let i = choose_light(b, u_light);
    let e = &b.emitters[i as usize];
    if e.kind == LIGHT_ENVIRONMENT {
        let tex = &b.textures[b.params.env_texture as usize];
        let row = sample_cdf(b, 0, tex.height, u[1]);
        let col = sample_cdf(b, tex.height + 1 + row.i * (tex.width + 1), tex.width, u[0]);
        let sin_theta = (PI * row.x).sin();
        if sin_theta > 0.0 {
            ls.dir = env_direction(b, Vec2::new(col.x, row.x));
            ls.pdf = e.prob * row.pdf * col.pdf / (2.0 * PI * PI * sin_theta);
            ls.light = if ls.pdf > 0.0 { i } else { NO_LIGHT };
        }
        return ls;
    }
    let lp = shape_light_sample(e, p, u);
    let (x, pdf) = (lp.x, lp.pdf);
    ls.uv = lp.uv;
    let v = x - p;
    let dist = v.length();
    if pdf > 0.0 && dist > 0.0 {
        ls.light = i;
        ls.dir = v / dist;
        ls.dist = dist;
        ls.pdf = e.prob * pdf;
    }
    ls
}

/// Solid-angle pdf of direction d from p under light sampling as a whole (every light's
/// surface along the ray, whatever lies in between).
pub fn light_pdf_total(b: &Bindings, p: Vec3, d: Vec3) -> f32 {
    let mut total = 0.0;
    for i in 0..b.params.num_emitters {
        let e = &b.emitters[i as usize];
        // the image background is along every ray, at no distance
        let t = if e.kind == LIGHT_ENVIRONMENT {
            0.0
        } else {
            shape_light_distance(e, p, d)
        };
        if t < FAR {
            total += light_pdf(b, i, p, p + t * d, d);
        }
    }
    total
}

/// The power heuristic (beta = 2) weight of pdf a against pdf b, by ratios.
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(a > 0.0) {
        return 0.0;
    }
    if a >= b {
        let r = b / a;
        return 1.0 / (1.0 + r * r);
    }
    let r = a / b;
    r * r / (1.0 + r * r)
}
