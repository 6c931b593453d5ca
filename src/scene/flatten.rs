//! Flattening: a validated scene into the records both backends read. Polygonal shapes and
//! similarity transforms are baked into world space; analytic shapes under other transforms
//! keep an object-space record and a transform in `shape_data`. Bounded primitives are
//! ordered by the BVH built over them; planes come first and stay outside it.

use glam::{Affine3A, Mat3, Vec2, Vec3};

use super::bvh::{self, Aabb};
use super::format::{
    ColorDesc, LightSampling, MaterialDesc, ObjectDesc, SamplerKind, SceneFile, TransformDesc,
};
use super::lights::{env_distribution, light_list, Environment};
use super::mesh::MeshData;
use super::records::{self, BvhNode, Material, Primitive, NO_DATA, NO_TEXTURE};
use super::textures::{color_slot, texture_records, ImageData};
use super::{CameraFrame, EnvironmentMap, FlatScene};

fn material_record(m: &MaterialDesc, textures: &[String]) -> Material {
    let slot = |c: &ColorDesc| color_slot(c, textures);
    let rgb = |c: [f32; 3]| [c[0], c[1], c[2], 0.0];
    let (tag, albedo, emission, params, extra) = match m {
        MaterialDesc::Lambertian {
            albedo, emission, ..
        } => (
            records::MAT_LAMBERTIAN,
            slot(albedo),
            slot(emission),
            [0.0; 4],
            ([0.0; 4], NO_TEXTURE),
        ),
        MaterialDesc::Metal {
            albedo,
            fuzz,
            emission,
            ..
        } => (
            records::MAT_METAL,
            slot(albedo),
            slot(emission),
            [*fuzz, 0.0, 0.0, 0.0],
            ([0.0; 4], NO_TEXTURE),
        ),
        MaterialDesc::Dielectric {
            ior,
            tint,
            absorption,
            emission,
            ..
        } => (
            records::MAT_DIELECTRIC,
            slot(tint),
            slot(emission),
            [*ior, 0.0, 0.0, 0.0],
            (rgb(*absorption), NO_TEXTURE),
        ),
        MaterialDesc::Microfacet {
            albedo,
            specular,
            roughness,
            ior,
            emission,
            ..
        } => (
            records::MAT_MICROFACET,
            slot(albedo),
            slot(emission),
            [*roughness, *ior, 0.0, 0.0],
            slot(specular.as_ref().unwrap_or(albedo)),
        ),
        MaterialDesc::Emissive { radiance, .. } => (
            records::MAT_EMISSIVE,
            ([0.0; 4], NO_TEXTURE),
            slot(radiance),
            [0.0; 4],
            ([0.0; 4], NO_TEXTURE),
        ),
    };
    let two_sided = m.two_sided();
    Material {
        tag,
        flags: if two_sided {
            records::MAT_FLAG_TWO_SIDED
        } else {
            0
        },
        albedo: albedo.0,
        tex_albedo: albedo.1,
        emission: emission.0,
        tex_emission: emission.1,
        params,
        extra: extra.0,
        tex_extra: extra.1,
        ..Default::default()
    }
}

/// Object-to-world matrix of a transform: translate * Rz * Ry * Rx * scale.
pub fn transform_matrix(t: &TransformDesc) -> Affine3A {
    let s = t.scale.map_or([1.0; 3], |s| s.axes());
    let [rx, ry, rz] = t.rotate.map(f32::to_radians);
    let rotation =
        Mat3::from_rotation_z(rz) * Mat3::from_rotation_y(ry) * Mat3::from_rotation_x(rx);
    Affine3A::from_mat3_translation(
        rotation * Mat3::from_diagonal(Vec3::from(s)),
        t.translate.into(),
    )
}

/// A transform and what can be baked exactly under it.
struct Placement {
    m: Affine3A,
    /// Inverse transpose of the linear part: maps normals.
    normal_m: Mat3,
    /// |scale| when the scale is uniform and there is no rotation: spheres, cylinders and
    /// disks bake into the same shape with the same uv frame. (A rotation is kept as a
    /// transform so that uv, and textures, turn with the object.)
    uniform: Option<f32>,
    /// No rotation: axis-aligned boxes stay axis-aligned.
    axis_aligned: bool,
    /// Orientation reversed (negative determinant): triangle windings are swapped to keep
    /// the front side outward.
    mirrored: bool,
}

