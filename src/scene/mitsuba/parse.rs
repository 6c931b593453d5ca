//! Mitsuba 3 scene files (XML), read into a tree of plugins with every value parsed and
//! every position kept: the first stage of the Mitsuba importer (issue 42), which the
//! mapping onto wgtrace's scene format builds on.
//!
//! What it reads, as Mitsuba 3's parser defines the format: the root `<scene
//! version="...">`; objects (`<shape type="...">`, `<bsdf>`, `<texture>`, `<emitter>`,
//! `<sensor>`, `<film>`, `<rfilter>`, `<sampler>`, `<integrator>`, `<medium>`, `<phase>`,
//! `<volume>`, and `<spectrum type="...">`) with optional `id` and `name`, nested or
//! referred to by `<ref id="..." name="..."/>` (before or after their definition) and
//! `<alias id="..." as="..."/>`; properties `float`, `integer`, `boolean`, `string`,
//! `point`, `vector` (`value` of 1 or 3 numbers, or `x`/`y`/`z`), `rgb` (1 or 3), `spectrum`
//! (a constant, `wavelength:value` pairs, or a `filename` of such pairs), `transform`
//! (`translate`, `rotate` by degrees about an axis (not normalized, as Mitsuba's), `scale`, `matrix` of 16 or 9 numbers,
//! `lookat`, each applied after the ones before it); `<default name value/>` and `$name`
//! in any attribute (the longest names first, as Mitsuba substitutes), with defines from
//! the command line (`-D name=value`) taking precedence; `<include filename/>` (a `<scene>`
//! file's children spliced in place, at most 15 deep) and `<path value/>` (a folder to
//! look files up in). Files of versions before 2.0 are upgraded as Mitsuba 3 upgrades
//! them: property names from camelCase to snake_case, `lookAt` to `lookat`, the diffuse
//! BSDF's `diffuse_reflectance` to `reflectance`, `uoffset`/`voffset`/`uscale`/`vscale` to
//! a `to_uv` transform. Every problem is one [`XmlError`] naming the file, line and column.

use std::collections::{HashMap, HashSet};
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{DMat4, DVec3};

/// Where in which file a node starts (1-based line and column).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pos {
    pub file: Arc<PathBuf>,
    pub line: u32,
    pub col: u32,
}

impl fmt::Display for Pos {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file.display(), self.line, self.col)
    }
}

/// A problem with a Mitsuba file, at the node it concerns.
#[derive(Debug, Clone, thiserror::Error)]
#[error("{pos}: {message}")]
pub struct XmlError {
    pub pos: Pos,
    pub message: String,
}

/// A spectrum property as written: Mitsuba's RGB mode turns either into a colour.
#[derive(Debug, Clone, PartialEq)]
pub enum Spectrum {
    /// The same value at every wavelength.
    Uniform(f64),
    /// (wavelength in nm, value) pairs in increasing wavelength.
    Samples(Vec<(f64, f64)>),
}

/// A property's value.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    Float(f64),
    Integer(i64),
    Boolean(bool),
    String(String),
    Point(DVec3),
    Vector(DVec3),
    Rgb(DVec3),
    Spectrum(Spectrum),
    Transform(DMat4),
    /// A nested or referred-to object: its index in [`SceneTree::objects`].
    Object(usize),
}

/// A named property of an object (an unnamed nested object or reference is named
/// `_arg_N`, N counting them within the object, as Mitsuba names them).
#[derive(Debug, Clone, PartialEq)]
pub struct Property {
    pub name: String,
    pub value: Value,
    pub pos: Pos,
}

/// A plugin instance: `<shape type="obj" id="...">` and its properties in file order.
#[derive(Debug, Clone, PartialEq)]
pub struct Object {
    /// The element's name: scene, shape, bsdf, texture, emitter, ...
    pub tag: String,
    /// Its `type` ("scene" for the root).
    pub plugin: String,
    pub id: Option<String>,
    pub pos: Pos,
    pub props: Vec<Property>,
}

impl Object {
    /// The first property of that name.
    pub fn get(&self, name: &str) -> Option<&Property> {
        self.props.iter().find(|p| p.name == name)
    }
}

/// A whole file: its objects (the root's index is `root`) and the folders its files are
/// looked for in (the `<path>` folders, latest first, then the scene file's).
#[derive(Debug, Clone)]
pub struct SceneTree {
    pub objects: Vec<Object>,
    pub root: usize,
    pub search_paths: Vec<PathBuf>,
}

