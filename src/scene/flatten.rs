//! Flattening: a validated scene into the records both backends read. Polygonal shapes and
//! similarity transforms are baked into world space; analytic shapes under other transforms
//! keep an object-space record and a transform in `shape_data`. Bounded primitives are
//! ordered by the BVH built over them; planes come first and stay outside it.

use glam::{Affine3A, Mat3, Vec2, Vec3, Vec4};

use super::bvh::{self, Aabb};
use super::flat::{CameraFrame, EnvironmentMap, FlatScene, RR_DEPTH};
use super::format::{
    LightDesc, MediumDesc, ObjectDesc, PixelFilter, Projection, SceneFile, ShadingNormals,
    TextureDesc, TransformDesc,
};
use super::imported::ImportedScene;
use super::lights::{env_distribution, light_list, punctual_lights};
use super::materials::{
    blend, dielectric, mark_own_colors, pbr, plastic, MaterialDesc, MaterialKind,
};
use super::mesh::MeshData;
use super::microfacet_albedo;
use super::primitives::{sort_for_loops, PrimitiveKind};
use super::records::{self, BvhNode, Material, Primitive, NO_DATA};
use super::shapes::{polygon_normal, record_ok, world_bounds};
use super::textures::{texture_records, ImageData, TextureData};
use super::volume::DensityGrid;

