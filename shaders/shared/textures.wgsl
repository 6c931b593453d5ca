// Textures: constant, checker, image (bilinear, wrapped), Perlin noise.
#import shared/bindings
#import shared/bsdf
#import shared/types

// A texture coordinate folded into [0, 1] by the wrap mode (0 repeat, 1 clamp, 2 mirror).
fn wrap_uv(t: f32, mode: u32) -> f32 {
    switch mode {
        case 1u: {
            return clamp(t, 0.0, 1.0);
        }
        case 2u: {
            let m = t - 2.0 * floor(0.5 * t);
            return select(m, 2.0 - m, m > 1.0);
        }
        default: {
            return t - floor(t);
        }
    }
}

// A texel index folded into 0 .. n - 1 by the wrap mode (neighbours of the edge texels).
fn wrap_texel(i: i32, n: i32, mode: u32) -> u32 {
    switch mode {
        case 0u: {
            return u32((i + n) % n);
        }
        default: {
            return u32(clamp(i, 0, n - 1));
        }
    }
}

// The sRGB transfer function undone (IEC 61966-2-1), per channel.
fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    return select(pow((c + 0.055) / 1.055, vec3<f32>(2.4)), c / 12.92, c <= vec3<f32>(0.04045));
}

// Texel (x, y) of an image texture: its block's texel in its bank and page (texel_load is
// generated for the scene's banks: gpu::bindings::wgsl_texel_load), its colour decoded
// from sRGB for an 8-bit sRGB image (TEX_FLAG_SRGB).
fn image_texel(tex: Texture, x: u32, y: u32) -> vec4<f32> {
    let t = texel_load(tex.bank, tex.layer, tex.x + x, tex.y + y);
#ifdef HAS_SRGB_TEXTURE
    let srgb = (tex.flags & TEX_FLAG_SRGB) != 0u;
    return select(t, vec4<f32>(srgb_to_linear(t.rgb), t.a), srgb);
#else
    return t;
#endif
}


// The texture's uv set of a surface's two (set 0 in .xy, set 1 in .zw).
fn uv_of(tex: Texture, uv: vec4<f32>) -> vec2<f32> {
#ifdef HAS_UV1
    return select(uv.xy, uv.zw, tex.uv_set != 0u);
#else
    return uv.xy;
#endif
}

// Image lookup of (r, g, b, alpha) at its uv set after the texture's uv transform (rows in
// color1 and params), wrapped per axis; v = 0 is the bottom row of the image, texel
// centres at half integers. Bilinear, or the nearest texel (TEX_FLAG_NEAREST: the texel
// whose square holds the point, as the same four-texel mix with weights 1, 0).
fn image_rgba(tex: Texture, surface_uv: vec4<f32>) -> vec4<f32> {
    let q = vec3<f32>(uv_of(tex, surface_uv), 1.0);
    let uv = vec2<f32>(dot(tex.color1.xyz, q), dot(tex.params.xyz, q));
    let mode_s = tex.flags & TEX_MODE_MASK;
    let mode_t = (tex.flags >> TEX_WRAP_T_SHIFT) & TEX_MODE_MASK;
    let nearest = (tex.flags & TEX_FLAG_NEAREST) != 0u;
    let centre = select(0.5, 0.0, nearest);
    let w = i32(tex.width);
    let h = i32(tex.height);
    let x = wrap_uv(uv.x, mode_s) * f32(w) - centre;
    let y = (1.0 - wrap_uv(uv.y, mode_t)) * f32(h) - centre;
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = select(x - x0, 0.0, nearest);
    let fy = select(y - y0, 0.0, nearest);
    let xa = wrap_texel(i32(x0), w, mode_s);
    let xb = wrap_texel(i32(x0) + 1, w, mode_s);
    let ya = wrap_texel(i32(y0), h, mode_t);
    let yb = wrap_texel(i32(y0) + 1, h, mode_t);
    let top = mix(image_texel(tex, xa, ya), image_texel(tex, xb, ya), fx);
    let bottom = mix(image_texel(tex, xa, yb), image_texel(tex, xb, yb), fx);
    return mix(top, bottom, fy);
}

// An image texture's colour: the bilinear texels times its factor (color0).
fn image_value(tex: Texture, uv: vec4<f32>) -> vec3<f32> {
    return image_rgba(tex, uv).rgb * tex.color0.rgb;
}

