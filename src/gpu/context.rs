//! Adapter and device: the first Vulkan adapter, preferring real GPUs over software ones.
//! One device per adapter is shared by every render of a process, so pipelines compiled
//! for one render serve the next.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

use super::error::GpuError;
use super::limits::DeviceFit;
use super::pipeline::{compile_trace_pipeline, TracePipeline};
use super::plan::ShaderSpec;
use super::select::{select, wants_uuids, AdapterFacts, Selected};

/// An open device on one adapter, with the trace pipelines compiled on it so far (one per
/// shader spec: feature set and scene code) and, where the driver supports one, a pipeline cache kept on disk.
pub struct GpuContext {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pipelines: Mutex<HashMap<ShaderSpec, Arc<TracePipeline>>>,
    disk_cache: Option<DiskCache>,
    /// The first error wgpu reported outside an error scope, or the device's loss: set by
    /// the device's callbacks, turned into a `GpuError` by [`GpuContext::check`].
    fault: Arc<Mutex<Option<Fault>>>,
}

/// How long the first submission of a pipeline may wait before the compile notice is
/// given ([`GpuContext::wait_first`]).
pub const COMPILE_NOTICE_AFTER: std::time::Duration = std::time::Duration::from_millis(1500);

static COMPILE_NOTICE: OnceLock<Box<dyn Fn() + Send + Sync>> = OnceLock::new();
static COMPILING: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// Sets what is called, once per slow first dispatch of a pipeline, while the driver
/// compiles its shader (the CLI prints a line); the first call wins.
pub fn set_compile_notice(notice: impl Fn() + Send + Sync + 'static) {
    let _ = COMPILE_NOTICE.set(Box::new(notice));
}

/// Whether a first dispatch is waiting (on the driver's compile, on llvmpipe), so that no
/// sample of this process's renders is in flight that an interrupt could keep.
pub fn compiling() -> bool {
    COMPILING.load(std::sync::atomic::Ordering::SeqCst) > 0
}

/// Runs `f`, which may wait on the driver compiling a shader: when it takes longer than
/// [`COMPILE_NOTICE_AFTER`], the notice set by [`set_compile_notice`] is called once, and
/// [`compiling`] is true while it runs.
fn watch_compile<T>(f: impl FnOnce() -> T) -> T {
    use std::sync::atomic::Ordering;
    COMPILING.fetch_add(1, Ordering::SeqCst);
    let (done, waiting) = std::sync::mpsc::channel::<()>();
    let watch = std::thread::spawn(move || {
        if let Err(std::sync::mpsc::RecvTimeoutError::Timeout) =
            waiting.recv_timeout(COMPILE_NOTICE_AFTER)
        {
            if let Some(notice) = COMPILE_NOTICE.get() {
                notice();
            }
        }
    });
    let result = f();
    let _ = done.send(());
    let _ = watch.join();
    COMPILING.fetch_sub(1, Ordering::SeqCst);
    result
}

/// What went wrong with a device, as its callbacks report it.
#[derive(Debug, Clone)]
enum Fault {
    Lost(String),
    Failed(String),
}

thread_local! {
    /// Set while a wgpu call that panics on a lost device runs under `catch_unwind`: the
    /// panic is turned into a `GpuError`, so its message is not printed.
    static QUIET_PANICS: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Runs `f`, turning a panic into its message. wgpu 30 panics where a wait meets a lost
/// device (`Device::poll` treats every error but a timeout as fatal); the render turns
/// that into [`GpuError::Lost`] and keeps its finished work.
fn catch_panic<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET_PANICS.with(|q| q.get()) {
                previous(info)
            }
        }));
    });
    QUIET_PANICS.with(|q| q.set(true));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    QUIET_PANICS.with(|q| q.set(false));
    result.map_err(|payload| {
        payload
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_else(|| "wgpu panicked".into())
    })
}

/// A driver pipeline cache and the file it is loaded from and saved to.
struct DiskCache {
    pub cache: wgpu::PipelineCache,
    pub path: PathBuf,
}

/// Where compiled pipelines persist between runs: `$WGTRACE_CACHE_DIR` (empty or `off`:
/// nowhere), else `$XDG_CACHE_HOME/wgtrace`, else `~/.cache/wgtrace`.
pub fn cache_dir() -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os("WGTRACE_CACHE_DIR") {
        if dir.is_empty() || dir == "off" {
            return None;
        }
        return Some(PathBuf::from(dir));
    }
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|d| !d.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?;
    Some(base.join("wgtrace"))
}