/// Object-to-world matrix of a transform: translate * Rz * Ry * Rx * scale.
pub fn transform_matrix(t: &TransformDesc) -> Affine3A {
    if let Some(m) = t.matrix {
        // row-major rows; the last is [0, 0, 0, 1] (validated)
        return Affine3A::from_cols_array_2d(&[
            [m[0][0], m[1][0], m[2][0]],
            [m[0][1], m[1][1], m[2][1]],
            [m[0][2], m[1][2], m[2][2]],
            [m[0][3], m[1][3], m[2][3]],
        ]);
    }
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
struct ObjectTransform {
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

impl ObjectTransform {
    /// A triangle mesh's placement by any affine matrix (a glTF node's): only what
    /// triangles need is exact; analytic shapes never come this way.
    fn from_matrix(m: Affine3A) -> Self {
        let linear = Mat3::from(m.matrix3);
        ObjectTransform {
            m,
            normal_m: linear.inverse().transpose(),
            uniform: None,
            axis_aligned: false,
            mirrored: linear.determinant() < 0.0,
        }
    }

    fn new(t: Option<TransformDesc>) -> Self {
        let t = t.unwrap_or_default();
        let m = transform_matrix(&t);
        let s = t.scale.map_or([1.0; 3], |s| s.axes()).map(f32::abs);
        let linear = Mat3::from(m.matrix3);
        ObjectTransform {
            m,
            normal_m: linear.inverse().transpose(),
            uniform: (s[0] == s[1] && s[1] == s[2] && t.rotate == [0.0; 3] && t.matrix.is_none())
                .then_some(s[0]),
            axis_aligned: t.rotate == [0.0; 3] && t.matrix.is_none(),
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
    /// Each group's primitives (`SceneFile::members`' order), in the group's space.
    groups: Vec<Vec<Primitive>>,
    /// Each instance's group and object-to-world matrix.
    instances: Vec<(usize, Affine3A)>,
}

impl Builder {
    /// An analytic primitive in object space with its transform (PRIM_FLAG_TRANSFORM).
    fn push_transformed(&mut self, mut prim: Primitive, at: &ObjectTransform) {
        prim.flags |= records::PRIM_FLAG_TRANSFORM;
        prim.data = self.push_transform(at.m);
        self.bounded.push(prim);
    }

    /// The rows of a transform (`TRANSFORM_ENTRIES`: world-to-object, then
    /// object-to-world), at the index returned.
    fn push_transform(&mut self, m: Affine3A) -> u32 {
        let data = self.shape_data.len() as u32;
        for m in [m.inverse(), m] {
            let (l, t) = (Mat3::from(m.matrix3), Vec3::from(m.translation));
            for r in 0..3 {
                self.shape_data.push(v4(l.row(r), t[r]));
            }
        }
        data
    }

    /// A triangle; `attributes` = its corners' normals, uvs and the rest when it has any,
    /// `tangents` the corners' tangents and bitangent signs (for normal maps; only with
    /// attributes).
    fn push_triangle(
        &mut self,
        v: [Vec3; 3],
        attributes: Option<Corners>,
        tangents: Option<[Vec4; 3]>,
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
            tag: PrimitiveKind::Triangle.tag(),
            material,
            data: NO_DATA,
            a: v4(v[0], 0.0),
            b: v4(v[1], 0.0),
            c: v4(v[2], 0.0),
            ..Default::default()
        };
        if let Some(Corners { n, uv, uv1, color }) = attributes {
            prim.flags |= records::PRIM_FLAG_ATTRIBUTES;
            if smooth {
                prim.flags |= records::PRIM_FLAG_SHADING_NORMALS;
            }
            prim.data = self.shape_data.len() as u32;
            for k in 0..3 {
                self.shape_data.push(v4(n[k], uv[k].x));
            }
            self.shape_data.push([uv[0].y, uv[1].y, uv[2].y, 0.0]);
            if let Some(t) = tangents {
                prim.flags |= records::PRIM_FLAG_TANGENTS;
                self.shape_data.extend(t.map(|t| t.to_array()));
            }
            if let Some(u) = uv1 {
                prim.flags |= records::PRIM_FLAG_UV1;
                self.shape_data.push([u[0].x, u[0].y, u[1].x, u[1].y]);
                self.shape_data.push([u[2].x, u[2].y, 0.0, 0.0]);
            }
            if let Some(c) = color {
                prim.flags |= records::PRIM_FLAG_COLORS;
                self.shape_data.extend(c.map(|c| c.to_array()));
            }
        }
        self.bounded.push(prim);
    }

    /// A triangle given in object space, baked into world space. A mirroring transform swaps
    /// two corners so the front side stays the mirror image of the original front.
    fn push_placed_triangle(
        &mut self,
        at: &ObjectTransform,
        mut v: [Vec3; 3],
        mut attributes: Option<Corners>,
        mut tangents: Option<[Vec4; 3]>,
        smooth: bool,
        material: u32,
    ) {
        v = v.map(|p| at.m.transform_point3(p));
        if at.mirrored && attributes.is_none() {
            // the default uvs must follow the corners being swapped below
            attributes = Some(Corners::uvs([Vec2::ZERO, Vec2::X, Vec2::Y]));
        }
        if let Some(Corners { n, .. }) = attributes.as_mut() {
            for k in n.iter_mut() {
                let m = at.normal_m * *k;
                *k = if m.length_squared() > 0.0 {
                    m.normalize()
                } else {
                    m
                };
            }
        }
        if let Some(t) = tangents.as_mut() {
            // tangents turn with the surface (the linear part, not the normals' inverse
            // transpose); a mirror flips the bitangent's handedness
            for k in t.iter_mut() {
                let d = Mat3::from(at.m.matrix3) * k.truncate();
                let sign = if at.mirrored { -k.w } else { k.w };
                *k = d.normalize_or_zero().extend(sign);
            }
        }
        if at.mirrored {
            v.swap(1, 2);
            if let Some(c) = attributes.as_mut() {
                c.n.swap(1, 2);
                c.uv.swap(1, 2);
                if let Some(u) = c.uv1.as_mut() {
                    u.swap(1, 2);
                }
                if let Some(k) = c.color.as_mut() {
                    k.swap(1, 2);
                }
            }
            if let Some(t) = tangents.as_mut() {
                t.swap(1, 2);
            }
        }
        self.push_triangle(v, attributes, tangents, smooth, material);
    }

    /// A glTF file's instances under the object's transform; its materials are numbered
    /// from `first_material`.
    fn push_imported(&mut self, o: &ObjectDesc, g: &ImportedScene, first_material: u32) {
        let object = transform_matrix(&o.transform().unwrap_or_default());
        for inst in &g.instances {
            let at = ObjectTransform::from_matrix(object * inst.transform);
            let material = first_material + inst.material as u32;
            self.push_mesh(&at, &g.meshes[inst.mesh], material);
        }
    }

    fn push_object(&mut self, o: &ObjectDesc, mesh: Option<&MeshData>, material: u32) {
        let at = ObjectTransform::new(o.transform());
        let base = Primitive {
            material,
            data: NO_DATA,
            ..Default::default()
        };
        match o {
            ObjectDesc::Sphere { center, radius, .. } => {
                let mut prim = Primitive {
                    tag: PrimitiveKind::Sphere.tag(),
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
                let attributes = uvs.map(|uv| Corners::uvs(uv.map(Vec2::from)));
                self.push_placed_triangle(&at, v, attributes, None, false, material);
            }
            ObjectDesc::Polygon { vertices, .. } => self.push_polygon(&at, vertices, material),
            ObjectDesc::Tetrahedron { vertices, .. } => {
                self.push_tetrahedron(&at, vertices, material)
            }
            ObjectDesc::Plane {
                point,
                normal,
                uv_scale,
                ..
            } => self.unbounded.push(Primitive {
                tag: PrimitiveKind::Plane.tag(),
                a: v4(at.point(*point), *uv_scale),
                b: v4(at.normal(*normal), 0.0),
                ..base
            }),
            ObjectDesc::Box { min, max, .. } => {
                let mut prim = Primitive {
                    tag: PrimitiveKind::Box.tag(),
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
                    tag: PrimitiveKind::Cylinder.tag(),
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
                    tag: PrimitiveKind::Disk.tag(),
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
                self.push_mesh(&at, mesh, material);
            }
            ObjectDesc::Gltf { .. } => unreachable!("glTF objects are pushed by push_imported"),
            ObjectDesc::Instance { .. } => unreachable!("instances are placed by flatten"),
        }
    }

    /// A planar convex polygon, fan-split into triangles with planar uvs: coordinates from
    /// vertex 0 along the first edge and across it.
    fn push_polygon(&mut self, at: &ObjectTransform, vertices: &[[f32; 3]], material: u32) {
        let pts: Vec<Vec3> = vertices.iter().map(|&p| Vec3::from(p)).collect();
        let n = polygon_normal(&pts).normalize();
        let t = (pts[1] - pts[0]).normalize();
        let b = n.cross(t);
        let uv = |p: Vec3| Vec2::new((p - pts[0]).dot(t), (p - pts[0]).dot(b));
        for i in 1..pts.len() - 1 {
            let v = [pts[0], pts[i], pts[i + 1]];
            let attributes = Some(Corners::uvs(v.map(uv)));
            self.push_placed_triangle(at, v, attributes, None, false, material);
        }
    }

    /// A tetrahedron as four triangles, each wound so its normal points away from the
    /// vertex opposite.
    fn push_tetrahedron(&mut self, at: &ObjectTransform, vertices: &[[f32; 3]; 4], material: u32) {
        let p = vertices.map(Vec3::from);
        for k in 0..4 {
            let mut f = [p[(k + 1) % 4], p[(k + 2) % 4], p[(k + 3) % 4]];
            if (f[1] - f[0]).cross(f[2] - f[0]).dot(p[k] - f[0]) > 0.0 {
                f.swap(1, 2);
            }
            self.push_placed_triangle(at, f, None, None, false, material);
        }
    }

    /// A mesh's triangles, with its vertex normals (smooth shading) and uvs when it has them.
    fn push_mesh(&mut self, at: &ObjectTransform, mesh: &MeshData, material: u32) {
        let smooth = !mesh.normals.is_empty();
        let has_attributes =
            smooth || !mesh.uvs.is_empty() || !mesh.uvs1.is_empty() || !mesh.colors.is_empty();
        self.bounded.reserve(mesh.triangles.len());
        for (i, t) in mesh.triangles.iter().enumerate() {
            let v = t.map(|i| mesh.positions[i as usize]);
            let attributes = has_attributes.then(|| {
                let corner = |list: &[Vec2]| t.map(|i| list[i as usize]);
                Corners {
                    n: if smooth {
                        t.map(|i| mesh.normals[i as usize])
                    } else {
                        [Vec3::ZERO; 3]
                    },
                    uv: if mesh.uvs.is_empty() {
                        [Vec2::ZERO, Vec2::X, Vec2::Y]
                    } else {
                        corner(&mesh.uvs)
                    },
                    uv1: (!mesh.uvs1.is_empty()).then(|| corner(&mesh.uvs1)),
                    color: (!mesh.colors.is_empty()).then(|| t.map(|i| mesh.colors[i as usize])),
                }
            });
            let tangents = mesh.tangents.get(i).copied().filter(|_| has_attributes);
            self.push_placed_triangle(at, v, attributes, tangents, smooth, material);
        }
    }
}

/// A triangle's per-corner attributes: normals (zero without shading normals), uvs, and
/// a second uv set and vertex colours when its mesh has them.
#[derive(Clone, Copy, Debug)]
struct Corners {
    n: [Vec3; 3],
    uv: [Vec2; 3],
    uv1: Option<[Vec2; 3]>,
    color: Option<[Vec4; 3]>,
}

impl Corners {
    /// Uvs alone.
    fn uvs(uv: [Vec2; 3]) -> Self {
        Corners {
            n: [Vec3::ZERO; 3],
            uv,
            uv1: None,
            color: None,
        }
    }
}

/// How closest-hit searches find the primitives a ray may hit. Both backends walk the
/// structure a scene was flattened with, and the choice orders its primitives (and so its
/// light list), so it is made once, when the scene is loaded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Acceleration {
    /// A bounding volume hierarchy over the bounded primitives, which are in its leaves'
    /// order.
    Bvh,
    /// Every bounded primitive tested on every ray, in one list grouped by type (a stable
    /// sort), so that a backend may run one loop per type; no BVH nodes.
    List,
    /// The list for a scene of at most `list_max` bounded primitives, none of them
    /// transformed; the BVH otherwise. The threshold is the caller's (a tuning value).
    Auto { list_max: usize },
}

impl Acceleration {
    /// Whether `bounded` primitives get the BVH.
    fn uses_bvh(self, bounded: &[Primitive]) -> bool {
        match self {
            Acceleration::Bvh => true,
            Acceleration::List => false,
            Acceleration::Auto { list_max } => {
                bounded.len() > list_max
                    || bounded
                        .iter()
                        .any(|p| p.flags & records::PRIM_FLAG_TRANSFORM != 0)
            }
        }
    }
}

/// Render settings the flattener writes into the scene besides the file's own.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Build {
    pub acceleration: Acceleration,
    /// Russian roulette from ray [`RR_DEPTH`] on (else every path runs to max_depth).
    pub russian_roulette: bool,
}

/// Why a scene cannot be flattened.
#[derive(Debug)]
pub enum FlattenError {
    /// The objects (by index) whose records degenerate in f32 (see `record_ok`).
    Degenerate(Vec<usize>),
    /// The texels do not fit the banks (`texels::pack`).
    Texels(String),
    /// The scene's BVH and a group's together are deeper than the walk's stack.
    Depth(u32),
    /// More media (the file's and those of absorbing glass) than a media word holds.
    Media(u32),
}

/// What a scene's objects and textures bring from files, read before flattening.
#[derive(Debug, Default)]
pub struct SceneFiles {
    /// Object i's mesh when it is a mesh.
    pub meshes: Vec<Option<MeshData>>,
    /// Object i's glTF scene when it is a glTF file.
    pub imported: Vec<Option<ImportedScene>>,
    /// Texture i's image (in the file's order of names) when it is an image.
    pub images: Vec<Option<ImageData>>,
    /// Medium i's density grid (in the file's order of names) when it is heterogeneous.
    pub grids: Vec<Option<crate::scene::volume::DensityGrid>>,
    /// Medium i's albedo grid (three channels) when it has one.
    pub albedo_grids: Vec<Option<crate::scene::volume::DensityGrid>>,
}

/// Flattens a validated scene into records, with the meshes, glTF scenes and images its
/// objects and textures name (`files`). The materials and textures of glTF objects
/// follow the file's own, object by object. With the BVH, the bounded primitives are in
/// its leaves' order; without it they are sorted by type (stable), and there are no BVH
/// nodes. Errors with the indices of objects whose records degenerate in f32 (see
/// `record_ok`).
pub fn flatten(
    file: &SceneFile,
    files: &SceneFiles,
    build: Build,
) -> Result<FlatScene, FlattenError> {
    let gltfs = || files.imported.iter().flatten();
    let texture_list: Vec<(String, &TextureDesc, Option<&ImageData>)> = file
        .textures
        .iter()
        .zip(&files.images)
        .map(|((name, t), image)| (name.clone(), t.get_ref(), image.as_ref()))
        .chain(gltfs().flat_map(|g| {
            g.textures
                .iter()
                .map(|t| (t.name.clone(), &t.desc, Some(&*t.image)))
        }))
        .collect();
    let texture_names: Vec<String> = texture_list.iter().map(|t| t.0.clone()).collect();
    let bg = &file.background;
    let env_texture = bg.texture.as_ref().map(|name| {
        texture_names
            .iter()
            .position(|n| n == name)
            .expect("validated") as u32
    });
    let strength = bg.strength.unwrap_or(1.0);
    let TextureData {
        records: textures,
        texels,
        mut tables,
    } = texture_records(&texture_list).map_err(FlattenError::Texels)?;
    // the image background's distribution, after the noise tables
    let env_cdf = tables.len() as u32;
    let env_dist = env_texture.map(|i| {
        let image = texture_list[i as usize]
            .2
            .expect("a background texture is an image");
        let (scalars, integral) = env_distribution(image, strength);
        tables.extend(scalars.chunks(4).map(|c| {
            let mut v = [0.0; 4];
            v[..c.len()].copy_from_slice(c);
            v
        }));
        integral
    });
    let material_list: Vec<(&String, &MaterialDesc)> = file
        .materials
        .iter()
        .map(|(name, m)| (name, m.get_ref()))
        .chain(gltfs().flat_map(|g| g.materials.iter().map(|(n, m)| (n, m))))
        .collect();
    let mut material_names: Vec<String> = material_list.iter().map(|m| m.0.clone()).collect();
    let mut materials: Vec<Material> = material_list
        .iter()
        .map(|m| m.1.record(&texture_names))
        .collect();
    // a material that reads a mesh attribute is not also tinted by the vertex colours
    for m in &mut materials {
        mark_own_colors(m, |t| {
            textures
                .get(t as usize)
                .is_some_and(|r| r.tag == records::TEX_MESH_ATTRIBUTE)
        });
    }
    // each blend's parts, by their places in the list
    for (i, m) in material_list.iter().enumerate() {
        if let MaterialDesc::Blend(b) = m.1 {
            let index = |name: &str| {
                material_names
                    .iter()
                    .position(|n| n == name)
                    .expect("validated") as u32
            };
            blend::point_at_parts(&mut materials[i], index(&b.first), index(&b.second));
        }
    }
    // the sheen's albedo table, after the background's distribution
    let is_pbr = |m: &Material| m.tag == MaterialKind::Pbr.tag();
    if materials.iter().any(|m| is_pbr(m) && pbr::has_sheen(m)) {
        let offset = tables.len() as u32;
        let table = pbr::sheen_albedo_table();
        tables.extend(table.chunks(4).map(|c| [c[0], c[1], c[2], c[3]]));
        for m in materials.iter_mut().filter(|m| is_pbr(m)) {
            pbr::point_at_sheen_table(m, offset);
        }
    }
    // shading normals taken strictly, by every material
    if file.render.shading_normals == ShadingNormals::Strict {
        for (m, (_, desc)) in materials.iter_mut().zip(&material_list) {
            m.flags |= desc.strict_shading_flags();
        }
    }
    // energy compensation: [render]'s choice for the materials without their own, and
    // the microfacet albedo tables once for all
    for (m, (_, desc)) in materials.iter_mut().zip(&material_list) {
        if desc.compensated(file.render.energy_compensation) {
            m.flags |= records::MAT_FLAG_ENERGY;
        }
    }
    let ms_tables = if materials
        .iter()
        .any(|m| m.flags & records::MAT_FLAG_ENERGY != 0)
    {
        let offset = tables.len() as u32;
        let mut dielectric = [false; 4];
        for m in &materials {
            let variant = match MaterialKind::from_tag(m.tag) {
                Some(MaterialKind::Dielectric) => dielectric::ms_variant(m),
                Some(MaterialKind::Plastic) => plastic::ms_variant(m),
                _ => None,
            };
            if let Some(v) = variant {
                dielectric[v as usize] = true;
            }
        }
        tables.extend(microfacet_albedo::table_entries(dielectric));
        offset
    } else {
        0
    };
    // each rough plastic's transmittance table
    for m in materials
        .iter_mut()
        .filter(|m| m.tag == MaterialKind::Plastic.tag() && plastic::is_rough(m))
    {
        let offset = tables.len() as u32;
        let table = plastic::table_of(m);
        tables.extend(table.chunks(4).map(|c| [c[0], c[1], c[2], c[3]]));
        plastic::point_at_table(m, offset);
    }
    let medium_index = |name: &str| {
        file.media
            .keys()
            .position(|n| n == name)
            .expect("validated") as u32
    };
    let camera_medium = file
        .camera
        .medium
        .as_deref()
        .map_or(records::NO_MEDIUM, medium_index);
    let (mut builder, mut media_words) =
        build_primitives(file, files, &mut materials, &mut material_names)
            .map_err(FlattenError::Degenerate)?;
    // absorbing glass: its absorption is a medium of albedo 0 inside it (the interior of
    // each record of it, one medium per coefficient), so that paths and shadow rays
    // meet it as they do any medium
    let absorbing = absorbing_glass(
        &mut materials,
        &mut media_words,
        file.media.len(),
        camera_medium,
    );
    let num_media = (file.media.len() + absorbing.len()) as u32;
    if num_media >= records::MEDIA_SIDE {
        return Err(FlattenError::Media(num_media));
    }
    // the media, after the other tables: (sigma_t, g), (albedo, 0) each
    let media = if num_media == 0 {
        0
    } else {
        tables.len() as u32
    };
    for m in file.media.values() {
        let (t, a, g) = m.get_ref().coefficients();
        tables.push([t[0], t[1], t[2], g]);
        tables.push([a[0], a[1], a[2], 0.0]);
    }
    for a in &absorbing {
        tables.push([a[0], a[1], a[2], 0.0]);
        tables.push([0.0; 4]);
    }
    // each density grid: its header (GRID_ENTRIES), its values, its cells' majorants; an
    // albedo grid's header and values after it
    let mut grid_media = false;
    let unit = DensityGrid {
        res: [1; 3],
        channels: 1,
        values: vec![1.0],
        bbox: ([0.0; 3], [1.0; 3]),
    };
    for (i, m) in file.media.values().enumerate() {
        let MediumDesc::Heterogeneous {
            transform,
            use_grid_bbox,
            ..
        } = m.get_ref()
        else {
            continue;
        };
        // without a grid, density 1 in the placed unit cube
        let grid = files.grids.get(i).and_then(Option::as_ref).unwrap_or(&unit);
        let albedo = files.albedo_grids.get(i).and_then(Option::as_ref);
        grid_media = true;
        let header = tables.len() as u32;
        tables[(media + i as u32 * records::MEDIUM_ENTRIES + 1) as usize][3] =
            f32::from_bits(header);
        // the scene to a grid's unit cube: the inverse of transform x (its file's box)
        let transform = transform
            .as_ref()
            .map_or(Affine3A::IDENTITY, transform_matrix);
        let rows_of = |g: &DensityGrid| {
            let mut to_world = transform;
            if *use_grid_bbox {
                let (lo, hi) = (Vec3::from(g.bbox.0), Vec3::from(g.bbox.1));
                to_world *=
                    Affine3A::from_scale_rotation_translation(hi - lo, Default::default(), lo);
            }
            glam::Mat4::from(to_world.inverse()).transpose()
        };
        let entries = |v: &[f32]| (v.len() as u32).div_ceil(4);
        let bits = |v: [u32; 3], at: u32| [v[0], v[1], v[2], at].map(f32::from_bits);
        let data = header + records::GRID_ENTRIES;
        let majorants = data + entries(&grid.values);
        let cell_majorants = grid.majorants();
        let albedo_header = albedo
            .as_ref()
            .map_or(0, |_| majorants + entries(&cell_majorants));
        let push_grid = |tables: &mut Vec<[f32; 4]>,
                         g: &DensityGrid,
                         data: u32,
                         cells: [u32; 3],
                         majorants: u32,
                         albedo: u32| {
            let rows = rows_of(g);
            for r in 0..3 {
                tables.push(rows.col(r).to_array());
            }
            tables.push(bits(g.res, data * 4));
            tables.push(bits(cells, majorants * 4));
            tables.push(bits([g.channels, 0, 0], albedo));
        };
        push_grid(
            &mut tables,
            grid,
            data,
            grid.cells(),
            majorants,
            albedo_header,
        );
        let pad = |tables: &mut Vec<[f32; 4]>, values: &[f32]| {
            tables.extend(values.chunks(4).map(|c| {
                let mut e = [0.0; 4];
                e[..c.len()].copy_from_slice(c);
                e
            }));
        };
        pad(&mut tables, &grid.values);
        pad(&mut tables, &cell_majorants);
        if let Some(a) = albedo {
            push_grid(
                &mut tables,
                a,
                albedo_header + records::GRID_ENTRIES,
                [0; 3],
                0,
                0,
            );
            pad(&mut tables, &a.values);
        }
    }
    // each material record's media word, four to an entry, after the media
    // (whenever the file has media: a path in a medium reads them at every surface)
    let shapes_hold_media = media_words.iter().any(|&w| w != 0);
    let material_media = if num_media == 0 {
        0
    } else {
        tables.len() as u32
    };
    if num_media != 0 {
        let mut words = media_words.clone();
        words.resize(materials.len().next_multiple_of(4), 0);
        tables.extend(
            words
                .chunks(4)
                .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32, c[3] as f32]),
        );
    }
    let groups = build_groups(&mut builder);
    let Builder {
        unbounded,
        mut bounded,
        shape_data,
        ..
    } = builder;
    let mut boxes: Vec<Aabb> = bounded
        .iter()
        .map(|p| world_bounds(p, &shape_data))
        .collect();
    for (prim, b) in &groups.instances {
        bounded.push(*prim);
        boxes.push(*b);
    }
    // instances are reached through the BVH only
    let use_bvh = !groups.instances.is_empty() || build.acceleration.uses_bvh(&bounded);
    let num_unbounded = unbounded.len() as u32;
    let (mut primitives, mut bvh, mut bvh_depth) = order(unbounded, bounded, &boxes, use_bvh);
    if !groups.trees.is_empty() {
        // a walk into an instance holds the scene's stack entries, the child nodes still
        // to visit of the node whose leaf holds the instance, and then the group's
        bvh_depth += 1 + groups.depth;
        if bvh_depth > records::BVH_STACK_SIZE {
            return Err(FlattenError::Depth(bvh_depth));
        }
        append_groups(&mut primitives, &mut bvh, groups);
    }

    // the scene's bounding radius, for the background's power
    let env = env_dist.map(|integral| (integral, bounding_sphere(&boxes).1));
    let (mut emitters, env_light) = light_list(
        &mut primitives,
        num_unbounded as usize,
        &materials,
        &shape_data,
        env,
    );
    let gltf_lights: Vec<LightDesc> = file
        .objects
        .iter()
        .zip(&files.imported)
        .filter_map(|(o, g)| {
            Some((
                transform_matrix(&o.get_ref().transform().unwrap_or_default()),
                g.as_ref()?,
            ))
        })
        .flat_map(|(m, g)| g.lights.iter().map(move |l| l.transformed(m)))
        .collect();
    let num_punctual = (file.lights.len() + gltf_lights.len()) as u32;
    let texture = |name: &str| {
        let i = texture_names
            .iter()
            .position(|n| n == name)
            .expect("validated");
        let aspect = texture_list[i]
            .2
            .map_or(1.0, |im| im.width as f32 / im.height as f32);
        (i as u32, aspect)
    };
    emitters.extend(punctual_lights(
        file.lights.iter().map(|l| l.get_ref()).chain(&gltf_lights),
        bounding_sphere(&boxes),
        &texture,
    ));
    let rotation = bg.rotation.unwrap_or(0.0).to_radians();

    let r = &file.render;
    let crop = r.crop.unwrap_or([0, 0, r.width, r.height]);
    Ok(FlatScene {
        warnings: Vec::new(),
        width: crop[2],
        height: crop[3],
        spp: r.spp,
        max_depth: r.max_depth,
        seed: r.seed,
        sampler: r.sampler,
        filter: PixelFilter::of(r),
        camera: cropped(
            camera_frame(file, r.width as f32 / r.height as f32),
            [r.width, r.height],
            crop,
        ),
        rr_depth: if build.russian_roulette { RR_DEPTH } else { 0 },
        hide_emitters: r.hide_emitters,
        light_sampling: r.light_sampling,
        background: bg.bottom.or(bg.color).unwrap_or([0.0; 3]),
        background_top: bg.top,
        env: env_texture.map(|texture| EnvironmentMap {
            texture,
            cdf: env_cdf,
            light: env_light,
            rotation: [rotation.cos(), rotation.sin()],
            strength,
        }),
        primitives,
        materials,
        emitters,
        material_names,
        bvh,
        num_punctual,
        bvh_depth,
        shape_data,
        num_unbounded,
        use_bvh,
        aovs: false,
        textures,
        texels,
        tables,
        ms_tables,
        media,
        num_media,
        camera_medium,
        material_media,
        shapes_hold_media,
        grid_media,
    })
}

/// Moves each absorbing dielectric record's absorption into a homogeneous medium of
/// albedo 0 (sigma_t the absorption), the interior of its media word (validation refuses
/// an object of absorbing glass that names its own); where the object names no exterior,
/// the camera's medium is outside (a glass in a fog that fills the scene leaves into the
/// fog). Returns the new media's extinctions, numbered from `first`, one per distinct
/// coefficient.
fn absorbing_glass(
    materials: &mut [Material],
    words: &mut [u32],
    first: usize,
    camera_medium: u32,
) -> Vec<[f32; 3]> {
    let mut media: Vec<[f32; 3]> = Vec::new();
    for (m, word) in materials.iter_mut().zip(words.iter_mut()) {
        if m.tag != MaterialKind::Dielectric.tag() {
            continue;
        }
        let mut p = dielectric::Params::read(m);
        let a: [f32; 3] = p.absorption.into();
        if a == [0.0; 3] {
            continue;
        }
        let i = media.iter().position(|x| *x == a).unwrap_or_else(|| {
            media.push(a);
            media.len() - 1
        });
        if *word % records::MEDIA_SIDE == 0 {
            *word += (first + i) as u32 + 1;
        }
        if *word / records::MEDIA_SIDE == 0 && camera_medium != records::NO_MEDIUM {
            *word += records::MEDIA_SIDE * (camera_medium + 1);
        }
        p.absorption = glam::Vec3::ZERO;
        p.write(m);
    }
    media
}

/// The centre and half the diagonal of the bounded primitives' box (the origin and 1
/// without any): the scene's extent for the power of lights, what reaches it.
fn bounding_sphere(boxes: &[Aabb]) -> (Vec3, f32) {
    if boxes.is_empty() {
        return (Vec3::ZERO, 1.0);
    }
    let bounds = boxes.iter().fold(Aabb::empty(), |a, b| a.union(b));
    (
        0.5 * (bounds.lo + bounds.hi),
        0.5 * (bounds.hi - bounds.lo).length(),
    )
}

/// Every object's primitives (planes apart) and shape data, a group's apart from the
/// scene's, and the instances; errors with the indices of objects whose records
/// degenerate in f32 (see `record_ok`).
fn build_primitives(
    file: &SceneFile,
    files: &SceneFiles,
    materials: &mut Vec<Material>,
    material_names: &mut Vec<String>,
) -> Result<(Builder, Vec<u32>), Vec<usize>> {
    // the materials of the file, by name (the list grows by the copies below)
    let named = material_names.clone();
    let material_index = |name: &str| named.iter().position(|n| n == name).unwrap() as u32;
    // a shape with media gets a copy of its material's record holding them, one per
    // material and pair of media
    let medium = |name: Option<&str>| {
        name.map_or(0, |n| {
            1 + file.media.keys().position(|m| m == n).expect("validated") as u32
        })
    };
    let mut copies: std::collections::HashMap<(u32, u32), u32> = Default::default();
    let mut words = vec![0; materials.len()];
    let mut with_media = |index: u32, o: &ObjectDesc| -> u32 {
        let (interior, exterior) = o.media();
        if interior.is_none() && exterior.is_none() {
            return index;
        }
        let word = medium(interior) + records::MEDIA_SIDE * medium(exterior);
        *copies.entry((index, word)).or_insert_with(|| {
            materials.push(materials[index as usize]);
            material_names.push(material_names[index as usize].clone());
            words.push(word);
            materials.len() as u32 - 1
        })
    };
    let mut builder = Builder {
        groups: vec![Vec::new(); file.members.len()],
        ..Default::default()
    };
    let mut degenerate = Vec::new();
    // the glTF objects' materials follow the file's, in object order
    let mut next_gltf_material = file.materials.len() as u32;
    for (i, obj) in file.objects.iter().enumerate() {
        let o = obj.get_ref();
        let (u, b) = (builder.unbounded.len(), builder.bounded.len());
        match (&files.imported[i], o.material(), o) {
            (_, _, ObjectDesc::Instance { group, transform }) => {
                let g = file.members.iter().position(|(n, _)| n == group);
                let m = transform_matrix(&transform.unwrap_or_default());
                let inverse = m.inverse();
                let finite = |m: Affine3A| m.to_cols_array().iter().all(|x| x.is_finite());
                if !(finite(m) && finite(inverse)) {
                    degenerate.push(i);
                }
                builder.instances.push((g.expect("validated"), m));
                continue;
            }
            (Some(g), _, _) => {
                builder.push_imported(o, g, next_gltf_material);
                next_gltf_material += g.materials.len() as u32;
            }
            (None, Some(m), _) => {
                let index = with_media(material_index(m), o);
                builder.push_object(o, files.meshes[i].as_ref(), index)
            }
            (None, None, _) => unreachable!("an object without a material is a glTF file"),
        }
        let added = builder.unbounded[u..].iter().chain(&builder.bounded[b..]);
        if !added.clone().all(|p| record_ok(p, &builder.shape_data)) {
            degenerate.push(i);
        }
        if let Some(g) = file.group_of(i) {
            let members: Vec<Primitive> = builder.bounded.drain(b..).collect();
            builder.groups[g].extend(members);
        }
    }
    if degenerate.is_empty() {
        Ok((builder, words))
    } else {
        Err(degenerate)
    }
}

/// The groups' BVHs and the instances over them: each group's primitives (in its BVH's
/// leaf order) and nodes, as `order` leaves them numbered from 0 and to be moved after the
/// scene's own (`append_groups`); an instance record per instance, with its box, for the
/// scene's BVH.
struct Groups {
    trees: Vec<(Vec<Primitive>, bvh::WideBvh)>,
    instances: Vec<(Primitive, Aabb)>,
    /// The deepest group's BVH (0 without groups).
    depth: u32,
}

fn build_groups(builder: &mut Builder) -> Groups {
    let mut trees = Vec::new();
    let mut bounds = Vec::new();
    for prims in &builder.groups {
        let boxes: Vec<Aabb> = prims
            .iter()
            .map(|p| world_bounds(p, &builder.shape_data))
            .collect();
        let tree = bvh::collapse(&bvh::build(&boxes), &boxes);
        let ordered = tree.order.iter().map(|&i| prims[i as usize]).collect();
        bounds.push(boxes.iter().fold(Aabb::empty(), |a, b| a.union(b)));
        trees.push((ordered, tree));
    }
    let instances = std::mem::take(&mut builder.instances)
        .into_iter()
        .map(|(g, m)| {
            let prim = Primitive {
                tag: records::PRIM_INSTANCE,
                data: builder.push_transform(m),
                // the root's index is known once the nodes are placed (append_groups)
                a: [0.0, f32::from_bits(g as u32), 0.0, 0.0],
                ..Default::default()
            };
            (prim, transformed_box(&bounds[g], m))
        })
        .collect();
    let depth = trees.iter().map(|t| t.1.depth).max().unwrap_or(0);
    Groups {
        trees,
        instances,
        depth,
    }
}

/// The box of `b`'s eight corners under `m`.
fn transformed_box(b: &Aabb, m: Affine3A) -> Aabb {
    let mut out = Aabb::empty();
    for k in 0..8 {
        let corner = Vec3::select(
            glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0),
            b.hi,
            b.lo,
        );
        out.grow(m.transform_point3(corner));
    }
    out
}

