//! The TOML scene format: a serde model of what a user writes. Unknown keys are rejected.

use std::collections::BTreeMap;
use std::ops::Range;

use serde::Deserialize;
use toml::Spanned;

use super::materials::common::{white_color, ColorDesc};
use super::materials::MaterialDesc;
use super::records;

/// A whole scene file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    #[serde(default)]
    pub render: RenderDesc,
    pub camera: CameraDesc,
    #[serde(default)]
    pub background: BackgroundDesc,
    #[serde(default)]
    pub textures: BTreeMap<String, Spanned<TextureDesc>>,
    #[serde(default)]
    pub materials: BTreeMap<String, Spanned<MaterialDesc>>,
    #[serde(default)]
    pub objects: Vec<Spanned<ObjectDesc>>,
    #[serde(default)]
    pub lights: Vec<Spanned<LightDesc>>,
    /// `[groups.NAME]`: objects stored once and drawn only where `instance` objects place
    /// them (each instance walks the group's own BVH, in the group's space).
    #[serde(default)]
    pub groups: BTreeMap<String, Spanned<GroupDesc>>,
    /// `[media.NAME]`: participating media, which objects hold inside (`interior`) or
    /// outside (`exterior`) and the camera may sit in (`[camera] medium`).
    #[serde(default)]
    pub media: BTreeMap<String, Spanned<MediumDesc>>,
    /// Set by [`SceneFile::gather_groups`]: the groups' objects follow the scene's own in
    /// `objects`, each group's at its range, so that every object is validated, read and
    /// flattened by the same code.
    #[serde(skip)]
    pub members: Vec<(String, Range<usize>)>,
}

/// `[groups.NAME]`: the objects of a group (bounded shapes and meshes, none emitting).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GroupDesc {
    pub objects: Vec<Spanned<ObjectDesc>>,
}

impl SceneFile {
    /// Appends every group's objects to `objects` and records where (`members`); done
    /// once, after parsing.
    pub fn gather_groups(&mut self) {
        if !self.members.is_empty() {
            return;
        }
        for (name, g) in &self.groups {
            let start = self.objects.len();
            self.objects.extend(g.get_ref().objects.iter().cloned());
            self.members.push((name.clone(), start..self.objects.len()));
        }
    }

    /// The group object i belongs to (after `gather_groups`), by its index in `members`.
    pub fn group_of(&self, i: usize) -> Option<usize> {
        self.members.iter().position(|(_, r)| r.contains(&i))
    }

    /// The key of object i in the file: `objects[i]`, or `groups.NAME.objects[j]` for a
    /// group's.
    pub fn object_key(&self, i: usize) -> String {
        match self.group_of(i) {
            Some(g) => {
                let (name, r) = &self.members[g];
                format!("groups.{name}.objects[{}]", i - r.start)
            }
            None => format!("objects[{i}]"),
        }
    }
}

/// `[render]`: image size, sample count, path length, seed.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RenderDesc {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel: one progressive pass each.
    pub spp: u32,
    /// Rays per path: 1 shows emitters and background, 2 adds direct lighting, ...
    pub max_depth: u32,
    pub seed: u32,
    /// Where the first bounce's 2D points come from (pixel position, lens, BSDF).
    pub sampler: SamplerKind,
    /// How paths find lights.
    pub light_sampling: LightSampling,
    /// The pixel filter (`box`, `tent`, `gaussian`), by filter importance sampling.
    pub filter: FilterKind,
    /// The tent's or Gaussian's radius in pixels (defaults: tent 1, Gaussian 4 standard
    /// deviations, as Mitsuba 3's; pbrt-v4's are 2 and 1.5).
    pub filter_radius: Option<f32>,
    /// The Gaussian's standard deviation in pixels (default 0.5, Mitsuba's and pbrt's).
    pub filter_stddev: Option<f32>,
    /// The tent or Gaussian as a step function of this many steps over [0, radius], each
    /// step the filter's value at its inner end (Mitsuba 3's scalar variants weigh their
    /// samples by such a table of 31 steps); none: the filter itself.
    pub filter_steps: Option<u32>,
    /// How the filter weighs samples: each pixel's own samples drawn from it
    /// (`importance`), or every sample weighed into the pixels its filter reaches
    /// (`splat`, Mitsuba 3's film).
    pub reconstruction: Reconstruction,
    /// Compensate every microfacet lobe for the energy it loses to multiple scattering
    /// (Kulla and Conty), but where a material's own `energy_compensation` says otherwise.
    pub energy_compensation: bool,
    /// How shading normals (interpolated, normal-mapped, bumped) are taken where they
    /// differ from the geometric one: bent and folded so nothing is lost (`bend`), or
    /// strictly, as Mitsuba 3 and pbrt-v4 take them (`strict`).
    pub shading_normals: ShadingNormals,
    /// Whether a wide filter's samples may land outside the image (true: every pixel
    /// weighs the filter's whole support, the border's included), or are kept on it
    /// (false: a border pixel weighs only the part of its filter over the image, as
    /// Mitsuba's film without `sample_border`).
    pub sample_border: bool,
    /// Camera rays see no emitter and no background (Mitsuba's `hide_emitters`); the
    /// lights still light what they see.
    pub hide_emitters: bool,
    /// `[x, y, width, height]`: only this rectangle of the `width` x `height` film is
    /// rendered and written, the image it makes being its size (Mitsuba's film crop
    /// window); x, y from the film's top left corner.
    pub crop: Option<[u32; 4]>,
}

