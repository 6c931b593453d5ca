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

pub fn scatter(mat: &Material, _ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
    match mat.tag {
        MAT_LAMBERTIAN => scatter_lambertian(mat, hit, u),
        // emissive and unknown materials absorb
        _ => ABSORBED,
    }
}
