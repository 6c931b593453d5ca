//! wgtrace: a path tracer whose per-pixel work runs in WGSL compute shaders through wgpu on
//! Vulkan, with a CPU reference that runs the same algorithms in plain Rust.
//!
//! Data flows one way: scene file -> [`scene`] (parse, validate, flatten into records) ->
//! a backend ([`gpu`] or [`cpu`], behind [`engine::Engine`]) -> [`accumulation`] ->
//! [`image_io`]. A [`session::Session`] drives a render from a loaded scene to its sums;
//! [`tuning`] holds the knobs of how it runs. Files of the crate import each other by
//! their own paths, never through the re-exports below, which are for the binary, the
//! tests and the benchmarks.

pub mod accumulation;
pub mod aov;
pub mod check;
pub mod checkpoint;
pub mod converge;
pub mod cpu;
pub mod denoise;
pub mod engine;
pub mod gpu;
pub mod image_io;
pub mod report;
pub mod scene;
pub mod session;
pub mod spot_check;
pub mod tuning;

pub use accumulation::Accumulation;
pub use engine::{BackendChoice, Engine};
pub use scene::{FlatScene, Overrides};
pub use session::{load_scene, load_scene_str, render_scene, Session, SessionOptions, StopRule};
pub use tuning::Tuning;