impl SceneTree {
    /// A file named by a property at `at`, found as Mitsuba finds it ([`find_in`]).
    pub fn find_file(&self, at: &Pos, name: &str) -> PathBuf {
        find_in(&self.search_paths, &at.file, name)
    }
}

/// The element names that make objects.
const OBJECT_TAGS: &[&str] = &[
    "scene",
    "shape",
    "bsdf",
    "texture",
    "emitter",
    "sensor",
    "film",
    "rfilter",
    "sampler",
    "integrator",
    "medium",
    "phase",
    "volume",
];

/// How deep `<include>` may nest (Mitsuba's limit).
const MAX_INCLUDE_DEPTH: usize = 15;

/// Reads a Mitsuba scene file with `defines` (`-D name=value`, which override the
/// file's `<default>`s).
pub fn parse_file(path: &Path, defines: &[(String, String)]) -> Result<SceneTree, XmlError> {
    let text = std::fs::read_to_string(path).map_err(|e| XmlError {
        pos: Pos {
            file: Arc::new(path.to_path_buf()),
            line: 0,
            col: 0,
        },
        message: format!("cannot read it: {e}"),
    })?;
    parse_str(&text, path, defines)
}

/// [`parse_file`] of a file's text (`path` names it in errors and is where relative
/// `<include>` and `<path>` start).
pub fn parse_str(
    text: &str,
    path: &Path,
    defines: &[(String, String)],
) -> Result<SceneTree, XmlError> {
    let mut p = Parser {
        objects: Vec::new(),
        params: defines.to_vec(),
        used: Default::default(),
        ids: HashMap::new(),
        refs: Vec::new(),
        // Mitsuba's file resolver starts with the scene file's folder: a file named in an
        // included file is found beside that file or, as Mitsuba finds it, beside the scene
        search_paths: vec![path.parent().unwrap_or(Path::new("")).to_path_buf()],
        include_depth: 0,
    };
    let file = Arc::new(path.to_path_buf());
    let doc = read_document(text, &file)?;
    let root_node = doc.root_element();
    let at = pos_of(&doc, &file, root_node);
    if root_node.tag_name().name() != "scene" {
        return Err(XmlError {
            pos: at,
            message: format!(
                "the root element is <{}>: a scene file's is <scene>",
                root_node.tag_name().name()
            ),
        });
    }
    let legacy = p.version(&doc, &file, root_node, true)?;
    let src = Source {
        doc: &doc,
        file: &file,
        legacy,
    };
    let root = p.object(&src, root_node)?;
    let unused: Vec<String> = defines
        .iter()
        .filter(|(k, _)| !p.used.borrow().contains(k))
        .map(|(k, v)| format!("{k}={v}"))
        .collect();
    if !unused.is_empty() {
        return Err(XmlError {
            pos: at,
            message: format!(
                "-D {}: the scene uses no such $parameter (Mitsuba refuses an unused one too)",
                unused.join(", -D ")
            ),
        });
    }
    p.resolve()?;
    p.check_cycles(root)?;
    Ok(SceneTree {
        objects: p.objects,
        root,
        search_paths: p.search_paths,
    })
}

fn read_document<'a>(
    text: &'a str,
    file: &Arc<PathBuf>,
) -> Result<roxmltree::Document<'a>, XmlError> {
    roxmltree::Document::parse(text).map_err(|e| {
        let p = e.pos();
        XmlError {
            pos: Pos {
                file: file.clone(),
                line: p.row,
                col: p.col,
            },
            message: format!("not well-formed XML: {e}"),
        }
    })
}

fn pos_of(doc: &roxmltree::Document, file: &Arc<PathBuf>, node: roxmltree::Node) -> Pos {
    let p = doc.text_pos_at(node.range().start);
    Pos {
        file: file.clone(),
        line: p.row,
        col: p.col,
    }
}

/// One file being read.
struct Source<'a, 'input> {
    doc: &'a roxmltree::Document<'input>,
    file: &'a Arc<PathBuf>,
    /// Written for Mitsuba before 2.0: upgraded as it is read.
    legacy: bool,
}

impl Source<'_, '_> {
    fn pos(&self, node: roxmltree::Node) -> Pos {
        pos_of(self.doc, self.file, node)
    }

    fn err<T>(&self, node: roxmltree::Node, message: impl Into<String>) -> Result<T, XmlError> {
        Err(XmlError {
            pos: self.pos(node),
            message: message.into(),
        })
    }
}