/// `[render] shading_normals`: what a material does where the shading normal differs from
/// the geometric one.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ShadingNormals {
    /// A normal that would leave the viewer's mirror direction under the geometric
    /// surface is bent toward the viewer (Keller et al. 2017), and a direction the lobes
    /// send under the surface is mirrored over it: a smooth-shaded or normal-mapped
    /// surface keeps the energy its shading gives it.
    #[default]
    Bend,
    /// The lobes about the shading normal as they are (Mitsuba 3's way): a direction on
    /// different sides of the shading and the unmapped or geometric surface is black, a
    /// mapped normal the viewer is behind is mirrored about the unmapped one, a map's
    /// bumps shadow grazing light (Mitsuba's `normalmap` and `bumpmap`), and a material
    /// that only reflects is black to a viewer under the shading normal.
    Strict,
}

/// `[render] filter` (and `--filter`): how a pixel weighs the image plane around it. Each
/// sample's position in the pixel is drawn from the filter (filter importance sampling),
/// so every sample weighs 1 and a pixel stays the mean of its samples.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum FilterKind {
    /// The pixel's square (radius 0.5).
    #[default]
    Box,
    /// 1 - |x| / radius per axis (Mitsuba's `tent`, pbrt-v4's `triangle`).
    Tent,
    /// exp(-x^2 / (2 stddev^2)) less its value at the radius, per axis (Mitsuba's and
    /// pbrt-v4's `gaussian`).
    Gaussian,
}

impl FilterKind {
    /// The name in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            FilterKind::Box => "box",
            FilterKind::Tent => "tent",
            FilterKind::Gaussian => "gaussian",
        }
    }

    /// Its value in `Params::pixel_filter` (`records::FILTER_*`).
    pub fn record(self) -> u32 {
        match self {
            FilterKind::Box => records::FILTER_BOX,
            FilterKind::Tent => records::FILTER_TENT,
            FilterKind::Gaussian => records::FILTER_GAUSSIAN,
        }
    }
}

/// `[render] reconstruction`: how a pixel's value is made from the samples around it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Reconstruction {
    /// Each pixel's samples are drawn from its filter (filter importance sampling), so
    /// each weighs 1 and the pixel is their mean: no sample is shared, the noise of
    /// neighbouring pixels is independent.
    #[default]
    Importance,
    /// Each sample lies uniformly in its pixel and is weighed into every pixel its filter
    /// reaches, each pixel the weighted mean sum(w L) / sum(w) (Mitsuba 3's film): the
    /// same expected image, but a pixel beside an edge sees the other side in every
    /// sample's tail instead of in rare ones, as Mitsuba's images do.
    Splat,
}

impl Reconstruction {
    /// The name in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Reconstruction::Importance => "importance",
            Reconstruction::Splat => "splat",
        }
    }
}

/// A pixel filter with its radius and standard deviation resolved (the defaults applied).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelFilter {
    pub kind: FilterKind,
    /// Half the filter's support, in pixels (0.5 for the box).
    pub radius: f32,
    /// The Gaussian's standard deviation (0 for the others).
    pub stddev: f32,
    /// Samples kept on the image (`[render] sample_border = false`).
    pub inside: bool,
    /// Steps of the stepped filter (`[render] filter_steps`); 0: the filter itself.
    pub steps: u32,
    /// Samples splatted over the pixels the filter reaches (`[render] reconstruction =
    /// "splat"`) rather than drawn from it.
    pub splat: bool,
}

impl PixelFilter {
    /// The filter `[render]` asks for, its defaults applied.
    pub fn of(r: &RenderDesc) -> Self {
        let stddev = match r.filter {
            FilterKind::Gaussian => r.filter_stddev.unwrap_or(0.5),
            _ => 0.0,
        };
        let radius = match r.filter {
            FilterKind::Box => 0.5,
            FilterKind::Tent => r.filter_radius.unwrap_or(1.0),
            FilterKind::Gaussian => r.filter_radius.unwrap_or(4.0 * stddev),
        };
        PixelFilter {
            kind: r.filter,
            radius,
            stddev,
            inside: !r.sample_border && r.filter != FilterKind::Box,
            steps: match r.filter {
                FilterKind::Box => 0,
                _ => r.filter_steps.unwrap_or(0),
            },
            // the box's splat is the sample's own pixel: the same as drawing from it
            splat: r.reconstruction == Reconstruction::Splat && r.filter != FilterKind::Box,
        }
    }

