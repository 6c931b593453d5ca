//! What can go wrong on the GPU side, as one error type.

use super::shader::ShaderError;

#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "no Vulkan adapter found (install a Vulkan driver; on Debian/Ubuntu the software one is \
         `apt-get install mesa-vulkan-drivers`)"
    )]
    NoAdapter,
    #[error("adapter index {index} out of range: {count} Vulkan adapter(s) found")]
    BadAdapterIndex { index: usize, count: usize },
    #[error("cannot open the GPU device: {0}")]
    Device(#[from] wgpu::RequestDeviceError),
    #[error("GPU buffer readback failed: {0}")]
    Readback(String),
    #[error(
        "the scene's {what} buffer needs {needed_mib} MiB, more than this adapter's \
         {limit_mib} MiB per storage binding; use fewer triangles or --backend cpu"
    )]
    SceneTooLarge {
        what: &'static str,
        needed_mib: u64,
        limit_mib: u64,
    },
    #[error(
        "this render would run {iterations} loop iterations per shader invocation (its \
         group of paths; every primitive on every ray with --tune no-bvh, every light at \
         every bounce with light_sampling = \"mixture\"), more than the {limit} that \
         llvmpipe (lavapipe) runs before it silently stops a shader's loops; use the BVH, \
         light_sampling = \"mis\", or --backend cpu"
    )]
    LoopLimit { iterations: u64, limit: u64 },
    #[error(transparent)]
    Shader(#[from] ShaderError),
    #[error("the GPU device was lost ({0})")]
    Lost(String),
    #[error("the GPU reported an error: {0}")]
    Failed(String),
}