struct Parser {
    objects: Vec<Object>,
    /// `-D` defines first, then `<default>`s in the order read.
    params: Vec<(String, String)>,
    /// The names a `$name` has been replaced by (a `-D` define never used is an error,
    /// as Mitsuba's).
    used: std::cell::RefCell<HashSet<String>>,
    ids: HashMap<String, (usize, Pos)>,
    /// (object, property, id referred to, where) to resolve once every id is known.
    refs: Vec<(usize, usize, String, Pos)>,
    search_paths: Vec<PathBuf>,
    include_depth: usize,
}

impl Parser {
    /// The root's `version` (required at the top, optional in included files): whether
    /// it predates Mitsuba 2 (and so is upgraded).
    fn version(
        &self,
        doc: &roxmltree::Document,
        file: &Arc<PathBuf>,
        node: roxmltree::Node,
        required: bool,
    ) -> Result<bool, XmlError> {
        let Some(v) = node.attribute("version") else {
            if required {
                return Err(XmlError {
                    pos: pos_of(doc, file, node),
                    message: "the root element needs a version attribute (e.g. version=\"3.0.0\")"
                        .into(),
                });
            }
            return Ok(false);
        };
        let parts: Vec<&str> = v.split(['.', ' ']).filter(|s| !s.is_empty()).collect();
        let numbers: Option<Vec<u32>> = parts.iter().map(|s| s.parse().ok()).collect();
        match numbers {
            Some(n) if n.len() == 3 => Ok(n[0] < 2),
            _ => Err(XmlError {
                pos: pos_of(doc, file, node),
                message: format!("version \"{v}\" is not three numbers separated by periods"),
            }),
        }
    }

    /// An attribute's value with `$name` replaced (the longest names first).
    fn attr(
        &self,
        src: &Source,
        node: roxmltree::Node,
        name: &str,
    ) -> Result<Option<String>, XmlError> {
        let Some(raw) = node.attribute(name) else {
            return Ok(None);
        };
        if !raw.contains('$') {
            return Ok(Some(raw.to_string()));
        }
        let mut params: Vec<&(String, String)> = self.params.iter().collect();
        params.sort_by_key(|(k, _)| std::cmp::Reverse(k.len()));
        let mut value = raw.to_string();
        for (k, v) in params {
            let name = format!("${k}");
            if value.contains(&name) {
                value = value.replace(&name, v);
                self.used.borrow_mut().insert(k.clone());
            }
        }
        if value.contains('$') {
            return src.err(
                node,
                format!(
                    "attribute {name}=\"{raw}\": undefined parameter (give it a <default> or -D)"
                ),
            );
        }
        Ok(Some(value))
    }

    fn required(
        &self,
        src: &Source,
        node: roxmltree::Node,
        name: &str,
    ) -> Result<String, XmlError> {
        match self.attr(src, node, name)? {
            Some(v) => Ok(v),
            None => src.err(
                node,
                format!("<{}> needs a \"{name}\" attribute", node.tag_name().name()),
            ),
        }
    }

    /// Refuses attributes outside `allowed`.
    fn only(&self, src: &Source, node: roxmltree::Node, allowed: &[&str]) -> Result<(), XmlError> {
        for a in node.attributes() {
            if !allowed.contains(&a.name()) {
                return src.err(
                    node,
                    format!(
                        "unexpected attribute \"{}\" in <{}> (it takes {})",
                        a.name(),
                        node.tag_name().name(),
                        allowed.join(", ")
                    ),
                );
            }
        }
        Ok(())
    }

    /// A property's name, upgraded from camelCase in a legacy file.
    fn prop_name(&self, src: &Source, node: roxmltree::Node) -> Result<String, XmlError> {
        let name = self.required(src, node, "name")?;
        if name.starts_with('_') {
            return src.err(
                node,
                format!("name \"{name}\": leading underscores are reserved"),
            );
        }
        Ok(if src.legacy { snake_case(&name) } else { name })
    }

    /// The property name of a nested object or reference: its `name`, else `_arg_N`
    /// (N counting the unnamed ones of the object, as Mitsuba names them).
    fn arg_name(
        &self,
        src: &Source,
        node: roxmltree::Node,
        unnamed: &mut usize,
    ) -> Result<String, XmlError> {
        if node.attribute("name").is_some() {
            return self.prop_name(src, node);
        }
        *unnamed += 1;
        Ok(format!("_arg_{}", *unnamed - 1))
    }

