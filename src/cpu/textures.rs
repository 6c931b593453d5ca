//! Mirrors `shaders/shared/textures.wgsl`.

use glam::{IVec3, Vec2, Vec3, Vec4};

use super::bindings::Bindings;
use super::bsdf::luminance;
use super::types::{xyz, Hit};
use crate::scene::records::{
    Texture, NO_TEXTURE, TEX_CHECKER, TEX_FLAG_NEAREST, TEX_FLAG_SOLID, TEX_FLAG_SRGB, TEX_IMAGE,
    TEX_MESH_ATTRIBUTE, TEX_MODE_MASK, TEX_NOISE, TEX_WRAP_T_SHIFT,
};

/// A texture coordinate folded into [0, 1] by the wrap mode (0 repeat, 1 clamp, 2 mirror).
pub fn wrap_uv(t: f32, mode: u32) -> f32 {
    match mode {
        1 => t.clamp(0.0, 1.0),
        2 => {
            let m = t - 2.0 * (0.5 * t).floor();
            if m > 1.0 {
                2.0 - m
            } else {
                m
            }
        }
        _ => t - t.floor(),
    }
}

/// A texel index folded into 0 .. n - 1 by the wrap mode.
pub fn wrap_texel(i: i32, n: i32, mode: u32) -> u32 {
    match mode {
        0 => ((i + n) % n) as u32,
        _ => i.clamp(0, n - 1) as u32,
    }
}

/// Texel (x, y) of an image texture, from its bank; its colour decoded from sRGB for an
/// 8-bit sRGB image (`TEX_FLAG_SRGB`).
pub fn image_texel(b: &Bindings, tex: &Texture, x: u32, y: u32) -> Vec4 {
    let srgb = tex.flags & TEX_FLAG_SRGB != 0;
    Vec4::from(
        b.texels
            .texel(tex.bank, tex.layer, tex.x + x, tex.y + y, srgb),
    )
}

/// The texture's uv set of a surface's two (set 0 in `.xy`, set 1 in `.zw`).
pub fn uv_of(tex: &Texture, uv: Vec4) -> Vec2 {
    if tex.uv_set != 0 {
        Vec2::new(uv.z, uv.w)
    } else {
        Vec2::new(uv.x, uv.y)
    }
}

/// Image lookup at its uv set after the uv transform, wrapped per axis; v = 0 is the
/// bottom row.
/// Bilinear, or the nearest texel (`TEX_FLAG_NEAREST`, as the same mix with weights 1, 0).
pub fn image_rgba(b: &Bindings, tex: &Texture, surface_uv: Vec4) -> Vec4 {
    let q = uv_of(tex, surface_uv).extend(1.0);
    let uv = Vec2::new(
        Vec3::from_slice(&tex.color1[..3]).dot(q),
        Vec3::from_slice(&tex.params[..3]).dot(q),
    );
    let mode_s = tex.flags & TEX_MODE_MASK;
    let mode_t = (tex.flags >> TEX_WRAP_T_SHIFT) & TEX_MODE_MASK;
    let nearest = tex.flags & TEX_FLAG_NEAREST != 0;
    let centre = if nearest { 0.0 } else { 0.5 };
    let (w, h) = (tex.width as i32, tex.height as i32);
    let x = wrap_uv(uv.x, mode_s) * w as f32 - centre;
    let y = (1.0 - wrap_uv(uv.y, mode_t)) * h as f32 - centre;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = if nearest {
        (0.0, 0.0)
    } else {
        (x - x0, y - y0)
    };
    let xa = wrap_texel(x0 as i32, w, mode_s);
    let xb = wrap_texel(x0 as i32 + 1, w, mode_s);
    let ya = wrap_texel(y0 as i32, h, mode_t);
    let yb = wrap_texel(y0 as i32 + 1, h, mode_t);
    let t = |x: u32, y: u32| image_texel(b, tex, x, y);
    let top = t(xa, ya).lerp(t(xb, ya), fx);
    let bottom = t(xa, yb).lerp(t(xb, yb), fx);
    top.lerp(bottom, fy)
}