    /// `Params::filter_shape`: radius, standard deviation, the Gaussian's value at the
    /// radius (which it subtracts), 1 when samples stay on the image; zeros for the box.
    pub fn shape(self) -> [f32; 4] {
        let inside = if self.inside { 1.0 } else { 0.0 };
        match self.kind {
            FilterKind::Box => [0.0; 4],
            FilterKind::Tent => [self.radius, 0.0, 0.0, inside],
            FilterKind::Gaussian => {
                let s = self.stddev;
                let bias = (-self.radius * self.radius / (2.0 * s * s)).exp();
                [self.radius, s, bias, inside]
            }
        }
    }
}

/// `[render] light_sampling` (and `--light-sampling`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum LightSampling {
    /// The material's own sampling only: lights are found by hitting them.
    Bsdf,
    /// With probability 1/2 a light, else the material, weighted by the mixture pdf
    /// ("Ray Tracing: The Rest of Your Life").
    Mixture,
    /// Next-event estimation plus material sampling, power heuristic (pbrt-v4).
    #[default]
    Mis,
}

/// `[render] sampler` (and `--sampler`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum SamplerKind {
    /// Independent uniform points.
    Random,
    /// One point per stratum of the pixel, strata spread over the passes.
    Jittered,
    /// (i / N, radical inverse of i), rotated per pixel.
    Hammersley,
    /// Owen-scrambled Sobol' points.
    #[default]
    Sobol,
}

impl LightSampling {
    /// The name in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            LightSampling::Bsdf => "bsdf",
            LightSampling::Mixture => "mixture",
            LightSampling::Mis => "mis",
        }
    }

    /// Its value in `Params::light_sampling` (`records::LIGHT_SAMPLING_*`).
    pub fn record(self) -> u32 {
        match self {
            LightSampling::Bsdf => records::LIGHT_SAMPLING_BSDF,
            LightSampling::Mixture => records::LIGHT_SAMPLING_MIXTURE,
            LightSampling::Mis => records::LIGHT_SAMPLING_MIS,
        }
    }
}

impl SamplerKind {
    /// The name in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            SamplerKind::Random => "random",
            SamplerKind::Jittered => "jittered",
            SamplerKind::Hammersley => "hammersley",
            SamplerKind::Sobol => "sobol",
        }
    }

    /// Its value in `Params::sampler` (`records::SAMPLER_*`).
    pub fn record(self) -> u32 {
        match self {
            SamplerKind::Random => records::SAMPLER_RANDOM,
            SamplerKind::Jittered => records::SAMPLER_JITTERED,
            SamplerKind::Hammersley => records::SAMPLER_HAMMERSLEY,
            SamplerKind::Sobol => records::SAMPLER_SOBOL,
        }
    }

    /// Whether the sampler's points depend on the render's total sample count N, so
    /// that the first k samples of an N-sample render are not those of a k-sample render:
    /// Hammersley's x = i / N, and jittered's grid of 2^k x 2^k strata with 4^k >= N. The
    /// one place that says so: a checkpoint's scene hash keeps N for these, a render
    /// limited by time or error keeps the scene's N as its cap, and a convergence study
    /// renders each sample count of its ladder apart instead of reading one render's
    /// prefixes.
    pub fn depends_on_spp(self) -> bool {
        matches!(self, SamplerKind::Hammersley | SamplerKind::Jittered)
    }
}

impl Default for RenderDesc {
    fn default() -> Self {
        Self {
            width: 256,
            height: 256,
            spp: 64,
            max_depth: 8,
            seed: 0,
            sampler: SamplerKind::default(),
            light_sampling: LightSampling::default(),
            filter: FilterKind::default(),
            filter_radius: None,
            filter_stddev: None,
            filter_steps: None,
            reconstruction: Reconstruction::default(),
            energy_compensation: false,
            shading_normals: ShadingNormals::default(),
            sample_border: true,
            hide_emitters: false,
            crop: None,
        }
    }
}

/// `[camera]`: a pinhole or thin-lens camera.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    pub look_from: [f32; 3],
    pub look_at: [f32; 3],
    #[serde(default = "default_up")]
    pub up: [f32; 3],
    /// Vertical field of view, degrees.
    #[serde(default = "default_vfov")]
    pub vfov: f32,
    /// Lens diameter; 0 is a pinhole.
    #[serde(default)]
    pub aperture: f32,
    /// Distance to the plane in focus; defaults to |look_at - look_from|.
    #[serde(default)]
    pub focus_distance: Option<f32>,
    /// `perspective` (vfov, aperture) or `orthographic` (parallel rays over a view
    /// `height` scene units tall; the width from the image's aspect).
    #[serde(default)]
    pub projection: Projection,
    /// An orthographic view's height in scene units.
    #[serde(default)]
    pub height: Option<f32>,
    /// The image mirrored left to right (a Mitsuba camera whose `to_world` has a negative
    /// determinant).
    #[serde(default)]
    pub mirror: bool,
    /// Camera rays start where they cross the plane this far in front of the camera, along
    /// its view direction: nearer surfaces are not seen (Mitsuba's `near_clip`). 0: none.
    #[serde(default)]
    pub near_clip: f32,
    /// The medium the camera sits in (a `[media.NAME]`); none: vacuum.
    #[serde(default)]
    pub medium: Option<String>,
}

/// `[camera] projection`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Projection {
    #[default]
    Perspective,
    Orthographic,
}

fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

