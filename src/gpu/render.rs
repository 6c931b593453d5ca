//! Progressive rendering on the GPU: buffers, the trace pipeline, passes split into tiles,
//! and readback of the accumulation buffer.

use wgpu::util::DeviceExt;

use std::sync::Arc;
use std::time::{Duration, Instant};

use super::context::{GpuContext, GpuError};
use super::pipeline::TracePipeline;
use super::shader;
use crate::scene::records::{self, Params};
use crate::scene::{FlatScene, Tile};

/// Most pixels of one band (one accumulation buffer, 8 MiB).
pub const MAX_TILE_PIXELS: u32 = 1 << 18;

/// Accumulation bytes per pixel: two vec4<f32> (sum with count, sum of squares).
pub const ACCUM_BYTES_PER_PIXEL: u64 = 32;

/// Workgroup size of `trace.wgsl`'s entry point.
const WORKGROUP: u32 = 8;

/// Binding numbers of `shaders/shared/bindings.wgsl`, in order.
const BINDINGS: [(u32, wgpu::BufferBindingType); 9] = [
    (0, wgpu::BufferBindingType::Uniform),
    (1, wgpu::BufferBindingType::Storage { read_only: true }),
    (2, wgpu::BufferBindingType::Storage { read_only: true }),
    (3, wgpu::BufferBindingType::Storage { read_only: true }),
    (4, wgpu::BufferBindingType::Storage { read_only: false }),
    (5, wgpu::BufferBindingType::Storage { read_only: true }),
    (6, wgpu::BufferBindingType::Storage { read_only: true }),
    (7, wgpu::BufferBindingType::Storage { read_only: true }),
    (8, wgpu::BufferBindingType::Storage { read_only: true }),
];

pub struct GpuRenderer {
    ctx: Arc<GpuContext>,
    scene: FlatScene,
    pipeline: Arc<TracePipeline>,
    /// One [`Params`] per dispatch of a submission, `params_stride` bytes apart, bound
    /// with a dynamic offset.
    params: wgpu::Buffer,
    params_stride: u64,
    bands: Vec<Band>,
    /// As large as the largest band's accumulation.
    readback: wgpu::Buffer,
    submissions: Submissions,
}

/// A band of whole rows with an accumulation buffer of its own, so no buffer exceeds a
/// storage binding however large the image. A submission traces part of a band (some of
/// its rows, one sample) or all of it (one or more samples).
struct Band {
    tile: Tile,
    accum: wgpu::Buffer,
    group: wgpu::BindGroup,
}

/// Most dispatches (sample groups of one band) in one submission.
pub const MAX_DISPATCHES_PER_SUBMISSION: u32 = 256;

/// Most samples one invocation traces in a row (`shaders/trace.wgsl`, `main`): a lane
/// whose path ends starts its next sample at once, so the 8 lanes of a SIMD batch stay
/// busy (llvmpipe runs a loop until its last lane is done), and the pixel's sums are read
/// and written once per group. Each sample is still added in index order, so the sums do
/// not depend on how the samples were grouped.
pub const SAMPLE_GROUP: u32 = 16;

/// The samples one invocation traces for `scene`: [`SAMPLE_GROUP`], fewer when that many
/// paths would pass llvmpipe's loop limit ([`loop_iterations`]), 1 when it was loaded with
/// `--no-sample-groups`.
pub fn sample_group(scene: &FlatScene) -> u32 {
    if !scene.sample_groups {
        return 1;
    }
    let per_path = path_loop_iterations(scene).max(1);
    (LLVMPIPE_LOOP_LIMIT / per_path).clamp(1, SAMPLE_GROUP as u64) as u32
}

/// `samples` in consecutive parts of at most `group`: one dispatch each.
pub fn group_parts(samples: std::ops::Range<u32>, group: u32) -> Vec<std::ops::Range<u32>> {
    let mut parts = Vec::new();
    let mut s = samples.start;
    while s < samples.end {
        let end = s.saturating_add(group).min(samples.end);
        parts.push(s..end);
        s = end;
    }
    parts
}

/// Default time one submission should take: far below the 2 s after which Windows
/// resets a GPU (TDR) and the few seconds of Linux display watchdogs, and short enough
/// that a stop request is heard within about this time; long enough that lavapipe's
/// per-submission cost (it looks the shader's machine code up again) stays small.
pub const DEFAULT_SUBMISSION_TARGET: Duration = Duration::from_millis(500);

