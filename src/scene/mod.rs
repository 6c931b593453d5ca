//! Scenes: parse (`format`), validate and flatten into the records both backends read.
//!
//! Data flows one way: file -> [`format::SceneFile`] -> [`validate`] -> [`flatten`] ->
//! [`flat::FlatScene`] (records). This module knows nothing of the backends. Files here
//! import each other by their own paths, never through the re-exports below, which are
//! for the rest of the crate and its users.

pub mod bvh;
pub mod error;
pub mod flat;
pub mod flatten;
pub mod format;
pub mod gltf;
pub mod imported;
pub mod lights;
pub mod load;
pub mod materials;
pub mod mesh;
pub mod metals;
pub mod microfacet_albedo;
pub mod mitsuba;
pub mod mtl;
pub mod primitives;
pub mod records;
pub mod shapes;
pub mod texels;
pub mod textures;
pub mod validate;
pub mod volume;

pub use error::{Problem, SceneError};
pub use flat::{Band, CameraFrame, EnvironmentMap, FlatScene, RR_DEPTH};
pub use flatten::{Acceleration, Build};
pub use load::{load, load_str, Overrides, MAX_SCENE_FILE_BYTES};
pub use validate::{MAX_DEPTH_LIMIT, MAX_IMAGE_SIDE, MAX_SPP};