impl Placement {
    fn new(t: Option<TransformDesc>) -> Self {
        let t = t.unwrap_or_default();
        let m = transform_matrix(&t);
        let s = t.scale.map_or([1.0; 3], |s| s.axes()).map(f32::abs);
        let linear = Mat3::from(m.matrix3);
        Placement {
            m,
            normal_m: linear.inverse().transpose(),
            uniform: (s[0] == s[1] && s[1] == s[2] && t.rotate == [0.0; 3]).then_some(s[0]),
            axis_aligned: t.rotate == [0.0; 3],
            mirrored: linear.determinant() < 0.0,
        }
    }

    fn point(&self, p: [f32; 3]) -> Vec3 {
        self.m.transform_point3(p.into())
    }

    fn normal(&self, n: [f32; 3]) -> Vec3 {
        (self.normal_m * Vec3::from(n)).normalize()
    }
}

fn v4(v: Vec3, w: f32) -> [f32; 4] {
    v.extend(w).to_array()
}

/// Collects primitives (planes apart) and their shape data.
#[derive(Default)]
struct Builder {
    unbounded: Vec<Primitive>,
    bounded: Vec<Primitive>,
    shape_data: Vec<[f32; 4]>,
}

impl Builder {
    /// An analytic primitive in object space with its transform (PRIM_FLAG_TRANSFORM).
    fn push_transformed(&mut self, mut prim: Primitive, at: &Placement) {
        let w2o = at.m.inverse();
        prim.flags |= records::PRIM_FLAG_TRANSFORM;
        prim.data = self.shape_data.len() as u32;
        for m in [w2o, at.m] {
            let (l, t) = (Mat3::from(m.matrix3), Vec3::from(m.translation));
            for r in 0..3 {
                self.shape_data.push(v4(l.row(r), t[r]));
            }
        }
        self.bounded.push(prim);
    }

    /// A triangle; `attributes` = per-vertex (normal, uv) when it has any.
    fn push_triangle(
        &mut self,
        v: [Vec3; 3],
        attributes: Option<([Vec3; 3], [Vec2; 3])>,
        smooth: bool,
        material: u32,
    ) {
        // Zero-area triangles (common in OBJ files) can never be hit reliably and have no
        // normal: leave them out.
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        if !(n.length_squared() > 0.0 && n.is_finite()) {
            return;
        }
        let mut prim = Primitive {
            tag: records::PRIM_TRIANGLE,
            material,
            data: NO_DATA,
            a: v4(v[0], 0.0),
            b: v4(v[1], 0.0),
            c: v4(v[2], 0.0),
            ..Default::default()
        };
        if let Some((n, uv)) = attributes {
            prim.flags |= records::PRIM_FLAG_ATTRIBUTES;
            if smooth {
                prim.flags |= records::PRIM_FLAG_SHADING_NORMALS;
            }
            prim.data = self.shape_data.len() as u32;
            for k in 0..3 {
                self.shape_data.push(v4(n[k], uv[k].x));
            }
            self.shape_data.push([uv[0].y, uv[1].y, uv[2].y, 0.0]);
        }
        self.bounded.push(prim);
    }

    /// A triangle given in object space, baked into world space. A mirroring transform swaps
    /// two corners so the front side stays the mirror image of the original front.
    fn push_placed_triangle(
        &mut self,
        at: &Placement,
        mut v: [Vec3; 3],
        mut attributes: Option<([Vec3; 3], [Vec2; 3])>,
        smooth: bool,
        material: u32,
    ) {
        v = v.map(|p| at.m.transform_point3(p));
        if at.mirrored && attributes.is_none() {
            // the default uvs must follow the corners being swapped below
            attributes = Some(([Vec3::ZERO; 3], [Vec2::ZERO, Vec2::X, Vec2::Y]));
        }
        if let Some((n, _)) = attributes.as_mut() {
            for k in n.iter_mut() {
                let m = at.normal_m * *k;
                *k = if m.length_squared() > 0.0 {
                    m.normalize()
                } else {
                    m
                };
            }
        }
        if at.mirrored {
            v.swap(1, 2);
            if let Some((n, uv)) = attributes.as_mut() {
                n.swap(1, 2);
                uv.swap(1, 2);
            }
        }
        self.push_triangle(v, attributes, smooth, material);
    }

