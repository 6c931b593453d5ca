// Materials: emission and scattering, dispatched by a switch on the material tag.
#import shared/sampling
#import shared/types

struct Scatter {
    // false: the path ends here (absorbed)
    ok: bool,
    dir: vec3<f32>,
    // BSDF * cos / pdf of the sampled direction
    weight: vec3<f32>,
}

// Radiance the surface emits toward the ray that hit it.
fn emitted(mat: Material, hit: Hit) -> vec3<f32> {
    if (hit.front_face || (mat.flags & MAT_FLAG_TWO_SIDED) != 0u) {
        return mat.emission.rgb;
    }
    return vec3<f32>(0.0);
}

// Lambertian: cosine-weighted about the shading normal on the side the ray came from, so
// either side of a surface scatters; weight = albedo exactly. A direction that an
// interpolated normal tilts under the geometric surface ends the path.
fn scatter_lambertian(mat: Material, hit: Hit, u: vec2<f32>) -> Scatter {
    let side = select(-1.0, 1.0, hit.front_face);
    let dir = sample_cosine_hemisphere(side * hit.ns, u);
    if (side * dot(dir, hit.ng) <= 0.0) {
        return Scatter(false, vec3<f32>(0.0), vec3<f32>(0.0));
    }
    return Scatter(true, dir, mat.albedo.rgb);
}

fn scatter(mat: Material, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
    switch mat.tag {
        case MAT_LAMBERTIAN: {
            return scatter_lambertian(mat, hit, u);
        }
        default: {
            // emissive and unknown materials absorb
            return Scatter(false, vec3<f32>(0.0), vec3<f32>(0.0));
        }
    }
}
