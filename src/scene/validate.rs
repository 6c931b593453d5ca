//! Validation: every problem of a parsed scene, each with its line, column and key.

use glam::Vec3;

use super::error::Problem;
use toml::Spanned;

use super::format::{
    is_mesh_attribute, CameraDesc, CheckerMapping, FilterKind, LightDesc, ObjectDesc, Projection,
    RenderDesc, SceneFile, TextureDesc, TransformDesc, UvTransformDesc, MESH_ATTRIBUTES,
};
use super::format::{MediumCoefficients, MediumDesc};
use super::materials::common::ColorDesc;
use super::materials::{blend, MaterialDesc};
use super::records::MAX_BLEND_DEPTH;
use super::shapes::polygon_normal;

/// Largest image side accepted.
pub const MAX_IMAGE_SIDE: u32 = 16384;
/// Most samples per pixel accepted (2^24): sample indices stay exact in f32 and far from
/// the u32 limit of the random streams.
pub const MAX_SPP: u32 = 1 << 24;
/// Longest path accepted (rays per path).
pub const MAX_DEPTH_LIMIT: u32 = 1024;

/// The widest pixel filter, in pixels from the pixel's centre.
pub const MAX_FILTER_RADIUS: f32 = 16.0;
/// The most steps a stepped filter has (`[render] filter_steps`): the shader walks them.
pub const MAX_FILTER_STEPS: u32 = 256;

/// Collects every problem of a parsed scene (not only the first). `overridden` names the
/// `[render]` keys whose values came from the command line (`--spp` for `spp`), so their
/// problems point there rather than at the file.
pub fn validate(file: &SceneFile, src: &str, overridden: &[&str]) -> Vec<Problem> {
    let mut v = Validator {
        src,
        doc: toml::de::DeTable::parse(src).ok().map(|d| d.into_inner()),
        overridden: overridden.iter().map(|k| format!("render.{k}")).collect(),
        problems: Vec::new(),
        textures: file
            .textures
            .iter()
            .map(|(name, t)| {
                (
                    name.clone(),
                    matches!(t.get_ref(), TextureDesc::Checker { .. }),
                )
            })
            .collect(),
        attributes: file
            .textures
            .iter()
            .filter(|(_, t)| matches!(t.get_ref(), TextureDesc::MeshAttribute { .. }))
            .map(|(name, _)| name.clone())
            .collect(),
    };
    v.render(&file.render);
    v.camera(&file.camera);
    v.background(file);
    for (name, t) in &file.textures {
        v.texture(name, t);
    }
    for (name, m) in &file.materials {
        v.material(name, m);
        if let MaterialDesc::Blend(b) = m.get_ref() {
            v.blend(name, b, m.span().start, file);
        }
    }
    for (i, obj) in file.objects.iter().enumerate() {
        v.object(i, obj, file);
    }
    v.groups(file);
    for (name, m) in &file.media {
        v.medium(name, m);
    }
    if file.media.len() >= crate::scene::records::MEDIA_SIDE as usize {
        v.push(
            0,
            "media",
            format!("at most {} media", crate::scene::records::MEDIA_SIDE - 1),
        );
    }
    if let Some(name) = file.camera.medium.as_deref() {
        v.medium_name("camera.medium", name, 0, file);
    }
    for (i, light) in file.lights.iter().enumerate() {
        v.light(i, light);
    }
    v.problems
}

struct Validator<'a> {
    src: &'a str,
    /// The text parsed again with spans, to place problems of keys that serde's records
    /// hold without one (`[render]`, `[camera]`, `[background]`).
    doc: Option<toml::de::DeTable<'a>>,
    /// `render.KEY` of values from the command line.
    overridden: Vec<String>,
    problems: Vec<Problem>,
    /// Texture names, and whether each is a checker.
    textures: Vec<(String, bool)>,
    /// The names of the `mesh_attribute` textures.
    attributes: Vec<String>,
}

