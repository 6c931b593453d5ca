//! CPU reference, one primitive at a time: hit distance, normal, side and uv; misses; t-range
//! limits; rays from inside; rays parallel to faces and along axes; transforms; meshes; the
//! BVH against brute force. No GPU (tests/gpu.rs compares the GPU with these functions).

mod common;

use common::shapes::{intersect_box, intersect_cylinder};
use glam::{Vec2, Vec3, Vec4Swizzles};
use wgtrace::cpu::bindings::Bindings;
use wgtrace::cpu::geometry::intersect_plane;
use wgtrace::cpu::intersect::{intersect_scene, surface_at};
use wgtrace::cpu::types::{Candidate, Hit, Ray, FAR, NO_HIT};
use wgtrace::scene::flatten::transform_matrix;
use wgtrace::scene::format::{ScaleDesc, TransformDesc};
use wgtrace::FlatScene;

const HEADER: &str = "[camera]\nlook_from = [0, 0, 10]\nlook_at = [0, 0, 0]\n\
    [materials]\nm = { type = \"lambertian\", albedo = [0.5, 0.5, 0.5] }\n";

/// A scene of the given `[[objects]]` entries (TOML), all of material `m`.
fn scene(objects: &str) -> FlatScene {
    common::scene_from_str(&format!("{HEADER}{objects}"))
}

fn ray(o: impl Into<Vec3>, d: impl Into<Vec3>) -> Ray {
    Ray {
        origin: o.into(),
        dir: d.into().normalize(),
    }
}

/// The closest hit of a ray in a scene (CPU reference), with its shading record.
fn trace(s: &FlatScene, r: Ray) -> Option<(Candidate, Hit)> {
    let b = Bindings::new(s, s.params(0, s.full_band()));
    let c = intersect_scene(&b, &r, FAR);
    (c.prim != NO_HIT).then(|| (c, surface_at(&b, &r, &c)))
}

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol * (1.0 + b.abs())
}

fn close3(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).abs().max_element() <= tol * (1.0 + b.abs().max_element())
}

#[track_caller]
fn assert_hit(s: &FlatScene, r: Ray, t: f32, n: Vec3, front: bool) -> Hit {
    let (c, h) = trace(s, r).unwrap_or_else(|| panic!("{r:?} should hit"));
    assert!(close(c.t, t, 1e-5), "{r:?}: t = {} (want {t})", c.t);
    assert!(close3(h.ng, n, 1e-5), "{r:?}: normal {} (want {n})", h.ng);
    assert_eq!(h.front_face, front, "{r:?}: front_face");
    assert!(
        close3(h.p, r.origin + t * r.dir, 1e-4),
        "{r:?}: p = {}",
        h.p
    );
    assert!(h.uv.xy().is_finite() && h.err.is_finite() && h.err >= 0.0);
    h
}

/// The error message of a scene (named `bad.toml`) holding the given objects.
fn load_error(objects: &str) -> String {
    let src = format!("{HEADER}{objects}");
    match wgtrace::load_scene_str(&src, std::path::Path::new("bad.toml"), &Default::default()) {
        Ok(_) => panic!("the scene should be refused:\n{objects}"),
        Err(e) => e.to_string(),
    }
}

#[track_caller]
fn assert_miss(s: &FlatScene, r: Ray) {
    if let Some((c, _)) = trace(s, r) {
        panic!("{r:?} should miss, hit t = {}", c.t);
    }
}

