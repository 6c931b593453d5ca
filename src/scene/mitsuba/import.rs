//! The Mitsuba importer's second stage: a scene tree mapped onto wgtrace's own scene format,
//! written as the TOML text a user could have written (`wgtrace convert` writes it out;
//! `wgtrace render scene.xml` loads it as any scene file). Each table of that text keeps
//! the position of the XML element it came from, so that a problem the scene checks find
//! in it is reported at the element.
//!
//! Mitsuba's conventions carried over: uv coordinates with v down (v' = 1 - v on shapes
//! whose uvs Mitsuba makes; OBJ files' uvs Mitsuba flips as it reads them, as wgtrace
//! keeps them), `to_uv` conjugated by that flip, BSDFs black from behind unless inside a
//! `twosided`, roughness alpha = roughness^2, the default diffuse BSDF on shapes without
//! one (reflectance 0.5, 0 on an emitter), area emitters on the front side only, spectra converted as its
//! RGB mode converts them, the horizontal field of view, the camera's local +x pointing
//! left, and its Gaussian pixel filter by default.

use std::collections::{HashMap, HashSet};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use glam::{DMat3, DMat4, DVec3};
use toml::{Table, Value as T};

use super::parse::{Object, Pos, SceneTree, Spectrum, Value, XmlError};
use super::spectrum::{self, Use};

/// A Mitsuba scene as wgtrace's TOML scene text.
#[derive(Debug, Clone)]
pub struct Imported {
    /// The scene in wgtrace's format.
    pub toml: String,
    /// Where each table of `toml` came from, in line order.
    pub origins: Vec<Origin>,
    /// What was mapped onto something that renders the same expected image by other
    /// means (a light tracer as a path tracer, Russian roulette's start), one line each.
    pub notes: Vec<String>,
}

/// The XML element a table of the TOML text was made from.
#[derive(Debug, Clone)]
pub struct Origin {
    /// The table's first line in the TOML text (1-based).
    pub line: usize,
    pub pos: Pos,
    /// The element, as "bsdf roughconductor" or "shape obj".
    pub what: String,
}

impl Imported {
    /// The element the TOML text's `line` came from.
    pub fn origin(&self, line: usize) -> Option<&Origin> {
        self.origins.iter().rev().find(|o| o.line <= line)
    }
}

/// Maps `tree` onto wgtrace's format. File paths are written relative to `base` (the
/// folder the TOML text is read from) where they lie under it, else absolute.
pub fn import(tree: &SceneTree, base: &Path) -> Result<Imported, XmlError> {
    let mut im = Importer {
        tree,
        base: base.to_path_buf(),
        // Mitsuba's BSDFs take shading normals strictly, its normalmap and bumpmap too
        render: Table::from_iter([("shading_normals".to_string(), text("strict"))]),
        camera: None,
        background: None,
        textures: Vec::new(),
        materials: Vec::new(),
        objects: Vec::new(),
        lights: Vec::new(),
        groups: Vec::new(),
        group_names: HashMap::new(),
        in_group: None,
        names: HashSet::new(),
        texture_names: HashMap::new(),
        material_names: HashMap::new(),
        media: Vec::new(),
        medium_names: HashMap::new(),
        notes: Vec::new(),
        world: DMat4::IDENTITY,
    };
    im.scene()?;
    Ok(im.write())
}

type Result<T, E = XmlError> = std::result::Result<T, E>;

fn err<V>(pos: &Pos, message: impl Into<String>) -> Result<V> {
    Err(XmlError {
        pos: pos.clone(),
        message: message.into(),
    })
}

/// One table of the output: its header, keys, and origin.
struct Entry {
    name: String,
    table: Table,
    pos: Pos,
    what: String,
}

struct Importer<'a> {
    tree: &'a SceneTree,
    /// A rotation of the whole scene (shapes, camera, lights, environment) applied as it is
    /// read: the inverse of an envmap's turn about another axis than +y, so that the
    /// environment turns about +y only, as wgtrace's does; the image is the same (the
    /// camera turns with the scene). The identity otherwise.
    world: DMat4,
    base: PathBuf,
    render: Table,
    camera: Option<Entry>,
    background: Option<Entry>,
    textures: Vec<Entry>,
    materials: Vec<Entry>,
    objects: Vec<Entry>,
    lights: Vec<Entry>,
    /// The objects of `[groups.NAME]`: each shapegroup's shapes, written once.
    groups: Vec<Entry>,
    /// shapegroup object -> its group's name.
    group_names: HashMap<usize, String>,
    /// While a shapegroup's shapes are read: the group's name (they go to `groups`).
    in_group: Option<String>,
    /// Texture, material and group names taken.
    names: HashSet<String>,
    /// By texture object and whether it is read as a scalar (a checkerboard's colours
    /// swap there).
    texture_names: HashMap<(usize, bool), String>,
    /// (BSDF object or none, emitter object or none) -> material name.
    material_names: HashMap<(Option<usize>, Option<usize>), String>,
    /// `[media.NAME]` tables, and the name of each medium object read.
    media: Vec<Entry>,
    medium_names: HashMap<usize, String>,
    notes: Vec<String>,
}

/// What an element is, for messages: `bsdf roughconductor`.
fn what(o: &Object) -> String {
    format!("{} {}", o.tag, o.plugin)
}

fn float(x: f64) -> T {
    // rounding residue (cos 90 degrees) as 0; then the shortest decimal that reads back
    // as the same f32: what wgtrace will hold
    let x = if x.abs() < 1e-12 { 0.0 } else { x };
    T::Float((x as f32).to_string().parse().unwrap_or(x))
}

fn vec3(v: DVec3) -> T {
    T::Array(v.to_array().into_iter().map(float).collect())
}

fn rgb(c: [f64; 3]) -> T {
    T::Array(c.into_iter().map(float).collect())
}

fn text(s: &str) -> T {
    T::String(s.to_string())
}

fn table<const N: usize>(entries: [(&str, T); N]) -> Table {
    entries
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
}

/// A Mitsuba transform as wgtrace's `transform = { matrix = ... }` (row-major 4 x 4).
fn matrix(m: DMat4) -> T {
    let rows = (0..4).map(|r| T::Array(m.row(r).to_array().into_iter().map(float).collect()));
    T::Table(table([("matrix", T::Array(rows.collect()))]))
}

/// The names of the objects a property list refers to, by tag.
fn children<'t>(
    tree: &'t SceneTree,
    o: &'t Object,
    tag: &'t str,
) -> impl Iterator<Item = usize> + 't {
    o.props.iter().filter_map(move |p| match p.value {
        Value::Object(i) if tree.objects[i].tag == tag => Some(i),
        _ => None,
    })
}