    /// Reads an object element and everything in it; returns its index.
    fn object(&mut self, src: &Source, node: roxmltree::Node) -> Result<usize, XmlError> {
        let tag = node.tag_name().name().to_string();
        let allowed: &[&str] = if tag == "scene" {
            &["version", "id"]
        } else {
            &["type", "id", "name", "version"]
        };
        self.only(src, node, allowed)?;
        let plugin = if tag == "scene" {
            "scene".to_string()
        } else {
            self.required(src, node, "type")?
        };
        let id = self.attr(src, node, "id")?;
        let pos = src.pos(node);
        let index = self.objects.len();
        if let Some(id) = &id {
            if id.starts_with('_') {
                return src.err(
                    node,
                    format!("id \"{id}\": leading underscores are reserved"),
                );
            }
            if let Some((_, previous)) = self.ids.get(id) {
                return src.err(node, format!("duplicate id \"{id}\" (first at {previous})"));
            }
            self.ids.insert(id.clone(), (index, pos.clone()));
        }
        self.objects.push(Object {
            tag,
            plugin,
            id,
            pos,
            props: Vec::new(),
        });
        let mut unnamed = 0;
        for child in node.children() {
            self.child(src, index, child, &mut unnamed)?;
        }
        if src.legacy {
            self.upgrade_uv(index);
            let o = &mut self.objects[index];
            if o.tag == "bsdf" && o.plugin == "diffuse" {
                for p in &mut o.props {
                    if p.name == "diffuse_reflectance" {
                        p.name = "reflectance".into();
                    }
                }
            }
        }
        Ok(index)
    }

    /// Legacy uoffset/voffset/uscale/vscale floats into one `to_uv` transform (the
    /// translation first, then the scale).
    fn upgrade_uv(&mut self, index: usize) {
        let o = &mut self.objects[index];
        let mut offset = [0.0, 0.0];
        let mut scale = [1.0, 1.0];
        let mut pos = None;
        o.props.retain(|p| {
            let slot = match p.name.as_str() {
                "uoffset" => &mut offset[0],
                "voffset" => &mut offset[1],
                "uscale" => &mut scale[0],
                "vscale" => &mut scale[1],
                _ => return true,
            };
            match p.value {
                Value::Float(v) => {
                    *slot = v;
                    pos.get_or_insert(p.pos.clone());
                    false
                }
                _ => true,
            }
        });
        if let Some(pos) = pos {
            let m = DMat4::from_scale(DVec3::new(scale[0], scale[1], 1.0))
                * DMat4::from_translation(DVec3::new(offset[0], offset[1], 0.0));
            o.props.push(Property {
                name: "to_uv".into(),
                value: Value::Transform(m),
                pos,
            });
        }
    }

