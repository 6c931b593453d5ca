// Materials at a hit: the material with its textures looked up, what it emits, the
// integrator's questions (whose answers its module packed into the flags), and BSDF x cos
// and pdf toward a direction. Scattering, BSDF and pdf by the material's type are in
// shaders/materials/NAME.wgsl, one file per material; the dispatch to them (scatter,
// material_eval, material_pdf, material_textures) and each material's view of the record
// (NAMEParams, NAME_params(), NAME_record(); SurfaceParams, surface_params()) are written
// from the type list and the views (gpu::codegen::materials) into generated/materials. A
// material whose view has textures of its own (tex_data0, tex_data1) looks them up in
// NAME_textures.
#import generated/materials
#import shared/bsdf
#import shared/bindings
#import shared/rng
#import shared/textures
#import shared/types

// Radiance the surface emits toward the ray that hit it.
fn emitted(mat: Material, hit: Hit) -> vec3<f32> {
    if (hit.front_face || (mat.flags & MAT_FLAG_TWO_SIDED) != 0u) {
        return surface_params(mat).emission;
    }
    return vec3<f32>(0.0);
}

// The material at a hit with its textured colours looked up, by the record's rules:
// color is a reflectance, clamped to 1 so that no texture makes a surface create energy;
// color2 too where MAT_FLAG_COLOR2_CLAMPED says it is one; emission as it is; then the
// material's own textures. Compiled only for scenes with textures (HAS_TEXTURES):
// llvmpipe runs untaken branches under a mask, and the look-ups cost an untextured scene
// about 30% of its speed. A triangle's vertex colour multiplies color (HAS_VERTEX_COLORS;
// still at most 1). The back of a one-sided surface (MAT_FLAG_ONE_SIDED, HAS_ONE_SIDED)
// is black: the tag MAT_BLACK, which the dispatch absorbs.
fn material_at(m: Material, hit: Hit) -> Material {
    var mat = m;
    // which side the hit is on, for a material whose eval needs it (rough glass's eta)
    mat.normal2.w = select(0.0, 1.0, !hit.front_face);
#ifdef HAS_NORMAL_MAP
    // an anisotropic roughness's frame follows the hit's tangent, or taken strictly its
    // dp/du, as Mitsuba's frames do
    if ((mat.flags & MAT_FLAG_ANISOTROPIC) != 0u) {
        mat.normal2 = vec4<f32>(hit.tangent.xyz, mat.normal2.w);
#ifdef HAS_BUMP
        if ((mat.flags & MAT_FLAG_STRICT_SHADING) != 0u) {
            mat.normal2 = vec4<f32>(hit.dpdu, mat.normal2.w);
        }
#endif
    }
#endif
#ifdef HAS_TEXTURES
    // the .w of each colour is a scalar of its own
    if (mat.tex_color != NO_TEXTURE) {
        mat.color = vec4<f32>(min(texture_at(mat.tex_color, hit), vec3<f32>(1.0)), mat.color.w);
    }
    if (mat.tex_color2 != NO_TEXTURE) {
        let c = texture_at(mat.tex_color2, hit);
        mat.color2 = vec4<f32>(select(c, min(c, vec3<f32>(1.0)), (mat.flags & MAT_FLAG_COLOR2_CLAMPED) != 0u), mat.color2.w);
    }
    if (mat.tex_emission != NO_TEXTURE) {
        mat.emission = vec4<f32>(texture_at(mat.tex_emission, hit), mat.emission.w);
    }
    mat = material_textures(mat, hit);
#endif
#ifdef HAS_VERTEX_COLORS
#ifdef HAS_MESH_ATTRIBUTE
    // a material that reads the mesh's colours itself is not also tinted by them
    if ((mat.flags & MAT_FLAG_OWN_COLORS) == 0u) {
        mat.color = vec4<f32>(min(mat.color.rgb * hit.color.rgb, vec3<f32>(1.0)), mat.color.w);
    }
#else
    mat.color = vec4<f32>(min(mat.color.rgb * hit.color.rgb, vec3<f32>(1.0)), mat.color.w);
#endif
#endif
#ifdef HAS_ONE_SIDED
    // the back of a one-sided surface absorbs (it still emits as its flags say)
    if ((mat.flags & MAT_FLAG_ONE_SIDED) != 0u && !hit.front_face) {
        mat.tag = MAT_BLACK;
        mat.flags &= ~(MAT_FLAG_NEE | MAT_FLAG_DELTA);
    }
#endif
    return mat;
}