impl<'a> Importer<'a> {
    fn obj(&self, i: usize) -> &'a Object {
        &self.tree.objects[i]
    }

    /// A position for a note: line and column in the scene file, the file too in an
    /// included one.
    fn at(&self, pos: &Pos) -> String {
        if pos.file == self.obj(self.tree.root).pos.file {
            format!("line {}:{}", pos.line, pos.col)
        } else {
            pos.to_string()
        }
    }

    // ---- typed property access -------------------------------------------------------

    fn float(&self, o: &Object, name: &str, default: f64) -> Result<f64> {
        match o.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Float(v) => Ok(v),
                Value::Integer(v) => Ok(v as f64),
                _ => err(&p.pos, format!("{}: `{name}` must be a float", what(o))),
            },
        }
    }

    fn integer(&self, o: &Object, name: &str, default: i64) -> Result<i64> {
        match o.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Integer(v) => Ok(v),
                _ => err(&p.pos, format!("{}: `{name}` must be an integer", what(o))),
            },
        }
    }

    fn boolean(&self, o: &Object, name: &str, default: bool) -> Result<bool> {
        match o.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Boolean(v) => Ok(v),
                _ => err(&p.pos, format!("{}: `{name}` must be a boolean", what(o))),
            },
        }
    }

    fn string(&self, o: &'a Object, name: &str) -> Result<Option<&'a str>> {
        match o.get(name) {
            None => Ok(None),
            Some(p) => match &p.value {
                Value::String(s) => Ok(Some(s.as_str())),
                _ => err(&p.pos, format!("{}: `{name}` must be a string", what(o))),
            },
        }
    }

    fn point(&self, o: &Object, name: &str, default: DVec3) -> Result<DVec3> {
        match o.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Point(v) | Value::Vector(v) => Ok(v),
                _ => err(&p.pos, format!("{}: `{name}` must be a point", what(o))),
            },
        }
    }

    fn transform(&self, o: &Object, name: &str) -> Result<DMat4> {
        match o.get(name) {
            None => Ok(DMat4::IDENTITY),
            Some(p) => match p.value {
                Value::Transform(m) => Ok(m),
                _ => err(&p.pos, format!("{}: `{name}` must be a transform", what(o))),
            },
        }
    }

    /// Properties the mapping does not read: refused unless `ignorable`.
    fn check_known(&self, o: &Object, known: &[&str], ignorable: &[&str]) -> Result<()> {
        for p in &o.props {
            // a nested object without a name; a shape's BSDF, emitter or media, a sensor's
            // medium, under any name (Mitsuba reads them by their kind; a shape's media by
            // `interior` and `exterior`)
            let nested_ok = match p.value {
                Value::Object(i) => {
                    p.name.starts_with("_arg_")
                        || o.tag == "shape"
                            && matches!(self.obj(i).tag.as_str(), "bsdf" | "emitter" | "medium")
                        || o.tag == "sensor" && self.obj(i).tag == "medium"
                }
                _ => false,
            };
            if !(nested_ok
                || known.contains(&p.name.as_str())
                || ignorable.contains(&p.name.as_str()))
            {
                return err(
                    &p.pos,
                    format!(
                        "{}: `{}` is not read by wgtrace's import (it reads: {})",
                        what(o),
                        p.name,
                        known.join(", ")
                    ),
                );
            }
        }
        Ok(())
    }

    /// A colour-or-texture value: a float, rgb, spectrum or texture (as its name).
    fn color(&mut self, o: &Object, name: &str, default: f64, use_: Use) -> Result<T> {
        let Some(p) = o.get(name) else {
            return Ok(rgb([default; 3]));
        };
        match &p.value {
            Value::Float(v) => Ok(rgb([*v; 3])),
            Value::Integer(v) => Ok(rgb([*v as f64; 3])),
            Value::Rgb(c) => Ok(rgb(c.to_array())),
            Value::Spectrum(s) => Ok(rgb(spectrum::to_rgb(s, use_))),
            Value::Object(i) if self.obj(*i).tag == "spectrum" => self.spectrum_object(*i).map(rgb),
            Value::Object(i) => self.texture(*i).map(T::String),
            _ => err(
                &p.pos,
                format!(
                    "{}: `{name}` must be a colour, spectrum or texture",
                    what(o)
                ),
            ),
        }
    }

    /// A `<spectrum type="...">` object's constant colour in RGB mode: `srgb` its `color`
    /// as written, `uniform` its `value` (Mitsuba's RGB variants read both so).
    fn spectrum_object(&mut self, i: usize) -> Result<[f64; 3]> {
        let o = self.obj(i);
        match o.plugin.as_str() {
            "srgb" => {
                self.check_known(o, &["color"], &["unbounded"])?;
                match o.get("color").map(|p| &p.value) {
                    Some(Value::Rgb(c)) => Ok(c.to_array()),
                    Some(Value::Float(v)) => Ok([*v; 3]),
                    _ => err(&o.pos, "spectrum srgb: needs an rgb `color`"),
                }
            }
            "uniform" => {
                self.check_known(o, &["value"], &[])?;
                Ok([self.float(o, "value", 1.0)?; 3])
            }
            other => err(
                &o.pos,
                format!(
                    "spectrum {other}: not read (wgtrace reads srgb and uniform spectrum objects)"
                ),
            ),
        }
    }

    /// A constant colour (no texture).
    fn color_const(&mut self, o: &Object, name: &str, default: f64, use_: Use) -> Result<T> {
        let v = self.color(o, name, default, use_)?;
        if let T::String(_) = v {
            return err(
                &o.get(name).unwrap().pos,
                format!(
                    "{}: `{name}` must be a constant colour here, not a texture",
                    what(o)
                ),
            );
        }
        Ok(v)
    }

    /// A conductor's `eta` or `k` with each component's sign dropped, with a note where one
    /// was negative (an exporter's artefact): the Fresnel reflectance of eta + i k is that
    /// of its conjugate and of its negative, so Mitsuba's image is the same.
    fn magnitudes(&mut self, o: &Object, name: &str, v: T) -> T {
        let negative = |x: &T| x.as_float().is_some_and(|f| f < 0.0);
        let any = match &v {
            T::Array(a) => a.iter().any(negative),
            x => negative(x),
        };
        if !any {
            return v;
        }
        self.notes.push(format!(
            "{}: {}: `{name}` has negative components, taken by their magnitude (the same Fresnel reflectance)",
            self.at(o.get(name).map_or(&o.pos, |p| &p.pos)),
            what(o)
        ));
        let abs = |x: &T| x.as_float().map_or(x.clone(), |f| float(f.abs()));
        match &v {
            T::Array(a) => T::Array(a.iter().map(abs).collect()),
            x => abs(x),
        }
    }

    /// A scalar-or-texture value (wgtrace reads a texture's luminance).
    fn scalar(&mut self, o: &Object, name: &str) -> Result<Option<T>> {
        let Some(p) = o.get(name) else {
            return Ok(None);
        };
        match &p.value {
            Value::Float(v) => Ok(Some(float(*v))),
            Value::Integer(v) => Ok(Some(float(*v as f64))),
            Value::Object(i) if self.obj(*i).tag == "spectrum" => {
                // read as a scalar: its luminance (a uniform one's value)
                let c = self.spectrum_object(*i)?;
                Ok(Some(float(0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2])))
            }
            Value::Object(i) => self.scalar_texture(*i).map(|n| Some(T::String(n))),
            Value::Spectrum(Spectrum::Uniform(v)) => Ok(Some(float(*v))),
            // an <rgb> read as a scalar: its luminance, as Mitsuba's eval_1 of it
            Value::Rgb(c) => Ok(Some(float(0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z))),
            _ => err(
                &p.pos,
                format!(
                    "{}: `{name}` must be a float, a colour or a texture",
                    what(o)
                ),
            ),
        }
    }

    /// An index of refraction: a number or one of Mitsuba's names.
    fn ior(&self, o: &Object, name: &str, default: f64) -> Result<f64> {
        let Some(p) = o.get(name) else {
            return Ok(default);
        };
        match &p.value {
            Value::Float(v) => Ok(*v),
            Value::Integer(v) => Ok(*v as f64),
            Value::String(s) => spectrum::named_ior(s).map_or_else(
                || {
                    let names: Vec<&str> = spectrum::NAMED_IORS.iter().map(|n| n.0).collect();
                    err(
                        &p.pos,
                        format!(
                            "{}: `{name}` \"{s}\" is not a known index of refraction (known: {})",
                            what(o),
                            names.join(", ")
                        ),
                    )
                },
                Ok,
            ),
            _ => err(
                &p.pos,
                format!("{}: `{name}` must be a number or a name", what(o)),
            ),
        }
    }

    /// A file a property names, as the TOML text names it.
    fn file(&self, o: &Object, name: &str) -> Result<String> {
        let Some(p) = o.get(name) else {
            return err(&o.pos, format!("{}: needs `{name}`", what(o)));
        };
        let Value::String(s) = &p.value else {
            return err(&p.pos, format!("{}: `{name}` must be a string", what(o)));
        };
        let path = self.tree.find_file(&p.pos, s);
        if !path.exists() {
            return err(
                &p.pos,
                format!("{}: {}: no such file", what(o), path.display()),
            );
        }
        let shown = match path.strip_prefix(&self.base) {
            Ok(rel) if !self.base.as_os_str().is_empty() => rel.to_path_buf(),
            _ if path.is_relative() && self.base.as_os_str().is_empty() => path.clone(),
            _ => std::path::absolute(&path).unwrap_or(path),
        };
        Ok(shown.to_string_lossy().replace('\\', "/"))
    }

    /// A fresh name for a texture or material, from the element's id where it has one.
    fn name(&mut self, o: &Object, fallback: &str) -> String {
        let stem: String =
            o.id.as_deref()
                .unwrap_or(fallback)
                .chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                        c
                    } else {
                        '_'
                    }
                })
                .collect();
        let stem = if stem.is_empty() {
            fallback.to_string()
        } else {
            stem
        };
        let mut name = stem.clone();
        let mut n = 2;
        while !self.names.insert(name.clone()) {
            name = format!("{stem}_{n}");
            n += 1;
        }
        name
    }

    // ---- the scene -------------------------------------------------------------------

    fn scene(&mut self) -> Result<()> {
        let root = self.obj(self.tree.root);
        self.world = self.world_turn()?;
        let mut sensors = 0;
        let mut integrator = None;
        for p in &root.props {
            let Value::Object(i) = p.value else {
                return err(
                    &p.pos,
                    format!(
                        "scene: a <{}> property at the top level is not read",
                        p.name
                    ),
                );
            };
            let o = self.obj(i);
            match o.tag.as_str() {
                "shape" => self.shape(i, self.world, None)?,
                "emitter" => self.emitter(i)?,
                "sensor" => {
                    sensors += 1;
                    if sensors > 1 {
                        return err(
                            &o.pos,
                            "sensor: wgtrace renders one camera; this file has several",
                        );
                    }
                    self.sensor(i)?;
                }
                "integrator" => integrator = Some(i),
                // named for reference only: used where they are referred to
                "bsdf" | "texture" | "medium" | "phase" => {}
                "volume" => {}
                _ => return err(&o.pos, format!("<{}> at the top level is not read", o.tag)),
            }
        }
        if sensors == 0 {
            return err(&root.pos, "scene: has no <sensor>; wgtrace needs a camera");
        }
        self.integrator(integrator)?;
        Ok(())
    }

    /// [`Importer::world`]: for an envmap whose to_world turns it about another axis than
    /// +y (a rotation times a uniform scale, as a z-up scene's), the inverse of that
    /// rotation; else the identity.
    fn world_turn(&self) -> Result<DMat4> {
        let root = self.obj(self.tree.root);
        let envmap = root.props.iter().find_map(|p| match p.value {
            Value::Object(i) if self.obj(i).tag == "emitter" && self.obj(i).plugin == "envmap" => {
                Some(i)
            }
            _ => None,
        });
        let Some(e) = envmap else {
            return Ok(DMat4::IDENTITY);
        };
        let m = self.transform(self.obj(e), "to_world")?;
        if y_rotation(m).is_some() {
            return Ok(DMat4::IDENTITY);
        }
        let l = glam::DMat3::from_mat4(m);
        let r = l * (1.0 / l.y_axis.length());
        let orthonormal = (r.transpose() * r - glam::DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .all(|v| v.abs() <= 1e-6);
        if !orthonormal || r.determinant() <= 0.0 {
            // not a turn: refused where the envmap is read
            return Ok(DMat4::IDENTITY);
        }
        Ok(DMat4::from_mat3(r.transpose()))
    }

    fn integrator(&mut self, i: Option<usize>) -> Result<()> {
        let Some(i) = i else {
            // Mitsuba's default: path tracing without a depth limit
            self.render.insert("max_depth".into(), T::Integer(1024));
            self.notes.push(
                "no <integrator>: Mitsuba's default path tracer (max_depth -1, here 1024)".into(),
            );
            return Ok(());
        };
        let o = self.obj(i);
        let max_depth = match o.plugin.as_str() {
            "path" | "volpath" | "volpathmis" | "ptracer" => self.integer(o, "max_depth", -1)?,
            "direct" => 2,
            "moment" => {
                let inner = children(self.tree, o, "integrator").next();
                let Some(inner) = inner else {
                    return err(&o.pos, "integrator moment: needs a nested integrator");
                };
                self.notes.push(format!(
                    "{}: integrator moment: rendered by its nested integrator (the same mean image; no second moment)",
                    self.at(&o.pos)
                ));
                return self.integrator(Some(inner));
            }
            other => {
                return err(
                    &o.pos,
                    format!(
                        "integrator {other}: not rendered by wgtrace (it renders path, direct, volpath, \
                         volpathmis, and ptracer and moment as a path tracer)"
                    ),
                )
            }
        };
        if o.plugin == "ptracer" {
            self.notes.push(format!(
                "{}: integrator ptracer: rendered by the path tracer (the same expected image, other noise)",
                self.at(&o.pos)
            ));
        }
        if o.plugin == "direct" {
            self.check_known(
                o,
                &["hide_emitters"],
                &["emitter_samples", "bsdf_samples", "shading_samples"],
            )?;
        } else {
            self.check_known(o, &["max_depth", "rr_depth", "hide_emitters"], &[])?;
        }
        if self.boolean(o, "hide_emitters", false)? {
            self.render.insert("hide_emitters".into(), T::Boolean(true));
        }
        let depth = match max_depth {
            -1 => 1024,
            d if d >= 1 => d.min(1024),
            0 => return err(&o.pos, format!("{}: max_depth 0 renders nothing", what(o))),
            d => {
                return err(
                    &o.pos,
                    format!("{}: max_depth {d} must be -1 or at least 1", what(o)),
                )
            }
        };
        self.render.insert("max_depth".into(), T::Integer(depth));
        if o.get("rr_depth").is_some() {
            self.notes.push(format!(
                "{}: rr_depth: Russian roulette starts at wgtrace's fourth ray (the same expected image)",
                self.at(&o.pos)
            ));
        }
        Ok(())
    }

    fn sensor(&mut self, i: usize) -> Result<()> {
        let o = self.obj(i);
        let film = children(self.tree, o, "film").next();
        let (width, height) = match film {
            Some(f) => self.film(f)?,
            None => {
                self.render.insert("filter".into(), text("gaussian"));
                self.render
                    .insert("sample_border".into(), T::Boolean(false));
                self.render.insert("reconstruction".into(), text("splat"));
                (768, 576)
            }
        };
        self.render.insert("width".into(), T::Integer(width));
        self.render.insert("height".into(), T::Integer(height));
        match children(self.tree, o, "sampler").next() {
            Some(s) => self.sampler(s)?,
            None => {
                self.render.insert("spp".into(), T::Integer(4));
                self.render.insert("sampler".into(), text("random"));
            }
        }
        let camera_medium = match children(self.tree, o, "medium").next() {
            Some(m) => Some(self.medium(m)?),
            None => None,
        };
        let aspect = width as f64 / height as f64;
        let m = self.world * self.transform(o, "to_world")?;
        let origin = m.transform_point3(DVec3::ZERO);
        let dir = m.transform_vector3(DVec3::Z).normalize();
        let up = m.transform_vector3(DVec3::Y);
        let left = m.transform_vector3(DVec3::X);
        if !(dir.is_finite() && up.length() > 0.0 && left.length() > 0.0) {
            return err(&o.pos, format!("{}: to_world is degenerate", what(o)));
        }
        let mut cam = table([
            ("look_from", vec3(origin)),
            ("look_at", vec3(origin + dir)),
            ("up", vec3(up.normalize())),
        ]);
        // a to_world with a negative determinant mirrors the image
        if up.cross(dir).dot(left) < 0.0 {
            cam.insert("mirror".into(), T::Boolean(true));
        }
        if let Some(m) = camera_medium {
            cam.insert("medium".into(), T::String(m));
        }
        // Mitsuba's projective cameras all read focus_distance; only thinlens uses it
        let known_projective = ["to_world", "near_clip", "far_clip", "focus_distance"];
        // rays start at the near clip plane, near_clip along the camera's z axis (its
        // length under to_world too, as Mitsuba's ray.o + to_world(d) near_clip / d.z)
        let near = self.float(o, "near_clip", 1e-2)?;
        let far = self.float(o, "far_clip", 1e4)?;
        if !(near >= 0.0 && near.is_finite() && far > near) {
            return err(
                &o.pos,
                format!(
                    "{}: near_clip {near} and far_clip {far} must be 0 <= near_clip < far_clip",
                    what(o)
                ),
            );
        }
        cam.insert(
            "near_clip".into(),
            float(near * m.transform_vector3(DVec3::Z).length()),
        );
        if o.get("far_clip").is_some() {
            self.notes.push(format!(
                "{}: far_clip {far}: camera rays are not cut off at a distance",
                self.at(&o.pos)
            ));
        }
        match o.plugin.as_str() {
            "perspective" | "thinlens" => {
                let fov_x = self.fov_x(o, aspect)?;
                let vfov = 2.0 * ((0.5 * fov_x.to_radians()).tan() / aspect).atan();
                cam.insert("vfov".into(), float(vfov.to_degrees()));
                let mut known = vec!["fov", "fov_axis", "focal_length"];
                known.extend(known_projective);
                if o.plugin == "thinlens" {
                    known.push("aperture_radius");
                    let r = self.float(o, "aperture_radius", 0.03)?;
                    cam.insert("aperture".into(), float(2.0 * r));
                    let d = self.float(o, "focus_distance", 1e4)?;
                    cam.insert("focus_distance".into(), float(d));
                } else {
                    known.extend(["principal_point_offset_x", "principal_point_offset_y"]);
                    for k in ["principal_point_offset_x", "principal_point_offset_y"] {
                        if self.float(o, k, 0.0)? != 0.0 {
                            return err(&o.get(k).unwrap().pos, format!("{}: `{k}` is not rendered", what(o)));
                        }
                    }
                }
                self.check_known(o, &known, &["srf"])?;
            }
            "orthographic" => {
                // camera space spans [-1, 1] across and [-1, 1] / aspect up, scaled by to_world
                cam.insert("projection".into(), text("orthographic"));
                cam.insert("height".into(), float(2.0 * up.length() / aspect));
                let mut known = vec![];
                known.extend(known_projective);
                self.check_known(o, &known, &["srf"])?;
            }
            other => {
                return err(
                    &o.pos,
                    format!("sensor {other}: not rendered (wgtrace reads perspective, thinlens and orthographic)"),
                )
            }
        }
        self.camera = Some(Entry {
            name: "camera".into(),
            table: cam,
            pos: o.pos.clone(),
            what: what(o),
        });
        Ok(())
    }

    /// Mitsuba's horizontal field of view, from `fov` along `fov_axis` or a 35 mm
    /// `focal_length`.
    fn fov_x(&self, o: &Object, aspect: f64) -> Result<f64> {
        let half_tan = |deg: f64| (0.5 * deg.to_radians()).tan();
        let (fov, axis) = match (o.get("fov"), self.string(o, "focal_length")?) {
            (Some(_), Some(_)) => {
                return err(
                    &o.pos,
                    format!("{}: give `fov` or `focal_length`, not both", what(o)),
                )
            }
            (Some(_), None) => {
                let axis = self
                    .string(o, "fov_axis")?
                    .unwrap_or("x")
                    .to_ascii_lowercase();
                let axis = match axis.as_str() {
                    "smaller" => if aspect > 1.0 { "y" } else { "x" }.to_string(),
                    "larger" => if aspect > 1.0 { "x" } else { "y" }.to_string(),
                    _ => axis,
                };
                (self.float(o, "fov", 0.0)?, axis)
            }
            (None, f) => {
                let f = f.unwrap_or("50mm");
                let mm: f64 = match f.trim_end_matches("mm").trim().parse() {
                    Ok(v) if v > 0.0 => v,
                    _ => {
                        return err(
                            &o.get("focal_length")
                                .map_or(o.pos.clone(), |p| p.pos.clone()),
                            format!(
                                "{}: focal_length \"{f}\" must be of the form <x>mm",
                                what(o)
                            ),
                        )
                    }
                };
                let diag = (36.0f64 * 36.0 + 24.0 * 24.0).sqrt();
                (
                    2.0 * (diag / (2.0 * mm)).atan().to_degrees(),
                    "diagonal".to_string(),
                )
            }
        };
        let x = match axis.as_str() {
            "x" => fov,
            "y" => 2.0 * (half_tan(fov) * aspect).atan().to_degrees(),
            "diagonal" => {
                let width = 2.0 * half_tan(fov) / (1.0 + 1.0 / (aspect * aspect)).sqrt();
                2.0 * (0.5 * width).atan().to_degrees()
            }
            other => {
                return err(
                    &o.get("fov_axis").unwrap().pos,
                    format!(
                        "{}: fov_axis \"{other}\" must be x, y, diagonal, smaller or larger",
                        what(o)
                    ),
                )
            }
        };
        if !(x > 0.0 && x < 180.0) {
            return err(
                &o.pos,
                format!(
                    "{}: the horizontal field of view {x} is outside (0, 180)",
                    what(o)
                ),
            );
        }
        Ok(x)
    }

    fn film(&mut self, i: usize) -> Result<(i64, i64)> {
        let f = self.obj(i);
        if f.plugin != "hdrfilm" {
            return err(
                &f.pos,
                format!("film {}: not read (wgtrace reads hdrfilm)", f.plugin),
            );
        }
        self.check_known(
            f,
            &[
                "width",
                "height",
                "crop_offset_x",
                "crop_offset_y",
                "crop_width",
                "crop_height",
                "sample_border",
            ],
            &[
                "pixel_format",
                "component_format",
                "file_format",
                "banner",
                "high_quality_edges",
            ],
        )?;
        let border = self.boolean(f, "sample_border", false)?;
        if !border {
            // Mitsuba's film keeps a wide filter's samples on the image
            self.render
                .insert("sample_border".into(), T::Boolean(false));
        }
        let width = self.integer(f, "width", 768)?;
        let height = self.integer(f, "height", 576)?;
        let crop = (
            self.integer(f, "crop_offset_x", 0)?,
            self.integer(f, "crop_offset_y", 0)?,
            self.integer(f, "crop_width", width)?,
            self.integer(f, "crop_height", height)?,
        );
        if crop != (0, 0, width, height) {
            let c = [crop.0, crop.1, crop.2, crop.3];
            let fits = |o: i64, n: i64, side: i64| {
                o >= 0 && n >= 1 && o.checked_add(n).is_some_and(|e| e <= side)
            };
            if !fits(c[0], c[2], width) || !fits(c[1], c[3], height) {
                return err(
                    &f.pos,
                    format!(
                        "film hdrfilm: the crop window (offset {}, {}; size {} x {}) is not inside the {width} x {height} film",
                        c[0], c[1], c[2], c[3]
                    ),
                );
            }
            self.render.insert(
                "crop".into(),
                T::Array(c.iter().map(|&v| T::Integer(v)).collect()),
            );
        }
        // Mitsuba's film splats each sample over the pixels its filter reaches, weighed by
        // the filter itself in its vectorized variants (llvm_ad_rgb, cuda_ad_rgb; its
        // scalar ones by a table of 31 steps, `[render] filter_steps`); with
        // sample_border its samples also come from beyond the image, which only drawing
        // from the filter gives
        let splatted = |render: &mut Table| {
            if !border {
                render.insert("reconstruction".into(), text("splat"));
            }
        };
        match children(self.tree, f, "rfilter").next() {
            None => {
                self.render.insert("filter".into(), text("gaussian"));
                splatted(&mut self.render);
            }
            Some(r) => {
                let r = self.obj(r);
                match r.plugin.as_str() {
                    "box" => {
                        self.check_known(r, &[], &[])?;
                        self.render.insert("filter".into(), text("box"));
                    }
                    "tent" => {
                        self.check_known(r, &["radius"], &[])?;
                        self.render.insert("filter".into(), text("tent"));
                        splatted(&mut self.render);
                        if r.get("radius").is_some() {
                            self.render.insert("filter_radius".into(), float(self.float(r, "radius", 1.0)?));
                        }
                    }
                    "gaussian" => {
                        self.check_known(r, &["stddev"], &[])?;
                        self.render.insert("filter".into(), text("gaussian"));
                        splatted(&mut self.render);
                        if r.get("stddev").is_some() {
                            self.render.insert("filter_stddev".into(), float(self.float(r, "stddev", 0.5)?));
                        }
                    }
                    other => {
                        return err(
                            &r.pos,
                            format!("rfilter {other}: not rendered (wgtrace filters box, tent and gaussian)"),
                        )
                    }
                }
            }
        }
        Ok((width, height))
    }

    fn sampler(&mut self, i: usize) -> Result<()> {
        let s = self.obj(i);
        let kind = match s.plugin.as_str() {
            "independent" => "random",
            "stratified" | "multijitter" | "correlated" => "jittered",
            "ldsampler" | "orthogonal" => "sobol",
            other => {
                return err(
                    &s.pos,
                    format!("sampler {other}: not read (wgtrace reads independent, stratified, multijitter, correlated, ldsampler, orthogonal)"),
                )
            }
        };
        self.check_known(
            s,
            &["sample_count", "seed"],
            &["jitter", "strength", "dimension"],
        )?;
        let spp = self.integer(s, "sample_count", 4)?;
        if spp < 1 {
            return err(
                &s.pos,
                format!("{}: sample_count must be at least 1", what(s)),
            );
        }
        self.render.insert("spp".into(), T::Integer(spp));
        self.render.insert("sampler".into(), text(kind));
        let seed = self.integer(s, "seed", 0)?;
        self.render.insert("seed".into(), T::Integer(seed.max(0)));
        Ok(())
    }

    // ---- textures --------------------------------------------------------------------

    /// The texture object `i` as a `[textures]` entry (once), by its name: read as a
    /// colour (Mitsuba's `eval`).
    fn texture(&mut self, i: usize) -> Result<String> {
        self.texture_read(i, false)
    }

    /// [`Self::texture`] read as a scalar (Mitsuba's `eval_1`: a principled BSDF's
    /// scalars, a mask's opacity, a blend's weight).
    fn scalar_texture(&mut self, i: usize) -> Result<String> {
        self.texture_read(i, true)
    }

    fn texture_read(&mut self, i: usize, scalar: bool) -> Result<String> {
        // only a checkerboard reads otherwise as a scalar
        let scalar = scalar && self.obj(i).plugin == "checkerboard";
        if let Some(n) = self.texture_names.get(&(i, scalar)) {
            return Ok(n.clone());
        }
        let o = self.obj(i);
        if o.tag != "texture" {
            return err(
                &o.pos,
                format!(
                    "<{} type=\"{}\"> stands where a texture is read",
                    o.tag, o.plugin
                ),
            );
        }
        let to_uv = self.transform(o, "to_uv")?;
        let t = match o.plugin.as_str() {
            "bitmap" => {
                self.check_known(o, &["filename", "filter_type", "wrap_mode", "raw", "to_uv"], &["format"])?;
                let mut t = table([("type", text("image")), ("path", text(&self.file(o, "filename")?))]);
                match self.string(o, "filter_type")?.unwrap_or("bilinear") {
                    "bilinear" => {}
                    "nearest" => {
                        t.insert("filter".into(), text("nearest"));
                    }
                    other => return err(&o.get("filter_type").unwrap().pos, format!("texture bitmap: filter_type \"{other}\" must be bilinear or nearest")),
                }
                match self.string(o, "wrap_mode")?.unwrap_or("repeat") {
                    "repeat" => {}
                    m @ ("mirror" | "clamp") => {
                        t.insert("wrap".into(), text(m));
                    }
                    other => return err(&o.get("wrap_mode").unwrap().pos, format!("texture bitmap: wrap_mode \"{other}\" must be repeat, mirror or clamp")),
                }
                if self.boolean(o, "raw", false)? {
                    t.insert("color_space".into(), text("linear"));
                }
                if to_uv != DMat4::IDENTITY {
                    t.insert("transform".into(), uv_matrix(o, to_uv)?);
                }
                t
            }
            "checkerboard" => {
                self.check_known(o, &["color0", "color1", "to_uv"], &[])?;
                let c0 = self.color(o, "color0", 0.4, Use::Reflectance)?;
                let c1 = self.color(o, "color1", 0.2, Use::Reflectance)?;
                // Mitsuba: color0 where the halves of to_uv's u and v agree (of v down),
                // the cells of 2 to_uv (u, 1 - v) whose coordinates sum to an even number;
                // a uniform scale s by a multiple of 1/2 is wgtrace's scale 2 s with v up,
                // whose cells are the same, their parity that of 2 s - 1
                let uniform = uniform_uv_scale(to_uv).filter(|s| (2.0 * s).fract() == 0.0 && *s > 0.0);
                let (even, odd, map) = match uniform {
                    Some(s) if (2.0 * s) as i64 % 2 == 0 => (c1, c0, ("scale", float(2.0 * s))),
                    Some(s) => (c0, c1, ("scale", float(2.0 * s))),
                    None => (c0, c1, ("transform", checker_matrix(o, to_uv)?)),
                };
                // Mitsuba's checkerboard read as a scalar (eval_1) gives color0 where the
                // halves differ, the other cells than as a colour (eval): measured against
                // Mitsuba 3.9.1, a principled metallic checker agrees only so
                let (even, odd) = if scalar { (odd, even) } else { (even, odd) };
                let general = map.0 == "transform";
                let mut t = table([("type", text("checker")), ("even", even), ("odd", odd), map]);
                if general {
                    t.insert("scale".into(), float(1.0));
                }
                t
            }
            "mesh_attribute" => {
                self.check_known(o, &["name"], &[])?;
                let name = self.string(o, "name")?.unwrap_or("");
                if !crate::scene::format::is_mesh_attribute(name) {
                    return err(&o.pos, format!("texture mesh_attribute: name \"{name}\": wgtrace reads vertex_color, face_color and a PLY file's vertex_NAME or face_NAME"));
                }
                table([("type", text("mesh_attribute")), ("name", text(name))])
            }
            other => {
                return err(&o.pos, format!("texture {other}: not read (wgtrace reads bitmap, checkerboard and mesh_attribute)"))
            }
        };
        let name = self.name(o, &format!("texture{}", self.textures.len() + 1));
        self.texture_names.insert((i, scalar), name.clone());
        self.textures.push(Entry {
            name: name.clone(),
            table: t,
            pos: o.pos.clone(),
            what: what(o),
        });
        Ok(name)
    }

    // ---- materials -------------------------------------------------------------------

    /// The material of a shape: its BSDF (Mitsuba's diffuse 0.5 without one) with its
    /// area emitter's radiance.
    fn material(
        &mut self,
        bsdf: Option<usize>,
        emitter: Option<usize>,
        at: &Pos,
    ) -> Result<String> {
        if let Some(n) = self.material_names.get(&(bsdf, emitter)) {
            return Ok(n.clone());
        }
        let (mut t, pos, w, fallback) = match bsdf {
            Some(b) => {
                let o = self.obj(b);
                (
                    self.bsdf(b)?,
                    o.pos.clone(),
                    what(o),
                    "material".to_string(),
                )
            }
            // Mitsuba's default: diffuse 0.5, black on an emitter
            None => (
                table([
                    ("type", text("lambertian")),
                    (
                        "albedo",
                        rgb([if emitter.is_some() { 0.0 } else { 0.5 }; 3]),
                    ),
                    ("one_sided", T::Boolean(true)),
                ]),
                at.clone(),
                "the default diffuse BSDF".into(),
                "default".to_string(),
            ),
        };
        let named_from = bsdf.map(|b| self.obj(b));
        if let Some(e) = emitter {
            let eo = self.obj(e);
            self.check_known(eo, &["radiance"], &["sampling_weight"])?;
            let radiance = self.color(eo, "radiance", 1.0, Use::Emission)?;
            if t.get("type").and_then(T::as_str) == Some("blend") || t.contains_key("opacity") {
                return err(
                    &eo.pos,
                    "emitter area: on a blendbsdf or mask, which wgtrace cannot make emit",
                );
            }
            t.insert("emission".into(), radiance);
            let base = match bsdf {
                Some(b) => self
                    .obj(b)
                    .id
                    .clone()
                    .map_or("light".to_string(), |id| format!("{id}_light")),
                None => "light".to_string(),
            };
            let name = self.name_str(&base);
            self.push_material(name.clone(), t, pos, w, bsdf, emitter);
            return Ok(name);
        }
        let name = match named_from {
            Some(o) => self.name(o, &fallback),
            None => self.name_str(&fallback),
        };
        self.push_material(name.clone(), t, pos, w, bsdf, emitter);
        Ok(name)
    }

    fn name_str(&mut self, stem: &str) -> String {
        let o = Object {
            tag: String::new(),
            plugin: String::new(),
            id: Some(stem.to_string()),
            pos: self.obj(self.tree.root).pos.clone(),
            props: Vec::new(),
        };
        self.name(&o, stem)
    }

    /// A `<medium>`'s `[media.NAME]` table (once per object), by its name.
    fn medium(&mut self, i: usize) -> Result<String> {
        if let Some(n) = self.medium_names.get(&i) {
            return Ok(n.clone());
        }
        let o = self.obj(i);
        let mut grid = None;
        let (albedo, sigma_t) = match o.plugin.as_str() {
            "homogeneous" => {
                // (medium_sampling_mode chooses how Mitsuba samples, not what it renders)
                self.check_known(
                    o,
                    &["albedo", "sigma_t", "scale", "sample_emitters"],
                    &["medium_sampling_mode"],
                )?;
                (
                    Some(self.color_const(o, "albedo", 0.75, Use::Reflectance)?),
                    self.color_const(o, "sigma_t", 1.0, Use::Unbounded)?,
                )
            }
            "heterogeneous" => {
                self.check_known(
                    o,
                    &["albedo", "sigma_t", "scale", "sample_emitters"],
                    &[
                        "has_spectral_extinction",
                        "majorant_resolution_factor",
                        "majorant_factor",
                        "medium_sampling_mode",
                    ],
                )?;
                let grid_of = |s: &Self, name: &str| match o.get(name).map(|p| &p.value) {
                    Some(Value::Object(v)) if s.obj(*v).plugin == "gridvolume" => Some(*v),
                    _ => None,
                };
                let sigma_t = match grid_of(self, "sigma_t") {
                    Some(v) => {
                        grid = Some(self.grid_volume(v)?);
                        float(1.0)
                    }
                    None => {
                        // a constant: density 1 in the unit cube its to_world places (the
                        // medium's extent in Mitsuba, the volume's box)
                        let mut placed = Table::new();
                        if let Some(Value::Object(v)) = o.get("sigma_t").map(|p| &p.value) {
                            let m = self.transform(self.obj(*v), "to_world")?;
                            if m != DMat4::IDENTITY {
                                placed.insert("transform".into(), matrix(m));
                            }
                        }
                        grid = Some(placed);
                        self.volume_const(o, "sigma_t", 1.0, Use::Unbounded)?
                    }
                };
                let albedo = match grid_of(self, "albedo") {
                    Some(v) => {
                        // an albedo grid, placed as the density grid is
                        let a = self.grid_volume(v)?;
                        let placed = |t: &Table| {
                            (t.get("transform").cloned(), t.get("use_grid_bbox").cloned())
                        };
                        match &mut grid {
                            Some(g) if g.contains_key("grid") && placed(g) == placed(&a) => {
                                g.insert("albedo_grid".into(), a["grid"].clone());
                            }
                            _ => {
                                return err(
                                    &self.obj(v).pos,
                                    "volume gridvolume: an albedo grid is read with a density \
                                         grid (`sigma_t`) placed the same way (the same to_world \
                                         and use_grid_bbox)",
                                )
                            }
                        }
                        None
                    }
                    None => Some(self.volume_const(o, "albedo", 0.75, Use::Reflectance)?),
                };
                (albedo, sigma_t)
            }
            other => {
                return err(
                    &o.pos,
                    format!(
                        "medium {other}: not read (wgtrace reads homogeneous and heterogeneous)"
                    ),
                )
            }
        };
        let scale = self.float(o, "scale", 1.0)?;
        let mut g = 0.0;
        let phases: Vec<usize> = children(self.tree, o, "phase").collect();
        if phases.len() > 1 {
            return err(
                &o.pos,
                format!(
                    "{}: has {} phase functions; a medium takes one",
                    what(o),
                    phases.len()
                ),
            );
        }
        if let Some(&ph) = phases.first() {
            let po = self.obj(ph);
            match po.plugin.as_str() {
                "isotropic" => self.check_known(po, &[], &[])?,
                "hg" => {
                    self.check_known(po, &["g"], &[])?;
                    // Mitsuba's default asymmetry
                    g = self.float(po, "g", 0.8)?;
                }
                other => {
                    return err(
                        &po.pos,
                        format!("phase {other}: not read (wgtrace reads isotropic and hg)"),
                    )
                }
            }
        }
        let mut t = table([("type", text(&o.plugin)), ("sigma_t", sigma_t)]);
        if let Some(a) = albedo {
            t.insert("albedo".into(), a);
        }
        if let Some(g) = grid {
            t.extend(g);
        }
        if scale != 1.0 {
            t.insert("scale".into(), float(scale));
        }
        if g != 0.0 {
            t.insert("g".into(), float(g));
        }
        let name = self.name(o, "medium");
        self.medium_names.insert(i, name.clone());
        self.media.push(Entry {
            name: name.clone(),
            table: t,
            pos: o.pos.clone(),
            what: what(o),
        });
        Ok(name)
    }

    /// A heterogeneous medium's `name`: a colour, or a `constvolume`'s value.
    fn volume_const(&mut self, o: &Object, name: &str, default: f64, use_: Use) -> Result<T> {
        if let Some(Value::Object(v)) = o.get(name).map(|p| &p.value) {
            let vo = self.obj(*v);
            if vo.tag == "volume" {
                if vo.plugin != "constvolume" {
                    return err(
                        &vo.pos,
                        format!(
                            "volume {}: `{name}` of a medium is read as a constant \
                             (constvolume) or a gridvolume",
                            vo.plugin
                        ),
                    );
                }
                // (a heterogeneous medium's extinction reads its to_world)
                self.check_known(vo, &["value", "to_world"], &[])?;
                return self.color_const(vo, "value", default, use_);
            }
        }
        self.color_const(o, name, default, use_)
    }

    /// A `gridvolume`'s keys of a `[media.NAME]` table: its `.vol` file, placement and
    /// whether the file's box places it.
    fn grid_volume(&mut self, i: usize) -> Result<Table> {
        let o = self.obj(i);
        self.check_known(
            o,
            &["filename", "to_world", "use_grid_bbox", "filter_type"],
            &["raw", "wrap_mode"],
        )?;
        if let Some(f) = self.string(o, "filter_type")? {
            if f != "trilinear" {
                return err(
                    &o.get("filter_type").unwrap().pos,
                    format!("volume gridvolume: filter_type {f} is not read (wgtrace interpolates trilinearly, Mitsuba's default)"),
                );
            }
        }
        if let Some(w) = self.string(o, "wrap_mode")? {
            if w != "clamp" {
                return err(
                    &o.get("wrap_mode").unwrap().pos,
                    format!("volume gridvolume: wrap_mode {w} is not read (wgtrace clamps, Mitsuba's default)"),
                );
            }
        }
        let mut t = table([("grid", text(&self.file(o, "filename")?))]);
        let m = self.transform(o, "to_world")?;
        if m != DMat4::IDENTITY {
            t.insert("transform".into(), matrix(m));
        }
        if self.boolean(o, "use_grid_bbox", false)? {
            t.insert("use_grid_bbox".into(), T::Boolean(true));
        }
        Ok(t)
    }

    fn push_material(
        &mut self,
        name: String,
        t: Table,
        pos: Pos,
        what: String,
        bsdf: Option<usize>,
        emitter: Option<usize>,
    ) {
        self.material_names.insert((bsdf, emitter), name.clone());
        self.materials.push(Entry {
            name,
            table: t,
            pos,
            what,
        });
    }

    /// A BSDF's table (wrappers folded into the material they wrap).
    fn bsdf(&mut self, i: usize) -> Result<Table> {
        let o = self.obj(i);
        if o.tag != "bsdf" {
            return err(
                &o.pos,
                format!(
                    "<{} type=\"{}\"> stands where a BSDF is read",
                    o.tag, o.plugin
                ),
            );
        }
        let alpha = |s: &Self, o: &Object| -> Result<Table> {
            let mut t = Table::new();
            let dist = s.string(o, "distribution")?.unwrap_or("beckmann");
            if dist != "beckmann" && dist != "ggx" {
                return err(
                    &o.get("distribution").unwrap().pos,
                    format!(
                        "{}: distribution \"{dist}\" must be beckmann or ggx",
                        what(o)
                    ),
                );
            }
            t.insert("distribution".into(), text(dist));
            let a = |name: &str| -> Result<Option<f64>> {
                match o.get(name) {
                    None => Ok(None),
                    Some(p) => match p.value {
                        Value::Float(v) => Ok(Some(v)),
                        Value::Integer(v) => Ok(Some(v as f64)),
                        _ => err(&p.pos, format!("{}: `{name}` must be a number (wgtrace takes no roughness texture)", what(o))),
                    },
                }
            };
            let r = |x: f64| float(x.max(0.0).sqrt());
            match (a("alpha")?, a("alpha_u")?, a("alpha_v")?) {
                (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
                    return err(
                        &o.pos,
                        format!("{}: give `alpha` or `alpha_u` and `alpha_v`", what(o)),
                    )
                }
                (_, Some(u), Some(v)) => {
                    t.insert("roughness_u".into(), r(u));
                    t.insert("roughness_v".into(), r(v));
                }
                (_, Some(_), None) | (_, None, Some(_)) => {
                    return err(
                        &o.pos,
                        format!("{}: `alpha_u` and `alpha_v` go together", what(o)),
                    )
                }
                (a, None, None) => {
                    t.insert("roughness".into(), r(a.unwrap_or(0.1)));
                }
            }
            Ok(t)
        };
        let only_child_bsdf = |s: &Self, o: &Object| -> Result<usize> {
            let mut kids = children(s.tree, o, "bsdf");
            match (kids.next(), kids.next()) {
                (Some(b), None) => Ok(b),
                (None, _) => err(&o.pos, format!("{}: needs a nested BSDF", what(o))),
                (Some(_), Some(_)) => err(&o.pos, format!("{}: takes one nested BSDF", what(o))),
            }
        };
        let t = match o.plugin.as_str() {
            "diffuse" => {
                self.check_known(o, &["reflectance"], &[])?;
                let albedo = self.color(o, "reflectance", 0.5, Use::Reflectance)?;
                table([("type", text("lambertian")), ("albedo", albedo), ("one_sided", T::Boolean(true))])
            }
            "conductor" | "roughconductor" => {
                let mut known = vec!["material", "eta", "k", "specular_reflectance"];
                let mut t = table([("type", text("conductor"))]);
                if o.plugin == "roughconductor" {
                    known.extend(["distribution", "alpha", "alpha_u", "alpha_v"]);
                    t.extend(alpha(self, o)?);
                }
                self.check_known(o, &known, &["sample_visible"])?;
                match (self.string(o, "material")?, o.get("eta").is_some() || o.get("k").is_some()) {
                    (Some(_), true) => return err(&o.pos, format!("{}: give `material` or `eta` and `k`", what(o))),
                    (m, false) => {
                        t.insert("material".into(), text(m.unwrap_or("none")));
                    }
                    (None, true) => {
                        let eta = self.color_const(o, "eta", 0.0, Use::Unbounded)?;
                        let k = self.color_const(o, "k", 1.0, Use::Unbounded)?;
                        t.insert("eta".into(), self.magnitudes(o, "eta", eta));
                        t.insert("k".into(), self.magnitudes(o, "k", k));
                    }
                }
                if o.get("specular_reflectance").is_some() {
                    let s = self.color(o, "specular_reflectance", 1.0, Use::Reflectance)?;
                    t.insert("specular".into(), s);
                }
                t.insert("one_sided".into(), T::Boolean(true));
                t
            }
            "dielectric" | "roughdielectric" | "thindielectric" => {
                let mut known = vec!["int_ior", "ext_ior", "specular_reflectance", "specular_transmittance"];
                let ior = self.ior(o, "int_ior", 1.5046)? / self.ior(o, "ext_ior", 1.000277)?;
                let thin = o.plugin == "thindielectric";
                let mut t = table([
                    ("type", text(if thin { "thin_dielectric" } else { "dielectric" })),
                    ("ior", float(ior)),
                ]);
                if o.plugin == "roughdielectric" {
                    known.extend(["distribution", "alpha", "alpha_u", "alpha_v"]);
                    t.extend(alpha(self, o)?);
                }
                self.check_known(o, &known, &["sample_visible"])?;
                let refl = self.color(o, "specular_reflectance", 1.0, Use::Reflectance)?;
                let trans = self.color(o, "specular_transmittance", 1.0, Use::Reflectance)?;
                if thin || refl != trans {
                    t.insert("specular".into(), refl);
                }
                t.insert("tint".into(), trans);
                t
            }
            "plastic" | "roughplastic" => {
                let mut known = vec!["diffuse_reflectance", "specular_reflectance", "int_ior", "ext_ior", "nonlinear"];
                let ior = self.ior(o, "int_ior", 1.49)? / self.ior(o, "ext_ior", 1.000277)?;
                let albedo = self.color(o, "diffuse_reflectance", 0.5, Use::Reflectance)?;
                let specular = self.color(o, "specular_reflectance", 1.0, Use::Reflectance)?;
                let mut t = table([
                    ("type", text("plastic")),
                    ("albedo", albedo),
                    ("specular", specular),
                    ("ior", float(ior)),
                    ("nonlinear", T::Boolean(self.boolean(o, "nonlinear", false)?)),
                    ("one_sided", T::Boolean(true)),
                ]);
                if o.plugin == "roughplastic" {
                    known.extend(["distribution", "alpha"]);
                    t.extend(alpha(self, o)?);
                }
                self.check_known(o, &known, &["sample_visible"])?;
                t
            }
            "principled" => {
                const SCALARS: [&str; 10] = [
                    "roughness", "anisotropic", "metallic", "spec_trans", "spec_tint", "sheen",
                    "sheen_tint", "flatness", "clearcoat", "clearcoat_gloss",
                ];
                let mut known = vec!["base_color", "eta", "specular"];
                known.extend(SCALARS);
                self.check_known(o, &known, &["sample_visible"])?;
                let base = self.color(o, "base_color", 0.5, Use::Reflectance)?;
                let mut t = table([("type", text("principled")), ("base_color", base)]);
                for k in SCALARS {
                    if let Some(v) = self.scalar(o, k)? {
                        t.insert(k.into(), v);
                    }
                }
                for k in ["eta", "specular"] {
                    if o.get(k).is_some() {
                        t.insert(k.into(), float(self.float(o, k, 0.0)?));
                    }
                }
                if o.get("spec_trans").is_none() {
                    t.insert("one_sided".into(), T::Boolean(true));
                }
                t
            }
            "twosided" => {
                self.check_known(o, &[], &[])?;
                let kids: Vec<usize> = children(self.tree, o, "bsdf").collect();
                let inner = match kids.as_slice() {
                    [b] => *b,
                    [a, b] if a == b => *a,
                    [_, _] => return err(&o.pos, "bsdf twosided: a different BSDF on each side is not rendered"),
                    _ => return err(&o.pos, "bsdf twosided: needs one nested BSDF"),
                };
                let mut t = self.bsdf(inner)?;
                t.remove("one_sided");
                t
            }
            "mask" => {
                self.check_known(o, &["opacity"], &[])?;
                let inner = only_child_bsdf(self, o)?;
                let mut t = self.bsdf(inner)?;
                let opacity = self.scalar(o, "opacity")?.unwrap_or(float(0.5));
                t.insert("opacity".into(), opacity);
                t
            }
            "bumpmap" => {
                self.check_known(o, &["scale"], &[])?;
                let inner = only_child_bsdf(self, o)?;
                let Some(tex) = children(self.tree, o, "texture").next() else {
                    return err(&o.pos, "bsdf bumpmap: needs a nested height texture");
                };
                let mut t = self.bsdf(inner)?;
                let tex = self.texture(tex)?;
                t.insert("bump".into(), T::String(tex));
                t.insert("bump_scale".into(), float(self.float(o, "scale", 1.0)?));
                t
            }
            "blendbsdf" => {
                self.check_known(o, &["weight"], &[])?;
                let kids: Vec<usize> = children(self.tree, o, "bsdf").collect();
                let [a, b] = kids[..] else {
                    return err(&o.pos, "bsdf blendbsdf: needs two nested BSDFs");
                };
                let first = self.material(Some(a), None, &o.pos)?;
                let second = self.material(Some(b), None, &o.pos)?;
                let weight = self.scalar(o, "weight")?.unwrap_or(float(0.5));
                table([("type", text("blend")), ("first", T::String(first)), ("second", T::String(second)), ("weight", weight)])
            }
            "normalmap" => {
                self.check_known(o, &["normalmap"], &[])?;
                let inner = only_child_bsdf(self, o)?;
                let unnamed = children(self.tree, o, "texture").next();
                if o.get("normalmap").is_none() && unnamed.is_none() {
                    return err(&o.pos, "bsdf normalmap: needs a nested normalmap texture");
                }
                let mut t = self.bsdf(inner)?;
                if t.contains_key("bump") {
                    return err(&o.pos, "bsdf normalmap: around a bumpmap: wgtrace takes one of the two");
                }
                let map = match (o.get("normalmap"), unnamed) {
                    (None, Some(tex)) => T::String(self.texture(tex)?),
                    _ => self.color(o, "normalmap", 0.0, Use::Unbounded)?,
                };
                let tex = match map {
                    T::String(tex) => Some(tex),
                    // a constant map: (0.5, 0.5, 1) leaves every normal as it is
                    T::Array(c) if c.iter().zip([0.5, 0.5, 1.0]).all(|(v, e)| v.as_float().is_some_and(|v| (v - e).abs() < 1e-6)) => None,
                    c => {
                        let name = self.name_str("normalmap");
                        self.textures.push(Entry {
                            name: name.clone(),
                            table: table([("type", text("constant")), ("color", c)]),
                            pos: o.pos.clone(),
                            what: what(o),
                        });
                        Some(name)
                    }
                };
                if let Some(tex) = tex {
                    t.insert("normal_map".into(), T::String(tex));
                }
                t
            }
            "null" => {
                self.check_known(o, &[], &[])?;
                table([("type", text("null"))])
            }
            other => {
                return err(
                    &o.pos,
                    format!(
                        "bsdf {other}: not rendered (wgtrace reads diffuse, conductor, roughconductor, dielectric, \
                         roughdielectric, thindielectric, plastic, roughplastic, principled, twosided, mask, \
                         bumpmap, normalmap, blendbsdf)"
                    ),
                )
            }
        };
        Ok(t)
    }

    // ---- shapes ----------------------------------------------------------------------

    /// Shape `i` placed by `outer`; `via` the instance that places it (its origin then).
    fn shape(&mut self, i: usize, outer: DMat4, via: Option<usize>) -> Result<()> {
        let o = self.obj(i);
        let (origin, origin_what) = match via {
            Some(v) => (
                self.obj(v).pos.clone(),
                format!("shape instance of {}", what(o)),
            ),
            None => (o.pos.clone(), what(o)),
        };
        let bsdfs: Vec<usize> = children(self.tree, o, "bsdf").collect();
        if bsdfs.len() > 1 {
            return err(
                &o.pos,
                format!("{}: has {} BSDFs; a shape takes one", what(o), bsdfs.len()),
            );
        }
        let mut emitter = None;
        for e in children(self.tree, o, "emitter") {
            let eo = self.obj(e);
            if eo.plugin != "area" {
                return err(
                    &eo.pos,
                    format!(
                        "emitter {}: inside a shape only area emitters are read",
                        eo.plugin
                    ),
                );
            }
            if emitter.replace(e).is_some() {
                return err(&eo.pos, "emitter area: a shape takes one");
            }
        }
        // its media: `interior` and `exterior`, nested or referred to
        let mut media = Vec::new();
        for p in &o.props {
            if let Value::Object(m) = p.value {
                if self.obj(m).tag != "medium" {
                    continue;
                }
                if p.name != "interior" && p.name != "exterior" {
                    return err(
                        &p.pos,
                        format!("{}: a medium must be named interior or exterior", what(o)),
                    );
                }
                media.push((p.name.clone(), self.medium(m)?));
            }
        }
        let to_world = outer * self.transform(o, "to_world")?;
        let flip = self.boolean(o, "flip_normals", false)?;
        let material = |s: &mut Self| s.material(bsdfs.first().copied(), emitter, &o.pos);
        let ignorable = ["id"];
        let push = |s: &mut Self, mut t: Table| {
            for (side, name) in &media {
                t.insert(side.clone(), T::String(name.clone()));
            }
            let entry = |name: String| Entry {
                name,
                table: t,
                pos: origin.clone(),
                what: origin_what.clone(),
            };
            match &s.in_group {
                Some(g) => s.groups.push(entry(format!("groups.{g}.objects"))),
                None => s.objects.push(entry("objects".into())),
            }
        };
        let with_transform = |mut t: Table, m: DMat4| {
            if m != DMat4::IDENTITY {
                t.insert("transform".into(), matrix(m));
            }
            t
        };
        let mirror = DMat4::from_scale(DVec3::new(1.0, 1.0, -1.0));
        match o.plugin.as_str() {
            "obj" | "ply" | "serialized" => {
                let mut known = vec!["filename", "to_world", "face_normals", "flip_normals"];
                if o.plugin == "obj" {
                    known.push("flip_tex_coords");
                    if !self.boolean(o, "flip_tex_coords", true)? {
                        return err(&o.get("flip_tex_coords").unwrap().pos, "shape obj: flip_tex_coords false is not read (wgtrace reads OBJ uvs as Mitsuba's default does)");
                    }
                }
                if o.plugin == "serialized" {
                    known.push("shape_index");
                }
                self.check_known(o, &known, &["max_smooth_angle"])?;
                let mut t = table([("type", text("mesh")), ("path", text(&self.file(o, "filename")?))]);
                if o.plugin == "serialized" {
                    t.insert("shape_index".into(), T::Integer(self.integer(o, "shape_index", 0)?));
                }
                if o.plugin == "ply" {
                    // Mitsuba takes a PLY file's float colours as they are
                    t.insert("color_space".into(), text("linear"));
                }
                if o.plugin == "ply" {
                    // Mitsuba keeps a PLY file's uvs as stored, v down (and its default
                    // barycentric uvs where it has none): wgtrace's v is 1 - those
                    t.insert("flip_tex_coords".into(), T::Boolean(true));
                }
                if to_world.determinant() < 0.0 {
                    // Mitsuba's normals of a file without them are the placed triangles'
                    t.insert("placed_winding".into(), T::Boolean(true));
                }
                t.insert("material".into(), T::String(material(self)?));
                if self.boolean(o, "face_normals", false)? {
                    t.insert("face_normals".into(), T::Boolean(true));
                } else {
                    // Mitsuba computes vertex normals for a mesh file without them
                    t.insert("smooth_normals".into(), T::Boolean(true));
                }
                if flip {
                    t.insert("flip_normals".into(), T::Boolean(true));
                }
                push(self, with_transform(t, to_world));
            }
            "rectangle" => {
                self.check_known(o, &["to_world", "flip_normals"], &ignorable)?;
                let name = material(self)?;
                // Mitsuba's uv ((x + 1) / 2, (y + 1) / 2) with v down: wgtrace's v is 1 - that
                let corner = |x: f64, y: f64| {
                    (to_world.transform_point3(DVec3::new(x, y, 0.0)), [(x + 1.0) / 2.0, 1.0 - (y + 1.0) / 2.0])
                };
                let c = [corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)];
                // the front side is Mitsuba's normal, +z mapped as a normal: against the
                // winding where the transform mirrors, and turned by flip_normals
                let swap = (DMat3::from_mat4(to_world).determinant() < 0.0) != flip;
                for tri in [[0, 1, 2], [0, 2, 3]] {
                    let tri = if swap { [tri[0], tri[2], tri[1]] } else { tri };
                    let t = table([
                        ("type", text("triangle")),
                        ("vertices", T::Array(tri.iter().map(|&k| vec3(c[k].0)).collect())),
                        ("uvs", T::Array(tri.iter().map(|&k| T::Array(c[k].1.into_iter().map(float).collect())).collect())),
                        ("material", T::String(name.clone())),
                    ]);
                    push(self, t);
                }
            }
            "cube" => {
                self.check_known(o, &["to_world"], &ignorable)?;
                if flip {
                    return err(&o.pos, "shape cube: flip_normals is not read");
                }
                // Mitsuba's cube is a mesh whose every face has the uv square (its texture,
                // bump and normal maps' frame): its 24 corners and 12 triangles, as Mitsuba's
                // cube plugin lists them (uv with v down: wgtrace's v is 1 - that)
                const CORNERS: [([f64; 3], [f64; 2]); 24] = [
                    ([1.0, -1.0, -1.0], [0.0, 1.0]), ([1.0, -1.0, 1.0], [1.0, 1.0]), ([-1.0, -1.0, 1.0], [1.0, 0.0]), ([-1.0, -1.0, -1.0], [0.0, 0.0]),
                    ([1.0, 1.0, -1.0], [0.0, 1.0]), ([-1.0, 1.0, -1.0], [1.0, 1.0]), ([-1.0, 1.0, 1.0], [1.0, 0.0]), ([1.0, 1.0, 1.0], [0.0, 0.0]),
                    ([1.0, -1.0, -1.0], [0.0, 1.0]), ([1.0, 1.0, -1.0], [1.0, 1.0]), ([1.0, 1.0, 1.0], [1.0, 0.0]), ([1.0, -1.0, 1.0], [0.0, 0.0]),
                    ([1.0, -1.0, 1.0], [0.0, 1.0]), ([1.0, 1.0, 1.0], [1.0, 1.0]), ([-1.0, 1.0, 1.0], [1.0, 0.0]), ([-1.0, -1.0, 1.0], [0.0, 0.0]),
                    ([-1.0, -1.0, 1.0], [0.0, 1.0]), ([-1.0, 1.0, 1.0], [1.0, 1.0]), ([-1.0, 1.0, -1.0], [1.0, 0.0]), ([-1.0, -1.0, -1.0], [0.0, 0.0]),
                    ([1.0, 1.0, -1.0], [0.0, 1.0]), ([1.0, -1.0, -1.0], [1.0, 1.0]), ([-1.0, -1.0, -1.0], [1.0, 0.0]), ([-1.0, 1.0, -1.0], [0.0, 0.0]),
                ];
                let name = material(self)?;
                let swap = DMat3::from_mat4(to_world).determinant() < 0.0;
                for face in 0..6 {
                    for tri in [[0, 1, 2], [3, 0, 2]] {
                        let tri = if swap { [tri[0], tri[2], tri[1]] } else { tri };
                        let corner = |k: usize| CORNERS[4 * face + tri[k]];
                        let t = table([
                            ("type", text("triangle")),
                            ("vertices", T::Array((0..3).map(|k| vec3(to_world.transform_point3(DVec3::from(corner(k).0)))).collect())),
                            ("uvs", T::Array((0..3).map(|k| T::Array(vec![float(corner(k).1[0]), float(1.0 - corner(k).1[1])])).collect())),
                            ("material", T::String(name.clone())),
                        ]);
                        push(self, t);
                    }
                }
            }
            "sphere" => {
                self.check_known(o, &["to_world", "center", "radius"], &ignorable)?;
                if flip {
                    return err(&o.pos, "shape sphere: flip_normals (a sphere seen from inside) is not read");
                }
                // Mitsuba's sphere has its pole along z and u = atan2(y, x) / 2 pi, v = acos(z) /
                // pi; wgtrace's its pole along y and u = atan2(-z, x) / 2 pi + 1/2, v = acos(-y)
                // / pi, which is 1 - Mitsuba's v (wgtrace's v is up) where wgtrace's point is
                // Mitsuba's turned by (x, y, z) -> (-x, z, y): placed through that rotation (its
                // own inverse), textures, bump and normal maps land where Mitsuba puts them
                let center = self.point(o, "center", DVec3::ZERO)?;
                let radius = self.float(o, "radius", 1.0)?;
                let turn = DMat4::from_cols(
                    glam::DVec4::new(-1.0, 0.0, 0.0, 0.0),
                    glam::DVec4::new(0.0, 0.0, 1.0, 0.0),
                    glam::DVec4::new(0.0, 1.0, 0.0, 0.0),
                    glam::DVec4::W,
                );
                let m = to_world * DMat4::from_translation(center) * turn;
                let t = table([
                    ("type", text("sphere")),
                    ("center", vec3(DVec3::ZERO)),
                    ("radius", float(radius)),
                    ("material", T::String(material(self)?)),
                ]);
                push(self, with_transform(t, m));
            }
            "disk" => {
                self.check_known(o, &["to_world", "flip_normals"], &ignorable)?;
                let m = if flip { to_world * mirror } else { to_world };
                let t = table([
                    ("type", text("disk")),
                    ("center", vec3(DVec3::ZERO)),
                    ("normal", vec3(DVec3::Z)),
                    ("radius", float(1.0)),
                    ("material", T::String(material(self)?)),
                ]);
                push(self, with_transform(t, m));
            }
            "cylinder" => {
                self.check_known(o, &["to_world", "p0", "p1", "radius"], &ignorable)?;
                if flip {
                    return err(&o.pos, "shape cylinder: flip_normals is not read");
                }
                let t = table([
                    ("type", text("cylinder")),
                    ("base", vec3(self.point(o, "p0", DVec3::ZERO)?)),
                    ("top", vec3(self.point(o, "p1", DVec3::Z)?)),
                    ("radius", float(self.float(o, "radius", 1.0)?)),
                    ("caps", T::Boolean(false)),
                    ("material", T::String(material(self)?)),
                ]);
                push(self, with_transform(t, to_world));
            }
            "shapegroup" => {
                // drawn only through its instances
            }
            "instance" => {
                self.check_known(o, &["to_world"], &[])?;
                let mut groups = o.props.iter().filter_map(|p| match p.value {
                    Value::Object(g) if self.obj(g).plugin == "shapegroup" => Some(g),
                    _ => None,
                });
                let Some(g) = groups.next() else {
                    return err(&o.pos, "shape instance: needs a reference to a shapegroup");
                };
                let group = self.obj(g);
                let mut shapes = Vec::new();
                for p in &group.props {
                    match p.value {
                        Value::Object(s) if self.obj(s).tag == "shape" => shapes.push(s),
                        // the group's own BSDFs and textures are read where its shapes use them
                        Value::Object(_) => {}
                        _ => return err(&p.pos, "shape shapegroup: holds shapes only"),
                    }
                }
                let emits = shapes
                    .iter()
                    .any(|&s| children(self.tree, self.obj(s), "emitter").next().is_some());
                if emits || via.is_some() || self.in_group.is_some() {
                    // a light is sampled on its own surface, which an instance does not
                    // place: the group's shapes are written out at each instance
                    if emits && self.group_names.insert(g, String::new()).is_none() {
                        self.notes.push(format!(
                            "{}: holds an emitter, so its shapes are written out at each \
                             instance rather than instanced",
                            what(group)
                        ));
                    }
                    for s in shapes {
                        self.shape(s, to_world, Some(via.unwrap_or(i)))?;
                    }
                } else {
                    let name = match self.group_names.get(&g) {
                        Some(name) => name.clone(),
                        None => {
                            let name = self.name(group, "group");
                            self.group_names.insert(g, name.clone());
                            self.in_group = Some(name.clone());
                            for s in shapes {
                                self.shape(s, DMat4::IDENTITY, None)?;
                            }
                            self.in_group = None;
                            name
                        }
                    };
                    let t = table([("type", text("instance")), ("group", T::String(name))]);
                    push(self, with_transform(t, to_world));
                }
            }
            other => {
                return err(
                    &o.pos,
                    format!(
                        "shape {other}: not rendered (wgtrace reads obj, ply, serialized, rectangle, cube, sphere, \
                         disk, cylinder, shapegroup and instance)"
                    ),
                )
            }
        }
        Ok(())
    }

    // ---- emitters --------------------------------------------------------------------

    fn emitter(&mut self, i: usize) -> Result<()> {
        let o = self.obj(i);
        let m = self.world * self.transform(o, "to_world")?;
        let at = |v: DVec3| m.transform_point3(v);
        let axis = || m.transform_vector3(DVec3::Z).normalize();
        let light = |s: &mut Self, t: Table| {
            s.lights.push(Entry {
                name: "lights".into(),
                table: t,
                pos: o.pos.clone(),
                what: what(o),
            })
        };
        match o.plugin.as_str() {
            "constant" | "envmap" => {
                if let Some(b) = &self.background {
                    return err(&o.pos, format!("{}: the scene already has a background ({} at {})", what(o), b.what, b.pos));
                }
                let t = if o.plugin == "constant" {
                    self.check_known(o, &["radiance"], &["sampling_weight"])?;
                    table([("color", self.color_const(o, "radiance", 1.0, Use::Emission)?)])
                } else {
                    self.check_known(o, &["filename", "scale", "to_world"], &["sampling_weight", "mis_compensation"])?;
                    let rotation = y_rotation(m).ok_or_else(|| XmlError {
                        pos: o.pos.clone(),
                        message: "emitter envmap: wgtrace turns an environment about +y (or the whole scene with it); this to_world is not a turn times a uniform scale".into(),
                    })?;
                    let path = self.file(o, "filename")?;
                    let name = self.name_str("envmap");
                    // Mitsuba 3.9.1's envmap puts texel i of w at u = (i + 1/2) / w, as
                    // wgtrace does, but row j of h at theta / pi = j / (h - 1) (its first
                    // and last rows on the poles), where wgtrace's look-up has row centres:
                    // v is moved to match (measured: its eval returns texel values exactly
                    // there)
                    let file = self.tree.find_file(&o.get("filename").unwrap().pos, self.string(o, "filename")?.unwrap_or(""));
                    let (_, h) = crate::scene::textures::image_size(&file).map_err(|e| XmlError {
                        pos: o.get("filename").unwrap().pos.clone(),
                        message: format!("emitter envmap: {}: {e}", file.display()),
                    })?;
                    let h = h as f64;
                    let remap = T::Array(vec![
                        T::Array(vec![float(1.0), float(0.0), float(0.0)]),
                        T::Array(vec![float(0.0), float((h - 1.0) / h), float(0.5 / h)]),
                    ]);
                    self.textures.push(Entry {
                        name: name.clone(),
                        table: table([
                            ("type", text("image")),
                            ("path", text(&path)),
                            ("transform", T::Table(table([("matrix", remap)]))),
                        ]),
                        pos: o.pos.clone(),
                        what: what(o),
                    });
                    // Mitsuba's image centre faces +z, wgtrace's -z: half a turn more
                    let mut t = table([("texture", T::String(name)), ("rotation", float((rotation + 180.0).rem_euclid(360.0)))]);
                    let scale = self.float(o, "scale", 1.0)?;
                    if scale != 1.0 {
                        t.insert("strength".into(), float(scale));
                    }
                    t
                };
                self.background = Some(Entry {
                    name: "background".into(),
                    table: t,
                    pos: o.pos.clone(),
                    what: what(o),
                });
            }
            "point" => {
                self.check_known(o, &["intensity", "position", "to_world"], &["sampling_weight"])?;
                let position = match o.get("position") {
                    Some(_) => self.world.transform_point3(self.point(o, "position", DVec3::ZERO)?),
                    None => at(DVec3::ZERO),
                };
                let intensity = self.color_const(o, "intensity", 1.0, Use::Emission)?;
                light(self, table([("type", text("point")), ("position", vec3(position)), ("intensity", intensity)]));
            }
            "spot" => {
                self.check_known(o, &["intensity", "cutoff_angle", "beam_width", "to_world", "texture"], &["sampling_weight"])?;
                let cutoff = self.float(o, "cutoff_angle", 20.0)?;
                let beam = self.float(o, "beam_width", cutoff * 3.0 / 4.0)?;
                let intensity = self.color_const(o, "intensity", 1.0, Use::Emission)?;
                let mut t = table([
                    ("type", text("spot")),
                    ("position", vec3(at(DVec3::ZERO))),
                    ("direction", vec3(axis())),
                    ("intensity", intensity),
                    ("inner_angle", float(beam)),
                    ("outer_angle", float(cutoff)),
                    ("falloff", text("mitsuba")),
                ]);
                if let Some(p) = o.get("texture") {
                    let Value::Object(i) = p.value else {
                        return err(&p.pos, "emitter spot: `texture` must be a texture");
                    };
                    t.insert("texture".into(), T::String(self.texture(i)?));
                    // Mitsuba looks the image up at 0.5 + 0.5 (x, y) / (z tan cutoff) in
                    // its local frame, v down the image: its top toward local -y
                    t.insert("up".into(), vec3(-m.transform_vector3(DVec3::Y).normalize()));
                }
                light(self, t);
            }
            "directional" => {
                self.check_known(o, &["irradiance", "direction", "to_world"], &["sampling_weight"])?;
                let direction = match o.get("direction") {
                    Some(_) => self.world.transform_vector3(self.point(o, "direction", DVec3::Z)?).normalize(),
                    None => axis(),
                };
                let irradiance = self.color_const(o, "irradiance", 1.0, Use::Emission)?;
                light(self, table([("type", text("directional")), ("direction", vec3(direction)), ("irradiance", irradiance)]));
            }
            "projector" => {
                self.check_known(o, &["irradiance", "scale", "fov", "fov_axis", "focal_length", "to_world"], &["sampling_weight"])?;
                let irradiance = self.color(o, "irradiance", 1.0, Use::Emission)?;
                // Mitsuba reads the field of view as its perspective camera does, for the
                // aspect of the image (1 for a constant)
                let aspect = match o.get("irradiance").map(|p| &p.value) {
                    Some(Value::Object(i)) if self.obj(*i).plugin == "bitmap" => {
                        let t = self.obj(*i);
                        let name = t.get("filename").map(|p| p.pos.clone()).unwrap_or(t.pos.clone());
                        let file = self.tree.find_file(&name, self.string(t, "filename")?.unwrap_or(""));
                        let (w, h) = crate::scene::textures::image_size(&file).map_err(|e| XmlError {
                            pos: name,
                            message: format!("texture bitmap: {}: {e}", file.display()),
                        })?;
                        f64::from(w) / f64::from(h)
                    }
                    _ => 1.0,
                };
                let fov = self.fov_x(o, aspect)?;
                let position = at(DVec3::ZERO);
                light(
                    self,
                    table([
                        ("type", text("projector")),
                        ("position", vec3(position)),
                        ("look_at", vec3(position + axis())),
                        ("up", vec3(m.transform_vector3(DVec3::Y).normalize())),
                        ("fov", float(fov)),
                        ("irradiance", irradiance),
                        ("scale", float(self.float(o, "scale", 1.0)?)),
                    ]),
                );
            }
            "area" => {
                // declared at the top with an id and referenced from a shape (which reads
                // it as its own): nothing to do here
                let referenced = self.tree.objects.iter().any(|s| {
                    s.tag == "shape" && s.props.iter().any(|p| matches!(p.value, Value::Object(t) if t == i))
                });
                if !referenced {
                    return err(&o.pos, "emitter area: belongs inside a shape");
                }
            }
            other => {
                return err(
                    &o.pos,
                    format!(
                        "emitter {other}: not rendered (wgtrace reads area, point, spot, directional, envmap, constant and projector)"
                    ),
                )
            }
        }
        Ok(())
    }

    // ---- output ----------------------------------------------------------------------

    fn write(self) -> Imported {
        let mut w = Writer::default();
        w.line(
            "# Converted from a Mitsuba 3 scene file by wgtrace; each table names the element it",
        );
        w.line("# came from.");
        for n in &self.notes {
            w.line(&format!("# note: {n}"));
        }
        let root = self.obj(self.tree.root);
        w.section("[render]", &root.pos, "scene", &self.render);
        w.line("light_sampling = \"mis\"");
        if let Some(c) = &self.camera {
            w.section("[camera]", &c.pos, &c.what, &c.table);
        }
        match &self.background {
            Some(b) => w.section("[background]", &b.pos, &b.what, &b.table),
            None => w.section(
                "[background]",
                &root.pos,
                "scene",
                &table([("color", rgb([0.0; 3]))]),
            ),
        }
        for (kind, list) in [
            ("textures", &self.textures),
            ("materials", &self.materials),
            ("media", &self.media),
        ] {
            for e in list {
                w.section(&format!("[{kind}.{}]", e.name), &e.pos, &e.what, &e.table);
            }
        }
        for e in self.objects.iter().chain(&self.lights).chain(&self.groups) {
            w.section(&format!("[[{}]]", e.name), &e.pos, &e.what, &e.table);
        }
        Imported {
            toml: w.text,
            origins: w.origins,
            notes: self.notes,
        }
    }
}