    /// One child element of object `index`.
    fn child(
        &mut self,
        src: &Source,
        index: usize,
        node: roxmltree::Node,
        unnamed: &mut usize,
    ) -> Result<(), XmlError> {
        if !node.is_element() {
            if node.is_text() && !node.text().unwrap_or("").trim().is_empty() {
                return src.err(node, "unexpected text");
            }
            return Ok(());
        }
        let name = node.tag_name().name();
        let tag = if src.legacy && name == "lookAt" {
            "lookat"
        } else {
            name
        };
        let is_object = OBJECT_TAGS.contains(&tag) && tag != "scene"
            || tag == "spectrum" && node.attribute("type").is_some();
        if is_object {
            let prop_name = self.arg_name(src, node, unnamed)?;
            let pos = src.pos(node);
            let child = self.object(src, node)?;
            self.objects[index].props.push(Property {
                name: prop_name,
                value: Value::Object(child),
                pos,
            });
            return Ok(());
        }
        let pos = src.pos(node);
        let value = match tag {
            "default" => {
                self.only(src, node, &["name", "value"])?;
                let name = self.required(src, node, "name")?;
                let value = self.required(src, node, "value")?;
                if name.is_empty() {
                    return src.err(node, "<default> needs a nonempty name");
                }
                if !self.params.iter().any(|(k, _)| *k == name) {
                    self.params.push((name, value));
                }
                return Ok(());
            }
            "path" => {
                self.only(src, node, &["value"])?;
                if self.objects[index].tag != "scene" {
                    return src.err(node, "<path> may only be a child of the scene");
                }
                let value = self.required(src, node, "value")?;
                let dir = resolve(src.file, Path::new(&value));
                if !dir.is_dir() {
                    return src.err(node, format!("<path>: folder {} not found", dir.display()));
                }
                self.search_paths.insert(0, dir);
                return Ok(());
            }
            "include" => {
                self.only(src, node, &["filename"])?;
                return self.include(src, index, node, unnamed);
            }
            "alias" => {
                self.only(src, node, &["id", "as"])?;
                let from = self.required(src, node, "id")?;
                let to = self.required(src, node, "as")?;
                let Some(&(target, _)) = self.ids.get(&from) else {
                    return src.err(
                        node,
                        format!("<alias>: no object has id \"{from}\" before it"),
                    );
                };
                if let Some((_, previous)) = self.ids.get(&to) {
                    return src.err(node, format!("duplicate id \"{to}\" (first at {previous})"));
                }
                self.ids.insert(to, (target, pos));
                return Ok(());
            }
            "ref" => {
                self.only(src, node, &["id", "name"])?;
                let id = self.required(src, node, "id")?;
                let prop_name = self.arg_name(src, node, unnamed)?;
                let o = &mut self.objects[index];
                self.refs.push((index, o.props.len(), id, pos.clone()));
                // resolved in `resolve`
                o.props.push(Property {
                    name: prop_name,
                    value: Value::Object(usize::MAX),
                    pos,
                });
                return Ok(());
            }
            "float" => {
                self.only(src, node, &["name", "value"])?;
                Value::Float(number(src, node, &self.required(src, node, "value")?)?)
            }
            "integer" => {
                self.only(src, node, &["name", "value"])?;
                let v = self.required(src, node, "value")?;
                match v.trim().parse::<i64>() {
                    Ok(i) => Value::Integer(i),
                    Err(_) => return src.err(node, format!("\"{v}\" is not an integer")),
                }
            }
            "boolean" => {
                self.only(src, node, &["name", "value"])?;
                let v = self.required(src, node, "value")?;
                match v.trim().to_lowercase().as_str() {
                    "true" => Value::Boolean(true),
                    "false" => Value::Boolean(false),
                    _ => return src.err(node, format!("\"{v}\" is not a boolean: true or false")),
                }
            }
            "string" => {
                self.only(src, node, &["name", "value"])?;
                Value::String(self.required(src, node, "value")?)
            }
            "point" | "vector" => {
                self.only(src, node, &["name", "value", "x", "y", "z"])?;
                let v = self.xyz(src, node, 0.0)?;
                if tag == "point" {
                    Value::Point(v)
                } else {
                    Value::Vector(v)
                }
            }
            "rgb" => {
                self.only(src, node, &["name", "value"])?;
                let v = self.required(src, node, "value")?;
                let n = numbers(src, node, &v)?;
                match n.len() {
                    1 => Value::Rgb(DVec3::splat(n[0])),
                    3 => Value::Rgb(DVec3::new(n[0], n[1], n[2])),
                    _ => return src.err(node, format!("<rgb> takes 1 or 3 numbers, got \"{v}\"")),
                }
            }
            "spectrum" => {
                self.only(src, node, &["name", "value", "filename"])?;
                Value::Spectrum(self.spectrum(src, node)?)
            }
            "transform" => {
                self.only(src, node, &["name"])?;
                Value::Transform(self.transform(src, node)?)
            }
            "translate" | "rotate" | "scale" | "matrix" | "lookat" => {
                return src.err(node, format!("<{tag}> may only stand in a <transform>"));
            }
            other => {
                return src.err(
                    node,
                    format!("unknown element <{other}> (not a Mitsuba 3 object or property)"),
                );
            }
        };
        let name = self.prop_name(src, node)?;
        self.objects[index]
            .props
            .push(Property { name, value, pos });
        Ok(())
    }

    /// `value` of 1 or 3 numbers, or `x`, `y`, `z` (each `default` when left out).
    fn xyz(&self, src: &Source, node: roxmltree::Node, default: f64) -> Result<DVec3, XmlError> {
        if let Some(v) = self.attr(src, node, "value")? {
            if ["x", "y", "z"].iter().any(|a| node.attribute(*a).is_some()) {
                return src.err(node, "give value or x/y/z, not both");
            }
            let n = numbers(src, node, &v)?;
            return match n.len() {
                1 => Ok(DVec3::splat(n[0])),
                3 => Ok(DVec3::new(n[0], n[1], n[2])),
                _ => src.err(node, format!("value \"{v}\" must have 1 or 3 numbers")),
            };
        }
        let mut out = [default; 3];
        for (i, a) in ["x", "y", "z"].iter().enumerate() {
            if let Some(v) = self.attr(src, node, a)? {
                out[i] = number(src, node, &v)?;
            }
        }
        Ok(DVec3::from_array(out))
    }