    fn push_object(&mut self, o: &ObjectDesc, mesh: Option<&MeshData>, material: u32) {
        let at = Placement::new(o.transform());
        let base = Primitive {
            material,
            data: NO_DATA,
            ..Default::default()
        };
        match o {
            ObjectDesc::Sphere { center, radius, .. } => {
                let mut prim = Primitive {
                    tag: records::PRIM_SPHERE,
                    ..base
                };
                if let Some(s) = at.uniform {
                    prim.a = v4(at.point(*center), radius * s);
                    self.bounded.push(prim);
                } else {
                    prim.a = v4((*center).into(), *radius);
                    self.push_transformed(prim, &at);
                }
            }
            ObjectDesc::Triangle { vertices, uvs, .. } => {
                let v = vertices.map(Vec3::from);
                let attributes = uvs.map(|uv| ([Vec3::ZERO; 3], uv.map(Vec2::from)));
                self.push_placed_triangle(&at, v, attributes, false, material);
            }
            ObjectDesc::Polygon { vertices, .. } => {
                // planar uvs: coordinates from vertex 0 along the first edge and across it
                let pts: Vec<Vec3> = vertices.iter().map(|&p| Vec3::from(p)).collect();
                let n = super::validate::polygon_normal(&pts).normalize();
                let t = (pts[1] - pts[0]).normalize();
                let b = n.cross(t);
                let uv = |p: Vec3| Vec2::new((p - pts[0]).dot(t), (p - pts[0]).dot(b));
                for i in 1..pts.len() - 1 {
                    let v = [pts[0], pts[i], pts[i + 1]];
                    let attributes = Some(([Vec3::ZERO; 3], v.map(uv)));
                    self.push_placed_triangle(&at, v, attributes, false, material);
                }
            }
            ObjectDesc::Tetrahedron { vertices, .. } => {
                let p = vertices.map(Vec3::from);
                for k in 0..4 {
                    // the face opposite vertex k, wound so its normal points away from it
                    let mut f = [p[(k + 1) % 4], p[(k + 2) % 4], p[(k + 3) % 4]];
                    if (f[1] - f[0]).cross(f[2] - f[0]).dot(p[k] - f[0]) > 0.0 {
                        f.swap(1, 2);
                    }
                    self.push_placed_triangle(&at, f, None, false, material);
                }
            }
            ObjectDesc::Plane {
                point,
                normal,
                uv_scale,
                ..
            } => self.unbounded.push(Primitive {
                tag: records::PRIM_PLANE,
                a: v4(at.point(*point), *uv_scale),
                b: v4(at.normal(*normal), 0.0),
                ..base
            }),
            ObjectDesc::Box { min, max, .. } => {
                let mut prim = Primitive {
                    tag: records::PRIM_BOX,
                    ..base
                };
                if at.axis_aligned {
                    let (p, q) = (at.point(*min), at.point(*max));
                    prim.a = v4(p.min(q), 0.0);
                    prim.b = v4(p.max(q), 0.0);
                    self.bounded.push(prim);
                } else {
                    prim.a = v4((*min).into(), 0.0);
                    prim.b = v4((*max).into(), 0.0);
                    self.push_transformed(prim, &at);
                }
            }
            ObjectDesc::Cylinder {
                base: b,
                top,
                radius,
                caps,
                ..
            } => {
                let mut prim = Primitive {
                    tag: records::PRIM_CYLINDER,
                    flags: if *caps { records::PRIM_FLAG_CAPS } else { 0 },
                    ..base
                };
                if let Some(s) = at.uniform {
                    prim.a = v4(at.point(*b), radius * s);
                    prim.b = v4(at.point(*top), 0.0);
                    self.bounded.push(prim);
                } else {
                    prim.a = v4((*b).into(), *radius);
                    prim.b = v4((*top).into(), 0.0);
                    self.push_transformed(prim, &at);
                }
            }
            ObjectDesc::Disk {
                center,
                normal,
                radius,
                ..
            } => {
                let mut prim = Primitive {
                    tag: records::PRIM_DISK,
                    ..base
                };
                if let Some(s) = at.uniform {
                    prim.a = v4(at.point(*center), radius * s);
                    prim.b = v4(at.normal(*normal), 0.0);
                    self.bounded.push(prim);
                } else {
                    prim.a = v4((*center).into(), *radius);
                    prim.b = v4(Vec3::from(*normal).normalize(), 0.0);
                    self.push_transformed(prim, &at);
                }
            }
            ObjectDesc::Mesh { .. } => {
                let mesh = mesh.expect("meshes are loaded before flattening");
                let smooth = !mesh.normals.is_empty();
                let has_attributes = smooth || !mesh.uvs.is_empty();
                self.bounded.reserve(mesh.triangles.len());
                for t in &mesh.triangles {
                    let v = t.map(|i| mesh.positions[i as usize]);
                    let attributes = has_attributes.then(|| {
                        let n = if smooth {
                            t.map(|i| mesh.normals[i as usize])
                        } else {
                            [Vec3::ZERO; 3]
                        };
                        let uv = if mesh.uvs.is_empty() {
                            [Vec2::ZERO, Vec2::X, Vec2::Y]
                        } else {
                            t.map(|i| mesh.uvs[i as usize])
                        };
                        (n, uv)
                    });
                    self.push_placed_triangle(&at, v, attributes, smooth, material);
                }
            }
        }
    }
}