/// An image texture's colour: the bilinear texels times its factor (`color0`).
pub fn image_value(b: &Bindings, tex: &Texture, uv: Vec4) -> Vec3 {
    image_rgba(b, tex, uv).truncate() * Vec3::from_slice(&tex.color0[..3])
}

/// One corner of Perlin's gradient noise.
pub fn perlin_corner(b: &Bindings, offset: u32, i: IVec3, t: Vec3, s: Vec3, d: IVec3) -> f32 {
    let perm =
        |k: i32, lane: usize| b.tables[(offset + 256 + (k & 255) as u32) as usize][lane] as u32;
    // wrapping, as WGSL's i32 addition (a saturated lattice index far away must not panic)
    let px = perm(i.x.wrapping_add(d.x), 0);
    let py = perm(i.y.wrapping_add(d.y), 1);
    let pz = perm(i.z.wrapping_add(d.z), 2);
    let g = xyz(b.tables[(offset + (px ^ py ^ pz)) as usize]);
    let df = d.as_vec3();
    let w = Vec3::select(d.cmpeq(IVec3::ONE), s, Vec3::ONE - s);
    w.x * w.y * w.z * g.dot(t - df)
}

/// Perlin gradient noise in about [-1, 1].
pub fn perlin(b: &Bindings, offset: u32, p: Vec3) -> f32 {
    let f = p.floor();
    let t = p - f;
    let s = t * t * (3.0 - 2.0 * t);
    let i = f.as_ivec3();
    let c = |x, y, z| perlin_corner(b, offset, i, t, s, IVec3::new(x, y, z));
    c(0, 0, 0)
        + c(1, 0, 0)
        + c(0, 1, 0)
        + c(1, 1, 0)
        + c(0, 0, 1)
        + c(1, 0, 1)
        + c(0, 1, 1)
        + c(1, 1, 1)
}

/// |Sum of 7 octaves of noise|.
pub fn turbulence(b: &Bindings, offset: u32, p: Vec3) -> f32 {
    let mut acc = 0.0;
    let mut q = p;
    let mut w = 1.0;
    for _ in 0..7 {
        acc += w * perlin(b, offset, q);
        w *= 0.5;
        q *= 2.0;
    }
    f32::abs(acc)
}

pub fn noise_value(b: &Bindings, tex: &Texture, p: Vec3) -> Vec3 {
    let scale = tex.params[0];
    let color = xyz(tex.color0);
    match tex.flags & TEX_MODE_MASK {
        1 => color * turbulence(b, tex.offset, scale * p),
        2 => color * (0.5 * (1.0 + (scale * p.z + 10.0 * turbulence(b, tex.offset, p)).sin())),
        _ => color * (0.5 * (1.0 + perlin(b, tex.offset, scale * p))),
    }
}

/// Whether (uv, p) falls in an odd checker cell.
pub fn checker_odd(tex: &Texture, uv: Vec2, p: Vec3) -> bool {
    let s = tex.params[0];
    if tex.flags & TEX_FLAG_SOLID != 0 {
        let c = (s * p).floor().as_ivec3();
        return (c.x.wrapping_add(c.y).wrapping_add(c.z) & 1) == 1;
    }
    // the uv checker's map (scale x transform), as textures.wgsl reads it
    let q = uv.extend(1.0);
    let p0 = Vec3::new(tex.params[0], tex.params[1], tex.params[2]);
    let p1 = Vec3::new(tex.params[3], tex.color0[3], tex.color1[3]);
    let c = Vec2::new(p0.dot(q), p1.dot(q)).floor().as_ivec2();
    (c.x.wrapping_add(c.y) & 1) == 1
}

/// A texture that is not a checker.
pub fn texture_leaf(b: &Bindings, index: u32, uv: Vec4, p: Vec3) -> Vec3 {
    let tex = &b.textures[index as usize];
    match tex.tag {
        TEX_IMAGE => image_value(b, tex, uv),
        TEX_NOISE => noise_value(b, tex, p),
        _ => xyz(tex.color0),
    }
}

