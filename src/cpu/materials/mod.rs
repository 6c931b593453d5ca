//! Mirrors `shaders/shared/materials.wgsl` and the dispatch `gpu::codegen` writes for it
//! (`generated/materials`): a material at a hit (its textures looked up), what it emits,
//! the integrator's questions, and scattering, BSDF and pdf by the material's type. One
//! file per material beside this one mirrors `shaders/materials/NAME.wgsl`; the dispatch
//! below is written from the type list (`scene::materials::for_each_material!`).

pub mod blend;
pub mod conductor;
pub mod dielectric;
pub mod emissive;
pub mod lambertian;
pub mod metal;
pub mod microfacet;
pub mod null;
pub mod pbr;
pub mod plastic;
pub mod principled;
pub mod thin_dielectric;

use glam::Vec3;

use super::bindings::Bindings;
use super::bsdf::{luminance, mirrored, Scatter, Shading, ABSORBED};
use super::textures::{bump_normal, map_normal, texture_alpha, texture_at};
use super::types::{Hit, Ray};
use crate::scene::materials::common::Surface;
use crate::scene::materials::{for_each_material, MaterialKind};
use crate::scene::records::{
    Material, MAT_BLACK, MAT_FLAG_ALPHA_BLEND, MAT_FLAG_ALPHA_MASK, MAT_FLAG_ANISOTROPIC,
    MAT_FLAG_BUMP, MAT_FLAG_COLOR2_CLAMPED, MAT_FLAG_DELTA, MAT_FLAG_NEE, MAT_FLAG_ONE_SIDED,
    MAT_FLAG_OPACITY_TEXTURE, MAT_FLAG_OWN_COLORS, MAT_FLAG_STRICT_SHADING, MAT_FLAG_STRICT_VIEW,
    MAT_FLAG_TRANSMITS, MAT_FLAG_TWO_SIDED, MAT_FLAG_UV_NORMAL_MAP, NO_TEXTURE, SHADING_LIFT,
};

