//! Trace pipelines: the shader assembled for one [`ShaderSpec`], with a layout holding only
//! the slots that shader reads. `gpu::context` keeps the compiled ones, one per spec and
//! process (and, where the driver keeps one, in the pipeline cache on disk).

use std::time::{Duration, Instant};

use super::bindings::{layout, Slot};
use super::error::GpuError;
use super::plan::{Feature, ShaderSpec};

/// A compiled trace pipeline.
pub struct TracePipeline {
    pub pipeline: wgpu::ComputePipeline,
    /// Splat reconstruction's second pass (`trace.wgsl`'s `gather`), for a spec that
    /// splats.
    pub gather: Option<wgpu::ComputePipeline>,
    pub layout: wgpu::BindGroupLayout,
    /// The slots of group 0 the shader reads; only these are in the layout and bound.
    pub slots: Vec<Slot>,
    /// Size of the assembled WGSL.
    pub shader_bytes: usize,
    /// Wall time to assemble and compile it.
    pub compile_time: Duration,
    /// Whether a submission has used it (llvmpipe compiles a shader at its first
    /// dispatch: `GpuContext::wait_first`).
    pub dispatched: std::sync::atomic::AtomicBool,
}

/// Compiles the trace pipeline for `spec` on `device`, through the driver's pipeline
/// `cache` when given. wgpu parses and validates the WGSL, once.
pub fn compile_trace_pipeline(
    device: &wgpu::Device,
    spec: &ShaderSpec,
    cache: Option<&wgpu::PipelineCache>,
) -> Result<TracePipeline, GpuError> {
    let start = Instant::now();
    let wgsl = spec.wgsl("trace")?;
    let slots = spec.trace_slots();
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("trace.wgsl"),
        source: wgpu::ShaderSource::Wgsl(wgsl.as_str().into()),
    });
    let layout = layout(device, &slots, &spec.placements);
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("trace layout"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("trace"),
        layout: Some(&pipeline_layout),
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache,
    });
    let gather = spec.features.contains(Feature::Splat).then(|| {
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("gather"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("gather"),
            compilation_options: Default::default(),
            cache,
        })
    });
    Ok(TracePipeline {
        pipeline,
        gather,
        layout,
        slots,
        shader_bytes: wgsl.len(),
        compile_time: start.elapsed(),
        dispatched: Default::default(),
    })
}
