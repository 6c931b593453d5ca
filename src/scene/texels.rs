//! Image texels at their source precision, in banks of pages: what image look-ups read,
//! on both backends.
//!
//! Every image has a [`TexelKind`]: 8-bit images stay 8 bits per channel (sRGB ones
//! decoded at look-up by the texture, [`srgb_texel`]), 16-bit ones become half floats,
//! float ones (HDR, EXR) stay 32-bit floats. Images of one kind are packed into pages of
//! one size (the widest and the tallest image of the kind), shelf by shelf, and the pages
//! into banks of at most [`MAX_BANK_BYTES`] and [`MAX_BANK_LAYERS`] pages. On the GPU a bank
//! is a 2D array texture of its kind's format (`gpu::bindings`), read with `textureLoad`;
//! on the CPU the same bytes are decoded the same way ([`Bank::texel`]). An image is found
//! by its [`Region`]: bank, page (layer) and the corner of the image in the page. (The
//! Perlin tables and the image background's distribution, read a component at a time, are
//! a storage buffer instead, `FlatScene::tables`: llvmpipe's `textureLoad` fetches and
//! converts a whole texel, which made Perlin noise 38% slower.)
//!
//! Why 8-bit sRGB images are not `rgba8unorm-srgb` textures: llvmpipe's sRGB decode is an
//! approximation (1.3e-4 off at 0.27), and a second 8-bit bank would put a second
//! texture fetch into every look-up (llvmpipe runs every case of the bank `switch`).

use half::f16;

/// How a bank stores a texel (always four channels: r, g, b, alpha).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum TexelKind {
    /// 8 bits per channel (`rgba8unorm`); an sRGB image's texture decodes its colour.
    Unorm8,
    /// Half floats (`rgba16float`): 16-bit images, linear.
    Half,
    /// 32-bit floats (`rgba32float`): HDR and EXR images.
    Float,
}

impl TexelKind {
    /// In the order banks are made.
    pub const ALL: [TexelKind; 3] = [TexelKind::Unorm8, TexelKind::Half, TexelKind::Float];

    /// Bytes of one texel.
    pub fn bytes(self) -> usize {
        match self {
            TexelKind::Unorm8 => 4,
            TexelKind::Half => 8,
            TexelKind::Float => 16,
        }
    }

    /// Its name in messages and reports.
    pub fn name(self) -> &'static str {
        match self {
            TexelKind::Unorm8 => "8-bit",
            TexelKind::Half => "16-bit (half float)",
            TexelKind::Float => "float",
        }
    }

    /// Texel `i` of `data` (this kind's bytes) as (r, g, b, alpha), as `textureLoad`
    /// returns it (8-bit channels as c / 255).
    pub fn decode(self, data: &[u8], i: usize) -> [f32; 4] {
        let at = i * self.bytes();
        match self {
            TexelKind::Unorm8 => {
                let c = &data[at..at + 4];
                [unorm8(c[0]), unorm8(c[1]), unorm8(c[2]), unorm8(c[3])]
            }
            TexelKind::Half => {
                let h = |k: usize| {
                    f16::from_le_bytes([data[at + 2 * k], data[at + 2 * k + 1]]).to_f32()
                };
                [h(0), h(1), h(2), h(3)]
            }
            TexelKind::Float => {
                let f = |k: usize| {
                    f32::from_le_bytes(data[at + 4 * k..at + 4 * k + 4].try_into().unwrap())
                };
                [f(0), f(1), f(2), f(3)]
            }
        }
    }
}

/// An 8-bit channel as a number in [0, 1] (Vulkan's unorm conversion, c / 255).
pub fn unorm8(c: u8) -> f32 {
    c as f32 / 255.0
}

/// The sRGB transfer function undone (IEC 61966-2-1).
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// [`srgb_to_linear`] of the 8-bit value c (c / 255), from a table.
pub fn srgb8(c: u8) -> f32 {
    static TABLE: std::sync::OnceLock<[f32; 256]> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(|c| srgb_to_linear(unorm8(c as u8))))[c as usize]
}

/// An 8-bit texel with its colour decoded from sRGB (its alpha is linear): what an sRGB
/// image's texture does to each texel before filtering (`shaders/shared/textures.wgsl`,
/// `srgb_texel`).
pub fn srgb_texel(data: &[u8], i: usize) -> [f32; 4] {
    let c = &data[4 * i..4 * i + 4];
    [srgb8(c[0]), srgb8(c[1]), srgb8(c[2]), unorm8(c[3])]
}

/// Most bytes one bank holds (a 2D array texture of 1 GiB: lavapipe allocates at most
/// 2 GiB at once, and real GPUs' drivers are happier with fewer, smaller resources).
pub const MAX_BANK_BYTES: u64 = 1 << 30;

/// Most pages one bank holds: WebGPU's default `maxTextureArrayLayers`, which every
/// Vulkan device meets.
pub const MAX_BANK_LAYERS: u32 = 256;

/// Most banks a scene has: each is one binding of the trace shader (`gpu::bindings`).
pub const MAX_BANKS: usize = 8;

/// A block of texels to place: `width` x `height` texels of `kind`, row by row, row 0 at
/// the top.
pub struct Block<'a> {
    pub kind: TexelKind,
    pub width: u32,
    pub height: u32,
    pub data: &'a [u8],
}

/// Where a block lies: its bank, its page in the bank, and the page texel of its
/// top-left corner.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Region {
    pub bank: u32,
    pub layer: u32,
    pub x: u32,
    pub y: u32,
}

