//! Primitives, one module each: its record view (`Params`, the names of its places in the
//! record), its host geometry (bounds, area, which records are usable, its geometry as a
//! light's) through [`common::Shape`]. Its intersection, surface and light sampling are
//! `shaders/primitives/NAME.wgsl`, with the CPU twin `cpu/primitives/NAME.rs` beside it.
//!
//! The type list below is the one place that names them all: the record's tag
//! (`PRIM_NAME` in the shaders), the shader define of the code a scene needs
//! (`HAS_NAME`), the GPU and CPU dispatch (`gpu::codegen::primitives`,
//! `cpu::primitives`), the shader files embedded, and the order of the plain loop's
//! per-type loops, which [`sort_for_loops`] gives the records, all follow from it. Adding
//! a primitive: its module here, its WGSL file, its CPU twin, a line of the list, its
//! entry in the scene format and the flattener, its rows in the tests.
//!
//! The primitive modules import `common` and never this file: it imports them.

pub mod r#box;
pub mod common;
pub mod cylinder;
pub mod disk;
pub mod plane;
pub mod sphere;
pub mod triangle;

use glam::{Mat3, Vec3};

use super::bvh::Aabb;
use super::materials::common::View;
use super::records::Primitive;
use common::Shape;

/// Calls macro `$then` with the type list: for each primitive, its doc comment, its
/// [`PrimitiveKind`] variant, its tag, its module, its name (the WGSL file and functions,
/// the tag's `PRIM_NAME`) and its shader define. `gpu::shader` (the embedded WGSL files)
/// and `cpu::primitives` (the dispatch) expand it too. Tags stay below
/// `records::LIGHT_ENVIRONMENT`: a light with a surface has its primitive's tag as its
/// kind.
macro_rules! for_each_primitive {
    ($then:ident) => {
        $then! {
            /// A sphere.
            Sphere = 0, sphere, "sphere", "HAS_SPHERE";
            /// A triangle, with a mesh's vertex attributes.
            Triangle = 1, triangle, "triangle", "HAS_TRIANGLE";
            /// An infinite plane: unbounded, tested before the BVH.
            Plane = 2, plane, "plane", "HAS_PLANE";
            /// An axis-aligned box.
            Box = 3, r#box, "box", "HAS_BOX";
            /// A finite cylinder, with or without its caps.
            Cylinder = 4, cylinder, "cylinder", "HAS_CYLINDER";
            /// A disk.
            Disk = 5, disk, "disk", "HAS_DISK";
        }
    };
}
pub(crate) use for_each_primitive;