/// The groups' primitives and nodes after the scene's, their nodes' indices moved with
/// them, and each instance pointed at its group's root (`a.x`, the bits of the index).
fn append_groups(primitives: &mut Vec<Primitive>, nodes: &mut Vec<BvhNode>, groups: Groups) {
    let mut roots = Vec::new();
    for (prims, tree) in groups.trees {
        let (first_prim, first_node) = (primitives.len() as u32, nodes.len() as u32);
        roots.push(first_node);
        primitives.extend(prims);
        nodes.extend(tree.nodes.into_iter().map(|mut n| {
            n.child += first_node;
            n.prim += first_prim;
            n
        }));
    }
    for p in primitives
        .iter_mut()
        .filter(|p| p.tag == records::PRIM_INSTANCE)
    {
        p.a[0] = f32::from_bits(roots[p.a[1].to_bits() as usize]);
    }
}

/// The primitives in their final order, with the BVH over the bounded ones
/// (`bvh::collapse`) and its depth: planes first, then the bounded primitives in the
/// BVH's leaf order, or, without it, grouped by type in the order of the shaders'
/// per-type loops (`primitives::sort_for_loops`), with no nodes.
fn order(
    unbounded: Vec<Primitive>,
    bounded: Vec<Primitive>,
    boxes: &[Aabb],
    use_bvh: bool,
) -> (Vec<Primitive>, Vec<BvhNode>, u32) {
    let num_unbounded = unbounded.len() as u32;
    let mut primitives = unbounded;
    if !use_bvh {
        let mut sorted = bounded;
        sort_for_loops(&mut sorted);
        primitives.extend(sorted);
        return (primitives, Vec::new(), 0);
    }
    let mut tree = bvh::collapse(&bvh::build(boxes), boxes);
    primitives.extend(tree.order.iter().map(|&i| bounded[i as usize]));
    // leaves index the primitives after the planes
    for n in &mut tree.nodes {
        n.prim += num_unbounded;
    }
    (primitives, tree.nodes, tree.depth)
}