fn default_vfov() -> f32 {
    40.0
}

/// `[background]`: radiance of rays that leave the scene: a constant `color`, a vertical
/// gradient from `bottom` (straight down) to `top` (straight up), linear in the direction's
/// y as in "Ray Tracing in One Weekend", or an equirectangular image `texture` (an image
/// in `[textures]`) turned `rotation` degrees about +y and scaled by `strength`.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BackgroundDesc {
    pub color: Option<[f32; 3]>,
    pub top: Option<[f32; 3]>,
    pub bottom: Option<[f32; 3]>,
    pub texture: Option<String>,
    pub rotation: Option<f32>,
    pub strength: Option<f32>,
}

/// `[textures]` entries, selected by `type`.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum TextureDesc {
    Constant {
        color: [f32; 3],
    },
    /// Alternating cells of `even` and `odd` (colours or non-checker textures), `scale`
    /// cells per unit of uv (`mapping = "uv"`) or of space (`mapping = "solid"`).
    Checker {
        even: ColorDesc,
        odd: ColorDesc,
        #[serde(default = "ten")]
        scale: f32,
        #[serde(default)]
        mapping: CheckerMapping,
        /// With `mapping = "uv"`: maps the surface's uv before `scale` cells per unit
        /// (the image's `transform`: offset, rotation and scale, or a matrix).
        #[serde(default)]
        transform: Option<UvTransformDesc>,
    },
    /// An image file (PNG, JPEG, HDR, EXR, PPM, PFM, BMP), `path` relative to the scene file; 8- and
    /// 16-bit images are sRGB-decoded to linear unless `color_space = "linear"` (data such
    /// as roughness); bilinear filtering, or the nearest texel. `factor` multiplies the
    /// texels; `transform` maps the surface's uv (of set `uv_set`) before the look-up;
    /// `wrap` says what lies outside [0, 1], for both axes or each.
    Image {
        path: String,
        #[serde(default)]
        wrap: Wrap,
        #[serde(default)]
        filter: Filter,
        #[serde(default)]
        uv_set: u32,
        #[serde(default = "white")]
        factor: [f32; 3],
        #[serde(default)]
        color_space: ColorSpace,
        transform: Option<UvTransformDesc>,
    },
    /// Perlin noise ("Ray Tracing: The Next Week"): `color` x 0.5 (1 + noise), turbulence,
    /// or marble, at `scale`.
    Noise {
        #[serde(default = "crate::scene::materials::common::one")]
        scale: f32,
        #[serde(default)]
        kind: NoiseKind,
        #[serde(default = "white")]
        color: [f32; 3],
    },
    /// A mesh's own colours at the hit (Mitsuba's `mesh_attribute`): `vertex_color`, its
    /// vertex colours interpolated, or `face_color`, its faces' colours (a PLY file's face
    /// `red`, `green`, `blue`), or a PLY file's named attribute, `vertex_NAME` or
    /// `face_NAME` ([`is_mesh_attribute`]); white where the surface has none. A material
    /// that reads one is not also tinted by the vertex colours.
    #[serde(rename = "mesh_attribute")]
    MeshAttribute {
        name: String,
    },
}

/// The colours every mesh file may have, as a `mesh_attribute` texture names them.
pub const MESH_ATTRIBUTES: [&str; 2] = ["vertex_color", "face_color"];

/// Whether `name` may name a mesh attribute: one of [`MESH_ATTRIBUTES`], or a PLY file's
/// named vertex or face attribute, `vertex_NAME` or `face_NAME`.
pub fn is_mesh_attribute(name: &str) -> bool {
    ["vertex_", "face_"]
        .iter()
        .any(|p| name.strip_prefix(p).is_some_and(|rest| !rest.is_empty()))
}

fn ten() -> f32 {
    10.0
}

#[derive(Debug, Clone, Copy, Default, PartialEq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CheckerMapping {
    #[default]
    Uv,
    Solid,
}

/// How an image texture's 8- and 16-bit values map to linear ones.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ColorSpace {
    /// The sRGB transfer function undone: colours.
    #[default]
    Srgb,
    /// Taken as they are (value / 255): data.
    Linear,
}

/// `transform = { offset, rotation, scale }` of an image texture's uv, as glTF's
/// KHR_texture_transform in wgtrace's uv (v up): uv' = offset + R(rotation) (scale * uv),
/// R turning counter-clockwise by `rotation` degrees; or `transform = { matrix = [[a, b,
/// c], [d, e, f]] }`, any affine map (Mitsuba's `to_uv`): uv' = (a u + b v + c, d u + e v
/// + f).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UvTransformDesc {
    #[serde(default)]
    pub offset: [f32; 2],
    #[serde(default)]
    pub rotation: f32,
    #[serde(default = "unit2")]
    pub scale: [f32; 2],
    /// The map's two rows, instead of offset, rotation and scale.
    #[serde(default)]
    pub matrix: Option<[[f32; 3]; 2]>,
}

fn unit2() -> [f32; 2] {
    [1.0; 2]
}