/// Pages of one kind and size: `layers` pages of `width` x `height` texels, page after
/// page, row after row; what no block covers is zero.
#[derive(Clone, Debug, PartialEq)]
pub struct Bank {
    pub kind: TexelKind,
    pub width: u32,
    pub height: u32,
    pub layers: u32,
    pub data: Vec<u8>,
}

impl Bank {
    /// Bytes of one page.
    pub fn page_bytes(&self) -> usize {
        self.width as usize * self.height as usize * self.kind.bytes()
    }

    /// Page `layer`'s bytes.
    pub fn page(&self, layer: u32) -> &[u8] {
        let n = self.page_bytes();
        &self.data[layer as usize * n..][..n]
    }

    /// Texel (x, y) of page `layer`, decoded as the GPU's `textureLoad` does; with `srgb`
    /// (an 8-bit bank), its colour decoded from sRGB.
    pub fn texel(&self, layer: u32, x: u32, y: u32, srgb: bool) -> [f32; 4] {
        let i =
            (layer as usize * self.height as usize + y as usize) * self.width as usize + x as usize;
        if srgb && self.kind == TexelKind::Unorm8 {
            srgb_texel(&self.data, i)
        } else {
            self.kind.decode(&self.data, i)
        }
    }
}

/// A scene's texels: its banks, in the order regions name them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Texels {
    pub banks: Vec<Bank>,
}

impl Texels {
    /// Bytes of every bank together.
    pub fn bytes(&self) -> u64 {
        self.banks.iter().map(|b| b.data.len() as u64).sum()
    }

    /// Texel (x, y) of page `layer` of bank `bank` ([`Bank::texel`]).
    pub fn texel(&self, bank: u32, layer: u32, x: u32, y: u32, srgb: bool) -> [f32; 4] {
        self.banks[bank as usize].texel(layer, x, y, srgb)
    }
}

/// Places `blocks` into banks: per kind (in [`TexelKind::ALL`]'s order), pages the size of
/// the kind's widest and tallest block, filled shelf by shelf with the blocks from the
/// tallest down, [`MAX_BANK_LAYERS`] pages and [`MAX_BANK_BYTES`] to a bank. Returns each
/// block's region, in `blocks`' order, or what does not fit (more than [`MAX_BANKS`]).
pub fn pack(blocks: &[Block]) -> Result<(Vec<Region>, Texels), String> {
    let mut regions = vec![Region::default(); blocks.len()];
    let mut banks: Vec<Bank> = Vec::new();
    for kind in TexelKind::ALL {
        let mut order: Vec<usize> = (0..blocks.len())
            .filter(|&i| blocks[i].kind == kind)
            .collect();
        if order.is_empty() {
            continue;
        }
        let width = order.iter().map(|&i| blocks[i].width).max().unwrap_or(1);
        let height = order.iter().map(|&i| blocks[i].height).max().unwrap_or(1);
        // tallest first (stable: equal heights keep the scene's order)
        order.sort_by_key(|&i| std::cmp::Reverse(blocks[i].height));
        // shelves: the page, the shelf's top row and height, the next free column
        let (mut page, mut top, mut shelf, mut x) = (0u32, 0u32, 0u32, 0u32);
        let mut pages = Vec::with_capacity(order.len());
        for &i in &order {
            let b = &blocks[i];
            if x + b.width > width {
                top += shelf;
                (shelf, x) = (0, 0);
            }
            if top + b.height > height {
                page += 1;
                (top, shelf, x) = (0, 0, 0);
            }
            pages.push((i, page, x, top));
            x += b.width;
            shelf = shelf.max(b.height);
        }
        let page_bytes = width as u64 * height as u64 * kind.bytes() as u64;
        let per_bank = ((MAX_BANK_BYTES / page_bytes).max(1) as u32).min(MAX_BANK_LAYERS);
        let count = page + 1;
        let first = banks.len();
        let needed = count.div_ceil(per_bank) as usize;
        if first + needed > MAX_BANKS {
            let total: u64 = order
                .iter()
                .map(|&i| blocks[i].width as u64 * blocks[i].height as u64)
                .sum::<u64>()
                * kind.bytes() as u64;
            return Err(format!(
                "the scene's {} texels need {} MiB in {count} pages of {width} x {height}, more \
                 than the {MAX_BANKS} banks of at most {} MiB wgtrace binds (with the other \
                 kinds' {first})",
                kind.name(),
                total.div_ceil(1 << 20),
                MAX_BANK_BYTES >> 20,
            ));
        }
        for k in 0..needed as u32 {
            let layers = per_bank.min(count - k * per_bank);
            banks.push(Bank {
                kind,
                width,
                height,
                layers,
                data: vec![0; layers as usize * page_bytes as usize],
            });
        }
        for (i, page, x, y) in pages {
            let region = Region {
                bank: (first as u32) + page / per_bank,
                layer: page % per_bank,
                x,
                y,
            };
            copy_block(&mut banks[region.bank as usize], &blocks[i], region);
            regions[i] = region;
        }
    }
    Ok((regions, Texels { banks }))
}

/// Writes `block` into `bank` at `region`, row by row.
fn copy_block(bank: &mut Bank, block: &Block, region: Region) {
    let t = bank.kind.bytes();
    let row = block.width as usize * t;
    let page = bank.page_bytes();
    for y in 0..block.height as usize {
        let at = region.layer as usize * page
            + ((region.y as usize + y) * bank.width as usize + region.x as usize) * t;
        bank.data[at..at + row].copy_from_slice(&block.data[y * row..(y + 1) * row]);
    }
}
