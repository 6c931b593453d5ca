//! Scenes: parse (`format`), validate and flatten into the records both backends read.
//!
//! Data flows one way: file -> [`format::SceneFile`] -> validation -> [`FlatScene`] (records).
//! This module knows nothing of the backends.

pub mod error;
pub mod format;
pub mod records;

use std::path::Path;

use glam::Vec3;

pub use error::{Problem, SceneError};
use format::{MaterialDesc, ObjectDesc, SceneFile};
use records::{Emitter, Material, Params, Primitive};

/// Command-line values that replace the scene's `[render]` settings.
#[derive(Debug, Clone, Copy, Default)]
pub struct Overrides {
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spp: Option<u32>,
    pub max_depth: Option<u32>,
    pub seed: Option<u32>,
}

/// Largest image side accepted.
pub const MAX_IMAGE_SIDE: u32 = 16384;
/// Longest path accepted (rays per path).
pub const MAX_DEPTH_LIMIT: u32 = 1024;

/// The camera reduced to what the shader needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraFrame {
    pub origin: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    pub forward: Vec3,
    pub half_width: f32,
    pub half_height: f32,
    pub focus_distance: f32,
    pub lens_radius: f32,
}

/// A validated scene flattened into shader records.
#[derive(Debug, Clone)]
pub struct FlatScene {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: u32,
    pub seed: u32,
    pub camera: CameraFrame,
    pub background: [f32; 3],
    pub primitives: Vec<Primitive>,
    pub materials: Vec<Material>,
    pub emitters: Vec<Emitter>,
    /// Material names, in record order.
    pub material_names: Vec<String>,
}

/// A rectangle of pixels rendered by one dispatch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tile {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

impl FlatScene {
    /// The uniform block for one dispatch: pass `sample_index` over `tile`.
    pub fn params(&self, sample_index: u32, tile: Tile) -> Params {
        let c = &self.camera;
        Params {
            cam_origin: c.origin.extend(c.lens_radius).to_array(),
            cam_right: c.right.extend(c.half_width).to_array(),
            cam_up: c.up.extend(c.half_height).to_array(),
            cam_forward: c.forward.extend(c.focus_distance).to_array(),
            background: [
                self.background[0],
                self.background[1],
                self.background[2],
                0.0,
            ],
            width: self.width,
            height: self.height,
            max_depth: self.max_depth,
            seed: self.seed,
            sample_index,
            num_primitives: self.primitives.len() as u32,
            num_emitters: self.emitters.len() as u32,
            tile_x: tile.x,
            tile_y: tile.y,
            tile_width: tile.width,
            tile_height: tile.height,
            pad: 0,
        }
    }

    /// The whole image as one tile.
    pub fn full_tile(&self) -> Tile {
        Tile {
            x: 0,
            y: 0,
            width: self.width,
            height: self.height,
        }
    }
}

/// Reads, validates and flattens a scene file.
pub fn load_scene(path: &Path, overrides: &Overrides) -> Result<FlatScene, SceneError> {
    let src = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    load_scene_str(&src, path, overrides)
}

/// Validates and flattens scene text; `path` names it in errors.
pub fn load_scene_str(
    src: &str,
    path: &Path,
    overrides: &Overrides,
) -> Result<FlatScene, SceneError> {
    let invalid = |problems| SceneError::Invalid {
        path: path.to_path_buf(),
        problems,
    };
    let mut file: SceneFile = toml::from_str(src).map_err(|e| {
        let (line, column) = e.span().map_or((0, 0), |s| error::line_col(src, s.start));
        invalid(vec![Problem {
            line,
            column,
            key: String::new(),
            message: e.message().trim().to_string(),
        }])
    })?;
    apply_overrides(&mut file, overrides);
    let problems = validate(&file, src);
    if !problems.is_empty() {
        return Err(invalid(problems));
    }
    Ok(flatten(&file))
}

fn apply_overrides(file: &mut SceneFile, o: &Overrides) {
    let r = &mut file.render;
    r.width = o.width.unwrap_or(r.width);
    r.height = o.height.unwrap_or(r.height);
    r.spp = o.spp.unwrap_or(r.spp);
    r.max_depth = o.max_depth.unwrap_or(r.max_depth);
    r.seed = o.seed.unwrap_or(r.seed);
}

