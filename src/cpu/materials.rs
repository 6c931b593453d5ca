//! Mirrors `shaders/shared/materials.wgsl`.

use glam::Vec3;

use super::sampling::sample_cosine_hemisphere;
use super::types::{xyz, Hit, Ray};
use crate::scene::records::{Material, MAT_FLAG_TWO_SIDED, MAT_LAMBERTIAN};

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

/// Lambertian: cosine-weighted about the normal on the side the ray came from.
pub fn scatter_lambertian(mat: &Material, hit: &Hit, u: [f32; 2]) -> Scatter {
    let n = if hit.front_face { hit.ng } else { -hit.ng };
    Scatter {
        ok: true,
        dir: sample_cosine_hemisphere(n, u),
        weight: xyz(mat.albedo),
    }
}

pub fn scatter(mat: &Material, _ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
    match mat.tag {
        MAT_LAMBERTIAN => scatter_lambertian(mat, hit, u),
        // emissive and unknown materials absorb
        _ => Scatter {
            ok: false,
            dir: Vec3::ZERO,
            weight: Vec3::ZERO,
        },
    }
}