    fn spectrum(&self, src: &Source, node: roxmltree::Node) -> Result<Spectrum, XmlError> {
        let value = self.attr(src, node, "value")?;
        let filename = self.attr(src, node, "filename")?;
        let pairs_text = match (value, filename) {
            (Some(v), None) => {
                let tokens = tokens(&v);
                if tokens.len() == 1 && !tokens[0].contains(':') {
                    return Ok(Spectrum::Uniform(number(src, node, tokens[0])?));
                }
                v
            }
            (None, Some(f)) => {
                let path = self.find(src.file, &f);
                let text = std::fs::read_to_string(&path)
                    .or_else(|e| src.err(node, format!("spectrum file {}: {e}", path.display())))?;
                // lines of "wavelength value", '#' comments
                text.lines()
                    .map(|l| l.split('#').next().unwrap_or("").trim())
                    .filter(|l| !l.is_empty())
                    .map(|l| l.split_whitespace().collect::<Vec<_>>().join(":"))
                    .collect::<Vec<_>>()
                    .join(" ")
            }
            _ => return src.err(node, "<spectrum> takes one of value or filename"),
        };
        let mut samples = Vec::new();
        for t in tokens(&pairs_text) {
            let Some((w, v)) = t.split_once(':') else {
                return src.err(node, format!("\"{t}\" is not a wavelength:value pair"));
            };
            samples.push((number(src, node, w)?, number(src, node, v)?));
        }
        if samples.is_empty() {
            return src.err(node, "an empty spectrum");
        }
        if samples.windows(2).any(|w| w[1].0 <= w[0].0) {
            return src.err(node, "the wavelengths must increase");
        }
        Ok(Spectrum::Samples(samples))
    }

    /// A `<transform>`'s operations, each applied after those before it.
    fn transform(&self, src: &Source, node: roxmltree::Node) -> Result<DMat4, XmlError> {
        let mut m = DMat4::IDENTITY;
        for op in node.children() {
            if !op.is_element() {
                if op.is_text() && !op.text().unwrap_or("").trim().is_empty() {
                    return src.err(op, "unexpected text in a <transform>");
                }
                continue;
            }
            let name = op.tag_name().name();
            let name = if src.legacy && name == "lookAt" {
                "lookat"
            } else {
                name
            };
            let step = match name {
                "translate" => {
                    self.only(src, op, &["value", "x", "y", "z"])?;
                    DMat4::from_translation(self.xyz(src, op, 0.0)?)
                }
                "scale" => {
                    self.only(src, op, &["value", "x", "y", "z"])?;
                    DMat4::from_scale(self.xyz(src, op, 1.0)?)
                }
                "rotate" => {
                    self.only(src, op, &["value", "x", "y", "z", "angle"])?;
                    let axis = self.xyz(src, op, 0.0)?;
                    let angle = number(src, op, &self.required(src, op, "angle")?)?;
                    if axis.length_squared() == 0.0 {
                        return src.err(op, "<rotate> needs a nonzero axis");
                    }
                    rotation(axis, angle.to_radians())
                }
                "matrix" => {
                    self.only(src, op, &["value"])?;
                    let v = self.required(src, op, "value")?;
                    let n = numbers(src, op, &v)?;
                    match n.len() {
                        // row-major in the file
                        16 => {
                            DMat4::from_cols_array(&std::array::from_fn(|i| n[(i % 4) * 4 + i / 4]))
                        }
                        9 => {
                            let mut a = [0.0; 16];
                            for r in 0..3 {
                                for c in 0..3 {
                                    a[c * 4 + r] = n[r * 3 + c];
                                }
                            }
                            a[15] = 1.0;
                            DMat4::from_cols_array(&a)
                        }
                        k => {
                            return src.err(op, format!("<matrix> takes 16 or 9 numbers, got {k}"))
                        }
                    }
                }
                "lookat" => {
                    self.only(src, op, &["origin", "target", "up"])?;
                    let vec3 = |attr: &str| -> Result<DVec3, XmlError> {
                        let v = self.required(src, op, attr)?;
                        let n = numbers(src, op, &v)?;
                        if n.len() != 3 {
                            return src.err(op, format!("{attr}=\"{v}\" must have 3 numbers"));
                        }
                        Ok(DVec3::new(n[0], n[1], n[2]))
                    };
                    let origin = vec3("origin")?;
                    let target = vec3("target")?;
                    let mut up = match op.attribute("up") {
                        Some(_) => vec3("up")?,
                        None => DVec3::ZERO,
                    };
                    let dir = (target - origin).normalize();
                    if !dir.is_finite() {
                        return src.err(op, "<lookat>: origin and target are the same point");
                    }
                    if up.length_squared() == 0.0 {
                        up = coordinate_system_s(dir);
                    }
                    let left = up.normalize().cross(dir).normalize();
                    if !left.is_finite() {
                        return src.err(op, "<lookat>: up is parallel to the view direction");
                    }
                    let new_up = dir.cross(left);
                    DMat4::from_cols(
                        left.extend(0.0),
                        new_up.extend(0.0),
                        dir.extend(0.0),
                        origin.extend(1.0),
                    )
                }
                other => {
                    return src.err(op, format!("<{other}> is not a transform operation"));
                }
            };
            m = step * m;
        }
        Ok(m)
    }

