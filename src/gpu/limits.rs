//! What a device can hold and run, read once from its limits and name: the bytes one
//! storage binding holds, whether the record arrays may be uniform buffers, the rows a
//! record texture may have, and the loop limit of llvmpipe (lavapipe), which ends a
//! shader's loops silently.

use super::bindings::{Slot, UNIFORM_BYTES};
use super::error::GpuError;
use crate::scene::flat::FlatScene;

/// Loop iterations llvmpipe runs per shader invocation, counted over all loops together,
/// before it ends them silently (Mesa's `LP_MAX_TGSI_LOOP_ITERATIONS`).
pub const LLVMPIPE_LOOP_LIMIT: u64 = 65535;

/// The device facts a plan is made for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DeviceFit {
    /// Bytes one storage binding, and one buffer, may hold.
    pub storage_bytes: u64,
    /// Every read-only record array may be a uniform buffer of [`UNIFORM_BYTES`] (one per
    /// array, plus the parameters).
    pub uniform_records: bool,
    /// Loop iterations one invocation may run before the driver cuts it short (llvmpipe),
    /// if it does.
    pub loop_limit: Option<u64>,
    /// Rows a 2D texture may have (`max_texture_dimension_2d`).
    pub texture_rows: u32,
}

impl DeviceFit {
    /// The facts of an adapter with these limits and this name.
    pub fn new(limits: &wgpu::Limits, adapter_name: &str) -> Self {
        DeviceFit {
            storage_bytes: limits
                .max_storage_buffer_binding_size
                .min(limits.max_buffer_size),
            uniform_records: limits.max_uniform_buffer_binding_size >= UNIFORM_BYTES
                && limits.max_uniform_buffers_per_shader_stage as usize > Slot::RECORDS.len(),
            loop_limit: adapter_name
                .contains("llvmpipe")
                .then_some(LLVMPIPE_LOOP_LIMIT),
            texture_rows: limits.max_texture_dimension_2d,
        }
    }

    /// WebGPU's default limits and no loop limit: what `wgtrace validate` and `wgtrace
    /// features` plan for without opening a device.
    pub fn portable() -> Self {
        Self::new(&wgpu::Limits::default(), "")
    }

    /// Refuses work whose loops the driver would cut short.
    pub fn check_loops(&self, iterations: u64) -> Result<(), GpuError> {
        match self.loop_limit {
            Some(limit) if iterations > limit => Err(GpuError::LoopLimit { iterations, limit }),
            _ => Ok(()),
        }
    }

    /// Refuses a scene whose record arrays exceed one storage binding (wgpu's default error
    /// handler would panic).
    pub fn check_scene(&self, scene: &FlatScene) -> Result<(), GpuError> {
        for slot in Slot::RECORDS.into_iter().chain([Slot::Texels]) {
            let bytes = slot.bytes(scene).len() as u64;
            if bytes > self.storage_bytes {
                return Err(GpuError::SceneTooLarge {
                    what: slot.name(),
                    needed_mib: bytes.div_ceil(1 << 20),
                    limit_mib: self.storage_bytes >> 20,
                });
            }
        }
        Ok(())
    }
}
