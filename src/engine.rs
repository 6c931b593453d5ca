//! The backend that renders: a Vulkan adapter or the CPU reference, behind one type.

use std::ops::Range;
use std::time::Duration;

use crate::accumulation::{entries_per_pixel, Accumulation};
use crate::cpu::trace::CpuRenderer;
use crate::gpu::context::GpuContext;
use crate::gpu::error::GpuError;
use crate::gpu::render::GpuRenderer;
use crate::scene::flat::FlatScene;
use crate::spot_check::open_checked;
use crate::tuning::Tuning;

/// Which backend renders.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BackendChoice {
    /// Vulkan adapter by index of [`crate::gpu::context::list_adapters`] (0: the preferred one).
    Gpu { adapter: usize },
    /// The CPU reference.
    Cpu,
}

/// An open backend holding one scene and its sums.
pub enum Engine {
    Gpu(Box<GpuRenderer>),
    Cpu(Box<CpuRenderer>),
}

impl Engine {
    /// Opens the GPU backend under the default tuning; fails when no Vulkan adapter exists.
    pub fn gpu(scene: &FlatScene, adapter: usize) -> Result<Self, GpuError> {
        Self::gpu_tuned(scene, adapter, &Tuning::default())
    }

    /// Opens the GPU backend under `tuning`, spot-checked against the CPU reference
    /// ([`crate::spot_check::open_checked`]: it may fall back to safer record placements,
    /// with a [`Engine::note`], or refuse the adapter).
    pub fn gpu_tuned(scene: &FlatScene, adapter: usize, tuning: &Tuning) -> Result<Self, GpuError> {
        let ctx = GpuContext::shared(adapter)?;
        Ok(Engine::Gpu(Box::new(open_checked(ctx, scene, tuning)?)))
    }

    /// A note for the user about how the backend was opened (a spot check that fell back
    /// to safer record placements), if any.
    pub fn note(&self) -> Option<&str> {
        match self {
            Engine::Gpu(g) => g.note(),
            Engine::Cpu(_) => None,
        }
    }

    /// Opens the CPU reference.
    pub fn cpu(scene: &FlatScene) -> Self {
        Engine::Cpu(Box::new(CpuRenderer::new(scene)))
    }

    /// Opens the chosen backend; with the GPU chosen and no Vulkan adapter,
    /// [`GpuError::NoAdapter`].
    pub fn with(
        scene: &FlatScene,
        choice: BackendChoice,
        tuning: &Tuning,
    ) -> Result<Self, GpuError> {
        match choice {
            BackendChoice::Cpu => Ok(Self::cpu(scene)),
            BackendChoice::Gpu { adapter } => Self::gpu_tuned(scene, adapter, tuning),
        }
    }

    /// Opens the chosen backend. When the GPU is chosen but no Vulkan adapter exists, falls
    /// back to the CPU and returns a one-line note saying so.
    pub fn open(
        scene: &FlatScene,
        choice: BackendChoice,
        tuning: &Tuning,
    ) -> Result<(Self, Option<String>), GpuError> {
        match Self::with(scene, choice, tuning) {
            Err(GpuError::NoAdapter) => Ok((
                Self::cpu(scene),
                Some(format!(
                    "{}; rendering on the CPU instead",
                    GpuError::NoAdapter
                )),
            )),
            opened => opened.map(|e| (e, None)),
        }
    }

    /// The device that renders, for the user.
    pub fn name(&self) -> String {
        match self {
            Engine::Gpu(g) => g.name(),
            Engine::Cpu(c) => c.name(),
        }
    }

    /// Whether the sums already hold sample 0 (the GPU's spot check renders it and keeps
    /// it), so the next [`Engine::render_samples`] from 0 renders from 1.
    pub fn holds_first_sample(&self) -> bool {
        match self {
            Engine::Gpu(g) => g.holds_first_sample(),
            Engine::Cpu(_) => false,
        }
    }

    /// Adds one sample per pixel.
    pub fn render_pass(&mut self, sample_index: u32) -> Result<(), GpuError> {
        self.render_samples(sample_index..sample_index + 1)
    }

    /// Adds the samples with indices `samples` to every pixel.
    pub fn render_samples(&mut self, samples: Range<u32>) -> Result<(), GpuError> {
        match self {
            Engine::Gpu(g) => g.render_samples(samples),
            Engine::Cpu(c) => {
                samples.for_each(|i| c.render_pass(i));
                Ok(())
            }
        }
    }

    /// How many samples per pixel one [`Engine::render_samples`] call should ask for: the
    /// GPU's submissions grow to several samples when one takes much less than its target
    /// time; the CPU renders one at a time.
    pub fn samples_per_call(&self) -> u32 {
        match self {
            Engine::Gpu(g) => g.samples_per_call(),
            Engine::Cpu(_) => 1,
        }
    }

    /// The time one GPU submission should take (see
    /// [`crate::gpu::render::DEFAULT_SUBMISSION_TARGET`]); the CPU ignores it.
    pub fn set_submission_target(&mut self, target: Duration) {
        if let Engine::Gpu(g) = self {
            g.set_submission_target(target);
        }
    }

    /// Replaces the accumulated sums with `acc` (of this engine's size): a resumed render
    /// continues from them.
    pub fn set_accumulation(&mut self, acc: &Accumulation) -> Result<(), GpuError> {
        match self {
            Engine::Gpu(g) => g.set_accumulation(&acc.data),
            Engine::Cpu(c) => {
                c.set_accumulation(&acc.data);
                Ok(())
            }
        }
    }

    /// The accumulated samples so far.
    pub fn accumulation(&mut self) -> Result<Accumulation, GpuError> {
        let ((width, height), data) = match self {
            Engine::Gpu(g) => (g.size(), g.accumulation()?),
            Engine::Cpu(c) => (c.size(), c.accumulation()),
        };
        let aovs = data.len() == width as usize * height as usize * entries_per_pixel(true);
        Ok(Accumulation {
            width,
            height,
            aovs,
            data,
        })
    }
}