impl UvTransformDesc {
    /// The two rows of the affine map uv -> uv'.
    pub fn rows(&self) -> [[f32; 3]; 2] {
        if let Some(m) = self.matrix {
            return m;
        }
        let (s, c) = self.rotation.to_radians().sin_cos();
        let [sx, sy] = self.scale;
        [
            [c * sx, -s * sy, self.offset[0]],
            [s * sx, c * sy, self.offset[1]],
        ]
    }

    /// The same map for uv whose v runs down (glTF's): conjugated by v -> 1 - v.
    pub fn from_v_down(offset: [f32; 2], rotation_radians: f32, scale: [f32; 2]) -> Self {
        let (s, c) = rotation_radians.sin_cos();
        UvTransformDesc {
            offset: [offset[0] + s * scale[1], 1.0 - offset[1] - c * scale[1]],
            rotation: rotation_radians.to_degrees(),
            scale,
            matrix: None,
        }
    }

    /// Whether offset, rotation or scale differ from the identity's.
    pub fn has_parts(&self) -> bool {
        self.offset != [0.0; 2] || self.rotation != 0.0 || self.scale != [1.0; 2]
    }
}

#[derive(Debug, Clone, Copy, Default, PartialEq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum WrapMode {
    #[default]
    Repeat,
    Clamp,
    Mirror,
}

/// An image's wrap modes: one for both axes (`wrap = "clamp"`), or one per axis, u then v
/// (`wrap = ["clamp", "repeat"]`, glTF's wrapS and wrapT).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wrap(pub [WrapMode; 2]);

impl Default for Wrap {
    fn default() -> Self {
        Wrap([WrapMode::Repeat; 2])
    }
}

impl<'de> Deserialize<'de> for Wrap {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Modes;
        impl<'de> serde::de::Visitor<'de> for Modes {
            type Value = Wrap;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a wrap mode, or an array of two (u, then v)")
            }
            fn visit_str<E: serde::de::Error>(self, s: &str) -> Result<Wrap, E> {
                use serde::de::IntoDeserializer;
                let mode = WrapMode::deserialize(s.into_deserializer())?;
                Ok(Wrap([mode; 2]))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut a: A) -> Result<Wrap, A::Error> {
                use serde::de::Error;
                let u = a
                    .next_element()?
                    .ok_or_else(|| A::Error::invalid_length(0, &self))?;
                let v = a
                    .next_element()?
                    .ok_or_else(|| A::Error::invalid_length(1, &self))?;
                if a.next_element::<WrapMode>()?.is_some() {
                    return Err(A::Error::invalid_length(3, &self));
                }
                Ok(Wrap([u, v]))
            }
        }
        d.deserialize_any(Modes)
    }
}

/// How an image is read between texel centres.
#[derive(Debug, Clone, Copy, Default, PartialEq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Filter {
    /// The bilinear mix of the four nearest texels.
    #[default]
    Bilinear,
    /// The texel the point falls in (glTF's NEAREST magnification filter).
    Nearest,
}

#[derive(Debug, Clone, Copy, Default, PartialEq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum NoiseKind {
    #[default]
    Perlin,
    Turbulence,
    Marble,
}

fn white() -> [f32; 3] {
    [1.0; 3]
}

/// `transform = { scale, rotate, translate }`: scale, then rotate about X, Y, Z (degrees),
/// then translate, all about the origin; or `transform = { matrix }`.
#[derive(Debug, Clone, Copy, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransformDesc {
    #[serde(default)]
    pub scale: Option<ScaleDesc>,
    #[serde(default)]
    pub rotate: [f32; 3],
    #[serde(default)]
    pub translate: [f32; 3],
    /// Any affine map, row-major 4 x 4 with a last row of [0, 0, 0, 1] (Mitsuba's
    /// `to_world`); instead of the others.
    #[serde(default)]
    pub matrix: Option<[[f32; 4]; 4]>,
}

/// A uniform scale factor or one per axis.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(untagged)]
pub enum ScaleDesc {
    Uniform(f32),
    Axes([f32; 3]),
}

impl ScaleDesc {
    pub fn axes(self) -> [f32; 3] {
        match self {
            ScaleDesc::Uniform(s) => [s; 3],
            ScaleDesc::Axes(a) => a,
        }
    }
}