/// The open contexts of this process, by adapter index.
fn shared_contexts() -> &'static Mutex<HashMap<usize, Arc<GpuContext>>> {
    static CONTEXTS: OnceLock<Mutex<HashMap<usize, Arc<GpuContext>>>> = OnceLock::new();
    CONTEXTS.get_or_init(Default::default)
}

fn instance() -> wgpu::Instance {
    quiet_device_select();
    llvmpipe_vector_width();
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::VULKAN;
    wgpu::Instance::new(desc)
}

/// Turns off Mesa's device-selection layer for this process, unless the user configured
/// it (`MESA_VK_DEVICE_SELECT`, `NODEVICE_SELECT`). The layer only reorders adapters, which
/// wgtrace ranks itself ([`rank`]); but on a headless machine it asks Wayland for the
/// default GPU, and libwayland prints `error: XDG_RUNTIME_DIR is invalid or not set in the
/// environment.` to stderr, once per instance, before renders that then succeed. Turned
/// off by the variable its manifest names (`"disable_environment": {"NODEVICE_SELECT":
/// "1"}`), read when the Vulkan loader creates an instance; the driver's own messages are
/// left alone.
fn quiet_device_select() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let configured = ["MESA_VK_DEVICE_SELECT", "NODEVICE_SELECT"]
            .iter()
            .any(|v| std::env::var_os(v).is_some());
        if !configured {
            // SAFETY (in the 2024 edition's terms): set once, before this process creates
            // its first Vulkan instance; wgtrace reads no other variable concurrently.
            std::env::set_var("NODEVICE_SELECT", "1");
        }
    });
}

/// Runs llvmpipe (lavapipe) 512 bits wide, 16 lanes, on a CPU with AVX-512, unless the
/// user set `LP_NATIVE_VECTOR_WIDTH`: llvmpipe keeps to 256 bits by default, where
/// Mitsuba's LLVM backend runs 16 lanes on such CPUs. Measured on `bench/nefertiti.toml` at
/// 32 spp on an AVX-512 machine: 0.546 and 0.582 Msamples/s at 256 bits, 0.621 and 0.627 at
/// 512 (issue 32). The variable is read by llvmpipe when the Vulkan loader first loads it;
/// other drivers ignore it. Nothing in the shaders depends on the subgroup size: the
/// traversal stacks have a column per invocation of the workgroup, and sample groups are
/// per invocation.
fn llvmpipe_vector_width() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        if std::env::var_os("LP_NATIVE_VECTOR_WIDTH").is_none() && has_avx512() {
            // SAFETY (in the 2024 edition's terms): as quiet_device_select's
            std::env::set_var("LP_NATIVE_VECTOR_WIDTH", "512");
        }
    });
}

/// Whether the CPU runs AVX-512's foundation, byte-word and double-quadword instructions.
fn has_avx512() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx512bw")
            && std::arch::is_x86_feature_detected!("avx512dq")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
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

/// What choosing an adapter needs to know of each (see [`select_adapter`]), in the order
/// `--adapter` counts them, with their device UUIDs.
pub fn adapter_facts() -> Vec<AdapterFacts> {
    facts(true)
}

/// The adapters' facts; their UUIDs only when `uuids` (a query of its own per adapter).
fn facts(uuids: bool) -> Vec<AdapterFacts> {
    adapters()
        .iter()
        .map(|a| {
            let info = a.get_info();
            AdapterFacts {
                name: info.name.clone(),
                vendor: info.vendor,
                pci_bus_id: info.device_pci_bus_id.clone(),
                uuid: uuids.then(|| device_uuid(a)).flatten(),
            }
        })
        .collect()
}

/// Vulkan's `deviceUUID` of an adapter (VkPhysicalDeviceIDProperties, Vulkan 1.1), which
/// wgpu does not report; None on a Vulkan 1.0 instance or device.
fn device_uuid(adapter: &wgpu::Adapter) -> Option<[u8; 16]> {
    // SAFETY: the raw handles are used only for this query, while `adapter` lives
    let hal = unsafe { adapter.as_hal::<wgpu::hal::api::Vulkan>() }?;
    let v1_1 = ash::vk::API_VERSION_1_1;
    if hal.shared_instance().instance_api_version() < v1_1
        || hal.physical_device_capabilities().properties().api_version < v1_1
    {
        return None;
    }
    let instance = hal.shared_instance().raw_instance();
    let mut id = ash::vk::PhysicalDeviceIDProperties::default();
    let mut props = ash::vk::PhysicalDeviceProperties2::default().push_next(&mut id);
    // SAFETY: a valid physical device of this instance, and a valid chain
    unsafe { instance.get_physical_device_properties2(hal.raw_physical_device(), &mut props) };
    Some(id.device_uuid)
}

