//! The GPU backend: wgpu on Vulkan. Reads `scene::records`; never imports the CPU backend.

pub mod context;
pub mod kernel;
pub mod pipeline;
pub mod render;
pub mod shader;

pub use context::{list_adapters, GpuContext, GpuError};
pub use pipeline::TracePipeline;
pub use render::GpuRenderer;
