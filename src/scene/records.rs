//! `#[repr(C)]` records shared with WGSL: the contract both backends read.
//!
//! Each struct mirrors the struct of the same name in `shaders/shared/types.wgsl`;
//! `tests/shaders.rs` compares every size and field offset below with naga's layout of
//! the shader, so a change on one side that is not made on the other fails the tests. The
//! constants both languages read are declared once, here ([`SHARED_CONSTANTS`]), and
//! written into the shaders from this list.

use bytemuck::{Pod, Zeroable};

/// A constant both languages read: its value as the shaders get it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SharedValue {
    U32(u32),
    F32(f32),
}

macro_rules! shared_value {
    (u32, $v:expr) => {
        SharedValue::U32($v)
    };
    (f32, $v:expr) => {
        SharedValue::F32($v)
    };
}

/// Declares each constant for Rust and lists it in [`SHARED_CONSTANTS`], from which
/// `gpu::codegen` writes the shaders' `const` declarations: the one source of their values.
macro_rules! shared_constants {
    ($( $(#[$doc:meta])* $name:ident : $ty:tt = $value:expr; )*) => {
        $( $(#[$doc])* pub const $name: $ty = $value; )*

        /// Every constant shared with WGSL, by name, in declaration order.
        pub const SHARED_CONSTANTS: &[(&str, SharedValue)] =
            &[$((stringify!($name), shared_value!($ty, $name))),*];
    };
}

shared_constants! {
    /// Primitive flag: `data` indexes a world-to-object transform in `shape_data` (analytic
    /// shapes whose transform cannot be baked exactly).
    PRIM_FLAG_TRANSFORM: u32 = 1;
    /// Primitive flag (triangles): `data` indexes per-vertex attributes in `shape_data`.
    PRIM_FLAG_ATTRIBUTES: u32 = 2;
    /// Primitive flag (triangles with attributes): the vertex normals are meaningful.
    PRIM_FLAG_SHADING_NORMALS: u32 = 4;
    /// Primitive flag (cylinders): closed by two cap disks.
    PRIM_FLAG_CAPS: u32 = 8;
    /// Primitive flag (triangles with attributes): `TANGENT_ENTRIES` more entries after
    /// the attributes hold each corner's tangent (xyz) and bitangent sign (w), for normal
    /// maps.
    PRIM_FLAG_TANGENTS: u32 = 16;
    /// Primitive flag (triangles with attributes): `UV1_ENTRIES` more entries (after the
    /// tangents, if any) hold each corner's second uv set.
    PRIM_FLAG_UV1: u32 = 32;
    /// Primitive flag (triangles with attributes): `COLOR_ENTRIES` more entries (after the
    /// second uv set, if any) hold each corner's vertex colour (linear rgb, alpha), which
    /// multiplies the material's colour and opacity.
    PRIM_FLAG_COLORS: u32 = 64;
    /// The tag of an instance of a group (`[groups.NAME]`): not a shape of the type list
    /// but a place where the BVH walk goes on into the group's own BVH, in the group's
    /// space. `data` indexes its world-to-object transform in `shape_data` (the rows of
    /// `PRIM_FLAG_TRANSFORM`'s, without the flag); `a.x` holds the bits of its group's
    /// root node index (`instance_root`).
    PRIM_INSTANCE: u32 = 15;
    /// Most surfaces a ray passes through where they are transparent (alpha) before it
    /// stops at the next one, whatever it is: a bound on the loop, never met in practice.
    MAX_ALPHA_SKIPS: u32 = 16;
    /// States of one path the kernel's `paths_main` reports: the camera ray's, then one
    /// after each `extend_path`, the last slot holding the path's final state however
    /// long it was.
    PATH_STEPS: u32 = 8;
    /// How deep `blend` materials may nest (a blend whose part is a blend ...).
    MAX_BLEND_DEPTH: u32 = 4;
    /// `vec4<f32>` entries per pixel of the accumulation: (sum rgb, count), (sum of squares
    /// rgb, samples dropped as not finite).
    ACCUM_ENTRIES: u32 = 2;
    /// Entries per pixel with AOVs (`HAS_AOVS`): the two above, then (albedo rgb, depth),
    /// (normal xyz, 0; a splat render's sample count), (position xyz, 0), each summed over
    /// every sample of the pixel.
    ACCUM_ENTRIES_AOVS: u32 = 5;

    /// Size of the BVH traversal stack in `intersect.wgsl`: an entry per ancestor of the
    /// node visited at most, and `bvh::collapse` keeps every node within this depth.
    BVH_STACK_SIZE: u32 = 32;
    /// Invocations in a workgroup of every entry point that traces rays (`@workgroup_size`
    /// of `trace.wgsl` and `kernel.wgsl`): the traversal stacks are in workgroup memory,
    /// one column per invocation, where llvmpipe writes an entry for the lanes that push
    /// one only; a stack in private memory costs it a masked write of all 8 lanes. (A
    /// shallow tree's walk keeps its stack in registers instead: `BVH_REGISTER_STACK`.)
    BVH_STACK_LANES: u32 = 64;
    /// Entries of the BVH walk's stack in registers (`gpu::plan::REGISTER_STACK`): a
    /// walk holds at most one per level below the root, so trees of this depth at most.
    BVH_REGISTER_STACK: u32 = 8;
    /// The bits of a BVH walk's hit mask (`BvhNode`'s meta bytes) that mark child nodes;
    /// the 24 below them mark primitives.
    BVH_NODE_BITS: u32 = 0xff00_0000;
    /// The slab distances of a BVH node's quantized child boxes are widened by this
    /// fraction of (|origin - ray origin| + 256 scale) / |direction| per axis: a bound on
    /// their rounding error (8 eps, eps = 2^-24; the terms of the slab distance in the
    /// node's grid can cancel, so a relative widening would not bound it: `bvh_node_hits`).
    BVH_SLAB_ERROR: f32 = 4.0 * f32::EPSILON;

    /// Material flag: emits from both sides.
    MAT_FLAG_TWO_SIDED: u32 = 1;
    /// Material flag: cut out where alpha (the surface view's `opacity` times the
    /// `color` texture's alpha) is below its `alpha_cutoff`, for every ray.
    MAT_FLAG_ALPHA_MASK: u32 = 2;
    /// Material flag: opaque with probability alpha, else passed through, for every ray
    /// (stochastic transparency).
    MAT_FLAG_ALPHA_BLEND: u32 = 4;
    /// Material flag: it has a lobe with a density, so next-event estimation weighs
    /// light samples at it (its `eval` and `pdf`): the material's answer
    /// (`scene::materials::Lobes`), which the shaders, the CPU and the GPU plan all read.
    MAT_FLAG_NEE: u32 = 8;
    /// Material flag: it may sample a delta lobe (a mirror, a refraction), which only its
    /// own sampling finds: the 50/50 mixture, whose pdf cannot hold one, leaves it out.
    MAT_FLAG_DELTA: u32 = 16;
    /// Material flag: a texture of `color2` is clamped to 1, as one of `color` always is
    /// (the second colour is a reflectance).
    MAT_FLAG_COLOR2_CLAMPED: u32 = 32;
    /// Material flag: its lobe with a density transmits (rough glass): `bsdf_eval` weighs
    /// directions under the surface, and shading normals send nothing over it.
    MAT_FLAG_TRANSMITS: u32 = 64;
    /// Material flag: its roughness differs along the tangent and the bitangent
    /// (`roughness_u`, `roughness_v`): `material_at` gives it the hit's tangent.
    MAT_FLAG_ANISOTROPIC: u32 = 128;
    /// Material flag: the surface view's `opacity_texture` names a texture whose luminance
    /// multiplies its alpha (an `opacity` mask of any material, Mitsuba's `mask`).
    MAT_FLAG_OPACITY_TEXTURE: u32 = 256;
    /// Material flag: its back side is black (`one_sided`): `material_at` gives a hit on
    /// it the tag `MAT_BLACK`.
    MAT_FLAG_ONE_SIDED: u32 = 512;
    /// Material flag: the surface view's `normal_texture` is a bump map (a height, times
    /// `normal_scale`), not a tangent-space normal map.
    MAT_FLAG_BUMP: u32 = 1024;
    /// Material flag: it reads a mesh's colours through a `mesh_attribute` texture, so
    /// `material_at` does not also multiply its colour by them.
    MAT_FLAG_OWN_COLORS: u32 = 2048;
    /// Material flag: its microfacet lobes are compensated for the energy they lose to
    /// multiple scattering (`energy_compensation`; the tables at `Params::ms_tables`).
    MAT_FLAG_ENERGY: u32 = 4096;
    /// Material flag: the surface view's `normal_texture` is a normal map in the frame of
    /// the hit's dp/du (made orthogonal to the shading normal n), n x dp/du and n
    /// (Mitsuba's `normalmap`), not in the frame of the vertex tangents.
    MAT_FLAG_UV_NORMAL_MAP: u32 = 8192;
    /// Material flag: shading normals are taken strictly, as Mitsuba 3 and pbrt-v4 take
    /// them (`[render] shading_normals = "strict"`): none is bent toward the viewer, no
    /// direction is folded over the surface; a mapped normal the viewer is behind is
    /// mirrored about the unmapped one (`bent_normal`), a direction on different sides of
    /// the shading and the unmapped or geometric surface is absorbed (`strictly_black`),
    /// and a map's bumps shadow grazing light (`map_shadowing`): Mitsuba's `normalmap` and
    /// `bumpmap`.
    MAT_FLAG_STRICT_SHADING: u32 = 16384;
    /// Material flag, with `MAT_FLAG_STRICT_SHADING` on a material that only reflects: a
    /// viewer under the shading normal sees it black, as Mitsuba's one-sided lobes are in
    /// their shading frame.
    MAT_FLAG_STRICT_VIEW: u32 = 32768;
    /// The tag `material_at` gives the back of a one-sided surface: no type has it, so
    /// the dispatch's default absorbs, with no BSDF and no density.
    MAT_BLACK: u32 = u32::MAX;

    /// Texture tags: the cases of the `switch` in `textures.wgsl`.
    TEX_CONSTANT: u32 = 0;
    TEX_CHECKER: u32 = 1;
    TEX_IMAGE: u32 = 2;
    TEX_NOISE: u32 = 3;
    /// A mesh's colours at the hit (`mesh_attribute`): `texture_at` reads the hit's.
    TEX_MESH_ATTRIBUTE: u32 = 4;
    /// Checker flag: cells in space (x, y, z) rather than in uv.
    TEX_FLAG_SOLID: u32 = 4;
    /// Image textures: the wrap mode along u in `flags & 3`, along v in
    /// `(flags >> TEX_WRAP_T_SHIFT) & 3`. Noise textures: kind in `flags & 3` (0 Perlin,
    /// 1 turbulence, 2 marble).
    TEX_MODE_MASK: u32 = 3;
    TEX_WRAP_T_SHIFT: u32 = 2;
    /// Wrap modes of image textures.
    WRAP_REPEAT: u32 = 0;
    WRAP_CLAMP: u32 = 1;
    WRAP_MIRROR: u32 = 2;
    /// Image flag: the nearest texel, not the bilinear mix of four (glTF's NEAREST
    /// magnification filter).
    TEX_FLAG_NEAREST: u32 = 16;
    /// Image flag: an 8-bit image whose colour is sRGB-encoded: each texel is decoded
    /// before filtering (`scene::texels`).
    TEX_FLAG_SRGB: u32 = 32;
    /// A material colour or checker cell with no texture.
    NO_TEXTURE: u32 = u32::MAX;

    /// Pixel samplers (`Params::sampler`).
    SAMPLER_RANDOM: u32 = 0;
    SAMPLER_JITTERED: u32 = 1;
    SAMPLER_HAMMERSLEY: u32 = 2;
    SAMPLER_SOBOL: u32 = 3;

    /// Pixel filters (`Params::pixel_filter`): drawn from, or splat weights.
    FILTER_BOX: u32 = 0;
    FILTER_TENT: u32 = 1;
    FILTER_GAUSSIAN: u32 = 2;
    /// A splatted sample whose colour (or its square) was not finite, in the first word of
    /// its place in the sample buffer (`trace.wgsl`'s `splat_record`): dropped.
    SPLAT_DROPPED: u32 = 0xffff_ffff;

    /// Light-sampling strategies (`Params::light_sampling`).
    LIGHT_SAMPLING_BSDF: u32 = 0;
    LIGHT_SAMPLING_MIXTURE: u32 = 1;
    LIGHT_SAMPLING_MIS: u32 = 2;

    /// Background kinds (`Params::background_kind`).
    BACKGROUND_CONSTANT: u32 = 0;
    BACKGROUND_GRADIENT: u32 = 1;
    BACKGROUND_IMAGE: u32 = 2;

    /// Light kinds (`Emitter::kind`). A light with a surface has its primitive's tag
    /// (`scene::primitives`, all below this), its geometry in the primitive's places of
    /// `a`, `b`, `c` in world space; the image background, then the lights without one.
    LIGHT_ENVIRONMENT: u32 = 16;
    /// Lights without a surface (`[[lights]]`), last in the list: `a` = position (a spot:
    /// `.w` = cos of the outer angle), `b` = intensity (a spot: `.w` = cos of the inner
    /// angle), `c` = a spot's unit axis (`.w` = 1 + its cones' difference in radians for
    /// Mitsuba's falloff, 0 for glTF's); a directional light's `a` = the unit direction
    /// toward it, `b` = its irradiance. A projector's `a.xyz` = position, `b.xyz` = its
    /// irradiance colour times its scale, `c.xyz` = its up vector over tan(half its
    /// height's angle) and (a.w, b.w, c.w) its right vector over tan(half its width's),
    /// `texture` = its irradiance texture (or `NO_TEXTURE`).
    LIGHT_POINT: u32 = 17;
    LIGHT_SPOT: u32 = 18;
    LIGHT_DIRECTIONAL: u32 = 19;
    LIGHT_PROJECTOR: u32 = 20;
    /// An index that names no light.
    NO_LIGHT: u32 = u32::MAX;
    /// `Primitive::flags >> PRIM_LIGHT_SHIFT` is the primitive's index in the light list
    /// plus one, or 0 when it is not in the list.
    PRIM_LIGHT_SHIFT: u32 = 8;

    /// Primitive index reported for a ray that hits nothing.
    NO_HIT: u32 = u32::MAX;
    /// Largest finite f32: "no intersection" and "unbounded" without relying on
    /// infinities.
    FAR: f32 = f32::MAX;

    /// Dimension pairs of the random numbers a bounce draws (`rand_2d`'s `dim`): the
    /// position in the pixel.
    DIM_PIXEL: u32 = 0;
    /// The point on the lens.
    DIM_LENS: u32 = 1;
    /// The BSDF sample.
    DIM_BSDF: u32 = 2;
    /// A point on a light.
    DIM_LIGHT: u32 = 3;
    /// `.x` chooses the light, `.y` the mixture's strategy.
    DIM_LIGHT_CHOICE: u32 = 4;
    /// `.x` decides Russian roulette.
    DIM_RR: u32 = 5;
    /// `.x` chooses the light without a surface.
    DIM_PUNCTUAL: u32 = 6;
    /// `.x` decides which transparent (alpha blend) surfaces the bounce's ray passes
    /// through, `.y` those of its shadow rays.
    DIM_ALPHA: u32 = 7;
    /// `.x` chooses among the parts of a `blend` material.
    DIM_BLEND: u32 = 8;
    /// The free flight through a medium along the k-th segment of a bounce's ray (k
    /// counts the surfaces passed through): dimension `DIM_MEDIUM + k`, `.x` choosing the
    /// colour channel whose extinction draws the distance, `.y` the distance.
    DIM_MEDIUM: u32 = 16;

    /// The path's medium when it is in none (vacuum).
    NO_MEDIUM: u32 = 0xffff_ffff;
    /// A candidate's `prim` when the ray scatters in a medium before any surface (at the
    /// candidate's `t`).
    MEDIUM_HIT: u32 = 0xffff_fffe;
    /// `vec4<f32>` entries of `tables` per medium (`Medium`): (sigma_t rgb, g), (albedo
    /// rgb, the entry of its density grid's header as u32 bits, 0 for a homogeneous one).
    MEDIUM_ENTRIES: u32 = 2;
    /// `vec4<f32>` entries of a density grid's header (`Grid`): the map from the scene
    /// into its unit cube (three rows), (voxels x, y, z, first value), (majorant cells
    /// x, y, z, first majorant) and (channels: 1, or 3 for a density per colour channel,
    /// 0, 0, the entry of its albedo grid's header, 0 without one), the counts and
    /// indices as u32 bits; a voxel's channels together. An albedo grid's header is the
    /// same, of three channels, without majorants.
    GRID_ENTRIES: u32 = 6;
    /// The voxels a side of a majorant cell: tracking steps through cells of this size,
    /// taking collisions at the rate of each one's highest density.
    MAJORANT_CELL: u32 = 8;
    /// The most cells and collisions one tracking takes (llvmpipe stops a loop after
    /// 65535 iterations); a flight that would take more ends there.
    MAX_TRACKING_STEPS: u32 = 16384;
    /// A shape's media word (`Params::material_media`): interior + 1 plus `MEDIA_SIDE` x
    /// (exterior + 1), 0 for vacuum on a side; a word of 0 leaves the medium as it is.
    /// At most `MEDIA_SIDE - 1` media, so a word is an exact f32.
    MEDIA_SIDE: u32 = 4096;

    /// The f32 nearest to pi.
    PI: f32 = std::f32::consts::PI;
    /// Below this cosine between a light's normal and the direction to it, the light is
    /// seen edge-on: pdf 0 and no sample, never an unbounded weight.
    EDGE_ON_COS: f32 = 1e-6;
    /// Below this GGX alpha the specular lobe is a perfect mirror (a delta, as in
    /// pbrt-v4): eval and pdf leave it out and the sampler takes the mirror direction
    /// itself, so roughness 0 never divides by zero.
    ALPHA_SMOOTH: f32 = 1e-3;
    /// Where a shading normal differs from the geometric one, the cosine under which the
    /// mirror direction of the viewer about it may not come to the geometric surface:
    /// the normal is bent to lift it there (`bent_normal`).
    SHADING_LIFT: f32 = 1e-2;
    /// The sheen's smallest alpha: the Charlie distribution's exponent 1 / alpha stays
    /// within f32 (pbr's `sheen_roughness` 0 and its textures are kept above it).
    SHEEN_ALPHA_MIN: f32 = 1e-2;
    /// Cosines and alphas of the sheen's albedo table (`pbr::sheen_albedo_table`), each
    /// from 0 to 1.
    SHEEN_TABLE_SIZE: u32 = 32;
    /// Cosines of a rough plastic's transmittance table (`plastic::transmittance_table`),
    /// from 0 to 1.
    PLASTIC_TABLE_SIZE: u32 = 64;
    /// Roughnesses and cosines of the microfacet albedo tables
    /// (`scene::microfacet_albedo`), each from 0 to 1.
    MS_TABLE_SIZE: u32 = 32;
    /// The microfacet albedo tables' variants (`microfacet_albedo::Variant`): GGX with
    /// Smith's height-correlated masking, GGX with the separable one, Beckmann with the
    /// separable one.
    MS_GGX_CORRELATED: u32 = 0;
    MS_GGX_SEPARABLE: u32 = 1;
    MS_BECKMANN_SEPARABLE: u32 = 2;
    /// The dielectric albedo tables' variants (`microfacet_albedo::DielectricVariant`,
    /// after the three above): GGX and Beckmann with the height-correlated masking
    /// (rough glass), GGX and Beckmann with the separable one (plastic's coating).
    MS_DIELECTRIC_GGX_CORRELATED: u32 = 0;
    MS_DIELECTRIC_BECKMANN_CORRELATED: u32 = 1;
    MS_DIELECTRIC_GGX_SEPARABLE: u32 = 2;
    MS_DIELECTRIC_BECKMANN_SEPARABLE: u32 = 3;
    /// Indices of refraction of the dielectric albedo tables, from 1 to MS_IOR_MAX
    /// spaced quadratically, closer toward 1 (`microfacet_albedo::table_ior`; a higher
    /// one is read at MS_IOR_MAX).
    MS_IORS: u32 = 16;
    MS_IOR_MAX: f32 = 3.0;
    /// `shape_data` entries of one triangle's attributes: (n0, u0), (n1, u1), (n2, u2),
    /// (v0, v1, v2, 0).
    ATTRIBUTE_ENTRIES: u32 = 4;
    /// `shape_data` entries of one triangle's tangents (after its attributes): (t0, w0),
    /// (t1, w1), (t2, w2).
    TANGENT_ENTRIES: u32 = 3;
    /// `shape_data` entries of one triangle's second uv set: (u0, v0, u1, v1),
    /// (u2, v2, 0, 0).
    UV1_ENTRIES: u32 = 2;
    /// `shape_data` entries of one triangle's vertex colours: one (r, g, b, alpha) per
    /// corner.
    COLOR_ENTRIES: u32 = 3;
}

/// `[f32; 4]` accumulation entries per pixel with or without the AOVs' sums.
pub fn accum_entries(aovs: bool) -> usize {
    (if aovs {
        ACCUM_ENTRIES_AOVS
    } else {
        ACCUM_ENTRIES
    }) as usize
}

/// `shape_data` entries of one transform: world-to-object rows, then object-to-world rows.
pub const TRANSFORM_ENTRIES: u32 = 6;
/// `Primitive::data` of a primitive with no extra data.
pub const NO_DATA: u32 = u32::MAX;
/// Texels of the Perlin tables (one row of float texels): 256 random unit vectors, then
/// 256 of the three permutations (x, y, z) stored as floats.
pub const NOISE_TABLE_ENTRIES: u32 = 512;
/// Most lights a scene may have (the index must fit the flag bits above the shift).
pub const MAX_LIGHTS: u32 = (1 << (32 - PRIM_LIGHT_SHIFT)) - 2;

/// A tagged primitive (object space when `PRIM_FLAG_TRANSFORM` is set). The record is
/// storage: each type names its places in its view (`scene::primitives::NAME::Params`),
/// e.g. a sphere's `a` = (center, radius), a disk's `b` = (unit normal, 0).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Primitive {
    pub tag: u32,
    pub material: u32,
    pub flags: u32,
    /// First `shape_data` entry of the transform or the vertex attributes, else `NO_DATA`.
    pub data: u32,
    pub a: [f32; 4],
    pub b: [f32; 4],
    pub c: [f32; 4],
}

/// A tagged material. The record is storage: each material names its places in its view
/// (`scene::materials::NAME::Params`, and `Surface` for what every material has), and no
/// code outside those views gives a place a meaning. The record's own rules, the same
/// for every material: a texture in `tex_color` replaces `color.rgb` at a hit, clamped
/// to 1 (a reflectance), and its alpha multiplies the surface's opacity; one in
/// `tex_color2` replaces `color2.rgb`, clamped with `MAT_FLAG_COLOR2_CLAMPED`; one in
/// `tex_emission` replaces `emission.rgb`; `normal2.w` is 1 at a back-face hit, else 0;
/// `tex_data0` to `tex_data5` and `tex_normal2` are read by the material's own texture
/// hook only, which may also write `normal2.xyz` (a second shading normal at the hit:
/// pbr's clearcoat's); with `MAT_FLAG_ANISOTROPIC` `normal2.xyz` is the hit's tangent
/// instead (written before the hook: a material has one or the other, never both);
/// `table` is the first `tables` entry of a table the material reads.
/// Flags: `MAT_FLAG_*`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Material {
    /// The material's type (`scene::materials::MaterialKind`).
    pub tag: u32,
    pub flags: u32,
    pub tex_color: u32,
    pub tex_emission: u32,
    pub color: [f32; 4],
    pub emission: [f32; 4],
    pub scalars: [f32; 4],
    pub color2: [f32; 4],
    pub tex_color2: u32,
    pub tex_data0: u32,
    pub tex_normal: u32,
    pub tex_data1: u32,
    pub color3: [f32; 4],
    pub scalars2: [f32; 4],
    pub normal2: [f32; 4],
    pub tex_data2: u32,
    pub tex_data3: u32,
    pub tex_data4: u32,
    pub tex_data5: u32,
    pub tex_normal2: u32,
    pub table: u32,
    /// The opacity mask's texture, with `MAT_FLAG_OPACITY_TEXTURE` (else 0).
    pub tex_opacity: u32,
    pub pad1: u32,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            tag: 0,
            flags: 0,
            tex_color: NO_TEXTURE,
            tex_emission: NO_TEXTURE,
            color: [0.0; 4],
            emission: [0.0; 4],
            scalars: [0.0; 4],
            color2: [0.0; 4],
            tex_color2: NO_TEXTURE,
            tex_data0: NO_TEXTURE,
            tex_normal: NO_TEXTURE,
            tex_data1: NO_TEXTURE,
            color3: [0.0; 4],
            scalars2: [0.0; 4],
            normal2: [0.0; 4],
            tex_data2: NO_TEXTURE,
            tex_data3: NO_TEXTURE,
            tex_data4: NO_TEXTURE,
            tex_data5: NO_TEXTURE,
            tex_normal2: NO_TEXTURE,
            table: 0,
            tex_opacity: 0,
            pad1: 0,
        }
    }
}