/// A 2 x 3 uv matrix for wgtrace's image transform from Mitsuba's `to_uv` (conjugated by
/// the v flip between the two conventions: F T F, F(u, v) = (u, 1 - v)).
fn uv_matrix(o: &Object, to_uv: DMat4) -> Result<T> {
    uv_map(o, flip_v() * uv_affine(to_uv) * flip_v())
}

/// The cells of Mitsuba's checkerboard under `to_uv`, in wgtrace's uv (v up): the rows of
/// 2 T F, as a checker's `transform` (its scale 1).
fn checker_matrix(o: &Object, to_uv: DMat4) -> Result<T> {
    uv_map(
        o,
        DMat3::from_diagonal(DVec3::new(2.0, 2.0, 1.0)) * uv_affine(to_uv) * flip_v(),
    )
}

/// `to_uv` as it acts on (u, v, 0, 1): its upper-left 2 x 2 and its translation column.
fn uv_affine(to_uv: DMat4) -> DMat3 {
    let c = to_uv.to_cols_array_2d();
    DMat3::from_cols(
        DVec3::new(c[0][0], c[0][1], 0.0),
        DVec3::new(c[1][0], c[1][1], 0.0),
        DVec3::new(c[3][0], c[3][1], 1.0),
    )
}

/// F(u, v) = (u, 1 - v): between Mitsuba's v down and wgtrace's v up.
fn flip_v() -> DMat3 {
    DMat3::from_cols(
        DVec3::X,
        DVec3::new(0.0, -1.0, 0.0),
        DVec3::new(0.0, 1.0, 1.0),
    )
}

