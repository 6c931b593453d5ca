//! The test kernels (`shaders/kernel.wgsl`): a batch of rays through the GPU's closest-hit
//! search and `surface_at`, of texture look-ups, of materials at hits, or of lights
//! sampled from points, for tests that compare the GPU with the CPU reference one by one.

use wgpu::util::DeviceExt;

use super::bindings::{bind_scene, layout, scene_buffers, Slot};
use super::context::GpuContext;
use super::error::GpuError;
use super::fault;
use super::plan::{Feature, GpuPlan};
use crate::scene::flat::FlatScene;
use crate::scene::records::{
    KernelHit, KernelRay, LightQuery, LightReply, MaterialQuery, MaterialReply, PathQuery,
    PathStep, TextureLookup, BVH_STACK_LANES, PATH_STEPS,
};
use crate::tuning::Tuning;

/// Workgroup size of `kernel.wgsl`'s entry points: one invocation per column of the
/// traversal stacks.
const WORKGROUP: u32 = BVH_STACK_LANES;

/// Group-1 bindings of `kernel.wgsl`: the inputs and outputs of `main`, `textures_main`,
/// `materials_main` and `lights_main` (`tests/shaders.rs` holds them to naga's view of the
/// shader).
pub const KERNEL_IO: [(&str, u32); 10] = [
    ("rays", 0),
    ("hits", 1),
    ("lookups", 2),
    ("colors", 3),
    ("material_queries", 4),
    ("material_replies", 5),
    ("light_queries", 6),
    ("light_replies", 7),
    ("path_queries", 8),
    ("path_steps", 9),
];

/// The plan `tuning` gives `scene` on the device, refused when one ray's loops would pass
/// the device's loop limit, and the scene the device gets under it (perturbed by
/// `--tune perturb`, `gpu::fault`, else the scene itself).
fn plan(
    ctx: &GpuContext,
    scene: &FlatScene,
    tuning: &Tuning,
) -> Result<(GpuPlan, Option<FlatScene>), GpuError> {
    let (plan, perturbed) = fault::device_plan(scene, &ctx.fit(), tuning);
    plan.fit.check_loops(plan.ray_loops)?;
    Ok((plan, perturbed))
}

/// The group-1 bindings of kernel `k` of [`KERNEL_IO`]: its inputs and its outputs.
fn io(k: usize) -> [u32; 2] {
    [KERNEL_IO[2 * k].1, KERNEL_IO[2 * k + 1].1]
}

/// Intersects `rays` with `scene` on the GPU, under the plan `tuning` gives it (its record
/// placements: `Tuning::default()` for a render's); one [`KernelHit`] per ray, in order.
pub fn intersect_rays(
    ctx: &GpuContext,
    scene: &FlatScene,
    tuning: &Tuning,
    rays: &[KernelRay],
) -> Result<Vec<KernelHit>, GpuError> {
    let (plan, device_scene) = plan(ctx, scene, tuning)?;
    let scene = device_scene.as_ref().unwrap_or(scene);
    run_kernel(ctx, scene, &plan, "main", io(0), rays)
}

/// Looks textures up on the GPU (`texture_value`); one linear RGB colour (`.w` = 0) each.
pub fn lookup_textures(
    ctx: &GpuContext,
    scene: &FlatScene,
    tuning: &Tuning,
    lookups: &[TextureLookup],
) -> Result<Vec<[f32; 4]>, GpuError> {
    let (plan, device_scene) = plan(ctx, scene, tuning)?;
    let scene = device_scene.as_ref().unwrap_or(scene);
    run_kernel(ctx, scene, &plan, "textures_main", io(1), lookups)
}

/// Asks the GPU's materials what the integrator asks of them (`materials_main`): each
/// query's material at its hit, scattered, evaluated and its pdf taken toward `wi`. A
/// query's shading normal may differ from its geometric one whatever the scene's
/// primitives, so the shading of such normals is compiled in.
pub fn shade_materials(
    ctx: &GpuContext,
    scene: &FlatScene,
    tuning: &Tuning,
    queries: &[MaterialQuery],
) -> Result<Vec<MaterialReply>, GpuError> {
    let (mut plan, device_scene) = plan(ctx, scene, tuning)?;
    let scene = device_scene.as_ref().unwrap_or(scene);
    plan.shader.features.insert(Feature::ShadingNormals);
    run_kernel(ctx, scene, &plan, "materials_main", io(2), queries)
}