/// `[[lights]]` entries, selected by `type`: lights without a surface. No ray can hit
/// them, so paths reach them by next-event estimation under every `light_sampling`.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum LightDesc {
    /// Light from one point: `intensity` is the radiant intensity [r, g, b] in W/sr, the
    /// irradiance at distance d facing it intensity / d^2.
    Point {
        position: [f32; 3],
        intensity: [f32; 3],
    },
    /// A point light in a cone about the axis `direction` (or toward `look_at`): the full
    /// `intensity` within `inner_angle` of the axis, none beyond `outer_angle` (degrees),
    /// and between them `falloff`'s ramp; with a `texture`, times that image spread over
    /// the square the outer cone fits in, its top toward `up` (Mitsuba 3's spot).
    Spot {
        position: [f32; 3],
        direction: Option<[f32; 3]>,
        look_at: Option<[f32; 3]>,
        intensity: [f32; 3],
        #[serde(default)]
        inner_angle: f32,
        #[serde(default = "spot_outer_angle")]
        outer_angle: f32,
        #[serde(default)]
        falloff: SpotFalloff,
        #[serde(default)]
        texture: Option<String>,
        #[serde(default = "default_up")]
        up: [f32; 3],
    },
    /// Parallel light travelling along `direction`: `irradiance` [r, g, b] in W/m^2 on a
    /// surface facing it, E cos(theta) on one tilted by theta.
    Directional {
        direction: [f32; 3],
        irradiance: [f32; 3],
    },
    /// A projector (Mitsuba 3's `projector`): a point light at `position` that projects
    /// `irradiance` (a colour or a texture's name, times `scale`) through a pinhole frustum
    /// toward `look_at`, `fov` degrees wide (along the image's width; its height from an
    /// image texture's aspect, else square). A surface facing it at distance 1 along its
    /// axis receives pi x scale x irradiance; none outside the frustum.
    Projector {
        position: [f32; 3],
        look_at: [f32; 3],
        #[serde(default = "default_up")]
        up: [f32; 3],
        fov: f32,
        #[serde(default = "white_color")]
        irradiance: ColorDesc,
        #[serde(default = "one")]
        scale: f32,
    },
}

fn one() -> f32 {
    1.0
}

impl LightDesc {
    /// The light placed by `m` (positions moved, directions turned; powers kept).
    pub fn transformed(&self, m: glam::Affine3A) -> LightDesc {
        let point = |p: [f32; 3]| m.transform_point3(p.into()).into();
        let dir = |d: [f32; 3]| m.transform_vector3(d.into()).normalize_or_zero().into();
        match self.clone() {
            LightDesc::Point {
                position,
                intensity,
            } => LightDesc::Point {
                position: point(position),
                intensity,
            },
            LightDesc::Spot {
                position,
                direction,
                look_at,
                intensity,
                inner_angle,
                outer_angle,
                falloff,
                texture,
                up,
            } => LightDesc::Spot {
                position: point(position),
                direction: direction.map(dir),
                look_at: look_at.map(point),
                intensity,
                inner_angle,
                outer_angle,
                falloff,
                texture,
                up: dir(up),
            },
            LightDesc::Directional {
                direction,
                irradiance,
            } => LightDesc::Directional {
                direction: dir(direction),
                irradiance,
            },
            LightDesc::Projector {
                position,
                look_at,
                up,
                fov,
                irradiance,
                scale,
            } => LightDesc::Projector {
                position: point(position),
                look_at: point(look_at),
                up: dir(up),
                fov,
                irradiance,
                scale,
            },
        }
    }
}

/// A spot light's ramp between its inner and outer cones.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SpotFalloff {
    /// KHR_lights_punctual's: the square of a linear ramp in the cosine of the angle.
    #[default]
    Gltf,
    /// Mitsuba 3's `spot`: linear in the angle itself (`beam_width` is the inner angle,
    /// `cutoff_angle` the outer).
    Mitsuba,
}

/// glTF's default outer cone angle, pi / 4.
fn spot_outer_angle() -> f32 {
    45.0
}

