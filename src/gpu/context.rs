//! Adapter and device: the first Vulkan adapter, preferring real GPUs over software ones.

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
        "a {width}x{height} image needs {needed_mib} MiB of accumulation buffer, more than \
         this adapter's {limit_mib} MiB per storage binding; use a smaller size or \
         --backend cpu"
    )]
    ImageTooLarge {
        width: u32,
        height: u32,
        needed_mib: u64,
        limit_mib: u64,
    },
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
        "this render would run {iterations} loop iterations per path (every primitive on \
         every ray with --no-bvh, every light at every bounce with light_sampling = \
         \"mixture\"), more than the {limit} that llvmpipe (lavapipe) runs before it \
         silently stops a shader's loops; use the BVH, light_sampling = \"mis\", or \
         --backend cpu"
    )]
    LoopLimit { iterations: u64, limit: u64 },
    #[error(transparent)]
    Shader(#[from] super::shader::ShaderError),
}

/// An open device on one adapter.
pub struct GpuContext {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
}

fn instance() -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::VULKAN;
    wgpu::Instance::new(desc)
}

/// Discrete before integrated before virtual before software; stable otherwise.
fn rank(info: &wgpu::AdapterInfo) -> u8 {
    match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

/// Every Vulkan adapter, in the order `--adapter` indexes them (preferred first).
fn adapters() -> Vec<wgpu::Adapter> {
    let mut list = pollster::block_on(instance().enumerate_adapters(wgpu::Backends::VULKAN));
    list.sort_by_key(|a| rank(&a.get_info()));
    list
}

/// Describes every Vulkan adapter this process can see.
pub fn list_adapters() -> Vec<wgpu::AdapterInfo> {
    adapters().iter().map(|a| a.get_info()).collect()
}

/// One line naming an adapter for the user.
pub fn describe(info: &wgpu::AdapterInfo) -> String {
    let driver = if info.driver_info.is_empty() {
        info.driver.clone()
    } else {
        format!("{} {}", info.driver, info.driver_info)
    };
    format!(
        "{} ({:?}, {:?}, {})",
        info.name, info.backend, info.device_type, driver
    )
}

impl GpuContext {
    /// Opens adapter `index` of [`list_adapters`] (0: the preferred one).
    pub fn new(index: usize) -> Result<Self, GpuError> {
        let mut list = adapters();
        if list.is_empty() {
            return Err(GpuError::NoAdapter);
        }
        if index >= list.len() {
            return Err(GpuError::BadAdapterIndex {
                index,
                count: list.len(),
            });
        }
        let adapter = list.swap_remove(index);
        let info = adapter.get_info();
        let (device, queue) =
            pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
                label: Some("wgtrace"),
                required_limits: adapter.limits(),
                ..Default::default()
            }))?;
        Ok(Self {
            adapter,
            device,
            queue,
            info,
        })
    }
}
