//! glTF 2.0 files (`.gltf` with its buffers and images, or `.glb`), read with the `gltf`
//! crate into what the rest of the loader knows ([`ImportedScene`]): meshes, placed
//! instances of them, materials and textures in the scene format's terms, cameras and
//! lights.
//!
//! Every accessor, buffer view and image is checked before it is read, so that a file
//! that lies about its sizes is refused with the JSON path of what lies, never read out
//! of bounds; the crate's own validation (indices that name nothing, missing fields) runs
//! first. Instances are flattened: each keeps its mesh by index here, and the flattener
//! writes the mesh's triangles once per instance.
//!
//! [`ImportedScene`]: crate::scene::imported::ImportedScene

pub mod accessors;
pub mod error;
pub mod file;
pub mod loader;
pub mod materials;
pub mod meshes;
pub mod meshopt;
pub mod reader;
pub mod textures;

pub use error::GltfError;
pub use file::{load_gltf, SUPPORTED_EXTENSIONS};
