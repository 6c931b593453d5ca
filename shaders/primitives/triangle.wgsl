// A triangle (scene::primitives::triangle: TriangleParams), with a mesh's vertex
// attributes in shape_data: intersection, surface, uv derivatives, and sampling as a
// light. CPU twin: src/cpu/primitives/triangle.rs.
#import shared/bindings
#import shared/geometry
#import shared/sampling
#import shared/types

// Watertight (Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection", JCGT 2013):
// the vertices are moved into the ray's frame (origin at 0, the dominant axis of the
// direction as z, sheared so that the ray runs along +z) and the 2D edge functions U, V,
// W of the point (0, 0) decide the hit. An edge shared by two triangles gives both the
// same value with opposite signs, and a zero counts as inside, so no ray slips between
// them, whatever the rounding. Returns (t, b1, b2): distance and the barycentric weights
// of v1 and v2; t = FAR on a miss or outside (0, t_max). Both sides are hit.
fn triangle_intersect(p: TriangleParams, ray: Ray, t_max: f32) -> vec3<f32> {
    let d = ray.dir;
    let kz = argmax3(abs(d));
    var kx = (kz + 1u) % 3u;
    var ky = (kx + 1u) % 3u;
    if (d[kz] < 0.0) {
        let k = kx;
        kx = ky;
        ky = k;
    }
    let sz = 1.0 / d[kz];
    let sx = d[kx] * sz;
    let sy = d[ky] * sz;
    let a = p.v0 - ray.origin;
    let b = p.v1 - ray.origin;
    let c = p.v2 - ray.origin;
    let ax = a[kx] - sx * a[kz];
    let ay = a[ky] - sy * a[kz];
    let bx = b[kx] - sx * b[kz];
    let by = b[ky] - sy * b[kz];
    let cx = c[kx] - sx * c[kz];
    let cy = c[ky] - sy * c[kz];
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    // no early return (see sphere_intersect); a division by det = 0 is never picked
    let outside = (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0);
    let det = u + v + w;
    let t = (u * (sz * a[kz]) + v * (sz * b[kz]) + w * (sz * c[kz])) / det;
    let hit = !outside && det != 0.0 && t > 0.0 && t < t_max;
    return select(vec3<f32>(FAR, 0.0, 0.0), vec3<f32>(t, v / det, w / det), hit);
}

// The point from the barycentrics; with attributes, the vertex uvs, the shading normal
// (on the side of ng whatever the file's winding), the tangent, the second uv set and the
// vertex colour. Default vertex uvs (0, 0), (1, 0), (0, 1).
fn triangle_surface(p: TriangleParams, ray: Ray, cand: Candidate) -> Surface {
    var s = blank_surface();
    let v0 = p.v0;
    let v1 = p.v1;
    let v2 = p.v2;
    let w = vec3<f32>(1.0 - cand.u - cand.v, cand.u, cand.v);
    s.p = w.x * v0 + w.y * v1 + w.z * v2;
    s.ng = normalize(cross(v1 - v0, v2 - v0));
    s.ns = s.ng;
    s.uv = vec2<f32>(cand.u, cand.v);
    s.err = max(max_abs(v0), max(max_abs(v1), max_abs(v2))) * (1.0 / 2097152.0);
    if ((p.flags & PRIM_FLAG_ATTRIBUTES) != 0u) {
        let a0 = shape_data[p.data];
        let a1 = shape_data[p.data + 1u];
        let a2 = shape_data[p.data + 2u];
        let a3 = shape_data[p.data + 3u];
        s.uv = w.x * vec2<f32>(a0.w, a3.x) + w.y * vec2<f32>(a1.w, a3.y) + w.z * vec2<f32>(a2.w, a3.z);
        if ((p.flags & PRIM_FLAG_SHADING_NORMALS) != 0u) {
            let n = w.x * a0.xyz + w.y * a1.xyz + w.z * a2.xyz;
            let len = length(n);
            if (len > 0.0) {
                s.ns = n * (select(-1.0, 1.0, dot(n, s.ng) >= 0.0) / len);
            }
        }
#ifdef HAS_NORMAL_MAP
        if ((p.flags & PRIM_FLAG_TANGENTS) != 0u) {
            let t0 = shape_data[p.data + 4u];
            let t1 = shape_data[p.data + 5u];
            let t2 = shape_data[p.data + 6u];
            // normals turned to ng's side turn the bitangent with them
            let nv = w.x * a0.xyz + w.y * a1.xyz + w.z * a2.xyz;
            let turned = (p.flags & PRIM_FLAG_SHADING_NORMALS) != 0u && dot(nv, s.ng) < 0.0;
            s.tangent = vec4<f32>(w.x * t0.xyz + w.y * t1.xyz + w.z * t2.xyz, select(t0.w, -t0.w, turned));
        }
#endif
        // the second uv set and the vertex colours follow the tangents
        var extra = p.data + ATTRIBUTE_ENTRIES + select(0u, TANGENT_ENTRIES, (p.flags & PRIM_FLAG_TANGENTS) != 0u);
#ifdef HAS_UV1
        if ((p.flags & PRIM_FLAG_UV1) != 0u) {
            let u01 = shape_data[extra];
            let u2 = shape_data[extra + 1u];
            s.uv1 = w.x * u01.xy + w.y * u01.zw + w.z * u2.xy;
            extra += UV1_ENTRIES;
        }
#endif
#ifdef HAS_VERTEX_COLORS
        if ((p.flags & PRIM_FLAG_COLORS) != 0u) {
            s.color = w.x * shape_data[extra] + w.y * shape_data[extra + 1u] + w.z * shape_data[extra + 2u];
        }
#endif
    }
    return s;
}