/// A tagged texture: constant (`color0`); checker (cells of `even`/`odd` textures, or of
/// `color0`/`color1` where those are `NO_TEXTURE`; `params.x` = cells per unit); image
/// (`width` x `height` texels of texel bank `bank`, page `layer`, from page texel (`x`,
/// `y`), row 0 at the top; its uv transform's rows in `color1` and `params`, its factor in
/// `color0`, read from uv set `uv_set`; see `scene::texels`); noise (`color0` x Perlin
/// noise of `params.x` x p, its tables at `tables[offset]`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Texture {
    pub tag: u32,
    pub flags: u32,
    pub even: u32,
    pub odd: u32,
    pub width: u32,
    pub height: u32,
    pub bank: u32,
    pub layer: u32,
    pub x: u32,
    pub y: u32,
    pub uv_set: u32,
    pub offset: u32,
    pub color0: [f32; 4],
    pub color1: [f32; 4],
    pub params: [f32; 4],
}

impl Default for Texture {
    fn default() -> Self {
        Texture {
            tag: TEX_CONSTANT,
            flags: 0,
            even: NO_TEXTURE,
            odd: NO_TEXTURE,
            width: 0,
            height: 0,
            bank: 0,
            layer: 0,
            x: 0,
            y: 0,
            uv_set: 0,
            offset: 0,
            color0: [0.0; 4],
            color1: [0.0; 4],
            params: [0.0; 4],
        }
    }
}