/// Pixel samples the first submission may trace, before any has been timed: one 256 x 256
/// pass.
const FIRST_SUBMISSION_WORK: u64 = 1 << 16;

/// How much work one submission gets: pixel samples, adapted after each submission to the
/// time it took, so that submissions stay near `target`.
#[derive(Debug, Clone, Copy)]
struct Submissions {
    target: Duration,
    /// Pixel samples the next submission may trace.
    budget: u64,
    /// Submissions made so far. The first traces one sample at most: its time, which may
    /// include the driver compiling the pipeline, is not yet known.
    count: u64,
}

/// The next submission's budget after one that traced `work` pixel samples in `took`:
/// scaled by target / took, by at most 2x up and 4x down per step, within `min..=max`.
/// A submission that traced less than its budget (the render's last samples) and ended
/// within the target does not lower it.
pub fn next_budget(
    budget: u64,
    work: u64,
    took: Duration,
    target: Duration,
    min: u64,
    max: u64,
) -> u64 {
    let ratio = (target.as_secs_f64() / took.as_secs_f64().max(1e-6)).clamp(0.25, 2.0);
    let scaled = (work as f64 * ratio) as u64;
    let next = if took <= target {
        scaled.max(budget)
    } else {
        scaled
    };
    next.clamp(min, max.max(min))
}

/// Most pixels per band: [`MAX_TILE_PIXELS`] (or `WGTRACE_MAX_TILE_PIXELS`, for tests),
/// and no more than one storage binding of `limit` bytes holds.
pub fn band_pixels(limit: u64) -> u32 {
    let wanted = std::env::var("WGTRACE_MAX_TILE_PIXELS")
        .ok()
        .and_then(|v| v.parse::<u32>().ok())
        .filter(|&n| n > 0)
        .unwrap_or(MAX_TILE_PIXELS);
    wanted.min((limit / ACCUM_BYTES_PER_PIXEL).min(u32::MAX as u64) as u32)
}

/// A storage buffer holding `bytes`, or 256 zero bytes when there are none (WebGPU
/// forbids empty bindings; every record is smaller).
fn storage_buffer(device: &wgpu::Device, label: &str, bytes: &[u8]) -> wgpu::Buffer {
    let zero = [0u8; 256];
    let bytes = if bytes.is_empty() { &zero[..] } else { bytes };
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytes,
        usage: wgpu::BufferUsages::STORAGE,
    })
}

/// A uniform buffer of [`shader::UNIFORM_BYTES`] starting with `bytes`: the shader declares
/// the record array at that fixed size.
fn uniform_buffer(device: &wgpu::Device, label: &str, bytes: &[u8]) -> wgpu::Buffer {
    let mut padded = bytes.to_vec();
    padded.resize(shader::UNIFORM_BYTES as usize, 0);
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: &padded,
        usage: wgpu::BufferUsages::UNIFORM,
    })
}

/// Splits the image into bands of whole rows of at most [`MAX_TILE_PIXELS`] pixels.
pub fn tiles(width: u32, height: u32) -> Vec<Tile> {
    tiles_within(width, height, MAX_TILE_PIXELS)
}

/// Splits the image into bands of whole rows of at most `max_pixels` pixels (one row at
/// least).
pub fn tiles_within(width: u32, height: u32, max_pixels: u32) -> Vec<Tile> {
    let rows = (max_pixels / width).max(1);
    (0..height)
        .step_by(rows as usize)
        .map(|y| Tile {
            x: 0,
            y,
            width,
            height: rows.min(height - y),
        })
        .collect()
}

/// Bytes between the [`Params`] of two dispatches in the parameter buffer: its size,
/// rounded up to the adapter's alignment of dynamic uniform offsets.
fn params_stride(device: &wgpu::Device) -> u64 {
    let align = device.limits().min_uniform_buffer_offset_alignment.max(1) as u64;
    (std::mem::size_of::<Params>() as u64).div_ceil(align) * align
}

impl GpuRenderer {
    /// Uploads `scene` and gets the trace pipeline for its feature set (compiled now, or
    /// already by an earlier render in this process).
    pub fn new(ctx: Arc<GpuContext>, scene: &FlatScene) -> Result<Self, GpuError> {
        let spec = shader::fit_to_limits(&shader::scene_shader(scene), &ctx.device.limits());
        let pipeline = ctx.trace_pipeline(&spec)?;
        Self::with_pipeline(ctx, scene, pipeline)
    }