/// Samples the GPU's lights from each query's point (`lights_main`), with the pdfs of what
/// they sampled and of the query's direction.
pub fn sample_lights(
    ctx: &GpuContext,
    scene: &FlatScene,
    tuning: &Tuning,
    queries: &[LightQuery],
) -> Result<Vec<LightReply>, GpuError> {
    let (plan, device_scene) = plan(ctx, scene, tuning)?;
    let scene = device_scene.as_ref().unwrap_or(scene);
    run_kernel(ctx, scene, &plan, "lights_main", io(3), queries)
}

/// Traces each query's camera path on the GPU (`paths_main`) as a render's `main` traces
/// it: `PATH_STEPS` states per query, in order (the start, then one after each
/// `extend_path`, the last slot the final state).
pub fn trace_paths(
    ctx: &GpuContext,
    scene: &FlatScene,
    tuning: &Tuning,
    queries: &[PathQuery],
) -> Result<Vec<PathStep>, GpuError> {
    let (plan, device_scene) = plan(ctx, scene, tuning)?;
    let scene = device_scene.as_ref().unwrap_or(scene);
    let steps: Vec<[PathStep; PATH_STEPS as usize]> =
        run_kernel(ctx, scene, &plan, "paths_main", io(4), queries)?;
    Ok(steps.into_iter().flatten().collect())
}

/// Dispatches one invocation per input of entry point `entry` of `kernel.wgsl`, with the
/// scene in group 0 (every slot bound, its texel banks only) and the inputs and outputs at `bindings` of group 1.
fn run_kernel<I: bytemuck::Pod, O: bytemuck::Pod>(
    ctx: &GpuContext,
    scene: &FlatScene,
    plan: &GpuPlan,
    entry: &str,
    bindings: [u32; 2],
    inputs: &[I],
) -> Result<Vec<O>, GpuError> {
    if inputs.is_empty() {
        return Ok(Vec::new());
    }
    let device = &ctx.device;
    plan.fit.check_scene(scene)?;
    let spec = &plan.shader;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("kernel.wgsl"),
        source: wgpu::ShaderSource::Wgsl(spec.wgsl("kernel")?.into()),
    });
    // every slot but the texel banks the scene does not have
    let slots: Vec<Slot> = Slot::ALL
        .into_iter()
        .filter(|s| !matches!(s, Slot::Texels(i) if u32::from(*i) >= spec.banks))
        .collect();
    let scene_bgl = layout(device, &slots, &spec.placements);
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
        entries: &[storage(bindings[0], true), storage(bindings[1], false)],
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
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    });

    // The kernels never touch the accumulation buffer nor a splatting plan's sample
    // buffer; one element each keeps the group valid.
    let accum = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("unused accumulation"),
        size: 32,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let buffers = scene_buffers(device, &ctx.queue, &slots, &spec.placements, scene, 0)?;
    let samples = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("unused samples"),
        size: 16,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let scene_group = bind_scene(device, &scene_bgl, &slots, &buffers, &accum, Some(&samples));
    let params = scene.params(0, scene.full_band());
    ctx.queue
        .write_buffer(&buffers.params, 0, bytemuck::bytes_of(&params));

    let input_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("kernel inputs"),
        contents: bytemuck::cast_slice(inputs),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let out_size = (inputs.len() * std::mem::size_of::<O>()) as u64;
    let out_buf = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("kernel outputs"),
        size: out_size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("kernel readback"),
        size: out_size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let io_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("kernel io"),
        layout: &io_bgl,
        entries: &[
            wgpu::BindGroupEntry {
                binding: bindings[0],
                resource: input_buf.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: bindings[1],
                resource: out_buf.as_entire_binding(),
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
        pass.set_bind_group(0, &scene_group, &[0]);
        pass.set_bind_group(1, &io_group, &[]);
        pass.dispatch_workgroups((inputs.len() as u32).div_ceil(WORKGROUP), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&out_buf, 0, &readback, 0, out_size);
    ctx.queue.submit([encoder.finish()]);
    ctx.read_buffer(&readback)
}
