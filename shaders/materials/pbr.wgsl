// type = "pbr": glTF's metallic-roughness material, its Appendix B with KHR_materials_ior
// and KHR_materials_specular, under KHR_materials_sheen's sheen (HAS_SHEEN) and
// KHR_materials_clearcoat's coat (HAS_CLEARCOAT) (scene::materials::pbr; CPU twin
// cpu/materials/pbr.rs).
#import shared/bindings
#import shared/bsdf
#import shared/sampling
#import shared/textures
#import shared/types

// glTF's metallicRoughnessTexture (green scales the roughness, so alpha by its square;
// blue the metallic factor) and KHR_materials_specular's specularTexture (its alpha scales
// the specular factor).
fn pbr_textures(p: PbrParams, hit: Hit) -> PbrParams {
    var q = p;
    if (p.metallic_roughness_texture != NO_TEXTURE) {
        let mr = min(texture_at(p.metallic_roughness_texture, hit), vec3<f32>(1.0));
        q.alpha = max(q.alpha * mr.y * mr.y, ALPHA_SMOOTH);
        q.metallic *= mr.z;
    }
    if (p.specular_texture != NO_TEXTURE) {
        q.specular *= min(texture_alpha(p.specular_texture, hit.uv), 1.0);
    }
#ifdef HAS_CLEARCOAT
    // the clearcoat texture's red scales the coat, its roughness texture's green the
    // coat's roughness (so alpha by its square)
    if (p.clearcoat_texture != NO_TEXTURE) {
        q.clearcoat *= min(texture_at(p.clearcoat_texture, hit).x, 1.0);
    }
    if (p.clearcoat_roughness_texture != NO_TEXTURE) {
        let g = min(texture_at(p.clearcoat_roughness_texture, hit).y, 1.0);
        q.coat_alpha = max(q.coat_alpha * g * g, ALPHA_SMOOTH);
    }
#ifdef HAS_NORMAL_MAP
    // the coat's own normal map, else the surface's normal as it is where the base has a
    // normal map, which is not the coat's
    if (p.coat_normal_texture != NO_TEXTURE) {
        q.coat_normal = map_normal(p.coat_normal_texture, p.coat_normal_scale, hit);
    } else if (p.base_normal_mapped > 0.0) {
        q.coat_normal = hit.ns;
    }
#endif
#endif
#ifdef HAS_SHEEN
    // the sheen colour texture (sRGB, times the factor), clamped to 1 as a reflectance;
    // the roughness texture's alpha scales the sheen's roughness
    if (p.sheen_color_texture != NO_TEXTURE) {
        q.sheen_color = min(texture_at(p.sheen_color_texture, hit), vec3<f32>(1.0));
    }
    if (p.sheen_roughness_texture != NO_TEXTURE) {
        let a = min(texture_alpha(p.sheen_roughness_texture, hit.uv), 1.0);
        q.sheen_alpha = max(q.sheen_alpha * a * a, SHEEN_ALPHA_MIN);
    }
#endif
    return q;
}

// Fresnel-Schlick of the dielectric layer at cos c (v . h):
// F0 = min(((ior - 1) / (ior + 1))^2 specular colour, 1) specular, F90 = specular.
fn pbr_dielectric_fresnel(p: PbrParams, c: f32) -> vec3<f32> {
    let r = (p.ior - 1.0) / (p.ior + 1.0);
    let f0 = min(vec3<f32>(r * r) * p.specular_color, vec3<f32>(1.0)) * p.specular;
    let m = 1.0 - clamp(c, 0.0, 1.0);
    return f0 + (vec3<f32>(p.specular) - f0) * (m * m * m * m * m);
}

// Fresnel-Schlick of the metal: F0 = the base colour, F90 = 1.
fn pbr_metal_fresnel(p: PbrParams, c: f32) -> vec3<f32> {
    let m = 1.0 - clamp(c, 0.0, 1.0);
    return p.base_color + (vec3<f32>(1.0) - p.base_color) * (m * m * m * m * m);
}

