//! The trace pipeline's group-0 bindings, in one place: each slot's binding number, WGSL
//! name and record type ([`Slot`]); where a plan keeps each read-only record array
//! ([`Placement`]); the WGSL declarations written from them (`#import generated/bindings`
//! in `shaders/shared/bindings.wgsl`); and the bind group layout, buffers and bind groups
//! made from the same table.

use wgpu::util::DeviceExt;

use crate::scene::flat::FlatScene;
use crate::scene::records::{BvhNode, Emitter, Material, Params, Primitive, Texture};

/// Bytes of a read-only record array that is a uniform buffer: WebGPU's and lavapipe's
/// `maxUniformBufferBindingSize` (Vulkan promises 16 KiB; desktop GPUs give 64 KiB). The
/// shader declares such an array at the fixed length `UNIFORM_BYTES / record size`.
pub const UNIFORM_BYTES: u64 = 1 << 16;

/// A resource of group 0, in binding order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Slot {
    /// The per-dispatch constants ([`Params`]), one block per dispatch of a submission at
    /// a dynamic offset.
    Params,
    Primitives,
    Materials,
    Emitters,
    /// Two vec4 per pixel of the band being rendered: sums and sums of squares.
    Accum,
    Bvh,
    /// Transforms and triangle vertex attributes, indexed by `Primitive::data`.
    ShapeData,
    Textures,
    /// Image texels (linear RGB) and the Perlin noise tables.
    Texels,
}

impl Slot {
    /// Every slot, in binding order.
    pub const ALL: [Slot; 9] = [
        Slot::Params,
        Slot::Primitives,
        Slot::Materials,
        Slot::Emitters,
        Slot::Accum,
        Slot::Bvh,
        Slot::ShapeData,
        Slot::Textures,
        Slot::Texels,
    ];

    /// The read-only record arrays a plan places (a storage or a uniform buffer, or
    /// written into the shader); the texels are always a storage buffer (too large).
    pub const RECORDS: [Slot; 6] = [
        Slot::Primitives,
        Slot::Materials,
        Slot::Emitters,
        Slot::Bvh,
        Slot::ShapeData,
        Slot::Textures,
    ];

    /// Its `@binding` number in group 0.
    pub fn binding(self) -> u32 {
        Slot::ALL.iter().position(|&s| s == self).unwrap() as u32
    }

    /// The name of its variable in the shaders.
    pub fn name(self) -> &'static str {
        match self {
            Slot::Params => "params",
            Slot::Primitives => "primitives",
            Slot::Materials => "materials",
            Slot::Emitters => "emitters",
            Slot::Accum => "accum",
            Slot::Bvh => "bvh",
            Slot::ShapeData => "shape_data",
            Slot::Textures => "textures",
            Slot::Texels => "texels",
        }
    }

    /// The WGSL type of one element and its size in bytes (of the whole block for the
    /// parameters).
    pub fn element(self) -> (&'static str, usize) {
        use std::mem::size_of;
        match self {
            Slot::Params => ("Params", size_of::<Params>()),
            Slot::Primitives => ("Primitive", size_of::<Primitive>()),
            Slot::Materials => ("Material", size_of::<Material>()),
            Slot::Emitters => ("Emitter", size_of::<Emitter>()),
            Slot::Bvh => ("BvhNode", size_of::<BvhNode>()),
            Slot::Textures => ("Texture", size_of::<Texture>()),
            Slot::Accum | Slot::ShapeData | Slot::Texels => ("vec4<f32>", 16),
        }
    }

    /// The scene's records this slot holds (none for the parameters and the sums).
    pub fn bytes(self, scene: &FlatScene) -> &[u8] {
        match self {
            Slot::Params | Slot::Accum => &[],
            Slot::Primitives => bytemuck::cast_slice(&scene.primitives),
            Slot::Materials => bytemuck::cast_slice(&scene.materials),
            Slot::Emitters => bytemuck::cast_slice(&scene.emitters),
            Slot::Bvh => bytemuck::cast_slice(&scene.bvh),
            Slot::ShapeData => bytemuck::cast_slice(&scene.shape_data),
            Slot::Textures => bytemuck::cast_slice(&scene.textures),
            Slot::Texels => bytemuck::cast_slice(&scene.texels),
        }
    }

    /// Records of this array that a uniform buffer of [`UNIFORM_BYTES`] holds.
    pub fn uniform_len(self) -> u64 {
        UNIFORM_BYTES / self.element().1 as u64
    }
}

/// Where a read-only record array lives.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Placement {
    /// A storage buffer of any length.
    #[default]
    Storage,
    /// A uniform buffer of [`UNIFORM_BYTES`] (the array fits).
    Uniform,
    /// Written into the shader as constants (`gpu::codegen`); no buffer is bound.
    Shader,
}

/// The placement of each of [`Slot::RECORDS`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Placements([Placement; 6]);

impl Placements {
    /// Where `slot`'s records live (the parameters are a uniform block, the sums and the
    /// texels storage buffers).
    pub fn get(&self, slot: Slot) -> Placement {
        match Slot::RECORDS.iter().position(|&s| s == slot) {
            Some(i) => self.0[i],
            None if slot == Slot::Params => Placement::Uniform,
            None => Placement::Storage,
        }
    }

