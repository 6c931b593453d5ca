//! The GPU backend: wgpu on Vulkan. Reads `scene::records`; never imports the CPU backend.
//!
//! A render's way through it: [`limits::DeviceFit`] (what the adapter holds and runs) and
//! the scene give a [`plan::GpuPlan`] (features, record placements, sample group, loop
//! verdict); the plan's [`plan::ShaderSpec`] is assembled by [`shader`] from the WGSL files
//! and what [`codegen`] and [`bindings`] write, compiled by [`pipeline`] and kept by
//! [`context`]; [`render::GpuRenderer`] uploads the buffers the plan binds and runs the
//! passes. Files here import each other by their own paths, never through the re-exports
//! below.

pub mod bindings;
pub mod codegen;
pub mod context;
pub mod error;
pub mod fault;
pub mod kernel;
pub mod limits;
pub mod pipeline;
pub mod plan;
pub mod render;
pub mod select;
pub mod shader;

pub use context::{list_adapters, GpuContext};
pub use error::GpuError;
pub use pipeline::TracePipeline;
pub use plan::GpuPlan;
pub use render::GpuRenderer;
