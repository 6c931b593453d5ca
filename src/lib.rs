//! wgtrace: a path tracer whose per-pixel work runs in WGSL compute shaders through wgpu on
//! Vulkan, with a CPU reference that runs the same algorithms in plain Rust.
//!
//! Data flows one way: scene file -> [`scene`] (parse, validate, flatten into records) ->
//! a backend ([`gpu`] or [`cpu`]) -> [`render::Accumulation`] -> [`image_io`].

pub mod checkpoint;
pub mod converge;
pub mod cpu;
pub mod gallery;
pub mod gpu;
pub mod image_io;
pub mod render;
pub mod scene;

pub use render::{render_scene, Accumulation, BackendChoice, Engine};
pub use scene::{load_scene, load_scene_str, FlatScene, Overrides};