#[test]
fn plane_hits_both_sides_misses_parallel_and_maps_uv() {
    let s = scene("[[objects]]\ntype = \"plane\"\npoint = [0, -1, 0]\nnormal = [0, 2, 0]\nuv_scale = 0.5\nmaterial = \"m\"\n");
    assert_eq!(s.num_unbounded, 1);
    assert!(s.bvh.is_empty());
    let h = assert_hit(
        &s,
        ray([3.0, 2.0, 4.0], [0.0, -1.0, 0.0]),
        3.0,
        Vec3::Y,
        true,
    );
    // uv = uv_scale x coordinates in the tangent frame: length 0.5 x |(3, 4)| = 2.5
    assert!(close(h.uv.xy().length(), 2.5, 1e-5), "uv {}", h.uv.xy());
    assert_hit(
        &s,
        ray([0.0, -3.0, 0.0], [0.0, 1.0, 0.0]),
        2.0,
        Vec3::Y,
        false,
    );
    // parallel to the plane, above it and inside it: a miss, never a NaN
    assert_miss(&s, ray([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]));
    assert_miss(&s, ray([0.0, -1.0, 0.0], [1.0, 0.0, 1.0]));
    assert_miss(&s, ray([0.0, 0.0, 0.0], [0.0, 1.0, 0.0]));
    let d = Vec3::new(1.0, 0.0, 0.0);
    assert_eq!(
        intersect_plane(Vec3::ZERO, Vec3::Y, &ray([0.0, 1.0, 0.0], d), FAR),
        FAR
    );
    // t-range: a hit at t = 3 is beyond t_max = 2.5
    let r = ray([0.0, 2.0, 0.0], [0.0, -1.0, 0.0]);
    assert_eq!(
        intersect_plane(Vec3::new(0.0, -1.0, 0.0), Vec3::Y, &r, 2.5),
        FAR
    );
    assert_eq!(
        intersect_plane(Vec3::new(0.0, -1.0, 0.0), Vec3::Y, &r, 3.5),
        3.0
    );
}

#[test]
fn box_slab_test_from_outside_inside_and_along_axes() {
    let s = scene(
        "[[objects]]\ntype = \"box\"\nmin = [-1, -2, -3]\nmax = [1, 2, 3]\nmaterial = \"m\"\n",
    );
    // each face from outside, along the axis (two direction components are zero)
    for (axis, half) in [(0, 1.0), (1, 2.0), (2, 3.0)] {
        for sign in [1.0f32, -1.0] {
            let n = Vec3::AXES[axis] * sign;
            let h = assert_hit(&s, ray(n * 10.0, -n), 10.0 - half, n, true);
            assert!(h.uv.xy().cmpge(Vec2::ZERO).all() && h.uv.xy().cmple(Vec2::ONE).all());
            // from the center: leaves through the same face, seen from inside
            assert_hit(&s, ray(Vec3::ZERO, n), half, n, false);
        }
    }
    // a ray in the plane of a face (grazing), parallel to two axes, off the box: a miss
    assert_miss(&s, ray([5.0, 2.5, 0.0], [-1.0, 0.0, 0.0]));
    assert_miss(&s, ray([0.0, 0.0, 10.0], [0.0, 0.0, 1.0]));
    // oblique hit on the x = 1 face and uv of that face: (y, z) scaled to [0, 1]
    let h = assert_hit(
        &s,
        ray([3.0, 1.0, 1.5], [-1.0, 0.0, 0.0]),
        2.0,
        Vec3::X,
        true,
    );
    assert!(
        (h.uv.xy() - Vec2::new(0.75, 0.75)).abs().max_element() < 1e-6,
        "uv {}",
        h.uv.xy()
    );
    // t-range
    let r = ray([5.0, 0.0, 0.0], [-1.0, 0.0, 0.0]);
    assert_eq!(intersect_box(Vec3::splat(-1.0), Vec3::ONE, &r, 3.9).x, FAR);
    assert_eq!(intersect_box(Vec3::splat(-1.0), Vec3::ONE, &r, 4.1).x, 4.0);
}