    /// `<include filename/>`: a scene file's children in place, or another root element
    /// as a child.
    fn include(
        &mut self,
        src: &Source,
        index: usize,
        node: roxmltree::Node,
        unnamed: &mut usize,
    ) -> Result<(), XmlError> {
        let filename = self.required(src, node, "filename")?;
        let path = self.find(src.file, &filename);
        if self.include_depth >= MAX_INCLUDE_DEPTH {
            return src.err(
                node,
                format!("<include> nests deeper than {MAX_INCLUDE_DEPTH} files"),
            );
        }
        let text = std::fs::read_to_string(&path)
            .or_else(|e| src.err(node, format!("included file {}: {e}", path.display())))?;
        let file = Arc::new(path);
        let doc = read_document(&text, &file)?;
        let root = doc.root_element();
        let legacy = self.version(&doc, &file, root, false)?;
        let nested = Source {
            doc: &doc,
            file: &file,
            legacy,
        };
        self.include_depth += 1;
        let result = if root.tag_name().name() == "scene" {
            nested.only_children(self, index, root, unnamed)
        } else {
            self.child(&nested, index, root, unnamed)
        };
        self.include_depth -= 1;
        result
    }

    /// A file named in the scene ([`find_in`]).
    fn find(&self, file: &Path, name: &str) -> PathBuf {
        find_in(&self.search_paths, file, name)
    }

    /// Every `<ref>` pointed at its object.
    fn resolve(&mut self) -> Result<(), XmlError> {
        for (object, prop, id, pos) in std::mem::take(&mut self.refs) {
            let Some(&(target, _)) = self.ids.get(&id) else {
                let mut known: Vec<&String> = self.ids.keys().collect();
                known.sort();
                return Err(XmlError {
                    pos,
                    message: format!(
                        "<ref id=\"{id}\">: no object has that id (ids: {})",
                        if known.is_empty() {
                            "none".to_string()
                        } else {
                            known
                                .iter()
                                .map(|s| s.as_str())
                                .collect::<Vec<_>>()
                                .join(", ")
                        }
                    ),
                });
            };
            self.objects[object].props[prop].value = Value::Object(target);
        }
        Ok(())
    }

    /// Refuses an object that contains itself through references.
    fn check_cycles(&self, root: usize) -> Result<(), XmlError> {
        fn visit(
            p: &Parser,
            o: usize,
            on_path: &mut Vec<usize>,
            done: &mut HashSet<usize>,
        ) -> Result<(), XmlError> {
            if done.contains(&o) {
                return Ok(());
            }
            on_path.push(o);
            for prop in &p.objects[o].props {
                if let Value::Object(c) = prop.value {
                    if on_path.contains(&c) {
                        let name = |i: usize| {
                            let o = &p.objects[i];
                            o.id.clone()
                                .unwrap_or_else(|| format!("<{} type=\"{}\">", o.tag, o.plugin))
                        };
                        return Err(XmlError {
                            pos: prop.pos.clone(),
                            message: format!("a cyclic reference: {} contains itself", name(c)),
                        });
                    }
                    visit(p, c, on_path, done)?;
                }
            }
            on_path.pop();
            done.insert(o);
            Ok(())
        }
        // from the root, then from any object only referred to outside its tree
        let mut done = HashSet::new();
        visit(self, root, &mut Vec::new(), &mut done)?;
        for o in 0..self.objects.len() {
            visit(self, o, &mut Vec::new(), &mut done)?;
        }
        Ok(())
    }
}

