//! The light list: every emissive primitive that can be sampled, and an image background,
//! with selection probabilities proportional to power; and the image background's 2D
//! sampling distribution. The shader side is `shaders/shared/lights.wgsl`.

use glam::{Mat3, Vec3};

use super::format::{LightDesc, SpotFalloff};
use super::materials::common::ColorDesc;
use super::materials::common::Surface;
use super::primitives;
use super::records::{
    self, Emitter, Material, Primitive, LIGHT_DIRECTIONAL, LIGHT_ENVIRONMENT, LIGHT_POINT,
    LIGHT_PROJECTOR, LIGHT_SPOT, NO_HIT, NO_LIGHT, NO_TEXTURE, PRIM_LIGHT_SHIFT,
};
use super::shapes::primitive_area;
use super::textures::ImageData;

/// Luminance of a linear RGB colour (Rec. 709 weights).
pub fn luminance(c: [f32; 4]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// The sampling distribution of an equirectangular image (at `strength`), as scalars:
/// the marginal CDF over rows (height + 1 values, row 0 at the top = +y), then one
/// conditional CDF per row (width + 1 values each). The density of texel (x, y) is
/// proportional to the mean over the texel of the bilinear look-up's luminance (weights
/// 1/8, 3/4, 1/8 per axis over it and its eight neighbours: the look-up's support, so every
/// direction with radiance can be sampled) times sin(theta) at the row's centre. (The
/// largest luminance of the nine would spread a small sun's samples over nine texels:
/// twice Mitsuba's noise per sample on the bench's heightfield.) Also returns the
/// integral of luminance over the sphere, sum L sin(theta) dphi dtheta.
pub fn env_distribution(image: &ImageData, strength: f32) -> (Vec<f32>, f64) {
    let (w, h) = (image.width as usize, image.height as usize);
    let luminances: Vec<f64> = (0..w * h)
        .map(|i| f64::from(luminance(image.texel(i))))
        .collect();
    let lum = |x: usize, y: usize| luminances[y * w + x];
    let (dphi, dtheta) = (
        2.0 * std::f64::consts::PI / w as f64,
        std::f64::consts::PI / h as f64,
    );
    let mut integral = 0.0;
    let mut rows = Vec::with_capacity(h);
    let mut row_sums = Vec::with_capacity(h);
    for y in 0..h {
        let sin_theta = ((y as f64 + 0.5) * dtheta).sin();
        let f: Vec<f64> = (0..w)
            .map(|x| {
                let mut m = 0.0f64;
                for (dy, wy) in [(-1i64, 0.125), (0, 0.75), (1, 0.125)] {
                    let yy = (y as i64 + dy).clamp(0, h as i64 - 1) as usize;
                    for (dx, wx) in [(-1i64, 0.125), (0, 0.75), (1, 0.125)] {
                        let xx = (x as i64 + dx).rem_euclid(w as i64) as usize;
                        m += wx * wy * lum(xx, yy);
                    }
                }
                integral += lum(x, y) * sin_theta * dphi * dtheta;
                m * sin_theta
            })
            .collect();
        row_sums.push(f.iter().sum::<f64>());
        rows.push(cdf(&f));
    }
    let mut scalars = cdf(&row_sums);
    for r in rows {
        scalars.extend(r);
    }
    (scalars, integral * f64::from(strength))
}

/// The records of the lights without a surface (`[[lights]]`, validated), each chosen
/// among them in proportion to the power it sends into the scene's bounding sphere
/// (`bounds`: centre, radius), in luminance: pi r^2 E for a directional light, and I
/// times a solid angle for a point light or a spot, the smaller of the one it lights
/// (4 pi; a spot's cone to the middle of its falloff, 2 pi (1 - (cos inner + cos outer) /
/// 2)) and the one the sphere subtends from it (4 pi from inside). Power alone (4 pi I,
/// as pbrt-v4's power light sampler has it) would all but never choose a directional
/// light over a point light in a small scene. A projector's is pi E times the area of its
/// frustum at distance 1 (the power it sends), for its colour E (a texture counted as 1).
/// `texture` gives a texture's index and aspect (width / height; 1 but for images).
pub fn punctual_lights<'a>(
    lights: impl IntoIterator<Item = &'a LightDesc>,
    bounds: (Vec3, f32),
    texture: &dyn Fn(&str) -> (u32, f32),
) -> Vec<Emitter> {
    use std::f32::consts::PI;
    let (center, radius) = bounds;
    let lum = |c: [f32; 3]| luminance([c[0], c[1], c[2], 0.0]);
    // the solid angle the scene's bounding sphere subtends from p
    let seen = |p: Vec3| {
        let s2 = radius * radius / (p - center).length_squared();
        if s2 >= 1.0 {
            4.0 * PI
        } else {
            2.0 * PI * s2 / (1.0 + (1.0 - s2).sqrt())
        }
    };
    let mut out: Vec<Emitter> = lights
        .into_iter()
        .map(|l| match l {
            LightDesc::Point {
                position,
                intensity,
            } => Emitter {
                primitive: NO_HIT,
                kind: LIGHT_POINT,
                a: Vec3::from(*position).extend(0.0).to_array(),
                b: Vec3::from(*intensity).extend(0.0).to_array(),
                power: (4.0 * PI).min(seen(Vec3::from(*position))) * lum(*intensity),
                ..Default::default()
            },
            LightDesc::Spot {
                position,
                direction,
                look_at,
                intensity,
                inner_angle,
                outer_angle,
                falloff,
                texture: image,
                up,
            } => {
                let p = Vec3::from(*position);
                let axis = match (direction, look_at) {
                    (Some(d), _) => Vec3::from(*d),
                    (None, Some(t)) => Vec3::from(*t) - p,
                    (None, None) => Vec3::NEG_Y,
                }
                .normalize();
                let (cos_in, cos_out) = (
                    inner_angle.to_radians().cos(),
                    outer_angle.to_radians().cos(),
                );
                Emitter {
                    primitive: NO_HIT,
                    kind: LIGHT_SPOT,
                    a: p.extend(cos_out).to_array(),
                    b: Vec3::from(*intensity).extend(cos_in).to_array(),
                    // c.w: for Mitsuba's ramp, linear in the angle, 1 + the cones'
                    // difference in radians; 0 for glTF's
                    c: axis
                        .extend(if *falloff == SpotFalloff::Mitsuba {
                            1.0 + (outer_angle - inner_angle).to_radians()
                        } else {
                            0.0
                        })
                        .to_array(),
                    power: (2.0 * PI * (1.0 - 0.5 * (cos_in + cos_out))).min(seen(p))
                        * lum(*intensity),
                    // a texture's up, square to the axis, over the outer angle's tangent:
                    // the outer cone's square spans the image
                    texture: image.as_deref().map_or(NO_TEXTURE, |t| texture(t).0),
                    d: if image.is_some() {
                        let up = Vec3::from(*up);
                        let up = (up - axis * up.dot(axis)).normalize();
                        (up / outer_angle.to_radians().tan()).extend(0.0).to_array()
                    } else {
                        [0.0; 4]
                    },
                    ..Default::default()
                }
            }
            LightDesc::Directional {
                direction,
                irradiance,
            } => Emitter {
                primitive: NO_HIT,
                kind: LIGHT_DIRECTIONAL,
                a: (-Vec3::from(*direction).normalize()).extend(0.0).to_array(),
                b: Vec3::from(*irradiance).extend(0.0).to_array(),
                power: PI * radius * radius * lum(*irradiance),
                ..Default::default()
            },
            LightDesc::Projector {
                position,
                look_at,
                up,
                fov,
                irradiance,
                scale,
            } => {
                let (color, index, aspect) = match irradiance {
                    ColorDesc::Rgb(c) => (*c, NO_TEXTURE, 1.0),
                    ColorDesc::Texture(name) => {
                        let (index, aspect) = texture(name);
                        ([1.0; 3], index, aspect)
                    }
                };
                let p = Vec3::from(*position);
                let forward = (Vec3::from(*look_at) - p).normalize();
                let right = forward.cross(Vec3::from(*up)).normalize();
                let up = right.cross(forward);
                let tan_x = (fov.to_radians() / 2.0).tan();
                let tan_y = tan_x / aspect;
                let (r, u) = (right / tan_x, up / tan_y);
                let color = Vec3::from(color) * *scale;
                Emitter {
                    primitive: NO_HIT,
                    kind: LIGHT_PROJECTOR,
                    a: p.extend(r.x).to_array(),
                    b: color.extend(r.y).to_array(),
                    c: u.extend(r.z).to_array(),
                    texture: index,
                    power: PI * (4.0 * tan_x * tan_y).min(seen(p)) * lum(color.to_array()),
                    ..Default::default()
                }
            }
        })
        .collect();
    let powers: Vec<f64> = out.iter().map(|e| f64::from(e.power.max(0.0))).collect();
    let c = cdf(&powers);
    for (i, e) in out.iter_mut().enumerate() {
        e.cdf = c[i + 1];
        e.prob = c[i + 1] - c[i];
    }
    out
}

