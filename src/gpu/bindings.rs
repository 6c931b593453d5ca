//! The trace pipeline's group-0 bindings, in one place: each slot's binding number, WGSL
//! name and record type ([`Slot`]); where a plan keeps each read-only record array
//! ([`Placement`]); the WGSL declarations written from them (`#import generated/bindings`
//! in `shaders/shared/bindings.wgsl`); and the bind group layout, buffers and bind groups
//! made from the same table.

use wgpu::util::DeviceExt;

use super::codegen::texture_accessor;
use super::error::GpuError;
use crate::scene::flat::FlatScene;
use crate::scene::records::{BvhNode, Emitter, Material, Params, Primitive, Texture};
use crate::scene::texels::{Bank, TexelKind, MAX_BANKS};

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
    /// The Perlin tables and the image background's distribution (`FlatScene::tables`).
    Tables,
    /// Splat reconstruction's samples of one dispatch (`trace.wgsl`'s `splat_record`):
    /// written by `main`, read by `gather`.
    Samples,
    /// Image texel bank i (`scene::texels`), a 2D array texture of the bank's format.
    Texels(u8),
}

impl Slot {
    /// Every slot, in binding order.
    pub const ALL: [Slot; 10 + MAX_BANKS] = [
        Slot::Params,
        Slot::Primitives,
        Slot::Materials,
        Slot::Emitters,
        Slot::Accum,
        Slot::Bvh,
        Slot::ShapeData,
        Slot::Textures,
        Slot::Tables,
        Slot::Samples,
        Slot::Texels(0),
        Slot::Texels(1),
        Slot::Texels(2),
        Slot::Texels(3),
        Slot::Texels(4),
        Slot::Texels(5),
        Slot::Texels(6),
        Slot::Texels(7),
    ];

    /// The read-only record arrays a plan places (a storage or a uniform buffer, a
    /// texture, or written into the shader); the tables are a storage buffer, the texel
    /// banks array textures.
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
            Slot::Tables => "tables",
            Slot::Samples => "samples",
            Slot::Texels(i) => TEXEL_BANK_NAMES[i as usize],
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
            Slot::Accum | Slot::ShapeData | Slot::Tables => ("vec4<f32>", 16),
            Slot::Samples => ("vec4<u32>", 16),
            Slot::Texels(_) => ("texture_2d_array<f32>", 0),
        }
    }

    /// The scene's records this slot holds (none for the parameters and the sums).
    pub fn bytes(self, scene: &FlatScene) -> &[u8] {
        match self {
            Slot::Params | Slot::Accum | Slot::Samples => &[],
            Slot::Primitives => bytemuck::cast_slice(&scene.primitives),
            Slot::Materials => bytemuck::cast_slice(&scene.materials),
            Slot::Emitters => bytemuck::cast_slice(&scene.emitters),
            Slot::Bvh => bytemuck::cast_slice(&scene.bvh),
            Slot::ShapeData => bytemuck::cast_slice(&scene.shape_data),
            Slot::Textures => bytemuck::cast_slice(&scene.textures),
            Slot::Tables => bytemuck::cast_slice(&scene.tables),
            Slot::Texels(i) => scene
                .texels
                .banks
                .get(i as usize)
                .map_or(&[], |b| &b.data[..]),
        }
    }

    /// Records of this array that a uniform buffer of [`UNIFORM_BYTES`] holds.
    pub fn uniform_len(self) -> u64 {
        UNIFORM_BYTES / self.element().1 as u64
    }
}

/// The shaders' names of the texel banks.
const TEXEL_BANK_NAMES: [&str; MAX_BANKS] = [
    "texels0", "texels1", "texels2", "texels3", "texels4", "texels5", "texels6", "texels7",
];