#ifdef HAS_NORMAL_MAP
// The hit with its shading normal taken from the surface's tangent-space normal map
// (map_normal; in the frame of dp/du with MAT_FLAG_UV_NORMAL_MAP, Mitsuba's normalmap),
// or from its bump map (MAT_FLAG_BUMP: bump_normal).
fn normal_mapped(mat: Material, hit: Hit) -> Hit {
    var h = hit;
#ifdef HAS_TEXTURES
    let s = surface_params(mat);
    if (s.normal_texture != NO_TEXTURE) {
#ifdef HAS_BUMP
        if ((mat.flags & MAT_FLAG_BUMP) != 0u) {
            h.ns = bump_normal(s.normal_texture, s.normal_scale, hit);
            return h;
        }
        if ((mat.flags & MAT_FLAG_UV_NORMAL_MAP) != 0u) {
            var uv_frame = hit;
            uv_frame.tangent = vec4<f32>(hit.dpdu, 1.0);
            h.ns = map_normal(s.normal_texture, s.normal_scale, uv_frame);
            return h;
        }
#endif
        h.ns = map_normal(s.normal_texture, s.normal_scale, hit);
    }
#endif
    return h;
}
#endif

#ifdef HAS_ALPHA
// Whether a ray passes through a hit: a surface with alpha (its opacity times the alpha
// of the texture in tex_color, and the luminance of its opacity texture with
// MAT_FLAG_OPACITY_TEXTURE) cut out below its alpha_cutoff with MAT_FLAG_ALPHA_MASK, or
// transparent when u >= alpha with MAT_FLAG_ALPHA_BLEND (u uniform in [0, 1)).
fn transparent_at(hit: Hit, u: f32) -> bool {
    let m = material_record(hit.material);
    if ((m.flags & (MAT_FLAG_ALPHA_MASK | MAT_FLAG_ALPHA_BLEND)) == 0u) {
        return false;
    }
    let s = surface_params(m);
    var alpha = s.opacity;
#ifdef HAS_VERTEX_COLORS
    alpha *= hit.color.a;
#endif
#ifdef HAS_TEXTURES
    if (m.tex_color != NO_TEXTURE) {
        alpha *= texture_alpha(m.tex_color, hit.uv);
    }
#ifdef HAS_OPACITY_TEXTURE
    if ((m.flags & MAT_FLAG_OPACITY_TEXTURE) != 0u) {
        alpha *= luminance(texture_at(s.opacity_texture, hit));
    }
#endif
#endif
    if ((m.flags & MAT_FLAG_ALPHA_MASK) != 0u) {
        return alpha < s.alpha_cutoff;
    }
    return u >= alpha;
}

// The uniform number of the k-th surface a ray meets: u itself for the first, then u's
// bits hashed with k, so that each surface decides independently of the others (a
// shift of u, as by the golden ratio, would keep the marginals but couple the decisions:
// two surfaces of opacity 0.5 would pass 12% of rays instead of 25%).
fn alpha_u(u: f32, k: u32) -> f32 {
    if (k == 0u) {
        return u;
    }
    return u32_to_unit_float(pcg4d(vec4<u32>(bitcast<u32>(u), k, 0x2545f491u, 0x9e3779b9u)).x);
}
#endif