// BSDF x cos(theta_i), for unit wo and wi about the unit normal n on wo's side:
// mix((1 - F_d(cos_i)) (1 - F_d(cos_o)) base / pi cos_i + F_d(v . h) S, F_m(v . h) S,
// metallic), S = D V cos_i = D G2 / (4 cos_o) the GGX lobe with Smith's height-correlated
// G2 (h the half vector). Appendix B weighs the base by 1 - F_d(v . h) instead, which
// reflects up to 1.026 of a white furnace near roughness 0 (seen at 60 degrees); the
// base here gets what the Fresnel of both directions lets through, as the microfacet
// material's does: reciprocal and within energy conservation (tests/materials.rs).
// With energy compensation (MAT_FLAG_ENERGY), Kulla and Conty's lobe for the GGX lobe's
// multiple scattering, coloured by the mix of the two Fresnels' averages, and the base
// weighted by what the compensated dielectric lobe leaves of both directions: a white
// base under glTF's default specular then reflects all that arrives.
fn pbr_base_eval(p: PbrParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let cos_o = dot(n, wo);
    let cos_i = dot(n, wi);
    if (cos_o <= 0.0 || cos_i <= 0.0) {
        return vec3<f32>(0.0);
    }
    let alpha = p.alpha;
    let h = normalize(wo + wi);
    let vh = dot(wo, h);
    let spec = ggx_d(dot(n, h), alpha) * smith_g2(cos_o, cos_i, alpha) / (4.0 * cos_o);
    var through = (vec3<f32>(1.0) - pbr_dielectric_fresnel(p, cos_i)) * (vec3<f32>(1.0) - pbr_dielectric_fresnel(p, cos_o));
    let metallic = p.metallic;
#ifdef HAS_ENERGY_COMPENSATION
    var ms = vec3<f32>(0.0);
    // compensated: both lobes' multiple scattering, and the base under what the
    // compensated dielectric lobe reflects (ms_under) instead of under its Fresnel
    if ((p.flags & MAT_FLAG_ENERGY) != 0u) {
        let f0 = pbr_dielectric_fresnel(p, 1.0);
        let f90 = vec3<f32>(p.specular);
        through = ms_under(MS_GGX_CORRELATED, alpha, cos_o, cos_i, f0, f90);
        let f_avg = mix(f0 + (f90 - f0) / 21.0, p.base_color + (vec3<f32>(1.0) - p.base_color) / 21.0, metallic);
        ms = ms_lobe(MS_GGX_CORRELATED, alpha, cos_o, cos_i, f_avg);
    }
#endif
    let dielectric = through * p.base_color * (cos_i / PI) + pbr_dielectric_fresnel(p, vh) * spec;
    var f = dielectric * (1.0 - metallic) + pbr_metal_fresnel(p, vh) * spec * metallic;
#ifdef HAS_ENERGY_COMPENSATION
    f += ms;
#endif
    return f;
}

// Probability of sampling the GGX lobe: its share at the view angle (both Fresnels at
// cos_o, the diffuse lobe's colour), kept in [0.1, 0.9] when both lobes reflect.
fn pbr_spec_prob(p: PbrParams, cos_o: f32) -> f32 {
    let fd = pbr_dielectric_fresnel(p, cos_o);
    let metallic = p.metallic;
    let ws = luminance(fd * (1.0 - metallic) + pbr_metal_fresnel(p, cos_o) * metallic);
    var wd = (1.0 - p.metallic) * luminance((vec3<f32>(1.0) - fd) * p.base_color);
#ifdef HAS_ENERGY_COMPENSATION
    // the cosine lobe samples the compensation's lobe too
    if ((p.flags & MAT_FLAG_ENERGY) != 0u) {
        wd += ms_loss(MS_GGX_CORRELATED, p.alpha, cos_o);
    }
#endif
    return lobe_prob(ws, wd);
}

#ifdef HAS_SHEEN
// The Charlie sheen distribution (Estevez and Kulla 2017) at cos(theta_h) = c:
// (2 + 1 / alpha) sin(theta_h)^(1 / alpha) / (2 pi).
fn pbr_charlie_d(c: f32, alpha: f32) -> f32 {
    let inv = 1.0 / alpha;
    return (2.0 + inv) * pow(max(1.0 - c * c, 0.0), 0.5 * inv) / (2.0 * PI);
}