    /// Uploads `scene` to render with a given trace pipeline (one compiled for the scene's
    /// feature set or a superset of it; benchmarks time the compilation apart).
    pub fn with_pipeline(
        ctx: Arc<GpuContext>,
        scene: &FlatScene,
        pipeline: Arc<TracePipeline>,
    ) -> Result<Self, GpuError> {
        ctx.check()?;
        let device = &ctx.device;
        check_scene_fits(device, scene)?;
        check_loop_limit(&ctx, scene, true)?;
        let limits = device.limits();
        let limit = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        let tiles = tiles_within(scene.width, scene.height, band_pixels(limit));
        let stride = params_stride(device);
        let buffers = scene_buffers(
            device,
            &pipeline.bindings,
            &pipeline.uniform,
            scene,
            stride * MAX_DISPATCHES_PER_SUBMISSION as u64,
        );
        // wgpu zero-initialises new buffers, so the sums start at 0.
        let bands: Vec<Band> = tiles
            .into_iter()
            .map(|tile| {
                let accum = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("accumulation"),
                    size: tile.width as u64 * tile.height as u64 * ACCUM_BYTES_PER_PIXEL,
                    usage: wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_SRC
                        | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                let group = bind_scene(
                    device,
                    &pipeline.layout,
                    &pipeline.bindings,
                    &buffers,
                    &accum,
                );
                Band { tile, accum, group }
            })
            .collect();
        let largest = bands.iter().map(|b| b.accum.size()).max().unwrap_or(0);
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: largest,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        ctx.check()?;
        Ok(Self {
            scene: scene.clone(),
            ctx,
            pipeline,
            params: buffers.params,
            params_stride: stride,
            bands,
            readback,
            submissions: Submissions {
                target: DEFAULT_SUBMISSION_TARGET,
                budget: FIRST_SUBMISSION_WORK,
                count: 0,
            },
        })
    }

    /// Image width and height.
    pub fn size(&self) -> (u32, u32) {
        (self.scene.width, self.scene.height)
    }

    /// The adapter's description.
    pub fn name(&self) -> String {
        super::context::describe(&self.ctx.info)
    }

    /// Sets the time one submission should take (default [`DEFAULT_SUBMISSION_TARGET`]).
    pub fn set_submission_target(&mut self, target: Duration) {
        self.submissions.target = target;
    }

    /// Ends the device as a driver reset would (for tests).
    pub fn lose_device(&mut self) {
        self.ctx.lose_device();
    }

    /// Submissions made so far.
    pub fn submission_count(&self) -> u64 {
        self.submissions.count
    }

    /// Pixel samples the next submission may trace.
    pub fn submission_budget(&self) -> u64 {
        self.submissions.budget
    }

    /// Samples per pixel that one call of [`Self::render_samples`] should ask for, so that
    /// it makes about one submission per band: whole groups ([`SAMPLE_GROUP`]), at least
    /// one group.
    pub fn samples_per_call(&self) -> u32 {
        let group = sample_group(&self.scene);
        if self.submissions.count == 0 {
            return group;
        }
        let groups = (self.submissions.budget / (self.largest_band() * group as u64))
            .clamp(1, MAX_DISPATCHES_PER_SUBMISSION as u64) as u32;
        groups * group
    }

    /// Pixels of the largest band.
    fn largest_band(&self) -> u64 {
        self.bands
            .iter()
            .map(|b| b.tile.width as u64 * b.tile.height as u64)
            .max()
            .unwrap_or(1)
    }

    /// Adds sample `sample_index` of every pixel.
    pub fn render_pass(&mut self, sample_index: u32) -> Result<(), GpuError> {
        self.render_samples(sample_index..sample_index + 1)
    }