// One corner of Perlin's gradient noise: the random vector picked by the three
// permutations at lattice point i + d, dotted with the offset from it, times the Hermite
// weights of that corner.
fn perlin_corner(offset: u32, i: vec3<i32>, t: vec3<f32>, s: vec3<f32>, d: vec3<i32>) -> f32 {
    let px = u32(tables[offset + 256u + u32((i.x + d.x) & 255)].x);
    let py = u32(tables[offset + 256u + u32((i.y + d.y) & 255)].y);
    let pz = u32(tables[offset + 256u + u32((i.z + d.z) & 255)].z);
    let g = tables[offset + (px ^ py ^ pz)].xyz;
    let df = vec3<f32>(d);
    let w = select(1.0 - s, s, d == vec3<i32>(1));
    return w.x * w.y * w.z * dot(g, t - df);
}

// Perlin gradient noise in about [-1, 1] ("Ray Tracing: The Next Week"), the eight corners
// written out (no loop).
fn perlin(offset: u32, p: vec3<f32>) -> f32 {
    let f = floor(p);
    let t = p - f;
    let s = t * t * (3.0 - 2.0 * t);
    let i = vec3<i32>(f);
    return perlin_corner(offset, i, t, s, vec3<i32>(0, 0, 0))
        + perlin_corner(offset, i, t, s, vec3<i32>(1, 0, 0))
        + perlin_corner(offset, i, t, s, vec3<i32>(0, 1, 0))
        + perlin_corner(offset, i, t, s, vec3<i32>(1, 1, 0))
        + perlin_corner(offset, i, t, s, vec3<i32>(0, 0, 1))
        + perlin_corner(offset, i, t, s, vec3<i32>(1, 0, 1))
        + perlin_corner(offset, i, t, s, vec3<i32>(0, 1, 1))
        + perlin_corner(offset, i, t, s, vec3<i32>(1, 1, 1));
}

// Turbulence: |sum of 7 octaves of noise, each at twice the frequency and half the weight|.
fn turbulence(offset: u32, p: vec3<f32>) -> f32 {
    var acc = 0.0;
    var q = p;
    var w = 1.0;
    for (var k = 0u; k < 7u; k++) {
        acc += w * perlin(offset, q);
        w *= 0.5;
        q *= 2.0;
    }
    return abs(acc);
}

fn noise_value(tex: Texture, p: vec3<f32>) -> vec3<f32> {
    let scale = tex.params.x;
    switch tex.flags & TEX_MODE_MASK {
        case 1u: {
            return tex.color0.rgb * turbulence(tex.offset, scale * p);
        }
        case 2u: {
            return tex.color0.rgb * (0.5 * (1.0 + sin(scale * p.z + 10.0 * turbulence(tex.offset, p))));
        }
        default: {
            return tex.color0.rgb * (0.5 * (1.0 + perlin(tex.offset, scale * p)));
        }
    }
}

// Whether (uv, p) falls in an odd checker cell: the parity of the cell's integer coordinates.
fn checker_odd(tex: Texture, uv: vec2<f32>, p: vec3<f32>) -> bool {
    let s = tex.params.x;
    if ((tex.flags & TEX_FLAG_SOLID) != 0u) {
        let c = vec3<i32>(floor(s * p));
        return ((c.x + c.y + c.z) & 1) == 1;
    }
    // the uv checker's map (scale x transform): params.xyz its first row, its second in
    // (params.w, color0.w, color1.w)
    let q = vec3<f32>(uv, 1.0);
    let c = vec2<i32>(floor(vec2<f32>(dot(tex.params.xyz, q), dot(vec3<f32>(tex.params.w, tex.color0.w, tex.color1.w), q))));
    return ((c.x + c.y) & 1) == 1;
}

// A texture that is not a checker.
fn texture_leaf(index: u32, uv: vec4<f32>, p: vec3<f32>) -> vec3<f32> {
    let tex = textures[index];
    switch tex.tag {
#ifdef HAS_IMAGE_TEXTURE
        case TEX_IMAGE: {
            return image_value(tex, uv);
        }
#endif
#ifdef HAS_NOISE_TEXTURE
        case TEX_NOISE: {
            return noise_value(tex, p);
        }
#endif
        default: {
            return tex.color0.rgb;
        }
    }
}

// The colour of texture `index` at surface coordinates uv (both sets) and point p; a
// checker's cells follow uv set 0. A checker's cells
// are colours or textures that are not checkers (the scene loader enforces it), so this
// needs no recursion.
fn texture_value(index: u32, uv: vec4<f32>, p: vec3<f32>) -> vec3<f32> {
#ifdef HAS_CHECKER_TEXTURE
    let tex = textures[index];
    if (tex.tag != TEX_CHECKER) {
        return texture_leaf(index, uv, p);
    }
    let odd = checker_odd(tex, uv.xy, p);
    let cell = select(tex.even, tex.odd, odd);
    if (cell == NO_TEXTURE) {
        return select(tex.color0.rgb, tex.color1.rgb, odd);
    }
    return texture_leaf(cell, uv, p);
#else
    return texture_leaf(index, uv, p);
#endif
}