// Estevez and Kulla's fit of the Charlie distribution's log Lambda at x, its five
// coefficients interpolated between alpha 1 and 0 by (1 - alpha)^2.
fn pbr_charlie_l(x: f32, alpha: f32) -> f32 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let a = mix(21.5473, 25.3245, t);
    let b = mix(3.82987, 3.32435, t);
    let c = mix(0.19823, 0.16801, t);
    let d = mix(-1.97760, -1.27393, t);
    let e = mix(-4.32054, -4.85967, t);
    return a / (1.0 + b * pow(x, c)) + d * x + e;
}

// Smith's Lambda of the Charlie distribution at cos(theta) = c > 0 (the fit, mirrored
// about 1/2 for the upper half).
fn pbr_charlie_lambda(c: f32, alpha: f32) -> f32 {
    if (c < 0.5) {
        return exp(pbr_charlie_l(c, alpha));
    }
    return exp(2.0 * pbr_charlie_l(0.5, alpha) - pbr_charlie_l(1.0 - c, alpha));
}

// The directional albedo of a white sheen lobe at cos c and its alpha: the table
// scene::materials::pbr::sheen_albedo_table integrates (SHEEN_TABLE_SIZE cosines by
// SHEEN_TABLE_SIZE alphas, their square roots and the alphas evenly from 0 to 1, four to
// a tables entry from `table`), read bilinearly in sqrt(c) and alpha: the albedo peaks
// within a few degrees of grazing.
fn pbr_sheen_albedo(table: u32, c: f32, alpha: f32) -> f32 {
    let last = f32(SHEEN_TABLE_SIZE - 1u);
    let x = sqrt(clamp(c, 0.0, 1.0)) * last;
    let y = clamp(alpha, 0.0, 1.0) * last;
    let x0 = min(u32(x), SHEEN_TABLE_SIZE - 2u);
    let y0 = min(u32(y), SHEEN_TABLE_SIZE - 2u);
    let fx = x - f32(x0);
    let fy = y - f32(y0);
    let i = y0 * SHEEN_TABLE_SIZE + x0;
    let j = i + SHEEN_TABLE_SIZE;
    let e0 = mix(tables[table + (i >> 2u)][i & 3u], tables[table + ((i + 1u) >> 2u)][(i + 1u) & 3u], fx);
    let e1 = mix(tables[table + (j >> 2u)][j & 3u], tables[table + ((j + 1u) >> 2u)][(j + 1u) & 3u], fx);
    return mix(e0, e1, fy);
}

// The sheen over what lies under it (`under`, BSDF x cos): KHR_materials_sheen's
// sheen_color D_charlie V cos_i with Estevez and Kulla's height-correlated visibility
// V = 1 / ((1 + Lambda(cos_o) + Lambda(cos_i)) 4 cos_o cos_i), and the layer under it
// scaled by min(1 - max(sheen_color) E(cos_o), 1 - max(sheen_color) E(cos_i)), E the
// white sheen's albedo: what the sheen reflects is taken from what goes through, from
// either side (reciprocal, and never above the energy that arrives). Near grazing at low
// roughness the fit's lobe reflects more than arrives (E up to 2.1 at alpha 0.01): the
// lobe is divided by max(1, E(cos_o), E(cos_i)) and E taken at most 1, which keeps both
// properties.
fn pbr_sheen_over(p: PbrParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, under: vec3<f32>) -> vec3<f32> {
    let cos_o = dot(n, wo);
    let cos_i = dot(n, wi);
    if (cos_o <= 0.0 || cos_i <= 0.0) {
        return under;
    }
    let a = p.sheen_alpha;
    let m = max(p.sheen_color.x, max(p.sheen_color.y, p.sheen_color.z));
    let e_o = pbr_sheen_albedo(p.sheen_table, cos_o, a);
    let e_i = pbr_sheen_albedo(p.sheen_table, cos_i, a);
    let scale = min(1.0 - m * min(e_o, 1.0), 1.0 - m * min(e_i, 1.0));
    let h = normalize(wo + wi);
    let s = pbr_charlie_d(dot(n, h), a) / (4.0 * cos_o * (1.0 + pbr_charlie_lambda(cos_o, a) + pbr_charlie_lambda(cos_i, a)) * max(1.0, max(e_o, e_i)));
    return under * scale + p.sheen_color * s;
}
#endif

