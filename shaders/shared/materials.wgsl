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

// Mirror direction of d about the unit normal n: d - 2 (d . n) n.
fn reflect_dir(d: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return d - 2.0 * dot(d, n) * n;
}

// Metal: the mirror direction about the shading normal, perturbed by fuzz x a uniform unit
// vector; weight = albedo. A direction under the geometric surface (or a perturbation that
// cancels the reflection) is absorbed.
fn scatter_metal(mat: Material, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
    let side = select(-1.0, 1.0, hit.front_face);
    let v = reflect_dir(ray.dir, side * hit.ns) + mat.params.x * sample_sphere(u);
    let len = length(v);
    if (!(len > 0.0) || side * dot(v, hit.ng) <= 0.0) {
        return Scatter(false, vec3<f32>(0.0), vec3<f32>(0.0));
    }
    return Scatter(true, v / len, mat.albedo.rgb);
}

// Schlick's approximation of the Fresnel reflectance at cosine c between media of relative
// index eta: R0 + (1 - R0)(1 - c)^5, R0 = ((1 - eta) / (1 + eta))^2.
fn schlick(c: f32, eta: f32) -> f32 {
    let r = (1.0 - eta) / (1.0 + eta);
    let r0 = r * r;
    let m = 1.0 - c;
    return r0 + (1.0 - r0) * m * m * m * m * m;
}

// Dielectric: eta = eta_i / eta_t (1 / ior entering, ior leaving, the normal turned toward
// the incoming ray). Snell's law in vector form, t = eta d + (eta cos_i - cos_t) n; total
// internal reflection when eta^2 sin^2(theta_i) >= 1; otherwise reflection with Schlick's
// probability, evaluated with the cosine on the less dense side. Weight = tint, times the
// Beer-Lambert transmittance exp(-absorption x distance) for a segment that ran inside.
fn scatter_dielectric(mat: Material, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
    let entering = hit.front_face;
    let n = select(-hit.ns, hit.ns, entering);
    let eta = select(mat.params.x, 1.0 / mat.params.x, entering);
    let cos_i = clamp(-dot(ray.dir, n), 0.0, 1.0);
    let sin2_t = eta * eta * max(0.0, 1.0 - cos_i * cos_i);
    var weight = mat.albedo.rgb;
    if (!entering) {
        weight *= exp(-mat.extra.rgb * length(hit.p - ray.origin));
    }
    if (sin2_t >= 1.0) {
        return Scatter(true, reflect_dir(ray.dir, n), weight);
    }
    let cos_t = sqrt(1.0 - sin2_t);
    if (u.x < schlick(select(cos_i, cos_t, eta > 1.0), eta)) {
        return Scatter(true, reflect_dir(ray.dir, n), weight);
    }
    return Scatter(true, normalize(eta * ray.dir + (eta * cos_i - cos_t) * n), weight);
}

fn scatter(mat: Material, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter {
    switch mat.tag {
        case MAT_LAMBERTIAN: {
            return scatter_lambertian(mat, hit, u);
        }
        case MAT_METAL: {
            return scatter_metal(mat, ray, hit, u);
        }
        case MAT_DIELECTRIC: {
            return scatter_dielectric(mat, ray, hit, u);
        }
        default: {
            // emissive and unknown materials absorb
            return Scatter(false, vec3<f32>(0.0), vec3<f32>(0.0));
        }
    }
}