impl Source<'_, '_> {
    /// An included `<scene>`'s children, read into object `index`.
    fn only_children(
        &self,
        p: &mut Parser,
        index: usize,
        root: roxmltree::Node,
        unnamed: &mut usize,
    ) -> Result<(), XmlError> {
        for child in root.children() {
            p.child(self, index, child, unnamed)?;
        }
        Ok(())
    }
}

/// A file named in `file`, found as Mitsuba's file resolver finds it: absolute, else in
/// the first of the `search_paths` that has it (the `<path>` folders, latest first, then
/// the scene file's folder), else beside `file` (an included file's folder; also the name
/// errors give when no folder has it).
fn find_in(search_paths: &[PathBuf], file: &Path, name: &str) -> PathBuf {
    let name = Path::new(name);
    if name.is_absolute() {
        return name.to_path_buf();
    }
    let beside = resolve(file, name);
    search_paths
        .iter()
        .map(|d| d.join(name))
        .find(|p| p.exists())
        .unwrap_or(beside)
}

/// `name` relative to the folder of `file`.
fn resolve(file: &Path, name: &Path) -> PathBuf {
    if name.is_absolute() {
        return name.to_path_buf();
    }
    file.parent().unwrap_or(Path::new("")).join(name)
}

/// Rodrigues' rotation about `axis` as Mitsuba 3 builds it: cos I + sin [a]x +
/// (1 - cos) a a^T with the axis as written. For a unit axis that is the rotation; Mitsuba
/// does not normalize the axis, so a longer one (`x="1" y="1"`) also scales and shears,
/// and the file renders as Mitsuba renders it.
fn rotation(a: DVec3, angle: f64) -> DMat4 {
    let (s, c) = angle.sin_cos();
    let k = 1.0 - c;
    let m = glam::DMat3::from_cols(
        DVec3::new(
            c + k * a.x * a.x,
            k * a.x * a.y + s * a.z,
            k * a.x * a.z - s * a.y,
        ),
        DVec3::new(
            k * a.x * a.y - s * a.z,
            c + k * a.y * a.y,
            k * a.y * a.z + s * a.x,
        ),
        DVec3::new(
            k * a.x * a.z + s * a.y,
            k * a.y * a.z - s * a.x,
            c + k * a.z * a.z,
        ),
    );
    DMat4::from_mat3(m)
}

/// Mitsuba's tokens: split at commas and whitespace.
fn tokens(s: &str) -> Vec<&str> {
    s.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .collect()
}

fn number(src: &Source, node: roxmltree::Node, s: &str) -> Result<f64, XmlError> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => src.err(node, format!("\"{s}\" is not a finite number")),
    }
}

fn numbers(src: &Source, node: roxmltree::Node, s: &str) -> Result<Vec<f64>, XmlError> {
    tokens(s)
        .into_iter()
        .map(|t| number(src, node, t))
        .collect()
}

/// camelCase to snake_case as Mitsuba 3 upgrades old names: an underscore before an
/// upper-case run that follows a lower-case letter, the run lowered, and the letter
/// after the run taken as it is ("intIOR" -> "int_ior", "diffuseReflectance" ->
/// "diffuse_reflectance").
pub fn snake_case(name: &str) -> String {
    let chars: Vec<char> = name.chars().collect();
    let mut out = String::with_capacity(name.len() + 4);
    let mut i = 0;
    while i < chars.len() {
        out.push(chars[i]);
        if chars[i].is_ascii_lowercase() && i + 1 < chars.len() && chars[i + 1].is_ascii_uppercase()
        {
            out.push('_');
            i += 1;
            while i < chars.len() && chars[i].is_ascii_uppercase() {
                out.push(chars[i].to_ascii_lowercase());
                i += 1;
            }
            // Mitsuba's loop steps past the letter after the run unexamined
            if i < chars.len() {
                out.push(chars[i]);
            }
        }
        i += 1;
    }
    out
}

/// The first of Mitsuba's `coordinate_system` vectors about unit n (Duff et al. 2017's
/// branchless orthonormal basis): what a `<lookat>` without `up` takes for up.
fn coordinate_system_s(n: DVec3) -> DVec3 {
    let sign = 1.0f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    DVec3::new(n.x * n.x * a * sign + 1.0, b * sign, -n.x * sign)
}