#ifdef HAS_CLEARCOAT
// The coat's normal toward wo: its own (its normal map's, or the surface's unmapped one,
// turned to n's side) where wo is over it, else n.
fn pbr_coat_normal(p: PbrParams, n: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    let c = p.coat_normal;
    if (dot(c, c) > 0.0) {
        let nc = c * select(-1.0, 1.0, dot(c, n) >= 0.0);
        if (dot(nc, wo) > 0.0) {
            return nc;
        }
    }
    return n;
}

// Fresnel-Schlick of the coat at cos c: a dielectric of ior 1.5 (F0 = 0.04), as
// KHR_materials_clearcoat has it.
fn pbr_coat_fresnel(c: f32) -> f32 {
    let m = 1.0 - clamp(c, 0.0, 1.0);
    return 0.04 + 0.96 * (m * m * m * m * m);
}

// The clearcoat over what lies under it (`under`, BSDF x cos): a GGX lobe of the coat's
// alpha about its normal nc, weighted clearcoat F_c(v . h), over the layer under it
// weighted by what the coat lets through both ways, (1 - clearcoat F_c(nc . wo))
// (1 - clearcoat F_c(nc . wi)): reciprocal, and within the energy that arrives. With
// energy compensation the layer under it gets all the coat does not reflect, its albedo
// from the tables (ms_scaling of ms_schlick_single): F_c at the normal is the albedo of
// a smooth coat, and a rough one reflects far less at grazing views (a white glTF
// material under a rough coat kept 0.15 of a white furnace at 89 degrees). What the
// coat's microfacets scatter more than once goes to the layer under it too: a
// dielectric of F_avg 0.09 sends on most of it, and its share that reflects is under
// 0.7% of the light.
fn pbr_coat_over(p: PbrParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, under: vec3<f32>) -> vec3<f32> {
    let nc = pbr_coat_normal(p, n, wo);
    let cos_o = dot(nc, wo);
    let cos_i = dot(nc, wi);
    let cc = p.clearcoat;
    var through = vec3<f32>((1.0 - cc * pbr_coat_fresnel(cos_o)) * (1.0 - cc * pbr_coat_fresnel(cos_i)));
#ifdef HAS_ENERGY_COMPENSATION
    if ((p.flags & MAT_FLAG_ENERGY) != 0u) {
        let f0 = vec3<f32>(0.04 * cc);
        let f90 = vec3<f32>(cc);
        let a = p.coat_alpha;
        let v = MS_GGX_CORRELATED;
        through = ms_scaling(ms_schlick_single(v, a, cos_o, f0, f90), ms_schlick_single(v, a, cos_i, f0, f90), ms_schlick_single_average(v, a, f0, f90));
    }
#endif
    var f = under * through;
    if (cos_o > 0.0 && cos_i > 0.0) {
        let h = normalize(wo + wi);
        let a = p.coat_alpha;
        f += vec3<f32>(cc * pbr_coat_fresnel(dot(wo, h)) * ggx_d(dot(nc, h), a) * smith_g2(cos_o, cos_i, a) / (4.0 * cos_o));
    }
    return f;
}
#endif

// BSDF x cos: the base (pbr_base_eval) under the sheen, under the clearcoat.
fn pbr_eval(p: PbrParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    var f = pbr_base_eval(p, n, wo, wi);
#ifdef HAS_SHEEN
    f = pbr_sheen_over(p, n, wo, wi, f);
#endif
#ifdef HAS_CLEARCOAT
    f = pbr_coat_over(p, n, wo, wi, f);
#endif
    return f;
}