/// The texture format of a bank of `kind`: `textureLoad` decodes it as the CPU's
/// `TexelKind::decode` does.
pub fn texel_format(kind: TexelKind) -> wgpu::TextureFormat {
    match kind {
        TexelKind::Unorm8 => wgpu::TextureFormat::Rgba8Unorm,
        TexelKind::Half => wgpu::TextureFormat::Rgba16Float,
        TexelKind::Float => wgpu::TextureFormat::Rgba32Float,
    }
}

/// `texel_load(bank, layer, x, y)`, which image look-ups read texels through, for a
/// shader with `banks` texel banks: a `switch` over them (none with one; zero with none).
pub fn wgsl_texel_load(banks: u32) -> String {
    let load = |i: u32| {
        format!(
            "textureLoad({}, vec2<u32>(x, y), layer, 0)",
            TEXEL_BANK_NAMES[i as usize]
        )
    };
    let body = match banks {
        0 => "    return vec4<f32>(0.0);\n".to_string(),
        1 => format!("    return {};\n", load(0)),
        n => {
            let mut body = "    switch bank {\n".to_string();
            for i in 1..n {
                body += &format!(
                    "        case {i}u: {{\n            return {};\n        }}\n",
                    load(i)
                );
            }
            body + &format!(
                "        default: {{\n            return {};\n        }}\n    }}\n",
                load(0)
            )
        }
    };
    format!("fn texel_load(bank: u32, layer: u32, x: u32, y: u32) -> vec4<f32> {{\n{body}}}\n")
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
    /// A texture of 16-byte texels (`rgba32uint`), [`TEXTURE_WIDTH`] wide, one record
    /// every few texels, read with `textureLoad`: llvmpipe fetches a texel for all 8 lanes with
    /// gathers, where a storage-buffer load is a loop over the lanes and the components.
    Texture,
}

impl Placement {
    /// Its bit in a set of placements (`Tuning::perturb`): the index of its name in
    /// `tuning::PLACEMENT_NAMES`.
    pub fn bit(self) -> u8 {
        1 << crate::tuning::PLACEMENT_NAMES
            .iter()
            .position(|&n| n == self.name())
            .expect("every placement is named")
    }

    /// Its name (`tuning::PLACEMENT_NAMES`).
    pub fn name(self) -> &'static str {
        match self {
            Placement::Storage => "storage",
            Placement::Uniform => "uniform",
            Placement::Shader => "shader",
            Placement::Texture => "texture",
        }
    }
}

/// Texels per row of a record texture (a power of two: the index splits by mask and
/// shift).
pub const TEXTURE_WIDTH: u32 = 2048;