// dp/du and dp/dv of the vertex uvs (its default (0, 0), (1, 0), (0, 1) without them; a
// frame of its normal where they are degenerate).
fn triangle_uv_derivatives(p: TriangleParams, s: Surface, cand: Candidate) -> array<vec3<f32>, 2> {
    var d = onb_tangents(s.ng);
    var uv0 = vec2<f32>(0.0);
    var uv1 = vec2<f32>(1.0, 0.0);
    var uv2 = vec2<f32>(0.0, 1.0);
    if ((p.flags & PRIM_FLAG_ATTRIBUTES) != 0u) {
        let a3 = shape_data[p.data + 3u];
        uv0 = vec2<f32>(shape_data[p.data].w, a3.x);
        uv1 = vec2<f32>(shape_data[p.data + 1u].w, a3.y);
        uv2 = vec2<f32>(shape_data[p.data + 2u].w, a3.z);
    }
    let duv02 = uv0 - uv2;
    let duv12 = uv1 - uv2;
    let dp02 = p.v0 - p.v2;
    let dp12 = p.v1 - p.v2;
    let det = duv02.x * duv12.y - duv02.y * duv12.x;
    if (abs(det) > 1e-12) {
        d[0] = (duv12.y * dp02 - duv02.y * dp12) / det;
        d[1] = (duv02.x * dp12 - duv12.x * dp02) / det;
    }
    return d;
}

// A point uniform by area: u = 1 - sqrt(xi1), v = xi2 sqrt(xi1) weigh vertices v0 and v1;
// its uv the candidate's barycentrics of v1 and v2.
fn triangle_light_sample(p: TriangleParams, area: f32, origin: vec3<f32>, u: vec2<f32>) -> LightPoint {
    let su = sqrt(u.x);
    let wa = 1.0 - su;
    let wb = u.y * su;
    let x = wa * p.v0 + wb * p.v1 + (1.0 - wa - wb) * p.v2;
    let n = normalize(cross(p.v1 - p.v0, p.v2 - p.v0));
    return LightPoint(x, area_pdf(origin, x, n, area), vec2<f32>(wb, 1.0 - wa - wb));
}

// The solid-angle pdf of triangle_light_sample toward x.
fn triangle_light_pdf(p: TriangleParams, area: f32, origin: vec3<f32>, x: vec3<f32>) -> f32 {
    let n = normalize(cross(p.v1 - p.v0, p.v2 - p.v0));
    return area_pdf(origin, x, n, area);
}

// Where the ray from `origin` along unit d meets the triangle (FAR: nowhere).
fn triangle_light_distance(p: TriangleParams, origin: vec3<f32>, d: vec3<f32>) -> f32 {
    return triangle_intersect(p, Ray(origin, d), FAR).x;
}
