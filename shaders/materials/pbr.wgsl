// type = "pbr": glTF's metallic-roughness material, its Appendix B with KHR_materials_ior
// and KHR_materials_specular (scene::materials::pbr; CPU twin cpu/materials/pbr.rs).
#import shared/bsdf
#import shared/textures
#import shared/types

// glTF's metallicRoughnessTexture (green scales the roughness, so alpha by its square;
// blue the metallic factor) and KHR_materials_specular's specularTexture (its alpha scales
// the specular factor).
fn pbr_textures(p: PbrParams, hit: Hit) -> PbrParams {
    var q = p;
    if (p.metallic_roughness_texture != NO_TEXTURE) {
        let mr = min(texture_value(p.metallic_roughness_texture, hit.uv, hit.p), vec3<f32>(1.0));
        q.alpha = max(q.alpha * mr.y * mr.y, ALPHA_SMOOTH);
        q.metallic *= mr.z;
    }
    if (p.specular_texture != NO_TEXTURE) {
        q.specular *= min(texture_alpha(p.specular_texture, hit.uv), 1.0);
    }
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
fn pbr_eval(p: PbrParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let cos_o = dot(n, wo);
    let cos_i = dot(n, wi);
    if (cos_o <= 0.0 || cos_i <= 0.0) {
        return vec3<f32>(0.0);
    }
    let alpha = p.alpha;
    let h = normalize(wo + wi);
    let vh = dot(wo, h);
    let spec = ggx_d(dot(n, h), alpha) * smith_g2(cos_o, cos_i, alpha) / (4.0 * cos_o);
    let through = (vec3<f32>(1.0) - pbr_dielectric_fresnel(p, cos_i)) * (vec3<f32>(1.0) - pbr_dielectric_fresnel(p, cos_o));
    let dielectric = through * p.base_color * (cos_i / PI) + pbr_dielectric_fresnel(p, vh) * spec;
    let metallic = p.metallic;
    return dielectric * (1.0 - metallic) + pbr_metal_fresnel(p, vh) * spec * metallic;
}

// Probability of sampling the GGX lobe: its share at the view angle (both Fresnels at
// cos_o, the diffuse lobe's colour), kept in [0.1, 0.9] when both lobes reflect.
fn pbr_spec_prob(p: PbrParams, cos_o: f32) -> f32 {
    let fd = pbr_dielectric_fresnel(p, cos_o);
    let metallic = p.metallic;
    let ws = luminance(fd * (1.0 - metallic) + pbr_metal_fresnel(p, cos_o) * metallic);
    let wd = (1.0 - p.metallic) * luminance((vec3<f32>(1.0) - fd) * p.base_color);
    return lobe_prob(ws, wd);
}

fn pbr_pdf(p: PbrParams, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    return ggx_lobes_pdf(pbr_spec_prob(p, dot(n, wo)), p.alpha, n, wo, wi);
}

// The GGX lobe or the cosine one, chosen by pbr_spec_prob; weight = eval / pdf of the
// mixture. A direction under the geometric surface is absorbed.
fn pbr_scatter(p: PbrParams, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
    let side = select(-1.0, 1.0, hit.front_face);
    let n = side * hit.ns;
    let wo = -ray.dir;
    let cos_o = dot(n, wo);
    if (cos_o <= 0.0) {
        return absorbed();
    }
    let wi = sample_ggx_lobes(pbr_spec_prob(p, cos_o), p.alpha, n, wo, u);
    return density_sample(wi, pbr_eval(p, n, wo, wi), pbr_pdf(p, n, wo, wi), side, hit);
}