fn camera_frame(file: &SceneFile, aspect: f32) -> CameraFrame {
    let c = &file.camera;
    let origin = Vec3::from(c.look_from);
    let to_target = Vec3::from(c.look_at) - origin;
    let forward = to_target.normalize();
    let right = forward.cross(Vec3::from(c.up)).normalize();
    let up = right.cross(forward);
    let right = if c.mirror { -right } else { right };
    let focus_distance = c.focus_distance.unwrap_or(to_target.length());
    let orthographic = c.projection == Projection::Orthographic;
    let half_height = match c.height {
        Some(h) if orthographic => 0.5 * h,
        _ => (c.vfov.to_radians() * 0.5).tan() * focus_distance,
    };
    CameraFrame {
        origin,
        right,
        up,
        forward,
        half_width: half_height * aspect,
        half_height,
        focus_distance,
        lens_radius: if orthographic { 0.0 } else { c.aperture * 0.5 },
        orthographic,
        near_clip: c.near_clip,
    }
}

/// The camera of the rectangle `crop` (`[x, y, width, height]` in pixels from the top
/// left) of a `film` (`[width, height]`) seen by `c`: the same rays for the same film
/// positions, each pixel of the crop being that pixel of the film (but for where a
/// near_clip plane starts them, below). The view rectangle
/// shrinks to the crop's share and its centre moves to the crop's: a perspective camera
/// looks through the crop's centre (forward times the focus distance becomes the vector
/// to it, right and up stay the film's), an orthographic one moves its origin there.
fn cropped(c: CameraFrame, film: [u32; 2], crop: [u32; 4]) -> CameraFrame {
    if crop == [0, 0, film[0], film[1]] {
        return c;
    }
    let (w, h) = (film[0] as f32, film[1] as f32);
    // the crop's centre in the view rectangle, from -1 to 1 (right, up)
    let sx = 2.0 * (crop[0] as f32 + 0.5 * crop[2] as f32) / w - 1.0;
    let sy = 1.0 - 2.0 * (crop[1] as f32 + 0.5 * crop[3] as f32) / h;
    let shift = c.right * (sx * c.half_width) + c.up * (sy * c.half_height);
    let half_width = c.half_width * crop[2] as f32 / w;
    let half_height = c.half_height * crop[3] as f32 / h;
    if c.orthographic {
        return CameraFrame {
            origin: c.origin + shift,
            half_width,
            half_height,
            ..c
        };
    }
    let to_centre = c.forward * c.focus_distance + shift;
    let forward = to_centre.normalize();
    CameraFrame {
        forward,
        focus_distance: to_centre.length(),
        half_width,
        half_height,
        // rays start on the plane square to the crop's central ray through the point
        // where that ray crosses the film's clip plane (the shader's plane is square to
        // forward): the film's plane there, tilted from it by the angle between the two
        near_clip: c.near_clip / forward.dot(c.forward),
        ..c
    }
}