/// The adapter a render uses: `--adapter` (an index of [`list_adapters`], or part of a
/// name) when given, else the GPU a cluster assigned (`CUDA_VISIBLE_DEVICES`,
/// `ROCR_VISIBLE_DEVICES`, `HIP_VISIBLE_DEVICES`; `gpu::select`), else the preferred one.
pub fn select_adapter(arg: Option<&str>) -> Result<Selected, GpuError> {
    let var = |name: &str| std::env::var(name).ok();
    let uuids = arg.is_none() && wants_uuids(&var);
    select(arg, &var, &facts(uuids)).map_err(GpuError::Adapter)
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
    /// The process's context on adapter `index` of [`list_adapters`], opened on first use.
    pub fn shared(index: usize) -> Result<Arc<Self>, GpuError> {
        let mut contexts = shared_contexts().lock().unwrap_or_else(|e| e.into_inner());
        // a context whose device was lost is replaced by a new one
        if let Some(ctx) = contexts.get(&index).filter(|c| c.check().is_ok()) {
            return Ok(ctx.clone());
        }
        let ctx = Arc::new(Self::new(index)?);
        contexts.insert(index, ctx.clone());
        Ok(ctx)
    }

    /// Opens adapter `index` of [`list_adapters`] (0: the preferred one) on a device of its
    /// own.
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
        let cache_file = cache_dir()
            .zip(wgpu::util::pipeline_cache_key(&info))
            .filter(|_| adapter.features().contains(wgpu::Features::PIPELINE_CACHE))
            .map(|(dir, key)| dir.join(format!("{key}.bin")));
        let mut required_features = if cache_file.is_some() {
            wgpu::Features::PIPELINE_CACHE
        } else {
            wgpu::Features::empty()
        };
        // subgroup operations, where the adapter has them: only `--tune lane-stats`'s
        // shader uses them
        required_features |= adapter.features() & wgpu::Features::SUBGROUP;
        let (device, queue) =
            pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
                label: Some("wgtrace"),
                required_features,
                required_limits: adapter.limits(),
                ..Default::default()
            }))?;
        let fault: Arc<Mutex<Option<Fault>>> = Arc::default();
        let record = |fault: &Arc<Mutex<Option<Fault>>>, new: Fault| {
            let mut slot = fault.lock().unwrap_or_else(|e| e.into_inner());
            // the first fault is the cause; a lost device outranks what it caused
            if !matches!(*slot, Some(Fault::Lost(_)))
                && (slot.is_none() || matches!(new, Fault::Lost(_)))
            {
                *slot = Some(new);
            }
        };
        {
            let fault = fault.clone();
            device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
                record(&fault, Fault::Failed(e.to_string()));
            }));
        }
        {
            let fault = fault.clone();
            device.set_device_lost_callback(move |reason, message| {
                let why = match reason {
                    wgpu::DeviceLostReason::Destroyed => "destroyed",
                    wgpu::DeviceLostReason::Unknown => "driver error",
                };
                let message = if message.is_empty() {
                    why.to_string()
                } else {
                    format!("{why}: {message}")
                };
                record(&fault, Fault::Lost(message));
            });
        }
        let disk_cache = cache_file.map(|path| {
            let data = std::fs::read(&path).ok();
            // SAFETY: the data was written by `get_data` of a cache with the same key (the
            // adapter's vendor and device), or is unreadable and then ignored: with
            // `fallback` the driver validates it and starts empty when it does not match.
            let cache = unsafe {
                device.create_pipeline_cache(&wgpu::PipelineCacheDescriptor {
                    label: Some("wgtrace pipelines"),
                    data: data.as_deref(),
                    fallback: true,
                })
            };
            DiskCache { cache, path }
        });
        Ok(Self {
            adapter,
            device,
            queue,
            info,
            pipelines: Mutex::new(HashMap::new()),
            disk_cache,
            fault,
        })
    }

    /// The device's first fault so far (lost, or an error wgpu reported), if any.
    pub fn check(&self) -> Result<(), GpuError> {
        let slot = self.fault.lock().unwrap_or_else(|e| e.into_inner());
        match &*slot {
            None => Ok(()),
            Some(Fault::Lost(m)) => Err(GpuError::Lost(m.clone())),
            Some(Fault::Failed(m)) => Err(GpuError::Failed(m.clone())),
        }
    }

    /// Waits for everything submitted so far; a lost device or an error reported meanwhile
    /// is returned rather than panicking.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.check()?;
        let waited = catch_panic(|| self.device.poll(wgpu::PollType::wait_indefinitely()));
        self.check()?;
        match waited {
            Ok(Ok(_)) => Ok(()),
            Ok(Err(e)) => Err(GpuError::Failed(e.to_string())),
            Err(panic) => Err(GpuError::Lost(panic)),
        }
    }

    /// [`Self::wait`] for a submission that used `pipeline`. The first one that does may
    /// wait on the driver compiling its shader (llvmpipe compiles at the first dispatch:
    /// seconds for a specialized shader, minutes for the full one); when that wait passes
    /// [`COMPILE_NOTICE_AFTER`], the notice set by [`set_compile_notice`] is called once
    /// (the CLI prints a line), and [`compiling`] is true until it ends, so a Ctrl-C
    /// handler can end the program at once rather than after it.
    pub fn wait_first(&self, pipeline: &TracePipeline) -> Result<(), GpuError> {
        use std::sync::atomic::Ordering;
        if pipeline.dispatched.swap(true, Ordering::SeqCst) {
            return self.wait();
        }
        watch_compile(|| self.wait())
    }

    /// What the device can hold and run, for its plans.
    pub fn fit(&self) -> DeviceFit {
        DeviceFit {
            subgroups: self.device.features().contains(wgpu::Features::SUBGROUP),
            ..DeviceFit::new(&self.device.limits(), &self.info.name)
        }
    }

    /// The trace pipeline for `spec`: compiled on first request, then shared by every
    /// render of this process.
    pub fn trace_pipeline(&self, spec: &ShaderSpec) -> Result<Arc<TracePipeline>, GpuError> {
        let lock = || self.pipelines.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(p) = lock().get(spec) {
            return Ok(p.clone());
        }
        // compiled outside the lock: two renders that race compile twice, and keep one
        let cache = self.disk_cache.as_ref().map(|d| &d.cache);
        let p = Arc::new(watch_compile(|| {
            compile_trace_pipeline(&self.device, spec, cache)
        })?);
        let p = lock().entry(spec.clone()).or_insert(p).clone();
        self.save_disk_cache();
        Ok(p)
    }

    /// Maps a MAP_READ buffer whose copy has been submitted, waits, and returns its
    /// contents.
    pub fn read_buffer<T: bytemuck::Pod>(&self, buffer: &wgpu::Buffer) -> Result<Vec<T>, GpuError> {
        let (tx, rx) = std::sync::mpsc::channel();
        buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.wait()?;
        rx.recv()
            .map_err(|e| GpuError::Readback(e.to_string()))?
            .map_err(|e| GpuError::Readback(e.to_string()))?;
        let data = {
            let view = buffer
                .get_mapped_range(..)
                .map_err(|e| GpuError::Readback(e.to_string()))?;
            bytemuck::cast_slice::<u8, T>(&view).to_vec()
        };
        buffer.unmap();
        Ok(data)
    }

    /// Writes the pipeline cache back to its file (write then rename, so a reader never sees
    /// half a file). Failures are ignored: the cache only saves time.
    fn save_disk_cache(&self) {
        let Some(disk) = &self.disk_cache else {
            return;
        };
        let Some(data) = disk.cache.get_data() else {
            return;
        };
        // unique per process and per save, as renders on several threads may save at once
        static SAVES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let n = SAVES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let tmp = disk
            .path
            .with_extension(format!("tmp{}-{n}", std::process::id()));
        let written = disk
            .path
            .parent()
            .map_or(Ok(()), std::fs::create_dir_all)
            .and_then(|_| std::fs::write(&tmp, &data))
            .and_then(|_| std::fs::rename(&tmp, &disk.path));
        if written.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
    }

    /// Whether compiled pipelines persist on disk between runs on this adapter.
    pub fn has_disk_cache(&self) -> bool {
        self.disk_cache.is_some()
    }
}