#[test]
fn sphere_normal_side_and_longitude_latitude_uv() {
    let s =
        scene("[[objects]]\ntype = \"sphere\"\ncenter = [1, 2, 3]\nradius = 2\nmaterial = \"m\"\n");
    let c = Vec3::new(1.0, 2.0, 3.0);
    let h = assert_hit(
        &s,
        ray(c + Vec3::new(0.0, 10.0, 0.0), [0.0, -1.0, 0.0]),
        8.0,
        Vec3::Y,
        true,
    );
    assert!(
        close(h.uv.xy().y, 1.0, 1e-6),
        "north pole v = {}",
        h.uv.xy().y
    );
    let h = assert_hit(
        &s,
        ray(c + Vec3::new(10.0, 0.0, 0.0), [-1.0, 0.0, 0.0]),
        8.0,
        Vec3::X,
        true,
    );
    assert!(
        close(h.uv.xy().x, 0.5, 1e-6) && close(h.uv.xy().y, 0.5, 1e-6),
        "uv {}",
        h.uv.xy()
    );
    let h = assert_hit(&s, ray(c, [0.0, 0.0, -1.0]), 2.0, -Vec3::Z, false);
    assert!(close(h.uv.xy().x, 0.75, 1e-6), "u at -z = {}", h.uv.xy().x);
    assert_miss(&s, ray(c + Vec3::new(2.01, 0.0, 10.0), [0.0, 0.0, -1.0]));
}

#[test]
fn triangle_uvs_interpolate_vertex_uvs_or_default_to_barycentrics() {
    let tri = "[[objects]]\ntype = \"triangle\"\nvertices = [[0, 0, 0], [2, 0, 0], [0, 2, 0]]\nmaterial = \"m\"\n";
    let h = assert_hit(
        &scene(tri),
        ray([0.5, 0.5, 5.0], [0.0, 0.0, -1.0]),
        5.0,
        Vec3::Z,
        true,
    );
    assert!(
        (h.uv.xy() - Vec2::new(0.25, 0.25)).abs().max_element() < 1e-6,
        "{}",
        h.uv.xy()
    );
    let with_uvs = tri.replace("material", "uvs = [[1, 1], [0, 1], [1, 0]]\nmaterial");
    let h = assert_hit(
        &scene(&with_uvs),
        ray([0.5, 0.5, -5.0], [0.0, 0.0, 1.0]),
        5.0,
        Vec3::Z,
        false,
    );
    // weights (0.5, 0.25, 0.25) of (1, 1), (0, 1), (1, 0)
    assert!(
        (h.uv.xy() - Vec2::new(0.75, 0.75)).abs().max_element() < 1e-6,
        "{}",
        h.uv.xy()
    );
}

#[test]
fn polygon_uvs_are_planar() {
    let s = scene("[[objects]]\ntype = \"polygon\"\nvertices = [[0, 0, 0], [4, 0, 0], [4, 2, 0], [0, 2, 0]]\nmaterial = \"m\"\n");
    for (x, y) in [(1.0, 0.5), (3.0, 1.5), (3.9, 0.1)] {
        let h = assert_hit(&s, ray([x, y, 3.0], [0.0, 0.0, -1.0]), 3.0, Vec3::Z, true);
        assert!(
            (h.uv.xy() - Vec2::new(x, y)).abs().max_element() < 1e-5,
            "{} at ({x}, {y})",
            h.uv.xy()
        );
    }
}

#[test]
fn tetrahedron_faces_point_outward() {
    let s = scene("[[objects]]\ntype = \"tetrahedron\"\nvertices = [[0, 0, 0], [0, 1, 0], [1, 0, 0], [0, 0, 1]]\nmaterial = \"m\"\n");
    assert_eq!(s.primitives.len(), 4);
    let centroid = Vec3::splat(0.25);
    let mut rng = 1u32;
    for _ in 0..500 {
        let d = common::random_unit(&mut rng);
        // from outside toward the centroid: a front face whose normal points out
        let (_, h) = trace(&s, ray(centroid + 5.0 * d, -d)).expect("hits");
        assert!(h.front_face && h.ng.dot(h.p - centroid) > 0.0);
        // from inside: a back face
        let (_, h) = trace(&s, ray(centroid, d)).expect("hits from inside");
        assert!(!h.front_face && h.ng.dot(h.p - centroid) > 0.0);
    }
}