/// One entry of the light list: an emissive primitive with its world-space geometry for
/// sampling, or the environment (`primitive` = `NO_HIT`). Lights are chosen with
/// probability `prob`, by inverting the running sum `cdf` (that of the lights up to and
/// including this one); `prob` is the difference of consecutive `cdf` values, so it is
/// exactly the probability that the inversion picks this light. A light with a surface
/// holds its primitive's places `a`, `b`, `c` in world space (its type's view reads them:
/// `scene::primitives::light_geometry`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Emitter {
    pub primitive: u32,
    /// `LIGHT_*`.
    pub kind: u32,
    pub prob: f32,
    pub cdf: f32,
    pub a: [f32; 4],
    pub b: [f32; 4],
    pub c: [f32; 4],
    /// World-space area (0 for the environment).
    pub area: f32,
    /// Emitted power estimate that `prob` is proportional to.
    pub power: f32,
    /// A projector's irradiance texture or a spot's texture, else `NO_TEXTURE` (0 for
    /// the lights that never read it).
    pub texture: u32,
    pub pad1: u32,
    /// A textured spot's up vector (square to its axis) over the tangent of its outer
    /// angle; else 0.
    pub d: [f32; 4],
}

/// Per-dispatch constants (a uniform buffer): camera, image, pass and band.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Params {
    /// Camera position; `.w` = lens radius.
    pub cam_origin: [f32; 4],
    /// Unit right vector; `.w` = half width of the focus plane.
    pub cam_right: [f32; 4],
    /// Unit up vector; `.w` = half height of the focus plane.
    pub cam_up: [f32; 4],
    /// Unit forward vector; `.w` = focus distance.
    pub cam_forward: [f32; 4],
    /// Radiance of rays that leave the scene (the bottom of a gradient).
    pub background: [f32; 4],
    /// The top of a vertical gradient.
    pub background_top: [f32; 4],
    /// Image background: (cos, sin) of its rotation about +y, its strength, 0.
    pub env: [f32; 4],
    pub width: u32,
    pub height: u32,
    pub max_depth: u32,
    pub seed: u32,
    pub sample_index: u32,
    pub num_primitives: u32,
    pub num_emitters: u32,
    pub band_x: u32,
    pub band_y: u32,
    pub band_width: u32,
    pub band_height: u32,
    /// Primitives `0..num_unbounded` (planes) are tested on every ray; the rest sit in the BVH.
    pub num_unbounded: u32,
    /// 1: traverse the BVH; 0: test every primitive (for benchmarks and tests).
    pub use_bvh: u32,
    /// `SAMPLER_*`: where the first bounce's 2D points come from.
    pub sampler: u32,
    /// Jittered sampling: the pixel is a 2^strata_log2 x 2^strata_log2 grid.
    pub strata_log2: u32,
    /// Samples per pixel of the whole render (Hammersley's N).
    pub spp: u32,
    /// `LIGHT_SAMPLING_*`.
    pub light_sampling: u32,
    /// `BACKGROUND_*`.
    pub background_kind: u32,
    /// Image background: its texture.
    pub env_texture: u32,
    /// Image background: the first `tables` entry of its sampling distribution.
    pub env_cdf: u32,
    /// Image background: its index in the light list, else `NO_LIGHT`.
    pub env_light: u32,
    /// Image row of the bound accumulation buffer's first pixel: the band a dispatch's
    /// band lies in starts there (the GPU keeps one buffer per band of rows).
    pub accum_y: u32,
    /// Russian roulette decides whether rays from this one on (0 = the camera ray) are
    /// traced; 0: no Russian roulette.
    pub rr_depth: u32,
    /// The dispatch traces samples `sample_index .. sample_index + sample_count` of each
    /// pixel (set per dispatch by the GPU backend; 0 in [`crate::scene::flat::FlatScene::params`],
    /// so it is not part of a checkpoint's scene hash).
    pub sample_count: u32,
    /// Lights without a surface: emitters `num_emitters .. num_emitters + num_punctual`,
    /// chosen among themselves (their `cdf` and `prob` are over them alone).
    pub num_punctual: u32,
    /// 1: an orthographic camera (parallel rays along `cam_forward` from the view
    /// rectangle), 0: a perspective one.
    pub orthographic: u32,
    /// `FILTER_*`: the pixel filter a sample's position in the pixel follows.
    pub pixel_filter: u32,
    /// The first `tables` entry of the microfacet albedo tables that energy compensation
    /// reads (`scene::microfacet_albedo`); 0 without any.
    pub ms_tables: u32,
    /// 1: camera rays see no emitter and no background (`[render] hide_emitters`,
    /// Mitsuba's); lights still light the scene.
    pub hide_emitters: u32,
    /// Camera rays start where they cross the plane this far in front of the camera
    /// (along `cam_forward`; `[camera] near_clip`, Mitsuba's): nearer surfaces are not
    /// seen. 0: from the camera.
    pub near_clip: f32,
    /// The tent or Gaussian as a step function of this many steps over [0, radius], each
    /// the filter's value at its inner end (`[render] filter_steps`, Mitsuba's film's
    /// table); 0: the filter itself.
    pub filter_steps: u32,
    /// 1: each sample lies uniformly in its pixel and is splatted over the pixels the
    /// filter reaches, by the gather pass (`[render] reconstruction = "splat"`); 0: each
    /// pixel's samples are drawn from the filter.
    pub splat: u32,
    /// The first `tables` entry of the media (`MEDIUM_ENTRIES` each, in `[media]`
    /// order); 0 without any.
    pub media: u32,
    /// The medium camera rays start in (`[camera] medium`), else `NO_MEDIUM`.
    pub camera_medium: u32,
    /// The first `tables` entry of the materials' media words (four to an entry, as
    /// f32 values; `MEDIA_SIDE`): the media the shapes of each material record hold
    /// (the flattener gives a shape with media a record of its own); 0 without media.
    pub material_media: u32,
    pub pad0: u32,
    /// The filter's radius in pixels, a Gaussian's standard deviation, its value at the
    /// radius (subtracted, so it falls to 0 there), and 1 when samples stay on the image
    /// (`[render] sample_border = false`: a border pixel's filter restricted to the
    /// image); zeros for the box.
    pub filter_shape: [f32; 4],
}

