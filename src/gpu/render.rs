//! Progressive rendering on the GPU: the plan's pipeline and buffers, passes split into
//! bands and submissions sized to a target time, and readback of the sums.

use std::ops::Range;
use std::sync::Arc;
use std::time::{Duration, Instant};

use super::bindings::{bind_scene, scene_buffers, SceneBuffers};
use super::context::{describe, GpuContext};
use super::error::GpuError;
use super::fault;
use super::pipeline::TracePipeline;
use super::plan::{Feature, GpuPlan};
use crate::scene::flat::{Band, FlatScene};
use crate::scene::records::{accum_entries as entries_per_pixel, Params};
use crate::tuning::Tuning;

/// Accumulation bytes per pixel: two `vec4<f32>` (sum with count, sum of squares).
pub const ACCUM_BYTES_PER_PIXEL: u64 = 32;

/// Bytes of one splatted sample in the sample buffer (`trace.wgsl`'s `splat_record`).
pub const SPLAT_BYTES_PER_SAMPLE: u64 = 16;

/// The most bytes the splat sample buffer takes beyond one sample of every pixel: it holds
/// the samples of one dispatch, this many or the plan's sample group, whichever is fewer.
pub const SPLAT_BUFFER_BYTES: u64 = 1 << 27;

/// Accumulation bytes per pixel with or without the AOVs' sums.
pub fn accum_bytes_per_pixel(aovs: bool) -> u64 {
    16 * entries_per_pixel(aovs) as u64
}

/// Tile side of `trace.wgsl`'s workgroups: 8 x 8 pixels, one invocation per column of
/// the traversal stacks. `main` declares them as 64 x 1 x 1 and finds its pixel from its
/// local index (row by row): Mesa 22.3.6's lavapipe on an AVX-512 CPU walked the BVH
/// wrong in 8 x 8 x 1 workgroups (docs/robustness.md, "A driver that computes wrong").
const WORKGROUP: u32 = 8;
const _: () = assert!(WORKGROUP * WORKGROUP == crate::scene::records::BVH_STACK_LANES);

pub struct GpuRenderer {
    ctx: Arc<GpuContext>,
    scene: FlatScene,
    plan: GpuPlan,
    pipeline: Arc<TracePipeline>,
    /// The scene's records on the device, and the parameter buffer: one [`Params`] per
    /// dispatch of a submission, `params_stride` bytes apart, bound with a dynamic offset.
    buffers: SceneBuffers,
    params_stride: u64,
    bands: Vec<BandBuffers>,
    /// As large as the largest band's accumulation.
    readback: wgpu::Buffer,
    /// Splat reconstruction: the sample buffer, and the samples per pixel it holds (one
    /// dispatch's, whose gather follows before the next).
    splat: Option<(wgpu::Buffer, u32)>,
    submissions: Submissions,
    /// A note for the user about how this renderer came to be (a spot check that fell
    /// back to safer record placements).
    note: Option<String>,
    /// The sums hold sample 0 alone ([`GpuRenderer::render_first_sample`], the spot
    /// check's pass): the next [`GpuRenderer::render_samples`] from 0 starts at 1.
    first_sample_kept: bool,
}

/// A band of whole rows with an accumulation buffer of its own, so no buffer exceeds a
/// storage binding however large the image. A submission traces part of a band (some of
/// its rows, one sample) or all of it (one or more samples).
struct BandBuffers {
    band: Band,
    accum: wgpu::Buffer,
    group: wgpu::BindGroup,
}

/// One dispatch of a submission: samples `samples` of rows `rows`, into the accumulation
/// of `group`'s band, which starts at row `accum_y`.
struct Dispatch<'a> {
    group: &'a wgpu::BindGroup,
    samples: Range<u32>,
    rows: Band,
    accum_y: u32,
}

/// Most dispatches (sample groups of one band) in one submission.
pub const MAX_DISPATCHES_PER_SUBMISSION: u32 = 256;