/// `[[objects]]` entries, selected by `type`. Every object names a `material` and may carry
/// a `transform`.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum ObjectDesc {
    Sphere {
        center: [f32; 3],
        radius: f32,
        material: String,
        interior: Option<String>,
        exterior: Option<String>,
        transform: Option<TransformDesc>,
    },
    /// Front side: right-hand-rule normal of the vertex order. `uvs` default to (0, 0),
    /// (1, 0), (0, 1).
    Triangle {
        vertices: [[f32; 3]; 3],
        uvs: Option<[[f32; 2]; 3]>,
        material: String,
        interior: Option<String>,
        exterior: Option<String>,
        transform: Option<TransformDesc>,
    },
    /// Planar and convex; split into a triangle fan. Front side as for triangles.
    Polygon {
        vertices: Vec<[f32; 3]>,
        material: String,
        interior: Option<String>,
        exterior: Option<String>,
        transform: Option<TransformDesc>,
    },
    /// Four vertices; four triangles facing outward.
    Tetrahedron {
        vertices: [[f32; 3]; 4],
        material: String,
        interior: Option<String>,
        exterior: Option<String>,
        transform: Option<TransformDesc>,
    },
    /// Infinite plane through `point`; front side along `normal`. uv = `uv_scale` x the
    /// coordinates in a tangent frame.
    Plane {
        point: [f32; 3],
        normal: [f32; 3],
        #[serde(default = "crate::scene::materials::common::one")]
        uv_scale: f32,
        material: String,
        interior: Option<String>,
        exterior: Option<String>,
        transform: Option<TransformDesc>,
    },
    /// Axis-aligned box from `min` to `max` (before its transform).
    Box {
        min: [f32; 3],
        max: [f32; 3],
        material: String,
        interior: Option<String>,
        exterior: Option<String>,
        transform: Option<TransformDesc>,
    },
    /// Finite cylinder between the centers of its end disks.
    Cylinder {
        base: [f32; 3],
        top: [f32; 3],
        radius: f32,
        #[serde(default = "yes")]
        caps: bool,
        material: String,
        interior: Option<String>,
        exterior: Option<String>,
        transform: Option<TransformDesc>,
    },
    /// Disk; front side along `normal`.
    Disk {
        center: [f32; 3],
        normal: [f32; 3],
        radius: f32,
        material: String,
        interior: Option<String>,
        exterior: Option<String>,
        transform: Option<TransformDesc>,
    },
    /// A Wavefront OBJ, PLY or Mitsuba `.serialized` file, `path` relative to the scene
    /// file. Without `material`, an OBJ file's own .mtl materials apply.
    Mesh {
        path: String,
        material: Option<String>,
        interior: Option<String>,
        exterior: Option<String>,
        transform: Option<TransformDesc>,
        /// Flat shading: the file's vertex normals left out.
        #[serde(default)]
        face_normals: bool,
        /// Where the file has no vertex normals, smooth ones: each vertex's the mean of
        /// its faces' normals weighted by their angles there (Mitsuba's default).
        #[serde(default)]
        smooth_normals: bool,
        /// The front side turned to the back (Mitsuba's `flip_normals`).
        #[serde(default)]
        flip_normals: bool,
        /// Which mesh of a `.serialized` file (Mitsuba's `shape_index`).
        #[serde(default)]
        shape_index: u32,
        /// A PLY file's uvs with v down: v' = 1 - v, and a file without uvs given its
        /// triangles' default ones flipped so (how Mitsuba reads PLY; a `.serialized`
        /// file is read so always).
        #[serde(default)]
        flip_tex_coords: bool,
        /// Under a mirroring `transform`, a mesh left without the file's vertex normals
        /// faces as its placed triangles wind (Mitsuba's front), not as the mirror image
        /// of the file's front.
        #[serde(default)]
        placed_winding: bool,
        /// How the file's vertex and face colours become linear ones: decoded from sRGB
        /// (display colours), or taken as they are (Mitsuba's reading).
        #[serde(default)]
        color_space: ColorSpace,
    },
    /// A glTF 2.0 file (`.gltf` or `.glb`), `path` relative to the scene file: its first
    /// scene's meshes with their materials, and its KHR_lights_punctual lights, placed by
    /// `transform`. Its cameras are left out: the scene file's camera applies.
    Gltf {
        path: String,
        transform: Option<TransformDesc>,
    },
    /// The objects of `[groups.NAME]` (`group`), placed by `transform` (after the
    /// group's own): stored once however many instances place them.
    Instance {
        group: String,
        transform: Option<TransformDesc>,
    },
}

fn yes() -> bool {
    true
}

impl ObjectDesc {
    /// The scene `type` name.
    pub fn type_name(&self) -> &'static str {
        match self {
            ObjectDesc::Sphere { .. } => "sphere",
            ObjectDesc::Triangle { .. } => "triangle",
            ObjectDesc::Polygon { .. } => "polygon",
            ObjectDesc::Tetrahedron { .. } => "tetrahedron",
            ObjectDesc::Plane { .. } => "plane",
            ObjectDesc::Box { .. } => "box",
            ObjectDesc::Cylinder { .. } => "cylinder",
            ObjectDesc::Disk { .. } => "disk",
            ObjectDesc::Mesh { .. } => "mesh",
            ObjectDesc::Gltf { .. } => "gltf",
            ObjectDesc::Instance { .. } => "instance",
        }
    }

    /// The material the object names (a glTF file brings its own).
    pub fn material(&self) -> Option<&str> {
        Some(match self {
            ObjectDesc::Sphere { material, .. }
            | ObjectDesc::Triangle { material, .. }
            | ObjectDesc::Polygon { material, .. }
            | ObjectDesc::Tetrahedron { material, .. }
            | ObjectDesc::Plane { material, .. }
            | ObjectDesc::Box { material, .. }
            | ObjectDesc::Cylinder { material, .. }
            | ObjectDesc::Disk { material, .. } => material,
            ObjectDesc::Mesh { material, .. } => return material.as_deref(),
            ObjectDesc::Gltf { .. } | ObjectDesc::Instance { .. } => return None,
        })
    }

    /// The media it holds inside and outside (`interior`, `exterior`), by name; (None,
    /// None): crossing it leaves the medium as it is.
    pub fn media(&self) -> (Option<&str>, Option<&str>) {
        match self {
            ObjectDesc::Sphere {
                interior, exterior, ..
            }
            | ObjectDesc::Triangle {
                interior, exterior, ..
            }
            | ObjectDesc::Polygon {
                interior, exterior, ..
            }
            | ObjectDesc::Tetrahedron {
                interior, exterior, ..
            }
            | ObjectDesc::Plane {
                interior, exterior, ..
            }
            | ObjectDesc::Box {
                interior, exterior, ..
            }
            | ObjectDesc::Cylinder {
                interior, exterior, ..
            }
            | ObjectDesc::Disk {
                interior, exterior, ..
            }
            | ObjectDesc::Mesh {
                interior, exterior, ..
            } => (interior.as_deref(), exterior.as_deref()),
            ObjectDesc::Gltf { .. } | ObjectDesc::Instance { .. } => (None, None),
        }
    }

    pub fn transform(&self) -> Option<TransformDesc> {
        match self {
            ObjectDesc::Sphere { transform, .. }
            | ObjectDesc::Triangle { transform, .. }
            | ObjectDesc::Polygon { transform, .. }
            | ObjectDesc::Tetrahedron { transform, .. }
            | ObjectDesc::Plane { transform, .. }
            | ObjectDesc::Box { transform, .. }
            | ObjectDesc::Cylinder { transform, .. }
            | ObjectDesc::Disk { transform, .. }
            | ObjectDesc::Mesh { transform, .. }
            | ObjectDesc::Gltf { transform, .. }
            | ObjectDesc::Instance { transform, .. } => *transform,
        }
    }
}