macro_rules! primitive_types {
    ($( $(#[$doc:meta])* $kind:ident = $tag:literal, $module:ident, $name:literal, $define:literal; )*) => {
        /// A primitive's type: the record's tag.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        #[repr(u32)]
        pub enum PrimitiveKind {
            $( $(#[$doc])* $kind = $tag, )*
        }

        impl PrimitiveKind {
            /// Every primitive, in tag order: the order of the plain loop's per-type
            /// loops too ([`sort_for_loops`]).
            pub const ALL: &'static [PrimitiveKind] = &[$(PrimitiveKind::$kind),*];

            pub fn from_tag(tag: u32) -> Option<Self> {
                match tag {
                    $( $tag => Some(PrimitiveKind::$kind), )*
                    _ => None,
                }
            }

            /// Its name: its WGSL file and the prefix of its functions.
            pub fn name(self) -> &'static str {
                match self {
                    $( PrimitiveKind::$kind => $name, )*
                }
            }

            /// The shader define that keeps its code.
            pub fn define(self) -> &'static str {
                match self {
                    $( PrimitiveKind::$kind => $define, )*
                }
            }

            /// Its view: the names of its places in the record.
            pub fn view(self) -> &'static View {
                match self {
                    $( PrimitiveKind::$kind => &$module::Params::VIEW, )*
                }
            }

            /// Whether it has bounds (a BVH leaf) or is tested on its own before the
            /// BVH (planes).
            pub fn bounded(self) -> bool {
                match self {
                    $( PrimitiveKind::$kind => <$module::Params as Shape>::BOUNDED, )*
                }
            }

            /// Whether it can be sampled as a light: its WGSL file has `NAME_light_sample`,
            /// `NAME_light_pdf` and `NAME_light_distance`.
            pub fn light(self) -> bool {
                match self {
                    $( PrimitiveKind::$kind => <$module::Params as Shape>::LIGHT, )*
                }
            }

            /// Whether its code reads `shape_data` beyond a transform (a mesh's vertex
            /// attributes).
            pub fn reads_shape_data(self) -> bool {
                match self {
                    $( PrimitiveKind::$kind => <$module::Params as Shape>::SHAPE_DATA, )*
                }
            }
        }

        /// Object-space bounds of a bounded primitive (an empty box at 0 for an unknown
        /// tag or an unbounded type).
        pub fn local_bounds(p: &Primitive) -> Aabb {
            match PrimitiveKind::from_tag(p.tag) {
                $( Some(PrimitiveKind::$kind) if <$module::Params as Shape>::BOUNDED => {
                    $module::Params::read(p).bounds()
                } )*
                _ => Aabb { lo: Vec3::ZERO, hi: Vec3::ZERO },
            }
        }

        /// Surface area in the primitive's own space (0 for an unknown tag).
        pub fn local_area(p: &Primitive) -> f32 {
            match PrimitiveKind::from_tag(p.tag) {
                $( Some(PrimitiveKind::$kind) => $module::Params::read(p).area(), )*
                None => 0.0,
            }
        }

        /// Whether the record's own values make a shape (sizes above 0, unit normals).
        pub fn shape_ok(p: &Primitive) -> bool {
            match PrimitiveKind::from_tag(p.tag) {
                $( Some(PrimitiveKind::$kind) => $module::Params::read(p).usable(), )*
                None => true,
            }
        }

        /// A light's geometry for the primitive: its record's places, in world space
        /// under the similarity (linear part `m`, translation `t`, scale `s`), or None
        /// when its type cannot be sampled.
        pub fn light_geometry(p: &Primitive, m: Mat3, t: Vec3, s: f32) -> Option<Primitive> {
            match PrimitiveKind::from_tag(p.tag) {
                $( Some(PrimitiveKind::$kind) => {
                    let world = $module::Params::read(p).light(m, t, s)?;
                    let mut out = Primitive::default();
                    world.write(&mut out);
                    Some(out)
                } )*
                None => None,
            }
        }
    };
}

for_each_primitive!(primitive_types);

impl PrimitiveKind {
    /// Its tag in the record.
    pub fn tag(self) -> u32 {
        self as u32
    }

    /// Its tag's name in the shaders (`PRIM_SPHERE`).
    pub fn wgsl_tag(self) -> String {
        format!("PRIM_{}", self.name().to_ascii_uppercase())
    }
}

// a light with a surface has its primitive's tag as its kind, below the other lights'
const _: () = {
    let mut i = 0;
    while i < PrimitiveKind::ALL.len() {
        assert!((PrimitiveKind::ALL[i] as u32) < super::records::LIGHT_ENVIRONMENT);
        i += 1;
    }
};

/// The primitive tags as shader constants (`PRIM_SPHERE`, ...).
pub fn tag_constants() -> Vec<(String, u32)> {
    PrimitiveKind::ALL
        .iter()
        .map(|k| (k.wgsl_tag(), k.tag()))
        .collect()
}

/// Sorts bounded primitives by type, in the order of the plain loop's per-type loops
/// (`gpu::codegen::primitives` writes one loop per type present, in [`PrimitiveKind::ALL`]'s
/// order, each ending at the first record of another type); stable, so the records of a
/// type keep their order.
pub fn sort_for_loops(primitives: &mut [Primitive]) {
    let rank = |p: &Primitive| {
        PrimitiveKind::ALL
            .iter()
            .position(|k| k.tag() == p.tag)
            .unwrap_or(usize::MAX)
    };
    primitives.sort_by_key(rank);
}