/// The colour of texture `index` at (uv, p): uv holds both uv sets; a checker's cells
/// follow set 0.
pub fn texture_value(b: &Bindings, index: u32, uv: Vec4, p: Vec3) -> Vec3 {
    let tex = &b.textures[index as usize];
    if tex.tag != TEX_CHECKER {
        return texture_leaf(b, index, uv, p);
    }
    let odd = checker_odd(tex, Vec2::new(uv.x, uv.y), p);
    let cell = if odd { tex.odd } else { tex.even };
    if cell == NO_TEXTURE {
        return xyz(if odd { tex.color1 } else { tex.color0 });
    }
    texture_leaf(b, cell, uv, p)
}

/// The colour of texture `index` at a hit (textures.wgsl's `texture_at`): `texture_value`,
/// or for a mesh attribute the hit's own colour.
pub fn texture_at(b: &Bindings, index: u32, hit: &Hit) -> Vec3 {
    if b.textures[index as usize].tag == TEX_MESH_ATTRIBUTE {
        return hit.color.truncate();
    }
    texture_value(b, index, hit.uv, hit.p)
}

/// The shading normal that tangent-space normal map `index` gives a hit (textures.wgsl's
/// `map_normal`): over the interpolated tangent's frame, x and y scaled by `scale`; the
/// hit's own normal without tangents or where the mapped one would face away.
pub fn map_normal(b: &Bindings, index: u32, scale: f32, hit: &Hit) -> Vec3 {
    let tangent = hit.tangent.truncate();
    if tangent.length() == 0.0 {
        return hit.ns;
    }
    let n = hit.ns;
    let t = (tangent - n * n.dot(tangent)).normalize();
    let sign = if hit.tangent.w >= 0.0 { 1.0 } else { -1.0 };
    let bt = n.cross(t) * sign;
    let c = 2.0 * texture_value(b, index, hit.uv, hit.p) - Vec3::ONE;
    let (x, y) = (c.x * scale, c.y * scale);
    let m = t * x + bt * y + n * c.z;
    let len = m.length();
    if len > 0.0 && m.dot(hit.ng) > 0.0 {
        return m / len;
    }
    hit.ns
}

/// A height texture's slopes (dh/du, dh/dv) at a hit (textures.wgsl's
/// `texture_slopes`): forward differences of its luminance along the first uv set, the
/// point moved along dp/du and dp/dv with it, by a 64th of an image's texel, else 1e-4.
pub fn texture_slopes(b: &Bindings, index: u32, hit: &Hit) -> Vec2 {
    let tex = &b.textures[index as usize];
    let delta = if tex.tag == TEX_IMAGE {
        1.0 / (64.0 * tex.width.max(tex.height) as f32)
    } else {
        1e-4
    };
    let h = luminance(texture_value(b, index, hit.uv, hit.p));
    let hu = luminance(texture_value(
        b,
        index,
        hit.uv + Vec4::new(delta, 0.0, delta, 0.0),
        hit.p + delta * hit.dpdu,
    ));
    let hv = luminance(texture_value(
        b,
        index,
        hit.uv + Vec4::new(0.0, delta, 0.0, delta),
        hit.p + delta * hit.dpdv,
    ));
    Vec2::new(hu - h, hv - h) / delta
}

/// The shading normal that bump map `index` (a height, times `scale`) gives a hit
/// (textures.wgsl's `bump_normal`): the normal of the surface displaced along its shading
/// normal; the hit's own without a parametrization or where it would face away.
pub fn bump_normal(b: &Bindings, index: u32, scale: f32, hit: &Hit) -> Vec3 {
    let n = hit.ns;
    let g = scale * texture_slopes(b, index, hit);
    let du = hit.dpdu - n * n.dot(hit.dpdu) + g.x * n;
    let dv = hit.dpdv - n * n.dot(hit.dpdv) + g.y * n;
    let m = du.cross(dv);
    let len = m.length();
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(len > 0.0) {
        return n;
    }
    let m = m * (if m.dot(n) >= 0.0 { 1.0 } else { -1.0 } / len);
    if m.dot(hit.ng) > 0.0 {
        m
    } else {
        n
    }
}

/// A texture's alpha at uv: an image's own, else 1.
pub fn texture_alpha(b: &Bindings, index: u32, uv: Vec4) -> f32 {
    let tex = &b.textures[index as usize];
    if tex.tag == TEX_IMAGE {
        image_rgba(b, tex, uv).w
    } else {
        1.0
    }
}
