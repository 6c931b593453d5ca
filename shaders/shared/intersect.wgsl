// Ray-primitive intersection, one function per primitive type, and the closest-hit search
// that switches on the primitive tag. Every function returns FAR for a miss.
#import shared/bindings
#import shared/sampling
#import shared/types

// Sphere, numerically stable form (Ray Tracing Gems, chapter 7). `dir` is unit length.
// Returns the nearest root in (0, t_max), else FAR.
fn intersect_sphere(center: vec3<f32>, radius: f32, ray: Ray, t_max: f32) -> f32 {
    let f = ray.origin - center;
    let b = dot(f, ray.dir);
    let perp = f - b * ray.dir;
    let r2 = radius * radius;
    let disc = r2 - dot(perp, perp);
    if (disc < 0.0) {
        return FAR;
    }
    let c = dot(f, f) - r2;
    let q = -b - select(-1.0, 1.0, b >= 0.0) * sqrt(disc);
    if (q == 0.0) {
        return FAR;
    }
    let t0 = min(c / q, q);
    let t1 = max(c / q, q);
    if (t0 > 0.0 && t0 < t_max) {
        return t0;
    }
    if (t1 > 0.0 && t1 < t_max) {
        return t1;
    }
    return FAR;
}

// Triangle (Moeller-Trumbore). Returns (t, b1, b2): distance and the barycentric weights of
// v1 and v2; t = FAR on a miss or outside (0, t_max). Both sides are hit.
fn intersect_triangle(v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>, ray: Ray, t_max: f32) -> vec3<f32> {
    let e1 = v1 - v0;
    let e2 = v2 - v0;
    let pv = cross(ray.dir, e2);
    let det = dot(e1, pv);
    if (det == 0.0) {
        return vec3<f32>(FAR, 0.0, 0.0);
    }
    let inv_det = 1.0 / det;
    let tv = ray.origin - v0;
    let b1 = dot(tv, pv) * inv_det;
    if (b1 < 0.0 || b1 > 1.0) {
        return vec3<f32>(FAR, 0.0, 0.0);
    }
    let qv = cross(tv, e1);
    let b2 = dot(ray.dir, qv) * inv_det;
    if (b2 < 0.0 || b1 + b2 > 1.0) {
        return vec3<f32>(FAR, 0.0, 0.0);
    }
    let t = dot(e2, qv) * inv_det;
    if (t <= 0.0 || t >= t_max) {
        return vec3<f32>(FAR, 0.0, 0.0);
    }
    return vec3<f32>(t, b1, b2);
}

// Closest hit along the ray among all primitives.
fn intersect_scene(ray: Ray) -> Candidate {
    var best = Candidate(FAR, NO_HIT, 0.0, 0.0);
    for (var i = 0u; i < params.num_primitives; i++) {
        let prim = primitives[i];
        switch prim.tag {
            case PRIM_SPHERE: {
                let t = intersect_sphere(prim.a.xyz, prim.a.w, ray, best.t);
                if (t < best.t) {
                    best = Candidate(t, i, 0.0, 0.0);
                }
            }
            case PRIM_TRIANGLE: {
                let h = intersect_triangle(prim.a.xyz, prim.b.xyz, prim.c.xyz, ray, best.t);
                if (h.x < best.t) {
                    best = Candidate(h.x, i, h.y, h.z);
                }
            }
            default: {}
        }
    }
    return best;
}

// Shading record of a candidate hit: the point is recomputed from the primitive (re-projected
// onto the sphere, barycentric on the triangle), which keeps it on the surface to within a
// few ulps whatever the distance travelled.
// The error bound grows with the magnitudes that formed p: center and radius for spheres
// (about 16 ulps), the vertices for triangles (about 8 ulps).
fn surface_at(ray: Ray, cand: Candidate) -> Hit {
    let prim = primitives[cand.prim];
    var p = vec3<f32>(0.0);
    var ng = vec3<f32>(0.0, 0.0, 1.0);
    var err = 0.0;
    switch prim.tag {
        case PRIM_SPHERE: {
            let center = prim.a.xyz;
            let radius = prim.a.w;
            ng = normalize(ray.origin + cand.t * ray.dir - center);
            p = center + radius * ng;
            err = (max_abs(center) + radius) * (1.0 / 1048576.0);
        }
        case PRIM_TRIANGLE: {
            let v0 = prim.a.xyz;
            let v1 = prim.b.xyz;
            let v2 = prim.c.xyz;
            p = (1.0 - cand.u - cand.v) * v0 + cand.u * v1 + cand.v * v2;
            ng = normalize(cross(v1 - v0, v2 - v0));
            err = max(max_abs(v0), max(max_abs(v1), max_abs(v2))) * (1.0 / 2097152.0);
        }
        default: {}
    }
    return Hit(p, ng, dot(ray.dir, ng) < 0.0, prim.material, err);
}