    /// Adds the samples with indices `samples` to every pixel, band by band, a dispatch
    /// per group of samples ([`group_parts`]), in submissions sized by the time the
    /// earlier ones took: several groups of a band in one submission when it is quick, a
    /// few of its rows per submission when it is slow. Each pixel adds its samples in
    /// index order, so the sums do not depend on how the work was split.
    pub fn render_samples(&mut self, samples: std::ops::Range<u32>) -> Result<(), GpuError> {
        let parts = group_parts(samples, sample_group(&self.scene));
        for b in 0..self.bands.len() {
            let band = self.bands[b].tile;
            let band_pixels = band.width as u64 * band.height as u64;
            let work = |p: &std::ops::Range<u32>| band_pixels * p.len() as u64;
            let mut i = 0;
            while i < parts.len() {
                let budget = self.submissions.budget;
                // the first submission, not yet timed, traces about one sample of the band
                let budget = if self.submissions.count == 0 {
                    budget.min(band_pixels)
                } else {
                    budget
                };
                if budget >= work(&parts[i]) {
                    // as many whole parts as the budget holds
                    let mut j = i + 1;
                    let mut total = work(&parts[i]);
                    while j < parts.len()
                        && j - i < MAX_DISPATCHES_PER_SUBMISSION as usize
                        && total + work(&parts[j]) <= budget
                    {
                        total += work(&parts[j]);
                        j += 1;
                    }
                    let dispatches: Vec<(std::ops::Range<u32>, Tile)> =
                        parts[i..j].iter().map(|p| (p.clone(), band)).collect();
                    self.submit(b, &dispatches)?;
                    i = j;
                } else {
                    // one part, a few rows at a time
                    let part = parts[i].clone();
                    let mut y = band.y;
                    while y < band.y + band.height {
                        let per_row = band.width as u64 * part.len() as u64;
                        let rows = (self.submissions.budget / per_row).max(1) as u32;
                        let rows = rows.min(band.y + band.height - y);
                        let tile = Tile {
                            x: band.x,
                            y,
                            width: band.width,
                            height: rows,
                        };
                        self.submit(b, &[(part.clone(), tile)])?;
                        y += rows;
                    }
                    i += 1;
                }
            }
        }
        Ok(())
    }

    /// One submission: a dispatch per (samples, tile) of band `b`, each with its own
    /// parameters; waits for it, then adapts the budget to the time it took.
    fn submit(
        &mut self,
        b: usize,
        dispatches: &[(std::ops::Range<u32>, Tile)],
    ) -> Result<(), GpuError> {
        let band = &self.bands[b];
        let stride = self.params_stride as usize;
        let mut bytes = vec![0u8; stride * dispatches.len()];
        for (i, (samples, tile)) in dispatches.iter().enumerate() {
            let mut params = self.scene.params(samples.start, *tile);
            params.sample_count = samples.len() as u32;
            params.accum_y = band.tile.y;
            bytes[i * stride..][..std::mem::size_of::<Params>()]
                .copy_from_slice(bytemuck::bytes_of(&params));
        }
        self.ctx.queue.write_buffer(&self.params, 0, &bytes);
        let mut encoder = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("trace pass"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipeline.pipeline);
            for (i, &(_, tile)) in dispatches.iter().enumerate() {
                pass.set_bind_group(0, &band.group, &[(i * stride) as u32]);
                pass.dispatch_workgroups(
                    tile.width.div_ceil(WORKGROUP),
                    tile.height.div_ceil(WORKGROUP),
                    1,
                );
            }
        }
        let start = Instant::now();
        self.ctx.queue.submit([encoder.finish()]);
        self.ctx.wait()?;
        let took = start.elapsed();
        let work: u64 = dispatches
            .iter()
            .map(|(s, t)| t.width as u64 * t.height as u64 * s.len() as u64)
            .sum();
        let largest = self.largest_band();
        let sub = &mut self.submissions;
        sub.budget = next_budget(
            sub.budget,
            work,
            took,
            sub.target,
            // the least a submission does: one row of one group
            self.scene.width as u64 * sample_group(&self.scene) as u64,
            largest * (MAX_DISPATCHES_PER_SUBMISSION * sample_group(&self.scene)) as u64,
        );
        sub.count += 1;
        Ok(())
    }

    /// Replaces the accumulation buffers' sums (a resumed render): two `[f32; 4]` per
    /// pixel of the image, row-major.
    pub fn set_accumulation(&mut self, data: &[[f32; 4]]) -> Result<(), GpuError> {
        let mut at = 0;
        for band in &self.bands {
            let n = 2 * band.tile.width as usize * band.tile.height as usize;
            self.ctx
                .queue
                .write_buffer(&band.accum, 0, bytemuck::cast_slice(&data[at..at + n]));
            at += n;
        }
        self.ctx.queue.submit([]);
        self.ctx.wait()
    }

    /// Copies the accumulation back, band by band: two `[f32; 4]` per pixel of the image,
    /// row-major.
    pub fn accumulation(&mut self) -> Result<Vec<[f32; 4]>, GpuError> {
        let mut out =
            Vec::with_capacity(2 * self.scene.width as usize * self.scene.height as usize);
        for band in &self.bands {
            let mut encoder = self
                .ctx
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
            encoder.copy_buffer_to_buffer(&band.accum, 0, &self.readback, 0, band.accum.size());
            self.ctx.queue.submit([encoder.finish()]);
            let n = 2 * band.tile.width as usize * band.tile.height as usize;
            let data: Vec<[f32; 4]> = read_mapped(&self.ctx, &self.readback)?;
            out.extend_from_slice(&data[..n]);
        }
        Ok(out)
    }
}