    /// Places `slot`, one of [`Slot::RECORDS`].
    pub fn set(&mut self, slot: Slot, placement: Placement) {
        let i = Slot::RECORDS
            .iter()
            .position(|&s| s == slot)
            .unwrap_or_else(|| panic!("{slot:?} is not a placed record array"));
        self.0[i] = placement;
    }
}

/// The WGSL declarations of every slot of group 0 under `placements`. Arrays written into
/// the shader are still declared (as storage) so that the code reading them from a buffer,
/// left unused, validates; they are not bound.
pub fn wgsl_declarations(placements: &Placements) -> String {
    let mut out = String::new();
    for slot in Slot::ALL {
        let (ty, _) = slot.element();
        let (space, ty) = match (slot, placements.get(slot)) {
            (Slot::Params, _) => ("uniform".to_string(), ty.to_string()),
            (Slot::Accum, _) => ("storage, read_write".into(), format!("array<{ty}>")),
            (_, Placement::Uniform) => (
                "uniform".into(),
                format!("array<{ty}, {}>", slot.uniform_len()),
            ),
            _ => ("storage, read".into(), format!("array<{ty}>")),
        };
        out += &format!(
            "@group(0) @binding({}) var<{space}> {}: {ty};\n",
            slot.binding(),
            slot.name()
        );
    }
    out
}

/// The buffer type of a bound slot.
fn buffer_type(slot: Slot, placements: &Placements) -> wgpu::BufferBindingType {
    match (slot, placements.get(slot)) {
        (Slot::Accum, _) => wgpu::BufferBindingType::Storage { read_only: false },
        (_, Placement::Uniform) => wgpu::BufferBindingType::Uniform,
        _ => wgpu::BufferBindingType::Storage { read_only: true },
    }
}

/// The layout of group 0 with `slots` only (those the shader reads).
pub fn layout(
    device: &wgpu::Device,
    slots: &[Slot],
    placements: &Placements,
) -> wgpu::BindGroupLayout {
    let entries: Vec<wgpu::BindGroupLayoutEntry> = slots
        .iter()
        .map(|&slot| wgpu::BindGroupLayoutEntry {
            binding: slot.binding(),
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: buffer_type(slot, placements),
                // the parameters of each dispatch of a submission lie at their own offset
                has_dynamic_offset: slot == Slot::Params,
                min_binding_size: None,
            },
            count: None,
        })
        .collect();
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("trace bindings"),
        entries: &entries,
    })
}

/// The scene's records on the device, for the slots a shader reads: the parameters
/// (written before each submission, one block per dispatch, bound at a dynamic offset)
/// and the record buffers, all but the sums.
pub struct SceneBuffers {
    pub params: wgpu::Buffer,
    records: Vec<(Slot, wgpu::Buffer)>,
}

/// Uploads the records of `slots`: a uniform buffer of [`UNIFORM_BYTES`] starting with
/// them (the shader declares the array at that size), or a storage buffer holding them (256
/// zero bytes when there are none: WebGPU forbids empty bindings, and every record is
/// smaller). The parameter buffer has `params_bytes` (at least one [`Params`]).
pub fn scene_buffers(
    device: &wgpu::Device,
    slots: &[Slot],
    placements: &Placements,
    scene: &FlatScene,
    params_bytes: u64,
) -> SceneBuffers {
    let params = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("params"),
        size: params_bytes.max(std::mem::size_of::<Params>() as u64),
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let records = slots
        .iter()
        .filter(|s| !matches!(s, Slot::Params | Slot::Accum))
        .map(|&slot| {
            let bytes = slot.bytes(scene);
            let (contents, usage) = match placements.get(slot) {
                Placement::Uniform => {
                    let mut padded = bytes.to_vec();
                    padded.resize(UNIFORM_BYTES as usize, 0);
                    (padded, wgpu::BufferUsages::UNIFORM)
                }
                _ if bytes.is_empty() => (vec![0; 256], wgpu::BufferUsages::STORAGE),
                _ => (bytes.to_vec(), wgpu::BufferUsages::STORAGE),
            };
            let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(slot.name()),
                contents: &contents,
                usage,
            });
            (slot, buffer)
        })
        .collect();
    SceneBuffers { params, records }
}

/// Group 0: the scene's buffers for `slots`, with `accum` as the sums.
pub fn bind_scene(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    slots: &[Slot],
    buffers: &SceneBuffers,
    accum: &wgpu::Buffer,
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = slots
        .iter()
        .map(|&slot| {
            let resource = match slot {
                // one Params at the offset each dispatch gives
                Slot::Params => wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &buffers.params,
                    offset: 0,
                    size: wgpu::BufferSize::new(std::mem::size_of::<Params>() as u64),
                }),
                Slot::Accum => accum.as_entire_binding(),
                _ => buffers
                    .records
                    .iter()
                    .find(|(s, _)| *s == slot)
                    .expect("uploaded with scene_buffers")
                    .1
                    .as_entire_binding(),
            };
            wgpu::BindGroupEntry {
                binding: slot.binding(),
                resource,
            }
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("scene bind group"),
        layout,
        entries: &entries,
    })
}