/// `[media.NAME]`: a participating medium, selected by `type`.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum MediumDesc {
    /// The same everywhere: extinction `sigma_t` (per scene unit, an RGB or one number)
    /// and single-scattering `albedo` (Mitsuba's defaults, 1 and 0.75), or absorption
    /// `sigma_a` and scattering `sigma_s` instead; all times `scale`. Scattered by the
    /// Henyey-Greenstein phase function of asymmetry `g` (0: isotropic, > 0 forward).
    Homogeneous {
        sigma_t: Option<Spectrum>,
        albedo: Option<Spectrum>,
        sigma_a: Option<Spectrum>,
        sigma_s: Option<Spectrum>,
        #[serde(default = "crate::scene::materials::common::one")]
        scale: f32,
        #[serde(default)]
        g: f32,
    },
    /// Densities in a grid: the extinction at a point is the grid's density there
    /// (trilinear between voxel centres) times `sigma_t` (or `sigma_a` + `sigma_s`) times
    /// `scale`; the albedo and `g` as for `homogeneous`. `grid` is a Mitsuba `.vol` file
    /// of one float32 channel (or three: a density per colour channel), its voxels
    /// filling the unit cube that `transform` places
    /// (or the file's own box, with `use_grid_bbox`); no density outside it. Without
    /// `grid`, density 1 in that cube (Mitsuba's constant extinction, its `constvolume`).
    /// `albedo_grid`, a `.vol` file of one or three channels placed the same way, varies
    /// the albedo instead of `albedo`.
    Heterogeneous {
        grid: Option<String>,
        albedo_grid: Option<String>,
        sigma_t: Option<Spectrum>,
        albedo: Option<Spectrum>,
        sigma_a: Option<Spectrum>,
        sigma_s: Option<Spectrum>,
        #[serde(default = "crate::scene::materials::common::one")]
        scale: f32,
        #[serde(default)]
        g: f32,
        #[serde(default)]
        transform: Option<TransformDesc>,
        #[serde(default)]
        use_grid_bbox: bool,
    },
}

/// The coefficients of a `[media.NAME]` table, whatever its type.
#[derive(Debug, Clone, Copy)]
pub struct MediumCoefficients {
    pub sigma_t: Option<Spectrum>,
    pub albedo: Option<Spectrum>,
    pub sigma_a: Option<Spectrum>,
    pub sigma_s: Option<Spectrum>,
    pub scale: f32,
    pub g: f32,
}

/// An RGB triple, or one number for all three.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum Spectrum {
    Rgb([f32; 3]),
    Value(f32),
}

impl Spectrum {
    pub fn rgb(self) -> [f32; 3] {
        match self {
            Spectrum::Rgb(c) => c,
            Spectrum::Value(v) => [v; 3],
        }
    }
}

impl MediumDesc {
    /// Its coefficients as written.
    pub fn written(&self) -> MediumCoefficients {
        match *self {
            MediumDesc::Homogeneous {
                sigma_t,
                albedo,
                sigma_a,
                sigma_s,
                scale,
                g,
            }
            | MediumDesc::Heterogeneous {
                sigma_t,
                albedo,
                sigma_a,
                sigma_s,
                scale,
                g,
                ..
            } => MediumCoefficients {
                sigma_t,
                albedo,
                sigma_a,
                sigma_s,
                scale,
                g,
            },
        }
    }

    /// Its extinction (a grid's: per unit density), albedo (each per channel, scale
    /// applied) and phase asymmetry.
    pub fn coefficients(&self) -> ([f32; 3], [f32; 3], f32) {
        let MediumCoefficients {
            sigma_t,
            albedo,
            sigma_a,
            sigma_s,
            scale,
            g,
        } = self.written();
        let (t, a) = match (sigma_a, sigma_s) {
            (None, None) => (
                sigma_t.map_or([1.0; 3], Spectrum::rgb),
                albedo.map_or([0.75; 3], Spectrum::rgb),
            ),
            (sa, ss) => {
                let sa = sa.map_or([0.0; 3], Spectrum::rgb);
                let ss = ss.map_or([0.0; 3], Spectrum::rgb);
                let t: [f32; 3] = std::array::from_fn(|k| sa[k] + ss[k]);
                let a = std::array::from_fn(|k| if t[k] > 0.0 { ss[k] / t[k] } else { 0.0 });
                (t, a)
            }
        };
        (t.map(|x| x * scale), a, g)
    }
}