/// A uv `transform` table of the first two rows of `m`.
fn uv_map(o: &Object, m: DMat3) -> Result<T> {
    if !m.is_finite() {
        return err(&o.pos, format!("{}: to_uv is not finite", what(o)));
    }
    let row = |r: usize| T::Array((0..3).map(|k| float(m.col(k)[r])).collect());
    Ok(T::Table(table([(
        "matrix",
        T::Array(vec![row(0), row(1)]),
    )])))
}

/// The uniform scale of a uv transform without rotation or offset, else None.
fn uniform_uv_scale(m: DMat4) -> Option<f64> {
    let s = m.x_axis.x;
    let expect = DMat4::from_scale(DVec3::new(s, s, m.z_axis.z));
    (m == expect).then_some(s)
}

/// The angle (degrees) of a rotation about +y, uniform scale allowed; None for anything
/// else.
fn y_rotation(m: DMat4) -> Option<f64> {
    let l = glam::DMat3::from_mat4(m);
    let s = l.y_axis.length();
    let angle = l.z_axis.x.atan2(l.x_axis.x);
    let expect = glam::DMat3::from_rotation_y(angle) * s;
    let ok = (0..3).all(|c| (l.col(c) - expect.col(c)).abs().max_element() <= 1e-6 * s.max(1.0));
    ok.then_some(angle.to_degrees())
}

