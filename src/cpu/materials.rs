//! Mirrors `shaders/shared/materials.wgsl`.

use glam::Vec3;

use super::sampling::{sample_cosine_hemisphere, sample_sphere};
use super::types::{xyz, Hit, Ray};
use crate::scene::records::{
    Material, MAT_DIELECTRIC, MAT_FLAG_TWO_SIDED, MAT_LAMBERTIAN, MAT_METAL,
};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scatter {
    /// false: the path ends here (absorbed).
    pub ok: bool,
    pub dir: Vec3,
    /// BSDF * cos / pdf of the sampled direction.
    pub weight: Vec3,
}

/// Radiance the surface emits toward the ray that hit it.
pub fn emitted(mat: &Material, hit: &Hit) -> Vec3 {
    if hit.front_face || (mat.flags & MAT_FLAG_TWO_SIDED) != 0 {
        xyz(mat.emission)
    } else {
        Vec3::ZERO
    }
}

/// Lambertian: cosine-weighted about the shading normal on the side the ray came from; a
/// direction under the geometric surface ends the path.
pub fn scatter_lambertian(mat: &Material, hit: &Hit, u: [f32; 2]) -> Scatter {
    let side = if hit.front_face { 1.0 } else { -1.0 };
    let dir = sample_cosine_hemisphere(side * hit.ns, u);
    if side * dir.dot(hit.ng) <= 0.0 {
        return ABSORBED;
    }
    Scatter {
        ok: true,
        dir,
        weight: xyz(mat.albedo),
    }
}

/// The path ends here.
const ABSORBED: Scatter = Scatter {
    ok: false,
    dir: Vec3::ZERO,
    weight: Vec3::ZERO,
};

/// Mirror direction of d about the unit normal n.
#[inline]
pub fn reflect_dir(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Metal: mirror direction perturbed by fuzz x a uniform unit vector; weight = albedo.
pub fn scatter_metal(mat: &Material, ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
    let side = if hit.front_face { 1.0 } else { -1.0 };
    let v = reflect_dir(ray.dir, side * hit.ns) + mat.params[0] * sample_sphere(u);
    let len = v.length();
    // Written as in WGSL, so a NaN length takes the same branch on both backends.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(len > 0.0) || side * v.dot(hit.ng) <= 0.0 {
        return ABSORBED;
    }
    Scatter {
        ok: true,
        dir: v / len,
        weight: xyz(mat.albedo),
    }
}

/// Schlick's Fresnel reflectance at cosine c for relative index eta.
#[inline]
pub fn schlick(c: f32, eta: f32) -> f32 {
    let r = (1.0 - eta) / (1.0 + eta);
    let r0 = r * r;
    let m = 1.0 - c;
    r0 + (1.0 - r0) * m * m * m * m * m
}

/// Dielectric: Snell refraction, total internal reflection, Schlick's Fresnel choice, tint
/// and Beer-Lambert absorption inside.
pub fn scatter_dielectric(mat: &Material, ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
    let entering = hit.front_face;
    let n = if entering { hit.ns } else { -hit.ns };
    let eta = if entering {
        1.0 / mat.params[0]
    } else {
        mat.params[0]
    };
    let cos_i = (-ray.dir.dot(n)).clamp(0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    let mut weight = xyz(mat.albedo);
    if !entering {
        weight *= (-xyz(mat.extra) * (hit.p - ray.origin).length()).exp();
    }
    let reflected = Scatter {
        ok: true,
        dir: reflect_dir(ray.dir, n),
        weight,
    };
    if sin2_t >= 1.0 {
        return reflected;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    if u[0] < schlick(if eta > 1.0 { cos_t } else { cos_i }, eta) {
        return reflected;
    }
    Scatter {
        ok: true,
        dir: (eta * ray.dir + (eta * cos_i - cos_t) * n).normalize(),
        weight,
    }
}

pub fn scatter(mat: &Material, ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
    match mat.tag {
        MAT_LAMBERTIAN => scatter_lambertian(mat, hit, u),
        MAT_METAL => scatter_metal(mat, ray, hit, u),
        MAT_DIELECTRIC => scatter_dielectric(mat, ray, hit, u),
        // emissive and unknown materials absorb
        _ => ABSORBED,
    }
}
