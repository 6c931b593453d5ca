//! Trace pipelines: the shader assembled for one feature set, with a layout holding only
//! the bindings that shader uses, compiled once per process and feature set (and, where the
//! driver keeps one, through the pipeline cache on disk).

use std::sync::Arc;
use std::time::{Duration, Instant};

use super::context::{GpuContext, GpuError};
use super::render::scene_layout;
use super::shader::{self, ShaderSpec};

/// A compiled trace pipeline.
pub struct TracePipeline {
    pub pipeline: wgpu::ComputePipeline,
    pub layout: wgpu::BindGroupLayout,
    /// Bindings of group 0 (`shaders/shared/bindings.wgsl`) the shader uses; only these are
    /// in the layout and bound.
    pub bindings: Vec<u32>,
    /// Those of them, other than the parameters, that are uniform buffers (UNIFORM_*
    /// defines) rather than storage buffers.
    pub uniform: Vec<u32>,
    /// Size of the assembled WGSL.
    pub shader_bytes: usize,
    /// Wall time to assemble, validate and compile it.
    pub compile_time: Duration,
}

impl GpuContext {
    /// The trace pipeline for `spec`: compiled on first request, then shared by every
    /// render of this process.
    pub fn trace_pipeline(&self, spec: &ShaderSpec) -> Result<Arc<TracePipeline>, GpuError> {
        let lock = || self.pipelines.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(p) = lock().get(spec) {
            return Ok(p.clone());
        }
        // compiled outside the lock: two renders that race compile twice, and keep one
        let p = Arc::new(self.compile_trace_pipeline(spec, true)?);
        let p = lock().entry(spec.clone()).or_insert(p).clone();
        self.save_disk_cache();
        Ok(p)
    }

    /// Compiles the trace pipeline for `spec` afresh, without this process's pipelines,
    /// and without the pipeline cache on disk unless `disk_cache` (benchmarks time this).
    pub fn compile_trace_pipeline(
        &self,
        spec: &ShaderSpec,
        disk_cache: bool,
    ) -> Result<TracePipeline, GpuError> {
        let start = Instant::now();
        let wgsl = shader::trace_shader(spec)?;
        let bindings = shader::used_bindings("trace", &wgsl, "main", 0)?;
        let uniform = shader::uniform_bindings("trace", &wgsl)?;
        let device = &self.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("trace.wgsl"),
            source: wgpu::ShaderSource::Wgsl(wgsl.as_str().into()),
        });
        let layout = scene_layout(device, &bindings, &uniform);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("trace layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let cache = self
            .disk_cache
            .as_ref()
            .filter(|_| disk_cache)
            .map(|d| &d.cache);
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("trace"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache,
        });
        Ok(TracePipeline {
            pipeline,
            layout,
            bindings,
            uniform,
            shader_bytes: wgsl.len(),
            compile_time: start.elapsed(),
        })
    }
}