#ifdef HAS_PBR_LAYERS
// The probabilities of drawing from the clearcoat's lobe (x) and the sheen's (y), the
// base taking the rest: each one's share of what leaves toward wo (the coat's clearcoat
// F_c(cos_o); the sheen's colour times its albedo under what the coat lets through; the
// base's Fresnel-weighted colours under both), each layer that reflects kept in
// [0.1, 0.9] of what is left to it. From wo alone, so the pdf is exact.
fn pbr_layer_probs(p: PbrParams, n: vec3<f32>, wo: vec3<f32>) -> vec2<f32> {
    let cos_o = dot(n, wo);
    var coat = 0.0;
    var sheen = 0.0;
    var through = 1.0;
#ifdef HAS_CLEARCOAT
    coat = p.clearcoat * pbr_coat_fresnel(dot(pbr_coat_normal(p, n, wo), wo));
    through = 1.0 - coat;
#endif
#ifdef HAS_SHEEN
    let e = min(pbr_sheen_albedo(p.sheen_table, cos_o, p.sheen_alpha), 1.0);
    sheen = through * luminance(p.sheen_color) * e;
    through *= 1.0 - max(p.sheen_color.x, max(p.sheen_color.y, p.sheen_color.z)) * e;
#endif
    let fd = pbr_dielectric_fresnel(p, cos_o);
    let m = p.metallic;
    let base = through * luminance((fd + (vec3<f32>(1.0) - fd) * p.base_color) * (1.0 - m) + pbr_metal_fresnel(p, cos_o) * m);
    var pc = 0.0;
    var ps = 0.0;
    if (coat > 0.0) {
        pc = clamp(coat / (coat + sheen + base), 0.1, 0.9);
    }
    if (sheen > 0.0) {
        ps = (1.0 - pc) * clamp(sheen / (sheen + base), 0.1, 0.9);
    }
    return vec2<f32>(pc, ps);
}
#endif

// The density of pbr_scatter's directions: the base's mixture of the GGX and the cosine
// lobe, and the layers' lobes (the coat's GGX lobe about its normal, the sheen's cosine
// lobe) with their probabilities.
fn pbr_pdf(p: PbrParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    var pdf = ggx_lobes_pdf(pbr_spec_prob(p, dot(n, wo)), p.alpha, n, wo, wi);
#ifdef HAS_PBR_LAYERS
    let lp = pbr_layer_probs(p, n, wo);
    pdf *= 1.0 - lp.x - lp.y;
#ifdef HAS_CLEARCOAT
    pdf += lp.x * ggx_lobes_pdf(1.0, p.coat_alpha, pbr_coat_normal(p, n, wo), wo, wi);
#endif
#ifdef HAS_SHEEN
    pdf += lp.y * max(dot(n, wi), 0.0) / PI;
#endif
#endif
    return pdf;
}

// The GGX lobe or the cosine one, chosen by pbr_spec_prob (after the coat's lobe and the
// sheen's, by pbr_layer_probs, with u.x reused); weight = eval / pdf of the mixture. A
// direction under the geometric surface is absorbed.
fn pbr_scatter(p: PbrParams, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
    let side = select(-1.0, 1.0, hit.front_face);
    let n = side * hit.ns;
    let wo = -ray.dir;
    let cos_o = dot(n, wo);
    if (cos_o <= 0.0) {
        return absorbed();
    }
#ifdef HAS_PBR_LAYERS
    let lp = pbr_layer_probs(p, n, wo);
    let ub = vec2<f32>((u.x - lp.x - lp.y) / (1.0 - lp.x - lp.y), u.y);
    var wi = sample_ggx_lobes(pbr_spec_prob(p, cos_o), p.alpha, n, wo, ub);
#ifdef HAS_SHEEN
    if (u.x >= lp.x && u.x < lp.x + lp.y) {
        wi = sample_cosine_hemisphere(n, vec2<f32>((u.x - lp.x) / lp.y, u.y));
    }
#endif
#ifdef HAS_CLEARCOAT
    if (u.x < lp.x) {
        wi = sample_ggx_lobes(1.0, p.coat_alpha, pbr_coat_normal(p, n, wo), wo, vec2<f32>(u.x / lp.x, u.y));
    }
#endif
#else
    let wi = sample_ggx_lobes(pbr_spec_prob(p, cos_o), p.alpha, n, wo, u);
#endif
    return density_sample(wi, pbr_eval(p, n, wo, wi), pbr_pdf(p, n, wo, wi), side, hit);
}