/// One node of the renderers' BVH (`bvh::collapse`): up to `BVH_WIDTH` = 8 children in 80
/// bytes (Ylitie, Karras and Laine 2017), their boxes quantized to 8 bits per plane in the
/// node's own grid. Child `i`'s box is `origin + scale * q` for its planes' bytes `q`,
/// rounded outwards, so it always holds the child's exact box.
///
/// * `origin`: the grid's origin (the node's lower corner); `scale`: the grid's steps on
///   x, y and z as the exponent bytes of powers of two (`f32::from_bits(byte << 23)`),
///   and in its top byte `imask`, bit `i` set when child `i` is a node.
/// * `child`: the index of the first child node; the child nodes follow it in slot order
///   (child `i` is `child + popcount(imask & ((1 << i) - 1))`).
/// * `prim`: the first primitive of the leaf children, whose primitives follow it in slot
///   order (at most `BVH_WIDTH * WIDE_LEAF_SIZE` = 24).
/// * `meta0`, `meta1`: one byte per child (children 0-3, 4-7, from the low byte). A
///   child node: `0b001_11iii` (`24 + i`); a leaf: its count in unary in the top 3 bits
///   (`0b001`, `0b011`, `0b111`) above its first primitive's offset from `prim` (0-23);
///   an empty slot: 0. A hit child thus marks `(meta >> 5) << (meta & 31)` in a 32-bit
///   mask: its primitives in bits 0-23, a node in bits 24-31.
/// * `q0` = (lo.x of children 0-3, lo.x 4-7, lo.y 0-3, lo.y 4-7), `q1` = (lo.z, lo.z,
///   hi.x, hi.x), `q2` = (hi.y, hi.y, hi.z, hi.z), a byte per child from the low byte.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    pub origin: [f32; 3],
    pub scale: u32,
    pub child: u32,
    pub prim: u32,
    pub meta0: u32,
    pub meta1: u32,
    pub q0: [u32; 4],
    pub q1: [u32; 4],
    pub q2: [u32; 4],
}