/// Rows of a record texture holding `bytes` (at least one: WebGPU forbids empty ones).
pub fn texture_rows(bytes: usize) -> u32 {
    (bytes.div_ceil(16 * TEXTURE_WIDTH as usize) as u32).max(1)
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

/// The record accessors the shaders read through (`primitive_record(i)`, ...), for the
/// arrays not written into the shader (whose code brings its own).
pub fn wgsl_accessors(placements: &Placements) -> String {
    let mut out = String::new();
    for (slot, name) in ACCESSORS {
        let (ty, _) = slot.element();
        out += &match placements.get(slot) {
            Placement::Shader => continue,
            // the plan places these two only in textures (gpu::plan::placement)
            Placement::Texture => match slot {
                Slot::Primitives => texture_accessor::<Primitive>(name, slot.name(), TEXTURE_WIDTH),
                Slot::Bvh => texture_accessor::<BvhNode>(name, slot.name(), TEXTURE_WIDTH),
                _ => unreachable!("{slot:?} is never placed in a texture"),
            },
            _ => format!(
                "fn {name}(i: u32) -> {ty} {{\n    return {}[i];\n}}\n",
                slot.name()
            ),
        };
    }
    out
}

/// The record arrays read through an accessor function, and its name.
const ACCESSORS: [(Slot, &str); 4] = [
    (Slot::Primitives, "primitive_record"),
    (Slot::Materials, "material_record"),
    (Slot::Emitters, "emitter_record"),
    (Slot::Bvh, "bvh_node"),
];

/// The WGSL declarations of every slot of group 0 under `placements`. Arrays written into
/// the shader are still declared (as storage, read by no code: the shaders read records
/// only through the accessors, which the scene code defines for them); they are not
/// bound.
pub fn wgsl_declarations(placements: &Placements) -> String {
    let mut out = String::new();
    for slot in Slot::ALL {
        let (ty, _) = slot.element();
        if let Slot::Texels(_) = slot {
            out += &format!(
                "@group(0) @binding({}) var {}: {ty};\n",
                slot.binding(),
                slot.name()
            );
            continue;
        }
        if placements.get(slot) == Placement::Texture {
            out += &format!(
                "@group(0) @binding({}) var {}: texture_storage_2d<rgba32uint, read>;\n",
                slot.binding(),
                slot.name()
            );
            continue;
        }
        let (space, ty) = match (slot, placements.get(slot)) {
            (Slot::Params, _) => ("uniform".to_string(), ty.to_string()),
            (Slot::Accum | Slot::Samples, _) => {
                ("storage, read_write".into(), format!("array<{ty}>"))
            }
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

/// The binding type of a bound slot.
fn binding_type(slot: Slot, placements: &Placements) -> wgpu::BindingType {
    let buffer = |ty| wgpu::BindingType::Buffer {
        ty,
        // the parameters of each dispatch of a submission lie at their own offset
        has_dynamic_offset: slot == Slot::Params,
        min_binding_size: None,
    };
    match (slot, placements.get(slot)) {
        (Slot::Texels(_), _) => wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2Array,
            multisampled: false,
        },
        (Slot::Accum | Slot::Samples, _) => {
            buffer(wgpu::BufferBindingType::Storage { read_only: false })
        }
        (_, Placement::Uniform) => buffer(wgpu::BufferBindingType::Uniform),
        (_, Placement::Texture) => wgpu::BindingType::StorageTexture {
            access: wgpu::StorageTextureAccess::ReadOnly,
            format: wgpu::TextureFormat::Rgba32Uint,
            view_dimension: wgpu::TextureViewDimension::D2,
        },
        _ => buffer(wgpu::BufferBindingType::Storage { read_only: true }),
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
            ty: binding_type(slot, placements),
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
/// and the record buffers and textures, all but the sums.
pub struct SceneBuffers {
    pub params: wgpu::Buffer,
    records: Vec<(Slot, Records)>,
}

/// One slot's records on the device.
enum Records {
    Buffer(wgpu::Buffer),
    Texture(wgpu::TextureView),
}

/// Uploads the records of `slots`: a uniform buffer of [`UNIFORM_BYTES`] starting with
/// them (the shader declares the array at that size), a texture (`record_texture`), or a
/// storage buffer holding them (256 zero bytes when there are none: WebGPU forbids empty
/// bindings, and every record is smaller); and the texel banks, as array textures
/// (`bank_texture`). The parameter buffer has `params_bytes` (at least one [`Params`]).
/// A device without the memory for them is an error naming what the scene needs, not a
/// fault of the shared device.
pub fn scene_buffers(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    slots: &[Slot],
    placements: &Placements,
    scene: &FlatScene,
    params_bytes: u64,
) -> Result<SceneBuffers, GpuError> {
    let scope = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let buffers = upload(device, queue, slots, placements, scene, params_bytes);
    match pollster::block_on(scope.pop()) {
        None => Ok(buffers),
        Some(e) => {
            let bytes: u64 = slots.iter().map(|s| s.bytes(scene).len() as u64).sum();
            Err(GpuError::OutOfMemory {
                needed_mib: bytes.div_ceil(1 << 20),
                texel_mib: scene.texels.bytes().div_ceil(1 << 20),
                detail: e.to_string(),
            })
        }
    }
}

fn upload(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
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
        .filter(|s| !matches!(s, Slot::Params | Slot::Accum | Slot::Samples))
        .map(|&slot| {
            if let Slot::Texels(i) = slot {
                let bank = &scene.texels.banks[i as usize];
                return (
                    slot,
                    Records::Texture(bank_texture(device, queue, slot, bank)),
                );
            }
            let bytes = slot.bytes(scene);
            if placements.get(slot) == Placement::Texture {
                return (
                    slot,
                    Records::Texture(record_texture(device, queue, slot, bytes)),
                );
            }
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
            (slot, Records::Buffer(buffer))
        })
        .collect();
    SceneBuffers { params, records }
}

/// A texture of `bytes` as 16-byte texels, [`TEXTURE_WIDTH`] to a row; the last row is
/// zero-padded (the whole rows are written from `bytes` as they are, with no copy).
fn record_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    slot: Slot,
    bytes: &[u8],
) -> wgpu::TextureView {
    let rows = texture_rows(bytes.len());
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(slot.name()),
        size: wgpu::Extent3d {
            width: TEXTURE_WIDTH,
            height: rows,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Uint,
        usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let row_bytes = TEXTURE_WIDTH as usize * 16;
    let whole = bytes.len() / row_bytes;
    let write = |first_row: usize, data: &[u8], rows: usize| {
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: 0,
                    y: first_row as u32,
                    z: 0,
                },
                aspect: wgpu::TextureAspect::All,
            },
            data,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row_bytes as u32),
                rows_per_image: Some(rows as u32),
            },
            wgpu::Extent3d {
                width: TEXTURE_WIDTH,
                height: rows as u32,
                depth_or_array_layers: 1,
            },
        )
    };
    if whole > 0 {
        write(0, &bytes[..whole * row_bytes], whole);
    }
    let rest = &bytes[whole * row_bytes..];
    if !rest.is_empty() || bytes.is_empty() {
        let mut last = rest.to_vec();
        last.resize(row_bytes, 0);
        write(whole, &last, 1);
    }
    texture.create_view(&Default::default())
}