/// Half-extent along each world axis of a disk of radius r with unit normal n.
fn disk_extent(n: Vec3, r: f32) -> Vec3 {
    r * (Vec3::ONE - n * n).max(Vec3::ZERO).powf(0.5)
}

/// Object-space bounds of a bounded primitive.
fn local_bounds(p: &Primitive) -> Aabb {
    let (a, b, c) = (
        Vec3::from_slice(&p.a),
        Vec3::from_slice(&p.b),
        Vec3::from_slice(&p.c),
    );
    let r = p.a[3];
    let (lo, hi) = match p.tag {
        records::PRIM_SPHERE => (a - r, a + r),
        records::PRIM_TRIANGLE => (a.min(b).min(c), a.max(b).max(c)),
        records::PRIM_BOX => (a, b),
        records::PRIM_CYLINDER => {
            let e = disk_extent((b - a).normalize(), r);
            (a.min(b) - e, a.max(b) + e)
        }
        records::PRIM_DISK => {
            let e = disk_extent(b, r);
            (a - e, a + e)
        }
        _ => (Vec3::ZERO, Vec3::ZERO),
    };
    Aabb { lo, hi }
}

/// World-space bounds: transformed primitives bound the eight corners of their object box.
fn world_bounds(p: &Primitive, shape_data: &[[f32; 4]]) -> Aabb {
    let local = local_bounds(p);
    if p.flags & records::PRIM_FLAG_TRANSFORM == 0 {
        return local;
    }
    let d = p.data as usize + 3;
    let rows = [0, 1, 2].map(|r| glam::Vec4::from_array(shape_data[d + r]));
    let mut out = Aabb {
        lo: Vec3::splat(f32::MAX),
        hi: Vec3::splat(f32::MIN),
    };
    for k in 0..8 {
        let corner = Vec3::select(
            glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0),
            local.hi,
            local.lo,
        )
        .extend(1.0);
        let q = Vec3::new(
            rows[0].dot(corner),
            rows[1].dot(corner),
            rows[2].dot(corner),
        );
        out.lo = out.lo.min(q);
        out.hi = out.hi.max(q);
    }
    out
}

/// Surface area of a primitive in world space (planes: 0, they are never emitters). A
/// transformed primitive's area is its object-space area times |det|^(2/3), exact for
/// similarities and an estimate otherwise.
pub fn primitive_area(p: &Primitive, shape_data: &[[f32; 4]]) -> f32 {
    use std::f32::consts::PI;
    let (a, b, c) = (
        Vec3::from_slice(&p.a),
        Vec3::from_slice(&p.b),
        Vec3::from_slice(&p.c),
    );
    let r = p.a[3];
    let local = match p.tag {
        records::PRIM_SPHERE => 4.0 * PI * r * r,
        records::PRIM_TRIANGLE => 0.5 * (b - a).cross(c - a).length(),
        records::PRIM_BOX => {
            let e = b - a;
            2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
        }
        records::PRIM_CYLINDER => {
            let caps = if p.flags & records::PRIM_FLAG_CAPS != 0 {
                2.0 * PI * r * r
            } else {
                0.0
            };
            2.0 * PI * r * (b - a).length() + caps
        }
        records::PRIM_DISK => PI * r * r,
        _ => 0.0,
    };
    if p.flags & records::PRIM_FLAG_TRANSFORM == 0 {
        return local;
    }
    let d = p.data as usize + 3;
    let m = Mat3::from_cols(
        Vec3::from_slice(&shape_data[d]),
        Vec3::from_slice(&shape_data[d + 1]),
        Vec3::from_slice(&shape_data[d + 2]),
    );
    local * m.determinant().abs().powf(2.0 / 3.0)
}