/// One ray of the intersection kernel (`shaders/kernel.wgsl`); `.w` unused.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct KernelRay {
    pub origin: [f32; 4],
    pub dir: [f32; 4],
}

/// What the intersection kernel reports for one ray: the closest-hit search, the shading
/// record (`prim` = `NO_HIT` on a miss, the rest then zero) and the shadow-ray search.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct KernelHit {
    pub t: f32,
    pub prim: u32,
    pub front_face: u32,
    /// `occluded(ray, FAR)` in bit 0, `occluded(ray, 0.999 t)` (anything well before the
    /// closest hit) in bit 1.
    pub occluded: u32,
    /// Hit point, `.w` = error bound.
    pub p: [f32; 4],
    pub ng: [f32; 4],
    pub ns: [f32; 4],
    /// uv in `.xy`, the candidate's own (u, v) in `.zw`.
    pub uv: [f32; 4],
    /// The second uv set in `.xy`; `.z`: the instance the hit was found through, plus 1
    /// (0: none).
    pub uv1: [f32; 4],
    /// The vertex colour.
    pub color: [f32; 4],
}

/// One texture look-up of the kernel's `textures_main`: uv sets 0 and 1 in `uv`, the
/// point in `p.xyz`, the texture index in `p.w` (as a float).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TextureLookup {
    pub uv: [f32; 4],
    pub p: [f32; 4],
}