#ifdef HAS_SHADING_NORMALS
// The hit with its shading normal bent where it differs from the geometric one and the
// mirror direction of the viewer about it would come within SHADING_LIFT of the geometric
// surface or under it (the viewer under the shading normal's horizon, as at a
// smooth-shaded silhouette): to the half vector of the viewer and that mirror direction
// lifted to SHADING_LIFT over the surface (after Keller et al. 2017, the Iray paper). The
// viewer is then over the shading horizon and a mirror reflects over the surface, where
// the unbent normal would have absorbed the path. Continuous: at SHADING_LIFT the half
// vector is the normal itself.
// A material that takes shading normals strictly (MAT_FLAG_STRICT_SHADING) is not bent
// but flipped: a mapped normal that leaves the viewer on the other side of it than of the
// unmapped one is mirrored about that (Mitsuba 3's normalmap and bumpmap, after
// Schuessler et al. 2017).
fn bent_normal(mat: Material, hit: Hit, ray: Ray) -> Hit {
    var h = hit;
    if ((mat.flags & MAT_FLAG_STRICT_SHADING) != 0u) {
        if (dot(ray.dir, hit.unmapped) * dot(ray.dir, hit.ns) <= 0.0) {
            h.ns = 2.0 * dot(hit.ns, hit.unmapped) * hit.unmapped - hit.ns;
        }
        return h;
    }
    if (any(hit.ns != hit.ng)) {
        let side = select(-1.0, 1.0, hit.front_face);
        let ng = side * hit.ng;
        let n = side * hit.ns;
        let wo = -ray.dir;
        let r = 2.0 * dot(wo, n) * n - wo;
        let c = dot(r, ng);
        if (c < SHADING_LIFT) {
            let lifted = normalize(r + (SHADING_LIFT - c) * ng);
            h.ns = side * normalize(wo + lifted);
        }
    }
    return h;
}
#endif

// Whether shading normals send a material's directions over the geometric surface
// (over_surface): where they differ from the geometric normal, for a material that does
// not transmit and does not take shading normals strictly.
fn folds(mat: Material, hit: Hit) -> bool {
    return any(hit.ns != hit.ng) && (mat.flags & (MAT_FLAG_TRANSMITS | MAT_FLAG_STRICT_SHADING)) == 0u;
}

#ifdef HAS_SHADING_NORMALS
// Where a material takes shading normals strictly (MAT_FLAG_STRICT_SHADING) and the hit's
// differs from its geometric one, whether its lobes are black toward wi: wi on one side
// of the shading surface and the other of the unmapped one (Mitsuba's normalmap and
// bumpmap rule) or of the geometric one, or, with MAT_FLAG_STRICT_VIEW, the viewer under
// the shading normal (Mitsuba's one-sided lobes).
fn strictly_black(mat: Material, ray: Ray, hit: Hit, wi: vec3<f32>) -> bool {
    if ((mat.flags & MAT_FLAG_STRICT_SHADING) == 0u || all(hit.ns == hit.ng)) {
        return false;
    }
    let side = select(-1.0, 1.0, hit.front_face);
    let viewer_under = (mat.flags & MAT_FLAG_STRICT_VIEW) != 0u && side * dot(ray.dir, hit.ns) >= 0.0;
    let c = dot(wi, hit.ns);
    return viewer_under || dot(wi, hit.unmapped) * c <= 0.0 || dot(wi, hit.ng) * c <= 0.0;
}

// Where a material takes shading normals strictly and a normal or bump map turned the
// shading normal, the share of light toward wi that the map's bumps shadow: Estevez et
// al. 2019's microfacet shadowing, 2 / (1 + sqrt(1 + a2 tan^2 wi)), a2 = min(tan^2 n / 8,
// 1), both angles from the unmapped normal (Mitsuba 3's normalmap and bumpmap); else 1.
fn map_shadowing(mat: Material, hit: Hit, wi: vec3<f32>) -> f32 {
    if ((mat.flags & MAT_FLAG_STRICT_SHADING) == 0u || all(hit.ns == hit.unmapped)) {
        return 1.0;
    }
    let cn = dot(hit.ns, hit.unmapped);
    let a2 = min(0.125 * max(1.0 - cn * cn, 0.0) / (cn * cn), 1.0);
    let ci = dot(wi, hit.unmapped);
    let t2 = max(1.0 - ci * ci, 0.0) / (ci * ci);
    return 2.0 / (1.0 + sqrt(1.0 + a2 * t2));
}
#endif