/// `samples` in consecutive parts of at most `group`: one dispatch each.
pub fn group_parts(samples: Range<u32>, group: u32) -> Vec<Range<u32>> {
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

/// Most pixels per band: the tuning's `band_pixels`, and no more than one storage binding
/// of `limit` bytes holds.
pub fn band_pixels(wanted: u32, limit: u64, aovs: bool) -> u32 {
    wanted.min((limit / accum_bytes_per_pixel(aovs)).min(u32::MAX as u64) as u32)
}

/// Splits the image into bands of whole rows of at most `max_pixels` pixels (one row at
/// least).
pub fn bands_within(width: u32, height: u32, max_pixels: u32) -> Vec<Band> {
    let rows = (max_pixels / width).max(1);
    (0..height)
        .step_by(rows as usize)
        .map(|y| Band {
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
    /// Plans `scene` for this device under `tuning`, uploads it and gets the trace
    /// pipeline of its plan (compiled now, or already by an earlier render in this
    /// process).
    pub fn new(ctx: Arc<GpuContext>, scene: &FlatScene, tuning: &Tuning) -> Result<Self, GpuError> {
        ctx.check()?;
        let (plan, perturbed) = fault::device_plan(scene, &ctx.fit(), tuning);
        let device_scene = perturbed.as_ref().unwrap_or(scene);
        plan.check(scene)?;
        let pipeline = ctx.trace_pipeline(&plan.shader)?;
        let device = &ctx.device;
        let bands = bands_within(
            scene.width,
            scene.height,
            band_pixels(tuning.band_pixels, plan.fit.storage_bytes, scene.aovs),
        );
        let stride = params_stride(device);
        let buffers = scene_buffers(
            device,
            &ctx.queue,
            &pipeline.slots,
            &plan.shader.placements,
            device_scene,
            stride * MAX_DISPATCHES_PER_SUBMISSION as u64,
        )?;
        let splat = if plan.shader.features.contains(Feature::Splat) {
            let per_sample = scene.width as u64 * scene.height as u64 * SPLAT_BYTES_PER_SAMPLE;
            let fit = plan.fit.storage_bytes / per_sample;
            if fit == 0 {
                return Err(GpuError::SceneTooLarge {
                    what: format!(
                        "splatted samples ({} x {} pixels, one sample each)",
                        scene.width, scene.height
                    ),
                    needed_mib: per_sample.div_ceil(1 << 20),
                    limit_mib: plan.fit.storage_bytes >> 20,
                    advice: "render fewer pixels or set [render] reconstruction = \"importance\"",
                });
            }
            // no more than SPLAT_BUFFER_BYTES unless one sample needs it
            let per_dispatch = fit
                .min(SPLAT_BUFFER_BYTES / per_sample)
                .clamp(1, plan.sample_group.max(1) as u64) as u32;
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("splatted samples"),
                size: per_sample * per_dispatch as u64,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            });
            Some((buffer, per_dispatch))
        } else {
            None
        };
        // wgpu zero-initialises new buffers, so the sums start at 0.
        let bands: Vec<BandBuffers> = bands
            .into_iter()
            .map(|band| {
                let accum = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("accumulation"),
                    size: band.width as u64
                        * band.height as u64
                        * accum_bytes_per_pixel(scene.aovs),
                    usage: wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_SRC
                        | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                let group = bind_scene(
                    device,
                    &pipeline.layout,
                    &pipeline.slots,
                    &buffers,
                    &accum,
                    splat.as_ref().map(|(b, _)| b),
                );
                BandBuffers { band, accum, group }
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
            plan,
            pipeline,
            buffers,
            params_stride: stride,
            bands,
            readback,
            splat,
            submissions: Submissions {
                target: DEFAULT_SUBMISSION_TARGET,
                budget: FIRST_SUBMISSION_WORK,
                count: 0,
            },
            note: None,
            first_sample_kept: false,
        })
    }

    /// The plan this renderer runs.
    pub fn plan(&self) -> &GpuPlan {
        &self.plan
    }

    /// A note for the user about this renderer (set by whoever opened it), if any.
    pub fn note(&self) -> Option<&str> {
        self.note.as_deref()
    }

    /// Sets the note [`Self::note`] returns.
    pub fn set_note(&mut self, note: Option<String>) {
        self.note = note;
    }

    /// Image width and height.
    pub fn size(&self) -> (u32, u32) {
        (self.scene.width, self.scene.height)
    }

    /// The adapter's description.
    pub fn name(&self) -> String {
        describe(&self.ctx.info)
    }

    /// Sets the time one submission should take (default [`DEFAULT_SUBMISSION_TARGET`]).
    pub fn set_submission_target(&mut self, target: Duration) {
        self.submissions.target = target;
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
    /// it makes about one submission per band: whole groups of the plan's sample group,
    /// at least one group.
    pub fn samples_per_call(&self) -> u32 {
        let group = self.plan.sample_group;
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
            .map(|b| b.band.width as u64 * b.band.height as u64)
            .max()
            .unwrap_or(1)
    }

    /// Adds sample `sample_index` of every pixel.
    pub fn render_pass(&mut self, sample_index: u32) -> Result<(), GpuError> {
        self.render_samples(sample_index..sample_index + 1)
    }

    /// Clears the sums and renders sample 0 of every pixel into them, in the dispatches a
    /// render's first sample takes, and returns them (`entries` `[f32; 4]` per pixel,
    /// row-major; what the spot check compares with the CPU reference). The sums keep it:
    /// a later [`GpuRenderer::render_samples`] from 0 starts at 1 (bit for bit the sums of
    /// a render without it, as each pixel adds its samples in index order), one from
    /// elsewhere clears them first.
    pub fn render_first_sample(&mut self) -> Result<Vec<[f32; 4]>, GpuError> {
        self.clear()?;
        self.render_samples(0..1)?;
        self.first_sample_kept = true;
        self.accumulation()
    }

    /// Whether the sums hold sample 0 alone, kept from [`GpuRenderer::render_first_sample`].
    pub fn holds_first_sample(&self) -> bool {
        self.first_sample_kept
    }

    /// Zeroes the sums.
    fn clear(&mut self) -> Result<(), GpuError> {
        let mut encoder = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        for band in &self.bands {
            encoder.clear_buffer(&band.accum, 0, None);
        }
        self.ctx.queue.submit([encoder.finish()]);
        self.first_sample_kept = false;
        self.ctx.wait()
    }

    /// Adds the samples with indices `samples` to every pixel, band by band, a dispatch
    /// per group of samples ([`group_parts`]), in submissions sized by the time the
    /// earlier ones took: several groups of a band in one submission when it is quick, a
    /// few of its rows per submission when it is slow. Each pixel adds its samples in
    /// index order, so the sums do not depend on how the work was split.
    pub fn render_samples(&mut self, samples: Range<u32>) -> Result<(), GpuError> {
        let mut samples = samples;
        if self.first_sample_kept {
            if samples.start == 0 {
                samples.start = 1;
                self.first_sample_kept = false;
            } else {
                self.clear()?;
            }
        }
        if let Some(per_dispatch) = self.splat.as_ref().map(|s| s.1) {
            // splatting: each dispatch's samples of the whole image, then their gather
            for part in group_parts(samples, per_dispatch) {
                for b in 0..self.bands.len() {
                    self.trace_parts(b, std::slice::from_ref(&part))?;
                }
                self.gather(&part)?;
            }
            return Ok(());
        }
        let parts = group_parts(samples, self.plan.sample_group);
        for b in 0..self.bands.len() {
            self.trace_parts(b, &parts)?;
        }
        Ok(())
    }

    /// Traces samples `parts` (one dispatch each) of every pixel of band `b`, in
    /// submissions sized by the time the earlier ones took ([`Self::render_samples`]).
    fn trace_parts(&mut self, b: usize, parts: &[Range<u32>]) -> Result<(), GpuError> {
        {
            let band = self.bands[b].band;
            let band_pixels = band.width as u64 * band.height as u64;
            let work = |p: &Range<u32>| band_pixels * p.len() as u64;
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
                    let dispatches: Vec<(Range<u32>, Band)> =
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
                        let some = Band {
                            x: band.x,
                            y,
                            width: band.width,
                            height: rows,
                        };
                        self.submit(b, &[(part.clone(), some)])?;
                        y += rows;
                    }
                    i += 1;
                }
            }
        }
        Ok(())
    }

    /// Splat reconstruction's second pass over samples `part` (in the sample buffer): a
    /// `gather` dispatch per band, up to [`MAX_DISPATCHES_PER_SUBMISSION`] per submission.
    fn gather(&mut self, part: &Range<u32>) -> Result<(), GpuError> {
        let gather = self
            .pipeline
            .gather
            .as_ref()
            .expect("a splatting plan has a gather pipeline");
        for bands in self.bands.chunks(MAX_DISPATCHES_PER_SUBMISSION as usize) {
            let dispatches: Vec<Dispatch> = bands
                .iter()
                .map(|band| Dispatch {
                    group: &band.group,
                    samples: part.clone(),
                    rows: band.band,
                    accum_y: band.band.y,
                })
                .collect();
            let commands = self.encode("gather pass", gather, &dispatches);
            self.ctx.queue.submit([commands]);
            self.ctx.wait()?;
        }
        Ok(())
    }

    /// Writes one [`Params`] per dispatch and encodes them in one compute pass of
    /// `pipeline`, each dispatch binding its group at its parameters' offset.
    fn encode(
        &self,
        label: &str,
        pipeline: &wgpu::ComputePipeline,
        dispatches: &[Dispatch],
    ) -> wgpu::CommandBuffer {
        let stride = self.params_stride as usize;
        self.write_params(dispatches.iter().map(|d| {
            let mut params = self.scene.params(d.samples.start, d.rows);
            params.sample_count = d.samples.len() as u32;
            params.accum_y = d.accum_y;
            params
        }));
        let mut encoder = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(label),
                timestamp_writes: None,
            });
            pass.set_pipeline(pipeline);
            for (i, d) in dispatches.iter().enumerate() {
                pass.set_bind_group(0, d.group, &[(i * stride) as u32]);
                pass.dispatch_workgroups(
                    d.rows.width.div_ceil(WORKGROUP),
                    d.rows.height.div_ceil(WORKGROUP),
                    1,
                );
            }
        }
        encoder.finish()
    }

    /// One submission: a dispatch per (samples, rows) of band `b`, each with its own
    /// parameters; waits for it, then adapts the budget to the time it took.
    fn submit(&mut self, b: usize, dispatches: &[(Range<u32>, Band)]) -> Result<(), GpuError> {
        let band = &self.bands[b];
        let traced: Vec<Dispatch> = dispatches
            .iter()
            .map(|(samples, rows)| Dispatch {
                group: &band.group,
                samples: samples.clone(),
                rows: *rows,
                accum_y: band.band.y,
            })
            .collect();
        let commands = self.encode("trace pass", &self.pipeline.pipeline, &traced);
        let start = Instant::now();
        self.ctx.queue.submit([commands]);
        self.ctx.wait_first(&self.pipeline)?;
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
            self.scene.width as u64 * self.plan.sample_group as u64,
            largest * (MAX_DISPATCHES_PER_SUBMISSION * self.plan.sample_group) as u64,
        );
        sub.count += 1;
        Ok(())
    }

    /// Writes one [`Params`] per dispatch of a submission into the parameter buffer,
    /// `params_stride` bytes apart (dispatch i binds offset i x stride).
    fn write_params(&self, params: impl ExactSizeIterator<Item = Params>) {
        let stride = self.params_stride as usize;
        let mut bytes = vec![0u8; stride * params.len()];
        for (i, p) in params.enumerate() {
            bytes[i * stride..][..std::mem::size_of::<Params>()]
                .copy_from_slice(bytemuck::bytes_of(&p));
        }
        self.ctx.queue.write_buffer(&self.buffers.params, 0, &bytes);
    }

    /// `[f32; 4]` entries per pixel of the sums.
    fn entries(&self) -> usize {
        entries_per_pixel(self.scene.aovs)
    }

    /// Replaces the accumulation buffers' sums (a resumed render): `entries` `[f32; 4]`
    /// per pixel of the image, row-major.
    pub fn set_accumulation(&mut self, data: &[[f32; 4]]) -> Result<(), GpuError> {
        self.first_sample_kept = false;
        let mut at = 0;
        for band in &self.bands {
            let n = self.entries() * band.band.width as usize * band.band.height as usize;
            self.ctx
                .queue
                .write_buffer(&band.accum, 0, bytemuck::cast_slice(&data[at..at + n]));
            at += n;
        }
        self.ctx.queue.submit([]);
        self.ctx.wait()
    }

    /// Copies the accumulation back, band by band: `entries` `[f32; 4]` per pixel of the
    /// image, row-major.
    pub fn accumulation(&mut self) -> Result<Vec<[f32; 4]>, GpuError> {
        let mut out = Vec::with_capacity(
            self.entries() * self.scene.width as usize * self.scene.height as usize,
        );
        for band in &self.bands {
            let mut encoder = self
                .ctx
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
            encoder.copy_buffer_to_buffer(&band.accum, 0, &self.readback, 0, band.accum.size());
            self.ctx.queue.submit([encoder.finish()]);
            let n = self.entries() * band.band.width as usize * band.band.height as usize;
            let data: Vec<[f32; 4]> = self.ctx.read_buffer(&self.readback)?;
            out.extend_from_slice(&data[..n]);
        }
        Ok(out)
    }
}