impl Validator<'_> {
    /// `[render]`: sizes, samples and path length in range.
    fn render(&mut self, r: &RenderDesc) {
        self.range_u32("render.width", r.width, 1, MAX_IMAGE_SIDE, 0);
        self.range_u32("render.height", r.height, 1, MAX_IMAGE_SIDE, 0);
        self.range_u32("render.spp", r.spp, 1, MAX_SPP, 0);
        self.range_u32("render.max_depth", r.max_depth, 1, MAX_DEPTH_LIMIT, 0);
        if let Some([x, y, w, h]) = r.crop {
            let fits =
                |o: u32, n: u32, side: u32| n >= 1 && o.checked_add(n).is_some_and(|e| e <= side);
            if !fits(x, w, r.width) || !fits(y, h, r.height) {
                self.push(
                    0,
                    "render.crop",
                    format!(
                        "[x, y, width, height] = [{x}, {y}, {w}, {h}] must be a rectangle of at least one pixel inside the {} x {} film",
                        r.width, r.height
                    ),
                );
            }
        }
        let kind = r.filter;
        if let Some(radius) = r.filter_radius {
            if kind == FilterKind::Box {
                self.push(
                    0,
                    "render.filter_radius",
                    "applies to the tent and gaussian filters (the box's is 0.5)".into(),
                );
            } else if !(radius > 0.0 && radius <= MAX_FILTER_RADIUS) {
                self.push(
                    0,
                    "render.filter_radius",
                    format!("must be in (0, {MAX_FILTER_RADIUS}] pixels, got {radius}"),
                );
            }
        }
        if let Some(steps) = r.filter_steps {
            if !(1..=MAX_FILTER_STEPS).contains(&steps) {
                self.push(
                    0,
                    "render.filter_steps",
                    format!("must be in [1, {MAX_FILTER_STEPS}], got {steps}"),
                );
            }
        }
        if let Some(stddev) = r.filter_stddev {
            if kind != FilterKind::Gaussian {
                self.push(
                    0,
                    "render.filter_stddev",
                    "applies to the gaussian filter only".into(),
                );
            } else if !(stddev > 0.0 && stddev <= MAX_FILTER_RADIUS / 4.0) {
                self.push(
                    0,
                    "render.filter_stddev",
                    format!(
                        "must be in (0, {}] pixels, got {stddev}",
                        MAX_FILTER_RADIUS / 4.0
                    ),
                );
            }
        }
    }

    /// `[camera]`: finite, a view direction, an up vector off it, a field of view and lens.
    fn camera(&mut self, c: &CameraDesc) {
        self.finite3("camera.look_from", c.look_from, 0);
        self.finite3("camera.look_at", c.look_at, 0);
        self.finite3("camera.up", c.up, 0);
        let forward = Vec3::from(c.look_at) - Vec3::from(c.look_from);
        if forward.length_squared() == 0.0 {
            self.push(0, "camera.look_at", "must differ from look_from".into());
        } else if forward.cross(Vec3::from(c.up)).length_squared()
            <= 1e-12 * forward.length_squared()
        {
            self.push(
                0,
                "camera.up",
                "must not be parallel to the view direction".into(),
            );
        }
        if !(c.vfov > 0.0 && c.vfov < 180.0) {
            self.push(
                0,
                "camera.vfov",
                format!("must be in (0, 180) degrees, got {}", c.vfov),
            );
        }
        if !(c.aperture >= 0.0 && c.aperture.is_finite()) {
            self.push(
                0,
                "camera.aperture",
                format!("must be >= 0, got {}", c.aperture),
            );
        }
        if let Some(fd) = c.focus_distance {
            if !(fd > 0.0 && fd.is_finite()) {
                self.push(0, "camera.focus_distance", format!("must be > 0, got {fd}"));
            }
        }
        if !(c.near_clip >= 0.0 && c.near_clip.is_finite()) {
            self.push(
                0,
                "camera.near_clip",
                format!("must be >= 0, got {}", c.near_clip),
            );
        }
        match (c.projection, c.height) {
            (Projection::Orthographic, None) => self.push(
                0,
                "camera.height",
                "an orthographic camera needs the view's height".into(),
            ),
            (Projection::Orthographic, Some(h)) => self.positive("camera.height", h, 0),
            (Projection::Perspective, Some(_)) => self.push(
                0,
                "camera.height",
                "applies to an orthographic camera only (projection = \"orthographic\")".into(),
            ),
            (Projection::Perspective, None) => {}
        }
    }

    /// `[background]`: one kind of background, its colours, texture, rotation and strength.
    fn background(&mut self, file: &SceneFile) {
        let bg = &file.background;
        for (key, c) in [
            ("background.color", bg.color),
            ("background.top", bg.top),
            ("background.bottom", bg.bottom),
        ] {
            if let Some(c) = c {
                self.nonnegative3(key, c, 0);
            }
        }
        let kinds = [
            bg.color.is_some(),
            bg.top.is_some() || bg.bottom.is_some(),
            bg.texture.is_some(),
        ];
        if kinds.iter().filter(|&&k| k).count() > 1 {
            self.push(
                0,
                "background",
                "give one of color, top and bottom, or texture".into(),
            );
        }
        if let Some(name) = &bg.texture {
            match file.textures.get(name).map(|t| t.get_ref()) {
                Some(TextureDesc::Image { factor, .. }) => {
                    // a factor belongs in strength; a transform moves the look-up, while
                    // the sampling distribution stays on the texels as they are (unbiased,
                    // and as efficient while the move is small: the Mitsuba importer's
                    // sub-texel shift to its envmap's texel grid)
                    if *factor != [1.0; 3] {
                        self.push(
                            0,
                            "background.texture",
                            format!(
                                "\"{name}\" has a factor; a background image takes none \
                                 (use strength)"
                            ),
                        );
                    }
                }
                Some(_) => self.push(
                    0,
                    "background.texture",
                    format!("\"{name}\" is not an image texture; an environment needs an image"),
                ),
                None => {
                    let known: Vec<&str> = file.textures.keys().map(String::as_str).collect();
                    self.push(
                        0,
                        "background.texture",
                        format!(
                            "no texture named \"{name}\" (textures: {})",
                            known.join(", ")
                        ),
                    );
                }
            }
        } else if bg.rotation.is_some() || bg.strength.is_some() {
            self.push(
                0,
                "background",
                "rotation and strength apply to a texture background only".into(),
            );
        }
        if let Some(r) = bg.rotation {
            if !r.is_finite() {
                self.push(0, "background.rotation", format!("must be finite, got {r}"));
            }
        }
        if let Some(k) = bg.strength {
            if !(k >= 0.0 && k.is_finite()) {
                self.push(0, "background.strength", format!("must be >= 0, got {k}"));
            }
        }
        if bg.top.is_some() != bg.bottom.is_some() {
            self.push(
                0,
                "background",
                "a gradient needs both top and bottom".into(),
            );
        }
    }

    /// One `[textures.NAME]`.
    fn texture(&mut self, name: &str, t: &Spanned<TextureDesc>) {
        let at = t.span().start;
        let key = format!("textures.{name}");
        match t.get_ref() {
            TextureDesc::Constant { color } => {
                self.nonnegative3(&format!("{key}.color"), *color, at)
            }
            TextureDesc::Checker {
                even,
                odd,
                scale,
                mapping,
                transform,
            } => {
                for (cell, c) in [("even", even), ("odd", odd)] {
                    let ckey = format!("{key}.{cell}");
                    self.color(&ckey, c, false, at);
                    if let Some(child) = c.texture() {
                        if self
                            .textures
                            .iter()
                            .any(|(n, checker)| n == child && *checker)
                        {
                            self.push(at, &ckey, format!("\"{child}\" is a checker; a checker's cells must be colours or other textures"));
                        }
                        if self.attributes.iter().any(|n| n == child) {
                            self.push(at, &ckey, format!("\"{child}\" is a mesh attribute; a checker's cells are looked up without a mesh"));
                        }
                    }
                }
                self.positive(&format!("{key}.scale"), *scale, at);
                if let Some(t) = transform {
                    if *mapping == CheckerMapping::Solid {
                        self.push(
                            at,
                            &format!("{key}.transform"),
                            "maps uv: a solid checker has none".into(),
                        );
                    }
                    self.uv_transform(&format!("{key}.transform"), t, at);
                }
            }
            TextureDesc::Image {
                path,
                factor,
                transform,
                uv_set,
                ..
            } => {
                if path.is_empty() {
                    self.push(at, &format!("{key}.path"), "must name an image file".into());
                }
                if *uv_set > 1 {
                    self.push(
                        at,
                        &format!("{key}.uv_set"),
                        format!("must be 0 or 1, got {uv_set}"),
                    );
                }
                self.nonnegative3(&format!("{key}.factor"), *factor, at);
                if let Some(t) = transform {
                    self.uv_transform(&format!("{key}.transform"), t, at);
                }
            }
            TextureDesc::MeshAttribute { name } => {
                if !is_mesh_attribute(name) {
                    self.push(
                        at,
                        &format!("{key}.name"),
                        format!(
                            "unknown mesh attribute \"{name}\" (known: {}, or a PLY \
                             file's vertex_NAME or face_NAME)",
                            MESH_ATTRIBUTES.join(", ")
                        ),
                    );
                }
            }
            TextureDesc::Noise { scale, color, .. } => {
                self.positive(&format!("{key}.scale"), *scale, at);
                self.nonnegative3(&format!("{key}.color"), *color, at);
            }
        }
    }

    /// One `[materials.NAME]`: its module's checks, under the scene file's keys.
    fn material(&mut self, name: &str, m: &Spanned<MaterialDesc>) {
        let names: Vec<String> = self.textures.iter().map(|(n, _)| n.clone()).collect();
        let key = |field: &str| format!("materials.{name}.{field}");
        for (key, message) in m.get_ref().check(&key, &names) {
            self.push(m.span().start, &key, message);
        }
    }

    /// A blend's parts: materials of the file, neither emitting nor masked (a blend
    /// chooses between them after the hit is found), nested at most `MAX_BLEND_DEPTH`
    /// levels and never in a cycle.
    fn blend(&mut self, name: &str, b: &blend::Desc, at: usize, file: &SceneFile) {
        for (field, part) in [("first", &b.first), ("second", &b.second)] {
            let key = format!("materials.{name}.{field}");
            let Some(m) = file.materials.get(part) else {
                let known: Vec<&str> = file.materials.keys().map(String::as_str).collect();
                self.push(
                    at,
                    &key,
                    format!(
                        "unknown material \"{part}\" (defined: {})",
                        known.join(", ")
                    ),
                );
                continue;
            };
            if m.get_ref().emits() {
                self.push(
                    at,
                    &key,
                    format!("\"{part}\" emits: a blend's parts cannot be lights"),
                );
            }
            if m.get_ref().model().opacity().is_some() {
                self.push(
                    at,
                    &key,
                    format!("\"{part}\" has an opacity mask: a blend's parts cannot be masked"),
                );
            }
            if matches!(m.get_ref(), MaterialDesc::Dielectric(d) if d.absorption != [0.0; 3]) {
                self.push(
                    at,
                    &key,
                    format!(
                        "\"{part}\" absorbs: a glass's absorption is a medium inside its shape, \
                         which a blend's part cannot hold (give the shape an `interior`)"
                    ),
                );
            }
        }
        // the depth of nesting below this blend, following parts that are blends
        fn depth(file: &SceneFile, name: &str, seen: &mut Vec<String>) -> Option<u32> {
            if seen.iter().any(|s| s == name) {
                return None;
            }
            let Some(MaterialDesc::Blend(b)) = file.materials.get(name).map(|m| m.get_ref()) else {
                return Some(0);
            };
            seen.push(name.to_string());
            let d = depth(file, &b.first, seen)?.max(depth(file, &b.second, seen)?);
            seen.pop();
            Some(d + 1)
        }
        match depth(file, name, &mut Vec::new()) {
            None => self.push(
                at,
                &format!("materials.{name}"),
                "a blend that contains itself (a cycle of parts)".into(),
            ),
            Some(d) if d > MAX_BLEND_DEPTH => self.push(
                at,
                &format!("materials.{name}"),
                format!("blends nest {d} deep; at most {MAX_BLEND_DEPTH}"),
            ),
            _ => {}
        }
    }

    /// One `[[objects]]` entry: its material, transform and shape.
    fn object(&mut self, i: usize, obj: &Spanned<ObjectDesc>, file: &SceneFile) {
        let at = obj.span().start;
        let key = file.object_key(i);
        let o = obj.get_ref();
        if let Some(material) = o.material().filter(|m| !file.materials.contains_key(*m)) {
            let known = names(file.materials.keys().map(String::as_str));
            self.push(
                at,
                &format!("{key}.material"),
                format!("unknown material \"{material}\" (defined: {known})"),
            );
        }
        if let Some(t) = o.transform() {
            self.transform(&format!("{key}.transform"), &t, at);
        }
        let (interior, exterior) = o.media();
        let absorbing = o
            .material()
            .and_then(|m| file.materials.get(m))
            .is_some_and(
                |m| matches!(m.get_ref(), MaterialDesc::Dielectric(d) if d.absorption != [0.0; 3]),
            );
        if interior.is_some() && absorbing {
            self.push(
                at,
                &format!("{key}.interior"),
                "its glass has an `absorption`, which is a medium inside it: give one or \
                 the other (the absorption as the medium's sigma_a)"
                    .into(),
            );
        }
        for (field, name) in [("interior", interior), ("exterior", exterior)] {
            if let Some(name) = name {
                self.medium_name(&format!("{key}.{field}"), name, at, file);
                // a mesh without `material` takes its OBJ file's own materials, which
                // hold no media
                if matches!(o, ObjectDesc::Mesh { material: None, .. }) {
                    self.push(
                        at,
                        &format!("{key}.{field}"),
                        "a mesh with media needs its `material` (an OBJ file's own \
                         materials take none)"
                            .into(),
                    );
                }
            }
        }
        self.shape(&key, o, at);
    }

    /// A medium named at `key`: one of `[media]`.
    fn medium_name(&mut self, key: &str, name: &str, at: usize, file: &SceneFile) {
        if !file.media.contains_key(name) {
            let known = names(file.media.keys().map(String::as_str));
            self.push(
                at,
                key,
                format!("unknown medium \"{name}\" (defined: {known})"),
            );
        }
    }

    /// One `[media.NAME]`: coefficients >= 0, an albedo in [0, 1], either sigma_t and
    /// albedo or sigma_a and sigma_s, a scale >= 0 and |g| < 1; a grid's transform, its
    /// file for `use_grid_bbox`, an albedo grid instead of the albedo.
    fn medium(&mut self, name: &str, m: &Spanned<MediumDesc>) {
        let at = m.span().start;
        let key = |field: &str| format!("media.{name}.{field}");
        let MediumCoefficients {
            sigma_t,
            albedo,
            sigma_a,
            sigma_s,
            scale,
            g,
        } = m.get_ref().written();
        if let MediumDesc::Heterogeneous {
            grid,
            transform,
            albedo_grid,
            use_grid_bbox,
            ..
        } = m.get_ref()
        {
            if grid.is_none() && *use_grid_bbox {
                self.push(
                    at,
                    &key("use_grid_bbox"),
                    "needs a `grid`, whose file gives the box".into(),
                );
            }
            if let Some(t) = transform {
                self.transform(&key("transform"), t, at);
            }
            if albedo_grid.is_some() && (albedo.is_some() || sigma_a.is_some() || sigma_s.is_some())
            {
                self.push(
                    at,
                    &key("albedo_grid"),
                    "gives the albedo: not with `albedo`, `sigma_a` or `sigma_s`".into(),
                );
            }
        }
        for (field, value) in [
            ("sigma_t", sigma_t),
            ("sigma_a", sigma_a),
            ("sigma_s", sigma_s),
        ] {
            if let Some(v) = value {
                self.nonnegative3(&key(field), v.rgb(), at);
            }
        }
        if let Some(a) = albedo {
            let a = a.rgb();
            if self.finite3(&key("albedo"), a, at) && a.iter().any(|x| !(0.0..=1.0).contains(x)) {
                self.push(at, &key("albedo"), format!("must be in [0, 1], got {a:?}"));
            }
        }
        let split = sigma_a.is_some() || sigma_s.is_some();
        for (field, given) in [("sigma_t", sigma_t.is_some()), ("albedo", albedo.is_some())] {
            if split && given {
                self.push(
                    at,
                    &key(field),
                    "give sigma_t and albedo, or sigma_a and sigma_s, not both".into(),
                );
            }
        }
        if !(scale >= 0.0 && scale.is_finite()) {
            self.push(at, &key("scale"), format!("must be >= 0, got {scale}"));
        } else if !m.get_ref().coefficients().0.iter().all(|x| x.is_finite()) {
            self.push(
                at,
                &key("scale"),
                format!("times the coefficients gives an infinite extinction ({scale})"),
            );
        }
        if g.is_nan() || g.abs() >= 1.0 {
            self.push(at, &key("g"), format!("must be in (-1, 1), got {g}"));
        }
    }

    /// One `[[lights]]` entry: finite placement, a non-zero axis, non-negative power,
    /// spot angles in order.
    fn light(&mut self, i: usize, light: &Spanned<LightDesc>) {
        let at = light.span().start;
        let key = format!("lights[{i}]");
        match light.get_ref() {
            LightDesc::Point {
                position,
                intensity,
            } => {
                self.finite3(&format!("{key}.position"), *position, at);
                self.nonnegative3(&format!("{key}.intensity"), *intensity, at);
            }
            LightDesc::Spot {
                position,
                direction,
                look_at,
                intensity,
                inner_angle,
                outer_angle,
                texture,
                up,
                ..
            } => {
                let placed = self.finite3(&format!("{key}.position"), *position, at);
                self.nonnegative3(&format!("{key}.intensity"), *intensity, at);
                let axis = match (direction, look_at) {
                    (Some(d), None) => {
                        self.light_axis(&format!("{key}.direction"), *d, at);
                        Vec3::from(*d).try_normalize()
                    }
                    (None, Some(t)) => {
                        let axis = (Vec3::from(*t) - Vec3::from(*position)).try_normalize();
                        if self.finite3(&format!("{key}.look_at"), *t, at)
                            && placed
                            && axis.is_none()
                        {
                            self.push(
                                at,
                                &format!("{key}.look_at"),
                                "must differ from position".into(),
                            );
                        }
                        axis
                    }
                    _ => {
                        self.push(
                            at,
                            &key,
                            "needs exactly one of direction and look_at".into(),
                        );
                        None
                    }
                };
                if let Some(t) = texture {
                    self.color(
                        &format!("{key}.texture"),
                        &ColorDesc::Texture(t.clone()),
                        false,
                        at,
                    );
                    if self.attributes.iter().any(|n| n == t) {
                        self.push(
                            at,
                            &format!("{key}.texture"),
                            format!("\"{t}\" is a mesh attribute; a spot's image has no mesh"),
                        );
                    }
                    if self.finite3(&format!("{key}.up"), *up, at)
                        && axis.is_some_and(|a| a.cross(Vec3::from(*up)).try_normalize().is_none())
                    {
                        self.push(
                            at,
                            &format!("{key}.up"),
                            "must not be parallel to the spot's axis".into(),
                        );
                    }
                    if *outer_angle >= 90.0 {
                        self.push(
                            at,
                            &format!("{key}.outer_angle"),
                            format!("must be under 90 degrees with a texture, got {outer_angle}"),
                        );
                    }
                }
                if !(*outer_angle > 0.0 && *outer_angle <= 90.0) {
                    self.push(
                        at,
                        &format!("{key}.outer_angle"),
                        format!("must be in (0, 90] degrees, got {outer_angle}"),
                    );
                } else if !(*inner_angle >= 0.0 && inner_angle <= outer_angle) {
                    self.push(
                        at,
                        &format!("{key}.inner_angle"),
                        format!("must be in [0, outer_angle = {outer_angle}] degrees, got {inner_angle}"),
                    );
                }
            }
            LightDesc::Directional {
                direction,
                irradiance,
            } => {
                self.light_axis(&format!("{key}.direction"), *direction, at);
                self.nonnegative3(&format!("{key}.irradiance"), *irradiance, at);
            }
            LightDesc::Projector {
                position,
                look_at,
                up,
                fov,
                irradiance,
                scale,
            } => {
                let placed = self.finite3(&format!("{key}.position"), *position, at)
                    & self.finite3(&format!("{key}.look_at"), *look_at, at)
                    & self.finite3(&format!("{key}.up"), *up, at);
                let axis = Vec3::from(*look_at) - Vec3::from(*position);
                if placed {
                    match axis.try_normalize() {
                        None => self.push(
                            at,
                            &format!("{key}.look_at"),
                            "must differ from position".into(),
                        ),
                        Some(a) if a.cross(Vec3::from(*up)).try_normalize().is_none() => self.push(
                            at,
                            &format!("{key}.up"),
                            "must not be parallel to the projector's axis".into(),
                        ),
                        Some(_) => {}
                    }
                }
                if !(*fov > 0.0 && *fov < 180.0) {
                    self.push(
                        at,
                        &format!("{key}.fov"),
                        format!("must be in (0, 180) degrees, got {fov}"),
                    );
                }
                self.color(&format!("{key}.irradiance"), irradiance, false, at);
                if let Some(t) = irradiance
                    .texture()
                    .filter(|t| self.attributes.iter().any(|n| n == t))
                {
                    self.push(
                        at,
                        &format!("{key}.irradiance"),
                        format!("\"{t}\" is a mesh attribute; a projector's image has no mesh"),
                    );
                }
                if !(*scale >= 0.0 && scale.is_finite()) {
                    self.push(
                        at,
                        &format!("{key}.scale"),
                        format!("must be >= 0, got {scale}"),
                    );
                }
            }
        }
    }

    /// A light's axis: a direction that normalizes in f32 (neither zero nor so large or
    /// small that its length overflows or underflows).
    fn light_axis(&mut self, key: &str, d: [f32; 3], at: usize) {
        if self.finite3(key, d, at) && Vec3::from(d).try_normalize().is_none() {
            self.push(at, key, "must be non-zero (and normalizable in f32)".into());
        }
    }

    /// An object's shape: finite, non-degenerate, in range.
    fn shape(&mut self, key: &str, o: &ObjectDesc, at: usize) {
        match o {
            ObjectDesc::Sphere { center, radius, .. } => {
                self.finite3(&format!("{key}.center"), *center, at);
                self.positive(&format!("{key}.radius"), *radius, at);
            }
            ObjectDesc::Triangle { vertices, uvs, .. } => {
                self.polygon(key, vertices, at);
                if let Some(uvs) = uvs {
                    if !uvs.iter().flatten().all(|x| x.is_finite()) {
                        self.push(at, &format!("{key}.uvs"), "must be finite".into());
                    }
                }
            }
            ObjectDesc::Polygon { vertices, .. } => {
                self.polygon(key, vertices, at);
            }
            ObjectDesc::Tetrahedron { vertices, .. } => {
                self.tetrahedron(key, vertices, at);
            }
            ObjectDesc::Plane {
                point,
                normal,
                uv_scale,
                ..
            } => {
                self.finite3(&format!("{key}.point"), *point, at);
                self.direction(&format!("{key}.normal"), *normal, at);
                if !(uv_scale.is_finite() && *uv_scale != 0.0) {
                    self.push(
                        at,
                        &format!("{key}.uv_scale"),
                        format!("must be finite and non-zero, got {uv_scale}"),
                    );
                }
            }
            ObjectDesc::Box { min, max, .. } => {
                let ok = self.finite3(&format!("{key}.min"), *min, at)
                    & self.finite3(&format!("{key}.max"), *max, at);
                if ok && (0..3).any(|i| min[i] >= max[i]) {
                    self.push(
                        at,
                        &format!("{key}.max"),
                        format!("must exceed min on every axis, got min {min:?}, max {max:?}"),
                    );
                }
            }
            ObjectDesc::Cylinder {
                base, top, radius, ..
            } => {
                let ok = self.finite3(&format!("{key}.base"), *base, at)
                    & self.finite3(&format!("{key}.top"), *top, at);
                if ok && base == top {
                    self.push(at, &format!("{key}.top"), "must differ from base".into());
                }
                self.positive(&format!("{key}.radius"), *radius, at);
            }
            ObjectDesc::Disk {
                center,
                normal,
                radius,
                ..
            } => {
                self.finite3(&format!("{key}.center"), *center, at);
                self.direction(&format!("{key}.normal"), *normal, at);
                self.positive(&format!("{key}.radius"), *radius, at);
            }
            ObjectDesc::Mesh { path, .. } => {
                if path.is_empty() {
                    self.push(at, &format!("{key}.path"), "must name an OBJ file".into());
                }
            }
            ObjectDesc::Gltf { path, .. } => {
                if path.is_empty() {
                    self.push(at, &format!("{key}.path"), "must name a glTF file".into());
                }
            }
            // its group is checked with the groups (`groups`)
            ObjectDesc::Instance { .. } => {}
        }
    }

    /// `[groups.NAME]` and the instances of them: an instance names a group; a group holds
    /// at least one object, each bounded, drawn by a material that does not emit (lights
    /// are sampled on their own surfaces, which an instance does not place), and no
    /// instance or glTF file (groups do not nest; a glTF file brings lights and cameras).
    fn groups(&mut self, file: &SceneFile) {
        for (name, g) in &file.groups {
            if g.get_ref().objects.is_empty() {
                self.push(
                    g.span().start,
                    &format!("groups.{name}.objects"),
                    "a group needs at least one object".into(),
                );
            }
        }
        for (i, obj) in file.objects.iter().enumerate() {
            let at = obj.span().start;
            let key = file.object_key(i);
            let in_group = file.group_of(i).is_some();
            let why = match obj.get_ref() {
                ObjectDesc::Instance { group, .. } if !file.groups.contains_key(group) => {
                    let known = names(file.groups.keys().map(String::as_str));
                    self.push(
                        at,
                        &format!("{key}.group"),
                        format!("unknown group \"{group}\" (defined: {known})"),
                    );
                    continue;
                }
                _ if !in_group => continue,
                ObjectDesc::Instance { .. } => "an instance in a group: groups do not nest",
                ObjectDesc::Plane { .. } => "a plane has no bounds, so no group can hold it",
                ObjectDesc::Gltf { .. } => {
                    "a glTF file in a group (its lights and cameras are placed once): make it \
                     an object"
                }
                o => match o.material().and_then(|m| file.materials.get(m)) {
                    Some(m) if m.get_ref().emits() => {
                        "an emitting material in a group (a light is sampled on its own \
                         surface, which an instance does not place): make it an object"
                    }
                    _ => continue,
                },
            };
            self.push(at, &key, why.into());
        }
    }

    fn push(&mut self, offset: usize, key: &str, message: String) {
        if self.overridden.iter().any(|k| k == key) {
            let flag = key.trim_start_matches("render.").replace('_', "-");
            let key = format!("{key} (from --{flag})");
            self.problems.push(Problem::at(self.src, 0, key, message));
            return;
        }
        let offset = if offset == 0 {
            self.locate(key)
        } else {
            offset
        };
        self.problems
            .push(Problem::at(self.src, offset, key, message));
    }

    /// Where `table.field` is in the text: the field's key, else the table's header, else
    /// nowhere (0). Records with spans of their own (objects, materials, textures) are
    /// placed by those instead.
    fn locate(&self, key: &str) -> usize {
        let Some((table, field)) = key.split_once('.') else {
            return 0;
        };
        let Some(doc) = &self.doc else {
            return 0;
        };
        let Some((name, value)) = doc.iter().find(|(k, _)| k.get_ref().as_ref() == table) else {
            return 0;
        };
        let field_key = match value.get_ref() {
            toml::de::DeValue::Table(t) => t
                .iter()
                .find(|(k, _)| k.get_ref().as_ref() == field)
                .map(|(k, _)| k.span().start),
            _ => None,
        };
        field_key.unwrap_or(name.span().start)
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

    /// A colour parameter: a colour (each component >= 0, and <= 1 for a reflectance), or
    /// the name of a texture that exists (reflectance textures are clamped to 1 at look-up).
    fn color(&mut self, key: &str, c: &ColorDesc, reflectance: bool, at: usize) {
        match c {
            ColorDesc::Rgb(rgb) if reflectance => self.reflectance(key, *rgb, at),
            ColorDesc::Rgb(rgb) => self.nonnegative3(key, *rgb, at),
            ColorDesc::Texture(name) => {
                if !self.textures.iter().any(|(n, _)| n == name) {
                    let known = names(self.textures.iter().map(|(n, _)| n.as_str()));
                    self.push(
                        at,
                        key,
                        format!("unknown texture \"{name}\" (defined: {known})"),
                    );
                }
            }
        }
    }

    /// A colour that scatters: each component in [0, 1].
    fn reflectance(&mut self, key: &str, c: [f32; 3], at: usize) {
        self.nonnegative3(key, c, at);
        if c.iter().any(|&a| a > 1.0) {
            self.push(at, key, "components must be <= 1".into());
        }
    }

    fn positive(&mut self, key: &str, x: f32, at: usize) {
        if !(x > 0.0 && x.is_finite()) {
            self.push(at, key, format!("must be > 0, got {x}"));
        }
    }

    /// A finite, non-zero vector (normalized when flattened).
    fn direction(&mut self, key: &str, d: [f32; 3], at: usize) {
        if self.finite3(key, d, at) && Vec3::from(d).length_squared() == 0.0 {
            self.push(at, key, "must be non-zero".into());
        }
    }

    /// A texture's uv `transform`: finite, and a matrix or the parts, not both.
    fn uv_transform(&mut self, key: &str, t: &UvTransformDesc, at: usize) {
        let [a, b] = t.scale;
        let matrix = t.matrix.unwrap_or_default();
        if ![a, b, t.rotation, t.offset[0], t.offset[1]]
            .iter()
            .chain(matrix.iter().flatten())
            .all(|x| x.is_finite())
        {
            self.push(at, key, "must be finite".into());
        }
        if t.matrix.is_some() && t.has_parts() {
            self.push(
                at,
                &format!("{key}.matrix"),
                "replaces offset, rotation and scale: give one or the others".into(),
            );
        }
    }

    fn transform(&mut self, key: &str, t: &TransformDesc, at: usize) {
        if let Some(m) = t.matrix {
            if t.scale.is_some() || t.rotate != [0.0; 3] || t.translate != [0.0; 3] {
                self.push(
                    at,
                    &format!("{key}.matrix"),
                    "give `matrix` or `scale`, `rotate` and `translate`, not both".into(),
                );
            }
            let linear = glam::Mat3::from_cols_array_2d(&[
                [m[0][0], m[1][0], m[2][0]],
                [m[0][1], m[1][1], m[2][1]],
                [m[0][2], m[1][2], m[2][2]],
            ]);
            if !m.iter().flatten().all(|x| x.is_finite()) {
                self.push(at, &format!("{key}.matrix"), "must be finite".into());
            } else if m[3] != [0.0, 0.0, 0.0, 1.0] {
                self.push(
                    at,
                    &format!("{key}.matrix"),
                    format!("must be affine: its last row [0, 0, 0, 1], got {:?}", m[3]),
                );
            } else if linear.determinant() == 0.0 {
                self.push(at, &format!("{key}.matrix"), "is singular".into());
            }
        }
        if let Some(scale) = t.scale {
            let s = scale.axes();
            if !s.iter().all(|x| x.is_finite() && *x != 0.0) {
                self.push(
                    at,
                    &format!("{key}.scale"),
                    format!("must be finite and non-zero, got {s:?}"),
                );
            }
        }
        self.finite3(&format!("{key}.rotate"), t.rotate, at);
        self.finite3(&format!("{key}.translate"), t.translate, at);
    }

    /// Four finite vertices spanning a volume.
    fn tetrahedron(&mut self, key: &str, vertices: &[[f32; 3]; 4], at: usize) {
        let vkey = format!("{key}.vertices");
        if !vertices.iter().flatten().all(|x| x.is_finite()) {
            self.push(at, &vkey, "must be finite".into());
            return;
        }
        let p: Vec<Vec3> = vertices.iter().map(|&v| Vec3::from(v)).collect();
        let (a, b, c) = (p[1] - p[0], p[2] - p[0], p[3] - p[0]);
        let scale = a.length().max(b.length()).max(c.length());
        if a.cross(b).dot(c).abs() <= 1e-6 * scale * scale * scale {
            self.push(at, &vkey, "are coplanar (zero volume)".into());
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
        if (0..k).any(|i| pts[i] == pts[(i + 1) % k]) {
            self.push(at, &vkey, "repeat a vertex (an edge of zero length)".into());
            return;
        }
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

/// Defined names for a message: `a, b`, or `none`.
fn names<'a>(list: impl Iterator<Item = &'a str>) -> String {
    let list: Vec<&str> = list.collect();
    if list.is_empty() {
        "none".to_string()
    } else {
        list.join(", ")
    }
}