#[derive(Default)]
struct Writer {
    text: String,
    origins: Vec<Origin>,
}

impl Writer {
    fn line(&mut self, s: &str) {
        self.text.push_str(s);
        self.text.push('\n');
    }

    fn section(&mut self, header: &str, pos: &Pos, what: &str, t: &Table) {
        self.line("");
        let line = self.text.matches('\n').count() + 1;
        self.origins.push(Origin {
            line,
            pos: pos.clone(),
            what: what.to_string(),
        });
        let file = pos
            .file
            .file_name()
            .map_or_else(String::new, |f| f.to_string_lossy().into_owned());
        self.line(&format!(
            "{header}  # {what}, {file}:{}:{}",
            pos.line, pos.col
        ));
        let mut keys: Vec<&String> = t.keys().collect();
        keys.sort_by_key(|k| (k.as_str() != "type", k.as_str() != "path"));
        for k in keys {
            let mut s = String::new();
            let _ = write!(s, "{k} = {}", inline(&t[k.as_str()]));
            self.line(&s);
        }
    }
}

/// A value as one line of TOML (tables inline).
fn inline(v: &T) -> String {
    match v {
        T::Table(t) => {
            let parts: Vec<String> = t
                .iter()
                .map(|(k, v)| format!("{k} = {}", inline(v)))
                .collect();
            format!("{{ {} }}", parts.join(", "))
        }
        T::Array(a) => format!("[{}]", a.iter().map(inline).collect::<Vec<_>>().join(", ")),
        other => other.to_string(),
    }
}
