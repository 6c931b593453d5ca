//! What can go wrong on the GPU side, as one error type.

use super::shader::ShaderError;

#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "no Vulkan adapter found (install a Vulkan driver; on Debian/Ubuntu the software one is \
         `apt-get install mesa-vulkan-drivers`)"
    )]
    NoAdapter,
    /// `--adapter` or a scheduler's variable names no usable adapter.
    #[error("{0}")]
    Adapter(String),
    #[error("adapter index {index} out of range: {count} Vulkan adapter(s) found")]
    BadAdapterIndex { index: usize, count: usize },
    #[error("cannot open the GPU device: {0}")]
    Device(#[from] wgpu::RequestDeviceError),
    #[error("GPU buffer readback failed: {0}")]
    Readback(String),
    #[error(
        "the scene's {what} need {needed_mib} MiB, more than this adapter's {limit_mib} MiB \
         per storage binding; {advice}, or render with --backend cpu"
    )]
    SceneTooLarge {
        /// The records, with their count (`"BVH nodes (2,024,301)"`).
        what: String,
        needed_mib: u64,
        limit_mib: u64,
        /// What makes them fewer.
        advice: &'static str,
    },
    #[error("the scene's image texels do not fit this adapter: {0}; use smaller images or --backend cpu")]
    TexelsTooLarge(String),
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
    #[error(
        "the GPU has no memory for the scene: {needed_mib} MiB of records and texels, of \
         which {texel_mib} MiB are image texels ({detail}); use smaller images or \
         --backend cpu"
    )]
    OutOfMemory {
        needed_mib: u64,
        texel_mib: u64,
        detail: String,
    },
    /// The spot check found the GPU's image of the scene's first sample unlike the CPU
    /// reference's under every record placement it tried (`crate::spot_check`).
    #[error(
        "{adapter} renders this scene wrong: the first sample of {pixels} pixels, rendered \
         on it and on the CPU reference, disagreed under every record placement tried \
         ({tried}); render with --backend cpu, or use another driver (on Debian 12, Mesa \
         25 from bookworm-backports renders right where Mesa 22.3.6's lavapipe on some \
         AVX-512 CPUs does not), and `wgtrace check` tells which placements this one gets \
         wrong"
    )]
    WrongResults {
        /// The adapter and its driver.
        adapter: String,
        pixels: usize,
        /// Each placement tried and what differed.
        tried: String,
    },
    #[error("the GPU device was lost ({0})")]
    Lost(String),
    #[error("the GPU reported an error: {0}")]
    Failed(String),
}