/// Loop iterations llvmpipe runs per shader invocation, counted over all loops together,
/// before it ends them silently (Mesa's `LP_MAX_TGSI_LOOP_ITERATIONS`).
pub const LLVMPIPE_LOOP_LIMIT: u64 = 65535;

/// Refuses work that llvmpipe would cut short: without the BVH, each ray (camera, bounce,
/// or MIS shadow ray) runs a loop over every primitive; the 50/50 mixture runs one over
/// every light at each bounce, with or without the BVH.
pub(crate) fn check_loop_limit(
    ctx: &GpuContext,
    scene: &FlatScene,
    paths: bool,
) -> Result<(), GpuError> {
    if !ctx.info.name.contains("llvmpipe") {
        return Ok(());
    }
    let iterations = loop_iterations(scene, paths);
    if iterations > LLVMPIPE_LOOP_LIMIT {
        return Err(GpuError::LoopLimit {
            iterations,
            limit: LLVMPIPE_LOOP_LIMIT,
        });
    }
    Ok(())
}

/// Loop iterations of one invocation's paths (its sample group; or of one kernel ray when
/// `paths` is false) that grow with the scene: primitive loops without the BVH (none when
/// the primitives are written into the shader), and the mixture's loop over lights.
pub fn loop_iterations(scene: &FlatScene, paths: bool) -> u64 {
    if !paths {
        return ray_loop_iterations(scene);
    }
    sample_group(scene) as u64 * path_loop_iterations(scene)
}

/// Loop iterations of one ray's closest-hit search that grow with the scene.
fn ray_loop_iterations(scene: &FlatScene) -> u64 {
    if scene.use_bvh || super::shader::bakes_primitives(scene) {
        0
    } else {
        scene.primitives.len() as u64 + 1
    }
}

/// Loop iterations of one path: a turn of the bounce loop per ray, plus the loops of its
/// rays and, for the mixture, the loop over lights.
fn path_loop_iterations(scene: &FlatScene) -> u64 {
    let lights = scene.light_sampling != records::LIGHT_SAMPLING_BSDF && !scene.emitters.is_empty();
    let depth = scene.max_depth as u64;
    let shadow = (lights && scene.light_sampling == records::LIGHT_SAMPLING_MIS) as u64;
    let mixture = if lights && scene.light_sampling == records::LIGHT_SAMPLING_MIXTURE {
        scene.emitters.len() as u64
    } else {
        0
    };
    depth * (1 + (1 + shadow) * ray_loop_iterations(scene) + mixture)
}

/// Refuses a scene whose buffers exceed the adapter's storage binding limit (wgpu's default
/// error handler would panic).
pub(crate) fn check_scene_fits(device: &wgpu::Device, scene: &FlatScene) -> Result<(), GpuError> {
    let limits = device.limits();
    let limit = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    for (what, bytes) in [
        ("primitives", std::mem::size_of_val(&scene.primitives[..])),
        ("emitters", std::mem::size_of_val(&scene.emitters[..])),
        ("bvh", std::mem::size_of_val(&scene.bvh[..])),
        ("shape_data", std::mem::size_of_val(&scene.shape_data[..])),
        ("textures", std::mem::size_of_val(&scene.textures[..])),
        ("texels", std::mem::size_of_val(&scene.texels[..])),
    ] {
        if bytes as u64 > limit {
            return Err(GpuError::SceneTooLarge {
                what,
                needed_mib: (bytes as u64).div_ceil(1 << 20),
                limit_mib: limit >> 20,
            });
        }
    }
    Ok(())
}