/// Running sums of `f` normalised to end at exactly 1 (n + 1 values from 0); uniform when
/// `f` sums to 0.
fn cdf(f: &[f64]) -> Vec<f32> {
    let total: f64 = f.iter().sum();
    let n = f.len();
    let mut out = Vec::with_capacity(n + 1);
    let mut acc = 0.0;
    out.push(0.0);
    for (i, v) in f.iter().enumerate() {
        acc += v;
        let c = if total > 0.0 {
            acc / total
        } else {
            (i + 1) as f64 / n as f64
        };
        out.push(c as f32);
    }
    out[n] = 1.0;
    out
}

/// The rows of a primitive's object-to-world transform as (linear part, translation), when
/// it is a similarity (rotation, uniform scale, translation), with the scale.
fn similarity(p: &Primitive, shape_data: &[[f32; 4]]) -> Option<(Mat3, Vec3, f32)> {
    if p.flags & records::PRIM_FLAG_TRANSFORM == 0 {
        return Some((Mat3::IDENTITY, Vec3::ZERO, 1.0));
    }
    let rows = &shape_data[p.data as usize + 3..][..3];
    let m = Mat3::from_cols(
        Vec3::from_slice(&rows[0]),
        Vec3::from_slice(&rows[1]),
        Vec3::from_slice(&rows[2]),
    )
    .transpose();
    let t = Vec3::new(rows[0][3], rows[1][3], rows[2][3]);
    let g = m.transpose() * m;
    let s2 = g.x_axis.x;
    let off = (g - Mat3::from_diagonal(Vec3::splat(s2))).to_cols_array();
    let similar = s2 > 0.0 && off.iter().all(|x| x.abs() <= 1e-5 * s2);
    similar.then(|| (m, t, s2.sqrt()))
}