/// A texel bank as a 2D array texture of its kind's format, written page by page.
fn bank_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    slot: Slot,
    bank: &Bank,
) -> wgpu::TextureView {
    let size = wgpu::Extent3d {
        width: bank.width,
        height: bank.height,
        depth_or_array_layers: bank.layers,
    };
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(slot.name()),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: texel_format(bank.kind),
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let mut staged = 0;
    for layer in 0..bank.layers {
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: 0,
                    y: 0,
                    z: layer,
                },
                aspect: wgpu::TextureAspect::All,
            },
            bank.page(layer),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(bank.width * bank.kind.bytes() as u32),
                rows_per_image: Some(bank.height),
            },
            wgpu::Extent3d {
                depth_or_array_layers: 1,
                ..size
            },
        );
        // each write is staged in a buffer of its own until a submission takes it: hand
        // them over every 256 MiB, so that a large bank is not staged whole
        staged += bank.page_bytes();
        if staged >= 1 << 28 {
            queue.submit(std::iter::empty());
            let _ = device.poll(wgpu::PollType::wait_indefinitely());
            staged = 0;
        }
    }
    texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    })
}

/// Group 0: the scene's buffers for `slots`, with `accum` as the sums and `samples` as the
/// splat reconstruction's sample buffer (needed when `slots` has it).
pub fn bind_scene(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    slots: &[Slot],
    buffers: &SceneBuffers,
    accum: &wgpu::Buffer,
    samples: Option<&wgpu::Buffer>,
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
                Slot::Samples => samples
                    .expect("a splatting plan has a sample buffer")
                    .as_entire_binding(),
                _ => match &buffers
                    .records
                    .iter()
                    .find(|(s, _)| *s == slot)
                    .expect("uploaded with scene_buffers")
                    .1
                {
                    Records::Buffer(b) => b.as_entire_binding(),
                    Records::Texture(view) => wgpu::BindingResource::TextureView(view),
                },
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
