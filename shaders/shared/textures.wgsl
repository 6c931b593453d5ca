// Textures: constant, checker, image (bilinear, wrapped), Perlin noise, and the lookup of a
// material's textured colours at a hit.
#import shared/bindings
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

// Bilinear image lookup of (r, g, b, alpha) after the texture's uv transform (rows in
// color1 and params); v = 0 is the bottom row of the image, texel centres at half
// integers.
fn image_rgba(tex: Texture, surface_uv: vec2<f32>) -> vec4<f32> {
    let q = vec3<f32>(surface_uv, 1.0);
    let uv = vec2<f32>(dot(tex.color1.xyz, q), dot(tex.params.xyz, q));
    let mode = tex.flags & TEX_MODE_MASK;
    let w = i32(tex.width);
    let h = i32(tex.height);
    let x = wrap_uv(uv.x, mode) * f32(w) - 0.5;
    let y = (1.0 - wrap_uv(uv.y, mode)) * f32(h) - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let xa = wrap_texel(i32(x0), w, mode);
    let xb = wrap_texel(i32(x0) + 1, w, mode);
    let ya = wrap_texel(i32(y0), h, mode);
    let yb = wrap_texel(i32(y0) + 1, h, mode);
    let row_a = tex.offset + ya * tex.width;
    let row_b = tex.offset + yb * tex.width;
    let top = mix(texels[row_a + xa], texels[row_a + xb], fx);
    let bottom = mix(texels[row_b + xa], texels[row_b + xb], fx);
    return mix(top, bottom, fy);
}

// An image texture's colour: the bilinear texels times its factor (color0).
fn image_value(tex: Texture, uv: vec2<f32>) -> vec3<f32> {
    return image_rgba(tex, uv).rgb * tex.color0.rgb;
}

// One corner of Perlin's gradient noise: the random vector picked by the three
// permutations at lattice point i + d, dotted with the offset from it, times the Hermite
// weights of that corner.
fn perlin_corner(offset: u32, i: vec3<i32>, t: vec3<f32>, s: vec3<f32>, d: vec3<i32>) -> f32 {
    let px = u32(texels[offset + 256u + u32((i.x + d.x) & 255)].x);
    let py = u32(texels[offset + 256u + u32((i.y + d.y) & 255)].y);
    let pz = u32(texels[offset + 256u + u32((i.z + d.z) & 255)].z);
    let g = texels[offset + (px ^ py ^ pz)].xyz;
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
    let c = vec2<i32>(floor(s * uv));
    return ((c.x + c.y) & 1) == 1;
}