/// One query of the kernel's `materials_main`: material `material` at a hit (point,
/// normals, uv, side) that a ray (`origin`, `dir`) arrived at; the 2D sample its
/// scattering draws with (`uv.zw`), and a direction `wi` its BSDF and pdf are asked
/// toward.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct MaterialQuery {
    pub material: u32,
    pub front_face: u32,
    pub pad0: u32,
    pub pad1: u32,
    pub origin: [f32; 4],
    pub dir: [f32; 4],
    pub p: [f32; 4],
    pub ng: [f32; 4],
    pub ns: [f32; 4],
    /// The shading normal before a normal map turned it to `ns`.
    pub unmapped: [f32; 4],
    /// The hit's uv in `.xy`, the sample in `.zw`.
    pub uv: [f32; 4],
    pub wi: [f32; 4],
    /// The hit's second uv set in `.xy`.
    pub uv1: [f32; 4],
    /// The hit's vertex colour.
    pub color: [f32; 4],
}

/// What `materials_main` reports for one query: the material at the hit (`material_at`)
/// asked everything the integrator asks of it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct MaterialReply {
    /// Bit 0: scatter's `ok`; bit 1: its `delta`; bit 2: `nee_applies`; bit 3:
    /// `mixture_applies`.
    pub flags: u32,
    pub pad0: u32,
    pub pad1: u32,
    pub pad2: u32,
    /// Scatter's direction, its pdf in `.w`.
    pub dir: [f32; 4],
    /// Scatter's weight.
    pub weight: [f32; 4],
    /// `bsdf_eval` toward `wi`, `bsdf_pdf` toward it in `.w`.
    pub eval: [f32; 4],
    /// `emitted` toward the ray.
    pub emitted: [f32; 4],
}