/// Every binding of group 0, `shaders/shared/bindings.wgsl`.
pub(crate) fn all_bindings() -> Vec<u32> {
    BINDINGS.iter().map(|&(b, _)| b).collect()
}

/// The layout of group 0 (`shaders/shared/bindings.wgsl`) with `bindings` only: those a
/// specialized shader uses; those in `uniform` are uniform buffers.
pub(crate) fn scene_layout(
    device: &wgpu::Device,
    bindings: &[u32],
    uniform: &[u32],
) -> wgpu::BindGroupLayout {
    let layout_entries: Vec<wgpu::BindGroupLayoutEntry> = BINDINGS
        .iter()
        .filter(|(binding, _)| bindings.contains(binding))
        .map(|&(binding, ty)| {
            (
                binding,
                if uniform.contains(&binding) {
                    wgpu::BufferBindingType::Uniform
                } else {
                    ty
                },
            )
        })
        .map(|(binding, ty)| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty,
                // the parameters of each dispatch of a submission lie at their own offset
                has_dynamic_offset: binding == 0,
                min_binding_size: None,
            },
            count: None,
        })
        .collect();
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("trace bindings"),
        entries: &layout_entries,
    })
}

/// The scene's records on the device, for the bindings a shader uses: the parameters
/// (written before each submission, one block per dispatch, bound at a dynamic offset)
/// and the storage buffers, all but the accumulation.
pub(crate) struct SceneBuffers {
    pub params: wgpu::Buffer,
    records: Vec<(u32, wgpu::Buffer)>,
}

/// Uploads the scene records that `bindings` name; records the shader does not use are
/// neither uploaded nor bound. The parameter buffer has `params_bytes` (at least one
/// [`Params`]).
pub(crate) fn scene_buffers(
    device: &wgpu::Device,
    bindings: &[u32],
    uniform: &[u32],
    scene: &FlatScene,
    params_bytes: u64,
) -> SceneBuffers {
    let records = |label: &str, bytes: &[u8], binding: u32| {
        if uniform.contains(&binding) {
            uniform_buffer(device, label, bytes)
        } else {
            storage_buffer(device, label, bytes)
        }
    };
    let params = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("params"),
        size: params_bytes.max(std::mem::size_of::<Params>() as u64),
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let records = bindings
        .iter()
        .filter_map(|&binding| {
            let buffer = match binding {
                0 | 4 => return None,
                1 => records("primitives", bytemuck::cast_slice(&scene.primitives), 1),
                2 => records("materials", bytemuck::cast_slice(&scene.materials), 2),
                3 => records("emitters", bytemuck::cast_slice(&scene.emitters), 3),
                5 => records("bvh", bytemuck::cast_slice(&scene.bvh), 5),
                6 => records("shape_data", bytemuck::cast_slice(&scene.shape_data), 6),
                7 => records("textures", bytemuck::cast_slice(&scene.textures), 7),
                8 => records("texels", bytemuck::cast_slice(&scene.texels), 8),
                _ => unreachable!("binding {binding} is not in BINDINGS"),
            };
            Some((binding, buffer))
        })
        .collect();
    SceneBuffers { params, records }
}

/// Group 0: the scene's buffers with `accum` as the accumulation buffer.
pub(crate) fn bind_scene(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    bindings: &[u32],
    buffers: &SceneBuffers,
    accum: &wgpu::Buffer,
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = bindings
        .iter()
        .map(|&binding| {
            let buffer = match binding {
                // one Params at the offset each dispatch gives
                0 => {
                    return wgpu::BindGroupEntry {
                        binding,
                        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                            buffer: &buffers.params,
                            offset: 0,
                            size: wgpu::BufferSize::new(std::mem::size_of::<Params>() as u64),
                        }),
                    }
                }
                4 => accum,
                _ => {
                    &buffers
                        .records
                        .iter()
                        .find(|(b, _)| *b == binding)
                        .expect("uploaded with scene_buffers")
                        .1
                }
            };
            wgpu::BindGroupEntry {
                binding,
                resource: buffer.as_entire_binding(),
            }
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("scene bind group"),
        layout,
        entries: &entries,
    })
}

/// Maps a MAP_READ buffer whose copy has been submitted, waits, and returns its contents.
pub(crate) fn read_mapped<T: bytemuck::Pod>(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
) -> Result<Vec<T>, GpuError> {
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    ctx.wait()?;
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