// A texture that is not a checker.
fn texture_leaf(index: u32, uv: vec2<f32>, p: vec3<f32>) -> vec3<f32> {
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

// The colour of texture `index` at surface coordinates uv and point p. A checker's cells
// are colours or textures that are not checkers (the scene loader enforces it), so this
// needs no recursion.
fn texture_value(index: u32, uv: vec2<f32>, p: vec3<f32>) -> vec3<f32> {
#ifdef HAS_CHECKER_TEXTURE
    let tex = textures[index];
    if (tex.tag != TEX_CHECKER) {
        return texture_leaf(index, uv, p);
    }
    let odd = checker_odd(tex, uv, p);
    let cell = select(tex.even, tex.odd, odd);
    if (cell == NO_TEXTURE) {
        return select(tex.color0.rgb, tex.color1.rgb, odd);
    }
    return texture_leaf(cell, uv, p);
#else
    return texture_leaf(index, uv, p);
#endif
}

// The material at a hit with its textured colours looked up; reflectances (albedo, tint,
// specular) are clamped to 1 so that no texture makes a surface create energy. Compiled only
// for scenes with textures (HAS_TEXTURES): llvmpipe runs untaken branches under a mask, and
// the look-ups cost an untextured scene about 30% of its speed.
fn material_at(m: Material, hit: Hit) -> Material {
    var mat = m;
#ifdef HAS_TEXTURES
    // the .w of each colour is a scalar of its own (pbr: alpha, normal scale, cutoff)
    if (mat.tex_albedo != NO_TEXTURE) {
        mat.albedo = vec4<f32>(min(texture_value(mat.tex_albedo, hit.uv, hit.p), vec3<f32>(1.0)), mat.albedo.w);
    }
    if (mat.tex_extra != NO_TEXTURE) {
        // a reflectance, but for pbr's specular colour, which may exceed 1
        // (KHR_materials_specular; its F0 is clamped to 1 instead)
        let extra = texture_value(mat.tex_extra, hit.uv, hit.p);
        mat.extra = vec4<f32>(select(min(extra, vec3<f32>(1.0)), extra, mat.tag == MAT_PBR), mat.extra.w);
    }
    if (mat.tex_emission != NO_TEXTURE) {
        mat.emission = vec4<f32>(texture_value(mat.tex_emission, hit.uv, hit.p), mat.emission.w);
    }
#ifdef HAS_PBR
    if (mat.tex_params != NO_TEXTURE) {
        // glTF's metallicRoughnessTexture: green scales the roughness (alpha = r^2), blue
        // the metallic factor
        let mr = min(texture_value(mat.tex_params, hit.uv, hit.p), vec3<f32>(1.0));
        mat.params.x = max(mat.params.x * mr.y * mr.y, ALPHA_SMOOTH);
        mat.params.z *= mr.z;
    }
    if (mat.tex_specular != NO_TEXTURE) {
        // KHR_materials_specular's specularTexture: its alpha scales the specular factor
        mat.params.w *= min(texture_alpha(mat.tex_specular, hit.uv), 1.0);
    }
#endif
#endif
    return mat;
}

#ifdef HAS_NORMAL_MAP
// The hit with its shading normal taken from the material's tangent-space normal map: n =
// normalize(t x + b y + ns z) over the frame of the interpolated tangent, made
// orthogonal to ns (b = sign x ns cross t), the map's x and y scaled by extra.w. A hit
// without tangents, or a mapped normal that would face away from the geometric side, keeps
// its normal.
fn normal_mapped(mat: Material, hit: Hit) -> Hit {
    var h = hit;
#ifdef HAS_TEXTURES
    let t_len = length(hit.tangent.xyz);
    if (mat.tex_normal == NO_TEXTURE || t_len == 0.0) {
        return h;
    }
    let n = hit.ns;
    let t = normalize(hit.tangent.xyz - n * dot(n, hit.tangent.xyz));
    let b = cross(n, t) * select(-1.0, 1.0, hit.tangent.w >= 0.0);
    var c = 2.0 * texture_value(mat.tex_normal, hit.uv, hit.p) - vec3<f32>(1.0);
    c = vec3<f32>(c.xy * mat.extra.w, c.z);
    let m = t * c.x + b * c.y + n * c.z;
    let len = length(m);
    if (len > 0.0 && dot(m, hit.ng) > 0.0) {
        h.ns = m / len;
    }
#endif
    return h;
}
#endif

// A texture's alpha at uv: an image's own, else 1.
fn texture_alpha(index: u32, uv: vec2<f32>) -> f32 {
    let tex = textures[index];
    if (tex.tag == TEX_IMAGE) {
        return image_rgba(tex, uv).a;
    }
    return 1.0;
}

#ifdef HAS_ALPHA
// Whether a ray passes through a hit: a pbr surface with alpha (albedo.w times its base
// colour texture's alpha) cut out below the cutoff (emission.w) with MAT_FLAG_ALPHA_MASK,
// or transparent when u >= alpha with MAT_FLAG_ALPHA_BLEND (u uniform in [0, 1)).
fn transparent_at(hit: Hit, u: f32) -> bool {
    let m = material_record(hit.material);
    if ((m.flags & (MAT_FLAG_ALPHA_MASK | MAT_FLAG_ALPHA_BLEND)) == 0u) {
        return false;
    }
    var alpha = m.albedo.w;
#ifdef HAS_TEXTURES
    if (m.tex_albedo != NO_TEXTURE) {
        alpha *= texture_alpha(m.tex_albedo, hit.uv);
    }
#endif
    if ((m.flags & MAT_FLAG_ALPHA_MASK) != 0u) {
        return alpha < m.emission.w;
    }
    return u >= alpha;
}

// The uniform number of the k-th surface a ray meets: u moved by k times the golden
// ratio's fraction, so that each surface has its own.
fn alpha_u(u: f32, k: u32) -> f32 {
    return fract(u + f32(k) * 0.618034);
}
#endif
