//! The intersection kernel (`shaders/kernel.wgsl`): a batch of rays through the GPU's
//! closest-hit search and `surface_at`, for tests that compare the GPU with the CPU
//! reference ray by ray.

use wgpu::util::DeviceExt;

use super::context::{GpuContext, GpuError};
use super::render::{
    check_loop_limit, check_scene_fits, read_mapped, scene_bindings, scene_layout,
};
use super::shader;
use crate::scene::records::{KernelHit, KernelRay};
use crate::scene::FlatScene;

/// Workgroup size of `kernel.wgsl`'s entry point.
const WORKGROUP: u32 = 64;

/// Intersects `rays` with `scene` on the GPU; one [`KernelHit`] per ray, in order.
pub fn intersect_rays(
    ctx: &GpuContext,
    scene: &FlatScene,
    rays: &[KernelRay],
) -> Result<Vec<KernelHit>, GpuError> {
    if rays.is_empty() {
        return Ok(Vec::new());
    }
    let device = &ctx.device;
    check_scene_fits(device, scene)?;
    check_loop_limit(ctx, scene, false)?;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("kernel.wgsl"),
        source: wgpu::ShaderSource::Wgsl(shader::kernel_shader()?.into()),
    });
    let scene_bgl = scene_layout(device);
    let storage = |binding, read_only| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let io_bgl = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("kernel io"),
        entries: &[storage(0, true), storage(1, false)],
    });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("kernel layout"),
        bind_group_layouts: &[Some(&scene_bgl), Some(&io_bgl)],
        immediate_size: 0,
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("kernel"),
        layout: Some(&layout),
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });

    // The kernel never touches the accumulation buffer; one element keeps the group valid.
    let accum = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("unused accumulation"),
        size: 32,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let scene_group = scene_bindings(device, &scene_bgl, scene, &accum);
    let params = scene.params(0, scene.full_tile());
    ctx.queue
        .write_buffer(&scene_group.params, 0, bytemuck::bytes_of(&params));

    let ray_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("rays"),
        contents: bytemuck::cast_slice(rays),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let hits_size = (rays.len() * std::mem::size_of::<KernelHit>()) as u64;
    let hit_buf = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("hits"),
        size: hits_size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("hits readback"),
        size: hits_size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let io_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("kernel io"),
        layout: &io_bgl,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: ray_buf.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: hit_buf.as_entire_binding(),
            },
        ],
    });

    let mut encoder =
        device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("kernel pass"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &scene_group.group, &[]);
        pass.set_bind_group(1, &io_group, &[]);
        pass.dispatch_workgroups((rays.len() as u32).div_ceil(WORKGROUP), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&hit_buf, 0, &readback, 0, hits_size);
    ctx.queue.submit([encoder.finish()]);
    read_mapped(device, &readback)
}