/// Whether a primitive's record, and its transform and bounds, are usable in f32: finite,
/// with non-zero sizes and unit normals. A valid scene can still fail this under an extreme
/// transform (a scale that underflows or overflows f32, a matrix that is singular in f32).
fn record_ok(p: &Primitive, shape_data: &[[f32; 4]]) -> bool {
    let (a, b) = (Vec3::from_slice(&p.a), Vec3::from_slice(&p.b));
    let unit = |n: Vec3| (n.length() - 1.0).abs() < 1e-3;
    let finite = [p.a, p.b, p.c].iter().flatten().all(|x| x.is_finite());
    let shape = match p.tag {
        records::PRIM_SPHERE => p.a[3] > 0.0,
        records::PRIM_PLANE => unit(b),
        records::PRIM_DISK => unit(b) && p.a[3] > 0.0,
        records::PRIM_BOX => a.cmplt(b).all(),
        records::PRIM_CYLINDER => (b - a).length().is_normal() && p.a[3] > 0.0,
        _ => true,
    };
    let transform = p.flags & records::PRIM_FLAG_TRANSFORM == 0
        || shape_data[p.data as usize..][..records::TRANSFORM_ENTRIES as usize]
            .iter()
            .flatten()
            .all(|x| x.is_finite());
    let bounded = p.tag == records::PRIM_PLANE || {
        let bb = world_bounds(p, shape_data);
        bb.lo.is_finite() && bb.hi.is_finite()
    };
    finite && shape && transform && bounded
}

/// Whether the shader walks the BVH or tests every bounded primitive in a loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BvhChoice {
    /// The loop for a small scene ([`super::SMALL_SCENE_PRIMITIVES`]), else the BVH.
    Auto,
    Always,
    Never,
}