/// Collects every problem of a parsed scene (not only the first).
fn validate(file: &SceneFile, src: &str) -> Vec<Problem> {
    let mut v = Validator {
        src,
        problems: Vec::new(),
    };
    let r = &file.render;
    v.range_u32("render.width", r.width, 1, MAX_IMAGE_SIDE, 0);
    v.range_u32("render.height", r.height, 1, MAX_IMAGE_SIDE, 0);
    v.range_u32("render.spp", r.spp, 1, u32::MAX, 0);
    v.range_u32("render.max_depth", r.max_depth, 1, MAX_DEPTH_LIMIT, 0);

    let c = &file.camera;
    v.finite3("camera.look_from", c.look_from, 0);
    v.finite3("camera.look_at", c.look_at, 0);
    v.finite3("camera.up", c.up, 0);
    let forward = Vec3::from(c.look_at) - Vec3::from(c.look_from);
    if forward.length_squared() == 0.0 {
        v.push(0, "camera.look_at", "must differ from look_from".into());
    } else if forward.cross(Vec3::from(c.up)).length_squared() <= 1e-12 * forward.length_squared() {
        v.push(
            0,
            "camera.up",
            "must not be parallel to the view direction".into(),
        );
    }
    if !(c.vfov > 0.0 && c.vfov < 180.0) {
        v.push(
            0,
            "camera.vfov",
            format!("must be in (0, 180) degrees, got {}", c.vfov),
        );
    }
    if !(c.aperture >= 0.0 && c.aperture.is_finite()) {
        v.push(
            0,
            "camera.aperture",
            format!("must be >= 0, got {}", c.aperture),
        );
    }
    if let Some(fd) = c.focus_distance {
        if !(fd > 0.0 && fd.is_finite()) {
            v.push(0, "camera.focus_distance", format!("must be > 0, got {fd}"));
        }
    }
    v.nonnegative3("background.color", file.background.color, 0);

    for (name, m) in &file.materials {
        let at = m.span().start;
        let key = format!("materials.{name}");
        match m.get_ref() {
            MaterialDesc::Lambertian { albedo } => {
                v.nonnegative3(&format!("{key}.albedo"), *albedo, at);
                if albedo.iter().any(|&a| a > 1.0) {
                    v.push(
                        at,
                        &format!("{key}.albedo"),
                        "components must be <= 1".into(),
                    );
                }
            }
            MaterialDesc::Emissive { radiance, .. } => {
                v.nonnegative3(&format!("{key}.radiance"), *radiance, at);
            }
        }
    }

    for (i, obj) in file.objects.iter().enumerate() {
        let at = obj.span().start;
        let key = format!("objects[{i}]");
        let o = obj.get_ref();
        if !file.materials.contains_key(o.material()) {
            let known: Vec<&str> = file.materials.keys().map(String::as_str).collect();
            v.push(
                at,
                &format!("{key}.material"),
                format!(
                    "unknown material \"{}\" (defined: {})",
                    o.material(),
                    if known.is_empty() {
                        "none".to_string()
                    } else {
                        known.join(", ")
                    }
                ),
            );
        }
        match o {
            ObjectDesc::Sphere { center, radius, .. } => {
                v.finite3(&format!("{key}.center"), *center, at);
                if !(*radius > 0.0 && radius.is_finite()) {
                    v.push(
                        at,
                        &format!("{key}.radius"),
                        format!("must be > 0, got {radius}"),
                    );
                }
            }
            ObjectDesc::Triangle { vertices, .. } => {
                v.polygon(&key, vertices, at);
            }
            ObjectDesc::Polygon { vertices, .. } => {
                v.polygon(&key, vertices, at);
            }
        }
    }
    v.problems
}

struct Validator<'a> {
    src: &'a str,
    problems: Vec<Problem>,
}

impl Validator<'_> {
    fn push(&mut self, offset: usize, key: &str, message: String) {
        let (line, column) = if offset == 0 {
            (0, 0)
        } else {
            error::line_col(self.src, offset)
        };
        self.problems.push(Problem {
            line,
            column,
            key: key.to_string(),
            message,
        });
    }

    fn range_u32(&mut self, key: &str, value: u32, lo: u32, hi: u32, at: usize) {
        if value < lo || value > hi {
            let range = if hi == u32::MAX {
                format!(">= {lo}")
            } else {
                format!("in {lo}..={hi}")
            };
            self.push(at, key, format!("must be {range}, got {value}"));
        }
    }

    fn finite3(&mut self, key: &str, v: [f32; 3], at: usize) -> bool {
        let ok = v.iter().all(|x| x.is_finite());
        if !ok {
            self.push(at, key, format!("must be finite, got {v:?}"));
        }
        ok
    }

    fn nonnegative3(&mut self, key: &str, v: [f32; 3], at: usize) {
        if self.finite3(key, v, at) && v.iter().any(|&x| x < 0.0) {
            self.push(at, key, format!("must be >= 0, got {v:?}"));
        }
    }

    /// Triangles and polygons: finite, at least 3 vertices, non-degenerate, planar, convex.
    fn polygon(&mut self, key: &str, vertices: &[[f32; 3]], at: usize) {
        let vkey = format!("{key}.vertices");
        if vertices.len() < 3 {
            self.push(
                at,
                &vkey,
                format!("needs at least 3 vertices, got {}", vertices.len()),
            );
            return;
        }
        if !vertices.iter().all(|p| p.iter().all(|x| x.is_finite())) {
            self.push(at, &vkey, "must be finite".into());
            return;
        }
        let pts: Vec<Vec3> = vertices.iter().map(|&p| Vec3::from(p)).collect();
        let normal = polygon_normal(&pts);
        let scale = pts
            .iter()
            .fold(0.0f32, |m, p| m.max((*p - pts[0]).length()));
        if normal.length() <= 1e-7 * scale * scale || scale == 0.0 {
            self.push(at, &vkey, "is degenerate (zero area)".into());
            return;
        }
        let n = normal.normalize();
        if pts
            .iter()
            .any(|p| (*p - pts[0]).dot(n).abs() > 1e-4 * scale)
        {
            self.push(at, &vkey, "are not coplanar".into());
            return;
        }
        let k = pts.len();
        for i in 0..k {
            let e0 = pts[(i + 1) % k] - pts[i];
            let e1 = pts[(i + 2) % k] - pts[(i + 1) % k];
            if e0.cross(e1).dot(n) < -1e-6 * scale * scale {
                self.push(at, &vkey, "must form a convex polygon".into());
                return;
            }
        }
    }
}

