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
    /// Rows a 2D texture may have, and columns (`max_texture_dimension_2d`).
    pub texture_rows: u32,
    /// Pages a texel bank may have (`max_texture_array_layers`).
    pub texture_layers: u32,
    /// Texel banks a shader may bind (`max_sampled_textures_per_shader_stage`).
    pub texel_banks: u32,
    /// The device has WGSL's subgroup operations (`--tune lane-stats` needs them).
    pub subgroups: bool,
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
            texture_layers: limits.max_texture_array_layers,
            texel_banks: limits.max_sampled_textures_per_shader_stage,
            subgroups: false,
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
    /// handler would panic), or whose texel banks exceed the device's textures, naming what
    /// is too large and what to do.
    pub fn check_scene(&self, scene: &FlatScene) -> Result<(), GpuError> {
        for slot in Slot::RECORDS.into_iter().chain([Slot::Tables]) {
            let bytes = slot.bytes(scene).len() as u64;
            if bytes > self.storage_bytes {
                let (what, count, advice) = match slot {
                    Slot::Primitives => (
                        "primitive records",
                        scene.primitives.len(),
                        "use fewer triangles (a decimated mesh)",
                    ),
                    Slot::Bvh => (
                        "BVH nodes",
                        scene.bvh_node_count(),
                        "use fewer triangles (a decimated mesh)",
                    ),
                    Slot::ShapeData => (
                        "vertex attributes and transforms",
                        scene.shape_data.len(),
                        "use fewer triangles (a decimated mesh) or fewer instances",
                    ),
                    Slot::Materials => ("materials", scene.materials.len(), "use fewer materials"),
                    Slot::Emitters => ("lights", scene.emitters.len(), "use fewer emitting shapes"),
                    Slot::Tables => (
                        "tables: the background's distribution, media and their grids (scalars / 4)",
                        scene.tables.len(),
                        "use a smaller background image or coarser density grids",
                    ),
                    _ => ("textures", scene.textures.len(), "use fewer textures"),
                };
                return Err(GpuError::SceneTooLarge {
                    what: format!("{what} ({count})"),
                    needed_mib: bytes.div_ceil(1 << 20),
                    limit_mib: self.storage_bytes >> 20,
                    advice,
                });
            }
        }
        let banks = &scene.texels.banks;
        if banks.len() as u32 > self.texel_banks {
            return Err(GpuError::TexelsTooLarge(format!(
                "{} texel banks, more than the {} textures it binds",
                banks.len(),
                self.texel_banks
            )));
        }
        for b in banks {
            if b.width.max(b.height) > self.texture_rows {
                return Err(GpuError::TexelsTooLarge(format!(
                    "{} pages of {} x {} texels, more than its {} per side",
                    b.kind.name(),
                    b.width,
                    b.height,
                    self.texture_rows
                )));
            }
            if b.layers > self.texture_layers {
                return Err(GpuError::TexelsTooLarge(format!(
                    "a bank of {} {} pages, more than its {} layers",
                    b.layers,
                    b.kind.name(),
                    self.texture_layers
                )));
            }
        }
        Ok(())
    }
}