// The colour of texture `index` at a hit: texture_value at its uv and point, or for a
// mesh attribute (HAS_MESH_ATTRIBUTE) the hit's own colour, its mesh's vertex or face
// colours (1 where it has none).
fn texture_at(index: u32, hit: Hit) -> vec3<f32> {
#ifdef HAS_MESH_ATTRIBUTE
    if (textures[index].tag == TEX_MESH_ATTRIBUTE) {
        return hit.color.rgb;
    }
#endif
    return texture_value(index, hit.uv, hit.p);
}

#ifdef HAS_NORMAL_MAP
// The shading normal that tangent-space normal map `index` gives a hit: normalize(t x +
// b y + ns z) over the frame of the interpolated tangent, made orthogonal to ns (b = sign
// x ns cross t), the map's x and y scaled by `scale`. A hit without tangents, or a
// mapped normal that would face away from the geometric side, keeps its normal.
fn map_normal(index: u32, scale: f32, hit: Hit) -> vec3<f32> {
    if (length(hit.tangent.xyz) == 0.0) {
        return hit.ns;
    }
    let n = hit.ns;
    let t = normalize(hit.tangent.xyz - n * dot(n, hit.tangent.xyz));
    let b = cross(n, t) * select(-1.0, 1.0, hit.tangent.w >= 0.0);
    var c = 2.0 * texture_value(index, hit.uv, hit.p) - vec3<f32>(1.0);
    c = vec3<f32>(c.xy * scale, c.z);
    let m = t * c.x + b * c.y + n * c.z;
    let len = length(m);
    if (len > 0.0 && dot(m, hit.ng) > 0.0) {
        return m / len;
    }
    return hit.ns;
}
#endif

#ifdef HAS_BUMP
// A height texture's slopes (dh/du, dh/dv) at a hit: forward differences of its
// luminance along the first uv set, the point moved along dp/du and dp/dv with it (so a
// solid texture has slopes too); the step a 64th of an image's texel (within a texel
// its bilinear look-up is linear along each axis, so this is its derivative there, as
// Mitsuba's analytic gradient), else 1e-4.
fn texture_slopes(index: u32, hit: Hit) -> vec2<f32> {
    let tex = textures[index];
    let delta = select(1e-4, 1.0 / (64.0 * f32(max(tex.width, tex.height))), tex.tag == TEX_IMAGE);
    let h = luminance(texture_value(index, hit.uv, hit.p));
    let hu = luminance(texture_value(index, hit.uv + vec4<f32>(delta, 0.0, delta, 0.0), hit.p + delta * hit.dpdu));
    let hv = luminance(texture_value(index, hit.uv + vec4<f32>(0.0, delta, 0.0, delta), hit.p + delta * hit.dpdv));
    return vec2<f32>(hu - h, hv - h) / delta;
}

// The shading normal that bump map `index` (a height, times `scale`) gives a hit: the
// normal of the surface displaced by the height along its shading normal n, dp/du and
// dp/dv made tangent to n and lifted by the height's slopes (dp'/du = dp/du - n (n .
// dp/du) + (dh/du) n, the same along v), n' = dp'/du x dp'/dv turned to n's side, as
// Mitsuba's `bumpmap`. A hit without a parametrization, or a normal that would face away
// from the geometric side, keeps its normal.
fn bump_normal(index: u32, scale: f32, hit: Hit) -> vec3<f32> {
    let n = hit.ns;
    let g = scale * texture_slopes(index, hit);
    let du = hit.dpdu - n * dot(n, hit.dpdu) + g.x * n;
    let dv = hit.dpdv - n * dot(n, hit.dpdv) + g.y * n;
    var m = cross(du, dv);
    let len = length(m);
    if (!(len > 0.0)) {
        return n;
    }
    m = m * (select(-1.0, 1.0, dot(m, n) >= 0.0) / len);
    return select(n, m, dot(m, hit.ng) > 0.0);
}
#endif

// A texture's alpha at uv: an image's own, else 1.
fn texture_alpha(index: u32, uv: vec4<f32>) -> f32 {
    let tex = textures[index];
    if (tex.tag == TEX_IMAGE) {
        return image_rgba(tex, uv).a;
    }
    return 1.0;
}