/// A primitive's light record with world-space geometry (its type's, `kind` = its tag),
/// or None when it cannot be sampled (planes, boxes, cylinders, and any shape under a
/// transform that is no similarity: they still emit, and paths find them by hitting
/// them).
fn emitter_geometry(p: &Primitive, shape_data: &[[f32; 4]]) -> Option<Emitter> {
    let (m, t, s) = similarity(p, shape_data)?;
    let world = primitives::light_geometry(p, m, t, s)?;
    Some(Emitter {
        kind: p.tag,
        a: world.a,
        b: world.b,
        c: world.c,
        ..Default::default()
    })
}

/// The light list, with each listed primitive's flags carrying its light index. Every
/// bounded primitive whose material emits and whose shape can be sampled is a light, and
/// so is an image background (`env`, with the scene's bounding radius for its power);
/// its index in the list is returned too. Probabilities are proportional to power:
/// pi x area x luminance of the emission (a texture counts as white) per emitting side,
/// and pi r^2 x the integral of the background's luminance over the sphere.
pub fn light_list(
    primitives: &mut [Primitive],
    num_unbounded: usize,
    materials: &[Material],
    shape_data: &[[f32; 4]],
    env: Option<(f64, f32)>,
) -> (Vec<Emitter>, u32) {
    let mut lights = Vec::new();
    for (i, p) in primitives.iter_mut().enumerate().skip(num_unbounded) {
        if p.tag == records::PRIM_INSTANCE {
            continue;
        }
        let mat = &materials[p.material as usize];
        let sides = if mat.flags & records::MAT_FLAG_TWO_SIDED != 0 {
            2.0
        } else {
            1.0
        };
        let emission = Surface::read(mat);
        let radiance = if emission.emission_texture != records::NO_TEXTURE {
            1.0
        } else {
            luminance(emission.emission.extend(0.0).to_array())
        };
        if radiance.is_nan() || radiance <= 0.0 {
            continue;
        }
        let area = primitive_area(p, shape_data);
        let Some(e) = emitter_geometry(p, shape_data) else {
            continue;
        };
        if !(area > 0.0 && area.is_finite()) || lights.len() as u32 >= records::MAX_LIGHTS {
            continue;
        }
        let power = radiance * area * std::f32::consts::PI * sides;
        p.flags |= (lights.len() as u32 + 1) << PRIM_LIGHT_SHIFT;
        lights.push(Emitter {
            primitive: i as u32,
            area,
            power,
            ..e
        });
    }
    let mut env_light = NO_LIGHT;
    if let Some((integral, radius)) = env {
        let power = std::f64::consts::PI * f64::from(radius).powi(2) * integral;
        if integral > 0.0 {
            env_light = lights.len() as u32;
            lights.push(Emitter {
                primitive: NO_HIT,
                kind: LIGHT_ENVIRONMENT,
                power: (power as f32).max(f32::MIN_POSITIVE),
                ..Default::default()
            });
        }
    }
    let powers: Vec<f64> = lights.iter().map(|e| f64::from(e.power)).collect();
    let c = cdf(&powers);
    for (i, e) in lights.iter_mut().enumerate() {
        e.cdf = c[i + 1];
        e.prob = c[i + 1] - c[i];
    }
    (lights, env_light)
}