// scatter by the material's type, with shading normals taken strictly where its flags say:
// its lobes drawn about the shading normal alone, with nothing folded over the geometric
// surface, a direction strictly_black absorbed and the weight shadowed by the map's bumps
// (map_shadowing).
fn bsdf_scatter(mat: Material, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
#ifdef HAS_SHADING_NORMALS
    if ((mat.flags & MAT_FLAG_STRICT_SHADING) != 0u && any(hit.ns != hit.ng)) {
        // the lobes' own tests of the side, and over_surface, read the shading normal
        var shading = hit;
        shading.ng = hit.ns;
        var s = scatter(mat, ray, shading, u);
        if (s.ok && strictly_black(mat, ray, hit, s.dir)) {
            return absorbed();
        }
        s.weight *= map_shadowing(mat, hit, s.dir);
        return s;
    }
#endif
    return scatter(mat, ray, hit, u);
}

// BSDF x cos toward wi: what scatter's weight is the ratio of, and 0 under the geometric
// surface, where scatter absorbs, and for delta lobes. A material that transmits
// (MAT_FLAG_TRANSMITS: rough glass) weighs directions under the surface too, where the
// shading normal agrees that they are. Where shading normals differ from the geometric
// one, what the lobes of a material that does not send to wi's mirror image under the
// surface is sent to wi too (over_surface). A material that takes them strictly is black
// where strictly_black says, and shadowed by a map's bumps (map_shadowing).
fn bsdf_eval(mat: Material, ray: Ray, hit: Hit, wi: vec3<f32>) -> vec3<f32> {
    let side = select(-1.0, 1.0, hit.front_face);
#ifdef HAS_SHADING_NORMALS
    if (strictly_black(mat, ray, hit, wi)) {
        return vec3<f32>(0.0);
    }
#endif
    if (side * dot(wi, hit.ng) <= 0.0) {
        if ((mat.flags & MAT_FLAG_TRANSMITS) == 0u || side * dot(wi, hit.ns) >= 0.0) {
            return vec3<f32>(0.0);
        }
#ifdef HAS_SHADING_NORMALS
        return material_eval(mat, side * hit.ns, -ray.dir, wi) * map_shadowing(mat, hit, wi);
#else
        return material_eval(mat, side * hit.ns, -ray.dir, wi);
#endif
    }
    if ((mat.flags & MAT_FLAG_TRANSMITS) != 0u && side * dot(wi, hit.ns) <= 0.0) {
        // over the geometric surface, under the shading one: scatter absorbs it
        return vec3<f32>(0.0);
    }
    var f = material_eval(mat, side * hit.ns, -ray.dir, wi);
#ifdef HAS_SHADING_NORMALS
    if (folds(mat, hit)) {
        f += material_eval(mat, side * hit.ns, -ray.dir, mirrored(wi, hit));
    }
    f *= map_shadowing(mat, hit, wi);
#endif
    return f;
}

// The density with which scatter draws wi (before it absorbs directions on the wrong
// side of the geometric surface); where shading normals fold, the density of its mirror
// image too, which over_surface sends to wi.
fn bsdf_pdf(mat: Material, ray: Ray, hit: Hit, wi: vec3<f32>) -> f32 {
    let n = select(-hit.ns, hit.ns, hit.front_face);
    var pdf = material_pdf(mat, n, -ray.dir, wi);
#ifdef HAS_SHADING_NORMALS
    if (folds(mat, hit)) {
        pdf += material_pdf(mat, n, -ray.dir, mirrored(wi, hit));
    }
#endif
    return pdf;
}

// The density of a scattered direction s as MIS weighs it against light sampling:
// scatter's own, or bsdf_pdf's where shading normals may have sent it over the surface.
fn scatter_pdf(mat: Material, ray: Ray, hit: Hit, s: Scatter) -> f32 {
#ifdef HAS_SHADING_NORMALS
    if (!s.delta && folds(mat, hit)) {
        return bsdf_pdf(mat, ray, hit, s.dir);
    }
#endif
    return s.pdf;
}

// Whether next-event estimation applies at a surface: it has a lobe with a density (its
// module's answer, in the flags).
fn nee_applies(mat: Material) -> bool {
    return (mat.flags & MAT_FLAG_NEE) != 0u;
}

// Whether the 50/50 mixture samples lights at a surface: as nee_applies, less a material
// that may sample a delta lobe, which the mixture's pdf cannot hold.
fn mixture_applies(mat: Material) -> bool {
    return (mat.flags & (MAT_FLAG_NEE | MAT_FLAG_DELTA)) == MAT_FLAG_NEE;
}