/// Area-weighted normal of a planar polygon (Newell's method): length = 2 x area.
fn polygon_normal(pts: &[Vec3]) -> Vec3 {
    let mut n = Vec3::ZERO;
    for i in 1..pts.len() - 1 {
        n += (pts[i] - pts[0]).cross(pts[i + 1] - pts[0]);
    }
    n
}

fn material_record(m: &MaterialDesc) -> Material {
    match *m {
        MaterialDesc::Lambertian { albedo } => Material {
            tag: records::MAT_LAMBERTIAN,
            albedo: [albedo[0], albedo[1], albedo[2], 0.0],
            ..Default::default()
        },
        MaterialDesc::Emissive {
            radiance,
            two_sided,
        } => Material {
            tag: records::MAT_EMISSIVE,
            flags: if two_sided {
                records::MAT_FLAG_TWO_SIDED
            } else {
                0
            },
            emission: [radiance[0], radiance[1], radiance[2], 0.0],
            ..Default::default()
        },
    }
}

fn triangle(v0: [f32; 3], v1: [f32; 3], v2: [f32; 3], material: u32) -> Primitive {
    Primitive {
        tag: records::PRIM_TRIANGLE,
        material,
        a: [v0[0], v0[1], v0[2], 0.0],
        b: [v1[0], v1[1], v1[2], 0.0],
        c: [v2[0], v2[1], v2[2], 0.0],
        ..Default::default()
    }
}

/// Surface area of a primitive.
pub fn primitive_area(p: &Primitive) -> f32 {
    match p.tag {
        records::PRIM_SPHERE => 4.0 * std::f32::consts::PI * p.a[3] * p.a[3],
        records::PRIM_TRIANGLE => {
            let a = Vec3::from_slice(&p.a);
            let b = Vec3::from_slice(&p.b);
            let c = Vec3::from_slice(&p.c);
            0.5 * (b - a).cross(c - a).length()
        }
        _ => 0.0,
    }
}

fn luminance(c: [f32; 4]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// Flattens a validated scene into records.
fn flatten(file: &SceneFile) -> FlatScene {
    let material_names: Vec<String> = file.materials.keys().cloned().collect();
    let materials: Vec<Material> = file
        .materials
        .values()
        .map(|m| material_record(m.get_ref()))
        .collect();
    let material_index = |name: &str| material_names.iter().position(|n| n == name).unwrap() as u32;

    let mut primitives = Vec::new();
    for obj in &file.objects {
        let o = obj.get_ref();
        let m = material_index(o.material());
        match o {
            ObjectDesc::Sphere { center, radius, .. } => primitives.push(Primitive {
                tag: records::PRIM_SPHERE,
                material: m,
                a: [center[0], center[1], center[2], *radius],
                ..Default::default()
            }),
            ObjectDesc::Triangle { vertices: v, .. } => {
                primitives.push(triangle(v[0], v[1], v[2], m))
            }
            ObjectDesc::Polygon { vertices: v, .. } => {
                for i in 1..v.len() - 1 {
                    primitives.push(triangle(v[0], v[i], v[i + 1], m));
                }
            }
        }
    }

    let emitters = primitives
        .iter()
        .enumerate()
        .filter_map(|(i, p)| {
            let mat = &materials[p.material as usize];
            let sides = if mat.flags & records::MAT_FLAG_TWO_SIDED != 0 {
                2.0
            } else {
                1.0
            };
            let area = primitive_area(p);
            let power = luminance(mat.emission) * area * std::f32::consts::PI * sides;
            (power > 0.0).then_some(Emitter {
                primitive: i as u32,
                material: p.material,
                area,
                power,
            })
        })
        .collect();

    let r = &file.render;
    FlatScene {
        width: r.width,
        height: r.height,
        spp: r.spp,
        max_depth: r.max_depth,
        seed: r.seed,
        camera: camera_frame(file, r.width as f32 / r.height as f32),
        background: file.background.color,
        primitives,
        materials,
        emitters,
        material_names,
    }
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