/// Flattens a validated scene into records; `meshes[i]` holds object i's mesh when it is
/// one, `images[i]` texture i's image. With the BVH, the bounded primitives are in its
/// leaves' order; without it they are sorted by type (stable), for the shader's one loop
/// per type, and there are no BVH nodes.
/// Errors with the indices of objects whose records degenerate in f32 (see `record_ok`).
pub fn flatten(
    file: &SceneFile,
    meshes: &[Option<MeshData>],
    images: &[Option<ImageData>],
    bvh_choice: BvhChoice,
) -> Result<FlatScene, Vec<usize>> {
    let texture_names: Vec<String> = file.textures.keys().cloned().collect();
    let (textures, texels) = texture_records(&file.textures, images);
    let material_names: Vec<String> = file.materials.keys().cloned().collect();
    let materials: Vec<Material> = file
        .materials
        .values()
        .map(|m| material_record(m.get_ref(), &texture_names))
        .collect();
    let material_index = |name: &str| material_names.iter().position(|n| n == name).unwrap() as u32;

    let mut builder = Builder::default();
    let mut degenerate = Vec::new();
    for (i, (obj, mesh)) in file.objects.iter().zip(meshes).enumerate() {
        let o = obj.get_ref();
        let (u, b) = (builder.unbounded.len(), builder.bounded.len());
        builder.push_object(o, mesh.as_ref(), material_index(o.material()));
        let added = builder.unbounded[u..].iter().chain(&builder.bounded[b..]);
        if !added.clone().all(|p| record_ok(p, &builder.shape_data)) {
            degenerate.push(i);
        }
    }
    if !degenerate.is_empty() {
        return Err(degenerate);
    }
    let Builder {
        unbounded,
        bounded,
        shape_data,
    } = builder;

    let boxes: Vec<Aabb> = bounded
        .iter()
        .map(|p| world_bounds(p, &shape_data))
        .collect();
    let small = bounded.len() <= super::SMALL_SCENE_PRIMITIVES
        && !bounded
            .iter()
            .any(|p| p.flags & records::PRIM_FLAG_TRANSFORM != 0);
    let use_bvh = match bvh_choice {
        BvhChoice::Auto => !small,
        BvhChoice::Always => true,
        BvhChoice::Never => false,
    };
    let bounds = boxes.iter().fold(Aabb::empty(), |a, b| a.union(b));
    let num_unbounded = unbounded.len() as u32;
    let mut primitives = unbounded;
    let (bvh, bvh_depth) = if use_bvh {
        let tree = bvh::build(&boxes);
        primitives.extend(tree.order.iter().map(|&i| bounded[i as usize]));
        let nodes: Vec<BvhNode> = tree
            .nodes
            .iter()
            .map(|n| BvhNode {
                offset: if n.count > 0 {
                    n.offset + num_unbounded
                } else {
                    n.offset
                },
                ..*n
            })
            .collect();
        (nodes, tree.depth)
    } else {
        let mut sorted = bounded;
        sorted.sort_by_key(|p| p.tag);
        primitives.extend(sorted);
        (Vec::new(), 0)
    };

    let bg = &file.background;
    let env_texture = bg.texture.as_ref().map(|name| {
        texture_names
            .iter()
            .position(|n| n == name)
            .expect("validated") as u32
    });
    let mut texels = texels;
    let mut env_cdf = 0;
    let env = env_texture.map(|i| {
        let (dist, integral) = env_distribution(&Environment {
            texture: &textures[i as usize],
            texels: &texels,
            strength: bg.strength.unwrap_or(1.0),
        });
        env_cdf = texels.len() as u32;
        texels.extend(dist);
        let radius = if boxes.is_empty() {
            1.0
        } else {
            0.5 * (bounds.hi - bounds.lo).length()
        };
        (integral, radius)
    });
    let (emitters, env_light) = light_list(
        &mut primitives,
        num_unbounded as usize,
        &materials,
        &shape_data,
        env,
    );
    let rotation = bg.rotation.unwrap_or(0.0).to_radians();

    let r = &file.render;
    Ok(FlatScene {
        width: r.width,
        height: r.height,
        spp: r.spp,
        max_depth: r.max_depth,
        seed: r.seed,
        sampler: match r.sampler {
            SamplerKind::Random => records::SAMPLER_RANDOM,
            SamplerKind::Jittered => records::SAMPLER_JITTERED,
            SamplerKind::Hammersley => records::SAMPLER_HAMMERSLEY,
            SamplerKind::Sobol => records::SAMPLER_SOBOL,
        },
        camera: camera_frame(file, r.width as f32 / r.height as f32),
        specialize: true,
        uniform_records: true,
        baked_records: true,
        sample_groups: true,
        rr_depth: super::RR_DEPTH,
        light_sampling: match r.light_sampling {
            LightSampling::Bsdf => records::LIGHT_SAMPLING_BSDF,
            LightSampling::Mixture => records::LIGHT_SAMPLING_MIXTURE,
            LightSampling::Mis => records::LIGHT_SAMPLING_MIS,
        },
        background: bg.bottom.or(bg.color).unwrap_or([0.0; 3]),
        background_top: bg.top,
        env: env_texture.map(|texture| EnvironmentMap {
            texture,
            cdf: env_cdf,
            light: env_light,
            rotation: [rotation.cos(), rotation.sin()],
            strength: bg.strength.unwrap_or(1.0),
        }),
        primitives,
        materials,
        emitters,
        material_names,
        bvh,
        bvh_depth,
        shape_data,
        num_unbounded,
        use_bvh,
        textures,
        texels,
    })
}

fn camera_frame(file: &SceneFile, aspect: f32) -> CameraFrame {
    let c = &file.camera;
    let origin = Vec3::from(c.look_from);
    let to_target = Vec3::from(c.look_at) - origin;
    let forward = to_target.normalize();
    let right = forward.cross(Vec3::from(c.up)).normalize();
    let up = right.cross(forward);
    let focus_distance = c.focus_distance.unwrap_or(to_target.length());
    let half_height = (c.vfov.to_radians() * 0.5).tan() * focus_distance;
    CameraFrame {
        origin,
        right,
        up,
        forward,
        half_width: half_height * aspect,
        half_height,
        focus_distance,
        lens_radius: c.aperture * 0.5,
    }
}