/// One query of the kernel's `lights_main`: a point `p` lights are sampled from (the
/// light's choice by `p.w`, the point on it by `u.xy`, the light without a surface by
/// `u.z`), and a direction `d` from it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct LightQuery {
    pub p: [f32; 4],
    pub u: [f32; 4],
    pub d: [f32; 4],
}

/// What `lights_main` reports for one query.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct LightReply {
    /// `sample_light`'s light, or `NO_LIGHT`.
    pub light: u32,
    /// `sample_punctual`'s light, or `NO_LIGHT` in a scene without one.
    pub punctual: u32,
    pub pad0: u32,
    pub pad1: u32,
    /// `sample_light`'s direction, its distance in `.w`.
    pub dir: [f32; 4],
    /// `.x`: `sample_light`'s pdf; `.y`: `light_pdf` of the point it sampled; `.z`:
    /// `light_pdf_total` of `d`.
    pub pdf: [f32; 4],
    /// `sample_light`'s candidate (u, v) in `.xy`.
    pub uv: [f32; 4],
    /// `background_radiance` of `d`.
    pub background: [f32; 4],
    /// `sample_punctual`'s direction, its squared distance in `.w`.
    pub punctual_dir: [f32; 4],
    /// `sample_punctual`'s radiance, its probability in `.w`.
    pub punctual_le: [f32; 4],
}

/// One path of the kernel's `paths_main`: the pixel (x, y) and the sample index whose
/// camera path it traces, as the render's `main` traces it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PathQuery {
    pub x: u32,
    pub y: u32,
    pub sample: u32,
    pub pad0: u32,
}

/// One state of a path in `paths_main` (`PATH_STEPS` per query): the ray to follow next,
/// its throughput and the radiance gathered so far.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PathStep {
    /// The ray's origin; `.w`: the path's depth (rays traced so far).
    pub origin: [f32; 4],
    /// The ray's direction; `.w`: 1 while the path goes on, 0 once it has ended (and in
    /// the slots after a shorter path's end, which are all zero).
    pub dir: [f32; 4],
    /// `.w`: how many `extend_path` calls the state follows.
    pub throughput: [f32; 4],
    pub radiance: [f32; 4],
}