#[test]
fn cylinder_side_caps_axis_rays_inside_rays_and_uv() {
    let capped = "[[objects]]\ntype = \"cylinder\"\nbase = [0, -1, 0]\ntop = [0, 1, 0]\nradius = 0.5\nmaterial = \"m\"\n";
    let s = scene(capped);
    let h = assert_hit(
        &s,
        ray([5.0, 0.5, 0.0], [-1.0, 0.0, 0.0]),
        4.5,
        Vec3::X,
        true,
    );
    assert!(close(h.uv.xy().y, 0.75, 1e-5), "height v = {}", h.uv.xy().y);
    // along the axis: the caps
    assert_hit(
        &s,
        ray([0.0, -5.0, 0.0], [0.0, 1.0, 0.0]),
        4.0,
        -Vec3::Y,
        true,
    );
    let h = assert_hit(
        &s,
        ray([0.2, 5.0, 0.0], [0.0, -1.0, 0.0]),
        4.0,
        Vec3::Y,
        true,
    );
    assert!(
        close(h.uv.xy().y, 0.4, 1e-5),
        "cap radius v = {}",
        h.uv.xy().y
    );
    // from inside: the side and the caps from the back
    assert_hit(
        &s,
        ray([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        0.5,
        Vec3::Z,
        false,
    );
    assert_hit(
        &s,
        ray([0.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        1.0,
        Vec3::Y,
        false,
    );
    // beyond the height, and outside the radius
    assert_miss(&s, ray([5.0, 1.2, 0.0], [-1.0, 0.0, 0.0]));
    assert_miss(&s, ray([0.6, -5.0, 0.0], [0.0, 1.0, 0.0]));
    // open: rays along the axis pass through; from inside, the side is seen from the back
    let open = scene(&capped.replace("material", "caps = false\nmaterial"));
    assert_miss(&open, ray([0.0, -5.0, 0.0], [0.0, 1.0, 0.0]));
    let h = assert_hit(
        &open,
        ray([0.0, -0.5, 0.0], [0.0, 1.0, 1.0]),
        0.5 * 2f32.sqrt(),
        Vec3::Z,
        false,
    );
    assert!(close(h.uv.xy().y, 0.5, 1e-5));
    // a tilted axis: the side normal is perpendicular to the axis
    let tilted = scene("[[objects]]\ntype = \"cylinder\"\nbase = [0, 0, 0]\ntop = [1, 1, 1]\nradius = 0.25\nmaterial = \"m\"\n");
    let (_, h) = trace(&tilted, ray([0.5, 0.5, 5.0], [0.0, 0.0, -1.0])).expect("hits");
    assert!(h.ng.dot(Vec3::ONE).abs() < 1e-5 && h.front_face);
    let direct = intersect_cylinder(
        Vec3::ZERO,
        Vec3::Y,
        1.0,
        false,
        &ray([0.0, 0.5, 0.0], [0.0, 1.0, 0.0]),
        FAR,
    );
    assert_eq!(direct.x, FAR, "a ray along the axis of an open cylinder");
}

#[test]
fn disk_in_any_orientation_with_polar_uv() {
    let s = scene("[[objects]]\ntype = \"disk\"\ncenter = [1, 1, 1]\nnormal = [1, 1, 0]\nradius = 2\nmaterial = \"m\"\n");
    let n = Vec3::new(1.0, 1.0, 0.0).normalize();
    let c = Vec3::ONE;
    let h = assert_hit(&s, ray(c + 3.0 * n, -n), 3.0, n, true);
    assert!(h.uv.xy().y.abs() < 1e-5, "center v = {}", h.uv.xy().y);
    let h = assert_hit(
        &s,
        ray(c + Vec3::new(0.0, 0.0, 1.0) - 3.0 * n, n),
        3.0,
        n,
        false,
    );
    assert!(close(h.uv.xy().y, 0.5, 1e-5), "v = {}", h.uv.xy().y);
    assert_miss(&s, ray(c + Vec3::new(0.0, 0.0, 2.1) + 3.0 * n, -n));
    // in the disk's plane: parallel, a miss
    assert_miss(&s, ray(c - 5.0 * Vec3::Z, Vec3::Z));
}

#[test]
fn transform_order_is_scale_rotate_xyz_translate() {
    let t = TransformDesc {
        scale: Some(ScaleDesc::Axes([2.0, 1.0, 1.0])),
        rotate: [90.0, 0.0, 0.0],
        translate: [0.0, 0.0, 5.0],
        matrix: None,
    };
    let m = transform_matrix(&t);
    // +Y turns to +Z about X; scale acts first, translation last
    assert!(close3(
        m.transform_point3(Vec3::Y),
        Vec3::new(0.0, 0.0, 6.0),
        1e-6
    ));
    assert!(close3(
        m.transform_point3(Vec3::X),
        Vec3::new(2.0, 0.0, 5.0),
        1e-6
    ));
    let r = transform_matrix(&TransformDesc {
        rotate: [90.0, 90.0, 0.0],
        ..Default::default()
    });
    // X first: Y -> Z; then Y: Z -> X
    assert!(close3(r.transform_point3(Vec3::Y), Vec3::X, 1e-6));
}

#[test]
fn transformed_analytic_shapes_are_exact() {
    // an ellipsoid: unit sphere scaled (2, 1, 0.5), rotated 90 degrees about Z, moved
    let s = scene("[[objects]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\ntransform = { scale = [2, 1, 0.5], rotate = [0, 0, 90], translate = [0, 0, -1] }\n");
    assert_ne!(
        s.primitives[0].flags & wgtrace::scene::records::PRIM_FLAG_TRANSFORM,
        0
    );
    // semi-axes after rotation: 2 along Y, 1 along X, 0.5 along Z
    assert_hit(
        &s,
        ray([0.0, 10.0, -1.0], [0.0, -1.0, 0.0]),
        8.0,
        Vec3::Y,
        true,
    );
    assert_hit(
        &s,
        ray([10.0, 0.0, -1.0], [-1.0, 0.0, 0.0]),
        9.0,
        Vec3::X,
        true,
    );
    assert_hit(
        &s,
        ray([0.0, 0.0, 10.0], [0.0, 0.0, -1.0]),
        10.5,
        Vec3::Z,
        true,
    );
    assert_hit(
        &s,
        ray([0.0, 0.0, -1.0], [0.0, 0.0, 1.0]),
        0.5,
        Vec3::Z,
        false,
    );
    // the normal at any hit is the normalized gradient of x^2 + y^2 / 4 + 4 z^2
    let mut rng = 7u32;
    for _ in 0..200 {
        let d = common::random_unit(&mut rng);
        let (_, h) = trace(&s, ray(Vec3::new(0.0, 0.0, -1.0) + 6.0 * d, -d)).expect("hits");
        let q = h.p - Vec3::new(0.0, 0.0, -1.0);
        assert!(
            close(q.x * q.x + q.y * q.y / 4.0 + 4.0 * q.z * q.z, 1.0, 1e-4),
            "{q} off the surface"
        );
        let grad = Vec3::new(q.x, q.y / 4.0, 4.0 * q.z).normalize();
        assert!(
            h.ng.dot(grad) > 0.99999,
            "normal {} vs gradient {grad}",
            h.ng
        );
    }
    // a cube turned 45 degrees about Y: its edge faces +Z at distance sqrt(2) / 2
    let s = scene("[[objects]]\ntype = \"box\"\nmin = [-0.5, -0.5, -0.5]\nmax = [0.5, 0.5, 0.5]\nmaterial = \"m\"\ntransform = { rotate = [0, 45, 0] }\n");
    let r2 = 0.5 * 2f32.sqrt();
    let (c, h) = trace(&s, ray([0.1, 0.0, 5.0], [0.0, 0.0, -1.0])).expect("hits");
    assert!(close(c.t, 5.0 - (r2 - 0.1), 1e-5), "t = {}", c.t);
    assert!(close3(h.ng, Vec3::new(r2, 0.0, r2), 1e-5), "{}", h.ng);
    assert_miss(&s, ray([0.72, 0.0, 5.0], [0.0, 0.0, -1.0]));
    // an elliptic cylinder (scale x 2): radius 1 along X, 0.5 along Z
    let s = scene("[[objects]]\ntype = \"cylinder\"\nbase = [0, 0, 0]\ntop = [0, 1, 0]\nradius = 0.5\nmaterial = \"m\"\ntransform = { scale = [2, 1, 1] }\n");
    assert_hit(
        &s,
        ray([5.0, 0.5, 0.0], [-1.0, 0.0, 0.0]),
        4.0,
        Vec3::X,
        true,
    );
    assert_hit(
        &s,
        ray([0.0, 0.5, 5.0], [0.0, 0.0, -1.0]),
        4.5,
        Vec3::Z,
        true,
    );
    // a uniformly scaled, unrotated sphere is baked: no transform record
    let s = scene("[[objects]]\ntype = \"sphere\"\ncenter = [1, 0, 0]\nradius = 1\nmaterial = \"m\"\ntransform = { scale = 2, translate = [0, 1, 0] }\n");
    assert_eq!(s.primitives[0].flags, 0);
    assert_eq!(s.primitives[0].a, [2.0, 1.0, 0.0, 2.0]);
    assert!(s.shape_data.is_empty());
    // a rotated one keeps its transform so that uv turns with it: +X (u = v = 0.5) now faces -Z
    let s = scene("[[objects]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\ntransform = { rotate = [0, 90, 0] }\n");
    let h = assert_hit(
        &s,
        ray([0.0, 0.0, -5.0], [0.0, 0.0, 1.0]),
        4.0,
        -Vec3::Z,
        true,
    );
    assert!(
        (h.uv.xy() - Vec2::splat(0.5)).abs().max_element() < 1e-5,
        "uv {}",
        h.uv.xy()
    );
}

#[test]
fn mirrored_polygonal_shapes_keep_their_front_side_outward() {
    let s = scene("[[objects]]\ntype = \"tetrahedron\"\nvertices = [[0, 0, 0], [0, 1, 0], [1, 0, 0], [0, 0, 1]]\nmaterial = \"m\"\ntransform = { scale = [-1, 1, 1] }\n");
    let centroid = Vec3::new(-0.25, 0.25, 0.25);
    let mut rng = 3u32;
    for _ in 0..100 {
        let d = common::random_unit(&mut rng);
        let (_, h) = trace(&s, ray(centroid + 5.0 * d, -d)).expect("hits");
        assert!(h.front_face && h.ng.dot(h.p - centroid) > 0.0);
    }
}

#[test]
fn a_mirrored_triangle_keeps_its_default_uvs_on_the_same_corners() {
    let s = scene("[[objects]]\ntype = \"triangle\"\nvertices = [[0, 0, 0], [2, 0, 0], [0, 2, 0]]\nmaterial = \"m\"\ntransform = { scale = [-1, 1, 1] }\n");
    // near the mirror image of vertex 1, whose uv is (1, 0)
    let (_, h) = trace(&s, ray([-1.9, 0.05, 5.0], [0.0, 0.0, -1.0])).expect("hits");
    assert!(
        (h.uv.xy() - Vec2::new(0.95, 0.025)).abs().max_element() < 1e-5,
        "uv {}",
        h.uv.xy()
    );
}

#[test]
fn degenerate_input_is_refused_or_left_out_never_a_nan() {
    let dir = std::env::temp_dir().join(format!("wgtrace-degenerate-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // one good triangle and two of zero area
    std::fs::write(
        dir.join("m.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 2 2\nf 1 2 3\nf 1 1 2\nf 4 4 4\n",
    )
    .unwrap();
    let src = format!("{HEADER}[[objects]]\ntype = \"mesh\"\npath = \"m.obj\"\nmaterial = \"m\"\n");
    let s = wgtrace::load_scene_str(&src, &dir.join("s.toml"), &Default::default()).unwrap();
    assert_eq!(
        s.primitives.len(),
        1,
        "zero-area mesh triangles are left out"
    );
    std::fs::remove_dir_all(&dir).ok();
    // valid as written, degenerate in f32: an axis that underflows, a scale that does
    let e = load_error("[[objects]]\ntype = \"cylinder\"\nbase = [0, 0, 0]\ntop = [1e-23, 0, 0]\nradius = 1\nmaterial = \"m\"\n");
    assert!(
        e.contains("bad.toml:6:") && e.contains("objects[0]: degenerates in f32"),
        "{e}"
    );
    let e = load_error("[[objects]]\ntype = \"disk\"\ncenter = [0, 0, 0]\nnormal = [0, 1, 0]\nradius = 1\nmaterial = \"m\"\ntransform = { scale = [1e-40, 1, 1] }\n");
    assert!(e.contains("objects[0]: degenerates in f32"), "{e}");
    let e = load_error("[[objects]]\ntype = \"polygon\"\nvertices = [[0, 0, 0], [0, 0, 0], [1, 0, 0], [0, 1, 0]]\nmaterial = \"m\"\n");
    assert!(e.contains("objects[0].vertices: repeat a vertex"), "{e}");
}

#[test]
fn mesh_has_smooth_normals_and_file_uvs() {
    let s = common::scene_from_file_str(
        &format!("{HEADER}[[objects]]\ntype = \"mesh\"\npath = \"meshes/icosphere.obj\"\nmaterial = \"m\"\n"),
        "scenes/test.toml",
    );
    assert_eq!(s.primitives.len(), 1280);
    let mut rng = 11u32;
    let (mut worst_ns, mut worst_ng) = (1.0f32, 1.0f32);
    for _ in 0..500 {
        let d = common::random_unit(&mut rng);
        let (c, h) = trace(&s, ray(4.0 * d, -d)).expect("hits the icosphere");
        assert!(c.t > 2.9 && c.t < 3.01 && h.front_face, "t = {}", c.t);
        let radial = h.p.normalize();
        worst_ns = worst_ns.min(h.ns.dot(radial));
        worst_ng = worst_ng.min(h.ng.dot(radial));
        assert!(
            h.uv.xy().cmpge(Vec2::ZERO).all() && h.uv.xy().cmple(Vec2::ONE).all(),
            "uv {}",
            h.uv.xy()
        );
    }
    // interpolated normals follow the sphere far more closely than the facets do
    assert!(
        worst_ns > 0.9995 && worst_ns > worst_ng,
        "ns {worst_ns}, ng {worst_ng}"
    );
}

#[test]
fn bvh_finds_the_same_closest_hit_as_brute_force() {
    let mut objects = String::new();
    let mut rng = 5u32;
    let coord = |rng: &mut u32| common::random_f32(rng) * 8.0 - 4.0;
    for i in 0..300 {
        let (x, y, z) = (coord(&mut rng), coord(&mut rng), coord(&mut rng));
        let obj = match i % 5 {
            0 => format!("type = \"sphere\"\ncenter = [{x}, {y}, {z}]\nradius = 0.3"),
            1 => format!("type = \"box\"\nmin = [{x}, {y}, {z}]\nmax = [{}, {}, {}]", x + 0.4, y + 0.2, z + 0.5),
            2 => format!("type = \"cylinder\"\nbase = [{x}, {y}, {z}]\ntop = [{}, {}, {z}]\nradius = 0.2", x + 0.3, y + 0.6),
            3 => format!("type = \"triangle\"\nvertices = [[{x}, {y}, {z}], [{}, {y}, {z}], [{x}, {}, {}]]", x + 0.7, y + 0.5, z + 0.2),
            _ => format!("type = \"disk\"\ncenter = [{x}, {y}, {z}]\nnormal = [1, 2, 3]\nradius = 0.3\ntransform = {{ scale = [1, 2, 1] }}"),
        };
        objects += &format!("[[objects]]\n{obj}\nmaterial = \"m\"\n");
    }
    let src = format!("{HEADER}{objects}");
    let with = common::scene_from_str(&src);
    let without = common::scene_without_bvh(&src);
    assert!(with.bvh_depth <= wgtrace::scene::records::BVH_STACK_SIZE);
    let (bw, bo) = (
        Bindings::new(&with, with.params(0, with.full_band())),
        Bindings::new(&without, without.params(0, without.full_band())),
    );
    let mut hits = 0;
    for _ in 0..10_000 {
        let o = Vec3::new(coord(&mut rng), coord(&mut rng), coord(&mut rng)) * 1.5;
        let r = ray(o, common::random_unit(&mut rng));
        let (a, b) = (intersect_scene(&bw, &r, FAR), intersect_scene(&bo, &r, FAR));
        // without the BVH the primitives are sorted by type, so the same primitive has
        // another index: compare the hit and the primitive's record
        let record = |s: &wgtrace::FlatScene, c: &wgtrace::cpu::types::Candidate| {
            (c.prim != NO_HIT).then(|| s.primitives[c.prim as usize])
        };
        assert_eq!((a.t, a.u, a.v), (b.t, b.u, b.v), "{r:?}");
        assert_eq!(record(&with, &a), record(&without, &b), "{r:?}");
        hits += (a.prim != NO_HIT) as u32;
    }
    assert!(
        hits > 1500,
        "only {hits} hits: the test scene is too sparse"
    );
}

#[test]
fn shape_errors_name_the_object_and_field() {
    let e = load_error(
        "[[objects]]\ntype = \"box\"\nmin = [0, 0, 0]\nmax = [1, 0, 1]\nmaterial = \"m\"\n",
    );
    assert!(
        e.contains("bad.toml:6:") && e.contains("objects[0].max: must exceed min"),
        "{e}"
    );
    let e = load_error("[[objects]]\ntype = \"cylinder\"\nbase = [0, 0, 0]\ntop = [0, 0, 0]\nradius = -1\nmaterial = \"m\"\n");
    assert!(
        e.contains("objects[0].top: must differ") && e.contains("objects[0].radius: must be > 0"),
        "{e}"
    );
    let e = load_error("[[objects]]\ntype = \"tetrahedron\"\nvertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]\nmaterial = \"m\"\n");
    assert!(e.contains("objects[0].vertices: are coplanar"), "{e}");
    let e = load_error("[[objects]]\ntype = \"disk\"\ncenter = [0, 0, 0]\nnormal = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\n");
    assert!(e.contains("objects[0].normal: must be non-zero"), "{e}");
    let e = load_error("[[objects]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\ntransform = { scale = [1, 0, 1] }\n");
    assert!(
        e.contains("objects[0].transform.scale: must be finite and non-zero"),
        "{e}"
    );
    let e = load_error("[[objects]]\ntype = \"mesh\"\npath = \"missing.obj\"\nmaterial = \"m\"\n");
    assert!(
        e.contains("bad.toml:6:") && e.contains("objects[0].path") && e.contains("missing.obj"),
        "{e}"
    );
    let e = load_error("[[objects]]\ntype = \"box\"\nmin = [0, 0, 0]\nmax = [1, 1, 1]\nmaterial = \"m\"\ntransform = { rotate = [0, 0] }\n");
    assert!(e.contains("bad.toml:"), "{e}");
}