macro_rules! dispatch {
    ($( $(#[$doc:meta])* $kind:ident = $tag:literal, $module:ident, $define:literal; )*) => {
        /// Scattering by the material's type (the shaders' generated `scatter`); an
        /// unknown type absorbs.
        pub fn scatter(mat: &Material, ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
            match MaterialKind::from_tag(mat.tag) {
                $( Some(MaterialKind::$kind) => {
                    crate::scene::materials::$module::Params::read(mat).scatter(ray, hit, u)
                } )*
                None => ABSORBED,
            }
        }

        /// BSDF x cos of the material's type for unit wo and wi about the unit normal n
        /// on wo's side (the generated `material_eval`).
        pub fn material_eval(mat: &Material, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
            match MaterialKind::from_tag(mat.tag) {
                $( Some(MaterialKind::$kind) => {
                    crate::scene::materials::$module::Params::read(mat).eval(n, wo, wi)
                } )*
                None => Vec3::ZERO,
            }
        }

        /// The density of the material's sampling (the generated `material_pdf`).
        pub fn material_pdf(mat: &Material, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
            match MaterialKind::from_tag(mat.tag) {
                $( Some(MaterialKind::$kind) => {
                    crate::scene::materials::$module::Params::read(mat).pdf(n, wo, wi)
                } )*
                None => 0.0,
            }
        }

        /// The look-ups of the material's own textures (the generated
        /// `material_textures`; a material without any is kept as it is).
        pub fn material_textures(b: &Bindings, mat: &Material, hit: &Hit) -> Material {
            let mut record = *mat;
            match MaterialKind::from_tag(mat.tag) {
                $( Some(MaterialKind::$kind) => {
                    crate::scene::materials::$module::Params::read(mat)
                        .textures(b, hit)
                        .write(&mut record)
                } )*
                None => {}
            }
            record
        }
    };
}

for_each_material!(dispatch);

/// Radiance the surface emits toward the ray that hit it.
pub fn emitted(mat: &Material, hit: &Hit) -> Vec3 {
    if hit.front_face || (mat.flags & MAT_FLAG_TWO_SIDED) != 0 {
        Surface::read(mat).emission
    } else {
        Vec3::ZERO
    }
}

/// The material at a hit with its textured colours looked up (the record's rules:
/// `color` clamped to 1, `color2` where `MAT_FLAG_COLOR2_CLAMPED` says, `emission` as it
/// is), then its own textures; the vertex colour multiplies `color` (at most 1). The
/// back of a one-sided surface is black (`MAT_BLACK`).
pub fn material_at(b: &Bindings, m: &Material, hit: &Hit) -> Material {
    let mut mat = *m;
    // which side the hit is on, for a material whose eval needs it (rough glass's eta)
    mat.normal2[3] = if hit.front_face { 0.0 } else { 1.0 };
    // an anisotropic roughness's frame follows the hit's tangent, or taken strictly its
    // dp/du, as Mitsuba's frames do
    if mat.flags & MAT_FLAG_ANISOTROPIC != 0 {
        let t = if mat.flags & MAT_FLAG_STRICT_SHADING != 0 {
            hit.dpdu
        } else {
            hit.tangent.truncate()
        };
        mat.normal2 = t.extend(mat.normal2[3]).to_array();
    }
    // the .w of each colour is a scalar of its own
    if mat.tex_color != NO_TEXTURE {
        mat.color = texture_at(b, mat.tex_color, hit)
            .min(Vec3::ONE)
            .extend(mat.color[3])
            .to_array();
    }
    if mat.tex_color2 != NO_TEXTURE {
        let c = texture_at(b, mat.tex_color2, hit);
        let c = if mat.flags & MAT_FLAG_COLOR2_CLAMPED != 0 {
            c.min(Vec3::ONE)
        } else {
            c
        };
        mat.color2 = c.extend(mat.color2[3]).to_array();
    }
    if mat.tex_emission != NO_TEXTURE {
        mat.emission = texture_at(b, mat.tex_emission, hit)
            .extend(mat.emission[3])
            .to_array();
    }
    let mut mat = material_textures(b, &mat, hit);
    // the vertex colours tint the colour, unless the material reads them itself
    if mat.flags & MAT_FLAG_OWN_COLORS == 0 {
        let c = (Vec3::from_slice(&mat.color[..3]) * hit.color.truncate()).min(Vec3::ONE);
        mat.color = c.extend(mat.color[3]).to_array();
    }
    // the back of a one-sided surface absorbs (it still emits as its flags say)
    if mat.flags & MAT_FLAG_ONE_SIDED != 0 && !hit.front_face {
        mat.tag = MAT_BLACK;
        mat.flags &= !(MAT_FLAG_NEE | MAT_FLAG_DELTA);
    }
    mat
}

/// The hit with its shading normal from the surface's normal map (in the frame of the
/// vertex tangents, or of dp/du with `MAT_FLAG_UV_NORMAL_MAP`) or bump map
/// (materials.wgsl's `normal_mapped`).
pub fn normal_mapped(b: &Bindings, mat: &Material, hit: &Hit) -> Hit {
    let mut h = *hit;
    let s = Surface::read(mat);
    if s.normal_texture != NO_TEXTURE {
        h.ns = if mat.flags & MAT_FLAG_BUMP != 0 {
            bump_normal(b, s.normal_texture, s.normal_scale, hit)
        } else if mat.flags & MAT_FLAG_UV_NORMAL_MAP != 0 {
            // Mitsuba's normalmap: the frame of dp/du, not the vertex tangents
            let uv_frame = Hit {
                tangent: hit.dpdu.extend(1.0),
                ..*hit
            };
            map_normal(b, s.normal_texture, s.normal_scale, &uv_frame)
        } else {
            map_normal(b, s.normal_texture, s.normal_scale, hit)
        };
    }
    h
}

/// Whether a ray passes through a hit (materials.wgsl's `transparent_at`): cut out below
/// the cutoff (mask), or transparent when u >= alpha (blend); an opacity texture's
/// luminance multiplies alpha.
pub fn transparent_at(b: &Bindings, hit: &Hit, u: f32) -> bool {
    let m = &b.materials[hit.material as usize];
    if m.flags & (MAT_FLAG_ALPHA_MASK | MAT_FLAG_ALPHA_BLEND) == 0 {
        return false;
    }
    let s = Surface::read(m);
    let mut alpha = s.opacity * hit.color.w;
    if m.tex_color != NO_TEXTURE {
        alpha *= texture_alpha(b, m.tex_color, hit.uv);
    }
    if m.flags & MAT_FLAG_OPACITY_TEXTURE != 0 {
        alpha *= luminance(texture_at(b, s.opacity_texture, hit));
    }
    if m.flags & MAT_FLAG_ALPHA_MASK != 0 {
        return alpha < s.alpha_cutoff;
    }
    u >= alpha
}

/// The uniform number of the k-th surface a ray meets (materials.wgsl's `alpha_u`): u for
/// the first, then u's bits hashed with k, independent from surface to surface.
pub fn alpha_u(u: f32, k: u32) -> f32 {
    if k == 0 {
        return u;
    }
    let h = super::rng::pcg4d([u.to_bits(), k, 0x2545f491, 0x9e3779b9]);
    super::rng::u32_to_unit_float(h[0])
}

/// The hit with its shading normal bent where the viewer's mirror direction about it
/// would come within `SHADING_LIFT` of the geometric surface or under it
/// (materials.wgsl's `bent_normal`, which says why). A material that takes shading
/// normals strictly (`MAT_FLAG_STRICT_SHADING`) is flipped instead: a mapped normal that
/// leaves the viewer on the other side of it than of the unmapped one is mirrored about
/// that (Mitsuba 3's normalmap and bumpmap).
pub fn bent_normal(mat: &Material, hit: &Hit, ray: &Ray) -> Hit {
    let mut h = *hit;
    if mat.flags & MAT_FLAG_STRICT_SHADING != 0 {
        if ray.dir.dot(hit.unmapped) * ray.dir.dot(hit.ns) <= 0.0 {
            h.ns = 2.0 * hit.ns.dot(hit.unmapped) * hit.unmapped - hit.ns;
        }
        return h;
    }
    if hit.ns != hit.ng {
        let side = if hit.front_face { 1.0 } else { -1.0 };
        let ng = side * hit.ng;
        let n = side * hit.ns;
        let wo = -ray.dir;
        let r = 2.0 * wo.dot(n) * n - wo;
        let c = r.dot(ng);
        if c < SHADING_LIFT {
            let lifted = (r + (SHADING_LIFT - c) * ng).normalize();
            h.ns = side * (wo + lifted).normalize();
        }
    }
    h
}

/// Whether shading normals send the material's directions over the geometric surface
/// (materials.wgsl's `folds`): not for a material that transmits or takes them strictly.
pub fn folds(mat: &Material, hit: &Hit) -> bool {
    hit.ns != hit.ng && mat.flags & (MAT_FLAG_TRANSMITS | MAT_FLAG_STRICT_SHADING) == 0
}

/// Where the material takes shading normals strictly and the hit's differs from its
/// geometric one, whether its lobes are black toward wi (materials.wgsl's
/// `strictly_black`): wi on one side of the shading surface and the other of the
/// unmapped or the geometric one, or, with `MAT_FLAG_STRICT_VIEW`, the viewer under the
/// shading normal.
pub fn strictly_black(mat: &Material, ray: &Ray, hit: &Hit, wi: Vec3) -> bool {
    if mat.flags & MAT_FLAG_STRICT_SHADING == 0 || hit.ns == hit.ng {
        return false;
    }
    let side = if hit.front_face { 1.0 } else { -1.0 };
    let viewer_under = mat.flags & MAT_FLAG_STRICT_VIEW != 0 && side * ray.dir.dot(hit.ns) >= 0.0;
    let c = wi.dot(hit.ns);
    viewer_under || wi.dot(hit.unmapped) * c <= 0.0 || wi.dot(hit.ng) * c <= 0.0
}

/// Where the material takes shading normals strictly and a map turned the shading
/// normal, the share of light toward wi the map's bumps shadow (materials.wgsl's
/// `map_shadowing`: Estevez et al. 2019, as Mitsuba 3's normalmap and bumpmap); else 1.
pub fn map_shadowing(mat: &Material, hit: &Hit, wi: Vec3) -> f32 {
    if mat.flags & MAT_FLAG_STRICT_SHADING == 0 || hit.ns == hit.unmapped {
        return 1.0;
    }
    let cn = hit.ns.dot(hit.unmapped);
    let a2 = (0.125 * (1.0 - cn * cn).max(0.0) / (cn * cn)).min(1.0);
    let ci = wi.dot(hit.unmapped);
    let t2 = (1.0 - ci * ci).max(0.0) / (ci * ci);
    2.0 / (1.0 + (1.0 + a2 * t2).sqrt())
}

/// `scatter` by the material's type, with shading normals taken strictly where its flags
/// say (materials.wgsl's `bsdf_scatter`): its lobes drawn about the shading normal alone,
/// nothing folded over the geometric surface, a direction `strictly_black` absorbed, the
/// weight shadowed by a map's bumps.
pub fn bsdf_scatter(mat: &Material, ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
    if mat.flags & MAT_FLAG_STRICT_SHADING != 0 && hit.ns != hit.ng {
        // the lobes' own tests of the side, and over_surface, read the shading normal
        let shading = Hit { ng: hit.ns, ..*hit };
        let mut s = scatter(mat, ray, &shading, u);
        if s.ok && strictly_black(mat, ray, hit, s.dir) {
            return ABSORBED;
        }
        s.weight *= map_shadowing(mat, hit, s.dir);
        return s;
    }
    scatter(mat, ray, hit, u)
}

/// BSDF x cos toward wi (materials.wgsl's `bsdf_eval`): 0 under the geometric surface
/// (where scatter absorbs), unless the material transmits and the shading normal agrees,
/// and for delta lobes; where shading normals fold, plus what the lobes send to wi's
/// mirror image (which `over_surface` sends to wi). Taken strictly: black where
/// `strictly_black` says, shadowed by a map's bumps (`map_shadowing`).
pub fn bsdf_eval(mat: &Material, ray: &Ray, hit: &Hit, wi: Vec3) -> Vec3 {
    if strictly_black(mat, ray, hit, wi) {
        return Vec3::ZERO;
    }
    let side = if hit.front_face { 1.0 } else { -1.0 };
    let transmits = mat.flags & MAT_FLAG_TRANSMITS != 0;
    if side * wi.dot(hit.ng) <= 0.0 {
        if !transmits || side * wi.dot(hit.ns) >= 0.0 {
            return Vec3::ZERO;
        }
        return material_eval(mat, side * hit.ns, -ray.dir, wi) * map_shadowing(mat, hit, wi);
    }
    if transmits && side * wi.dot(hit.ns) <= 0.0 {
        return Vec3::ZERO;
    }
    let f = material_eval(mat, side * hit.ns, -ray.dir, wi);
    if folds(mat, hit) {
        return f + material_eval(mat, side * hit.ns, -ray.dir, mirrored(wi, hit));
    }
    f * map_shadowing(mat, hit, wi)
}

/// The density with which scatter draws wi (before it absorbs directions on the wrong
/// side of the geometric surface), plus its mirror image's where shading normals fold.
pub fn bsdf_pdf(mat: &Material, ray: &Ray, hit: &Hit, wi: Vec3) -> f32 {
    let n = if hit.front_face { hit.ns } else { -hit.ns };
    let pdf = material_pdf(mat, n, -ray.dir, wi);
    if folds(mat, hit) {
        return pdf + material_pdf(mat, n, -ray.dir, mirrored(wi, hit));
    }
    pdf
}

/// The density of a scattered direction as MIS weighs it (materials.wgsl's
/// `scatter_pdf`): scatter's own, or `bsdf_pdf`'s where shading normals fold.
pub fn scatter_pdf(mat: &Material, ray: &Ray, hit: &Hit, s: &Scatter) -> f32 {
    if !s.delta && folds(mat, hit) {
        return bsdf_pdf(mat, ray, hit, s.dir);
    }
    s.pdf
}

/// Whether next-event estimation applies: the material has a lobe with a density (its
/// module's answer, in the flags).
pub fn nee_applies(mat: &Material) -> bool {
    mat.flags & MAT_FLAG_NEE != 0
}

/// Whether the 50/50 mixture samples lights: as `nee_applies`, less a material that may
/// sample a delta lobe, which the mixture's pdf cannot hold.
pub fn mixture_applies(mat: &Material) -> bool {
    mat.flags & (MAT_FLAG_NEE | MAT_FLAG_DELTA) == MAT_FLAG_NEE
}