/// Size and field offsets of one record, for the layout test against naga.
#[derive(Debug)]
pub struct RecordLayout {
    pub name: &'static str,
    pub size: usize,
    pub fields: Vec<(&'static str, usize)>,
}

/// One field's value, as a record written into a shader needs it (`gpu::codegen`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FieldValue {
    U32(u32),
    F32(f32),
    Vec3([f32; 3]),
    Vec4([f32; 4]),
    UVec4([u32; 4]),
}

impl From<u32> for FieldValue {
    fn from(v: u32) -> Self {
        FieldValue::U32(v)
    }
}
impl From<f32> for FieldValue {
    fn from(v: f32) -> Self {
        FieldValue::F32(v)
    }
}
impl From<[f32; 3]> for FieldValue {
    fn from(v: [f32; 3]) -> Self {
        FieldValue::Vec3(v)
    }
}
impl From<[f32; 4]> for FieldValue {
    fn from(v: [f32; 4]) -> Self {
        FieldValue::Vec4(v)
    }
}
impl From<[u32; 4]> for FieldValue {
    fn from(v: [u32; 4]) -> Self {
        FieldValue::UVec4(v)
    }
}

/// A record shared with WGSL: its struct's name there, its fields in order with their
/// values, and its layout. The field order is written once, in `shared_record!`'s list,
/// which must name every field (it destructures the struct without `..`), and which the
/// layout test holds to naga's view of the WGSL struct.
pub trait SharedRecord {
    /// The WGSL struct's name.
    const NAME: &'static str;
    /// Every field, in declaration order, with its value.
    fn fields(&self) -> Vec<(&'static str, FieldValue)>;
    /// Size and field offsets.
    fn layout() -> RecordLayout;
}

macro_rules! shared_record {
    ($ty:ident { $($field:ident),* $(,)? }) => {
        impl SharedRecord for $ty {
            const NAME: &'static str = stringify!($ty);
            fn fields(&self) -> Vec<(&'static str, FieldValue)> {
                let $ty { $($field),* } = *self;
                vec![$((stringify!($field), FieldValue::from($field))),*]
            }
            fn layout() -> RecordLayout {
                RecordLayout {
                    name: stringify!($ty),
                    size: core::mem::size_of::<$ty>(),
                    fields: vec![$((stringify!($field), core::mem::offset_of!($ty, $field))),*],
                }
            }
        }
    };
}

shared_record!(Primitive {
    tag,
    material,
    flags,
    data,
    a,
    b,
    c
});
shared_record!(Material {
    tag,
    flags,
    tex_color,
    tex_emission,
    color,
    emission,
    scalars,
    color2,
    tex_color2,
    tex_data0,
    tex_normal,
    tex_data1,
    color3,
    scalars2,
    normal2,
    tex_data2,
    tex_data3,
    tex_data4,
    tex_data5,
    tex_normal2,
    table,
    tex_opacity,
    pad1
});
shared_record!(Texture {
    tag,
    flags,
    even,
    odd,
    width,
    height,
    bank,
    layer,
    x,
    y,
    uv_set,
    offset,
    color0,
    color1,
    params
});
shared_record!(Emitter {
    primitive,
    kind,
    prob,
    cdf,
    a,
    b,
    c,
    area,
    power,
    texture,
    pad1,
    d
});
shared_record!(Params {
    cam_origin,
    cam_right,
    cam_up,
    cam_forward,
    background,
    background_top,
    env,
    width,
    height,
    max_depth,
    seed,
    sample_index,
    num_primitives,
    num_emitters,
    band_x,
    band_y,
    band_width,
    band_height,
    num_unbounded,
    use_bvh,
    sampler,
    strata_log2,
    spp,
    light_sampling,
    background_kind,
    env_texture,
    env_cdf,
    env_light,
    accum_y,
    rr_depth,
    sample_count,
    num_punctual,
    orthographic,
    pixel_filter,
    ms_tables,
    hide_emitters,
    near_clip,
    filter_steps,
    splat,
    media,
    camera_medium,
    material_media,
    pad0,
    filter_shape
});
shared_record!(KernelRay { origin, dir });
shared_record!(TextureLookup { uv, p });
shared_record!(KernelHit {
    t,
    prim,
    front_face,
    occluded,
    p,
    ng,
    ns,
    uv,
    uv1,
    color
});
shared_record!(MaterialQuery {
    material,
    front_face,
    pad0,
    pad1,
    origin,
    dir,
    p,
    ng,
    ns,
    unmapped,
    uv,
    wi,
    uv1,
    color
});
shared_record!(MaterialReply {
    flags,
    pad0,
    pad1,
    pad2,
    dir,
    weight,
    eval,
    emitted
});
shared_record!(LightQuery { p, u, d });
shared_record!(LightReply {
    light,
    punctual,
    pad0,
    pad1,
    dir,
    pdf,
    uv,
    background,
    punctual_dir,
    punctual_le
});
shared_record!(PathQuery { x, y, sample, pad0 });
shared_record!(PathStep {
    origin,
    dir,
    throughput,
    radiance
});
shared_record!(BvhNode {
    origin,
    scale,
    child,
    prim,
    meta0,
    meta1,
    q0,
    q1,
    q2
});

/// The layout of every record shared with WGSL.
pub fn record_layouts() -> Vec<RecordLayout> {
    vec![
        Primitive::layout(),
        Material::layout(),
        Texture::layout(),
        Emitter::layout(),
        Params::layout(),
        KernelRay::layout(),
        TextureLookup::layout(),
        KernelHit::layout(),
        MaterialQuery::layout(),
        MaterialReply::layout(),
        LightQuery::layout(),
        LightReply::layout(),
        PathQuery::layout(),
        PathStep::layout(),
        BvhNode::layout(),
    ]
}
