//! Density grids of heterogeneous media: Mitsuba's `.vol` files (the binary grid format
//! of its `gridvolume`) and the majorants of their cells that tracking steps through.
//!
//! A `.vol` file: the bytes `VOL`, version 3, then little-endian: the encoding (i32, 1 =
//! float32, the one read here), the voxel counts x, y, z (i32 each), the channels (i32:
//! 1, or 3 for an RGB density or albedo), the box (six f32: min x, y, z, max x, y, z), and the values, x fastest, then
//! y, then z.

use std::path::Path;

use crate::scene::records::MAJORANT_CELL;

/// The most values one grid may hold (each an f32 of the tables, whose binding llvmpipe
/// limits to 128 MiB).
pub const MAX_VOXELS: u64 = 16 << 20;

/// A grid of densities (one channel) or albedos (three).
#[derive(Debug, Clone, PartialEq)]
pub struct DensityGrid {
    /// Voxels along x, y and z.
    pub res: [u32; 3],
    /// Values per voxel.
    pub channels: u32,
    /// The values, a voxel's channels together, x fastest.
    pub values: Vec<f32>,
    /// The box the file gives the grid (min, max).
    pub bbox: ([f32; 3], [f32; 3]),
}

/// Reads a `.vol` file of densities: one float32 channel, or three (a density per
/// colour channel), finite and 0 or more.
pub fn read_vol(path: &Path) -> Result<DensityGrid, String> {
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    parse_vol(&bytes)
}

/// Reads a `.vol` file of albedos: one (grey) or three float32 channels, each 0 to 1;
/// returned with three.
pub fn read_albedo_vol(path: &Path) -> Result<DensityGrid, String> {
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    let mut g = parse_vol(&bytes)?;
    if let Some(i) = g.values.iter().position(|v| *v > 1.0) {
        return Err(format!("value {i} is {}: an albedo is 0 to 1", g.values[i]));
    }
    if g.channels == 1 {
        if g.values.len() as u64 * 3 > MAX_VOXELS {
            return Err(format!(
                "{} voxels of one channel: an albedo grid is kept as three, at most {MAX_VOXELS} values",
                g.values.len()
            ));
        }
        g.values = g.values.iter().flat_map(|&v| [v; 3]).collect();
        g.channels = 3;
    }
    Ok(g)
}

/// A `.vol` file's grid from its bytes: one channel or three.
pub fn parse_vol(bytes: &[u8]) -> Result<DensityGrid, String> {
    const HEADER: usize = 3 + 1 + 4 * 5 + 4 * 6;
    if bytes.len() < HEADER || &bytes[..3] != b"VOL" {
        return Err("not a Mitsuba .vol grid (it does not start with `VOL` and its header)".into());
    }
    if bytes[3] != 3 {
        return Err(format!(
            "a .vol file of version {}: version 3 is read",
            bytes[3]
        ));
    }
    let int = |i: usize| i32::from_le_bytes(bytes[4 + 4 * i..8 + 4 * i].try_into().unwrap());
    let float =
        |at: usize| f32::from_le_bytes(bytes[at..at + 4].try_into().expect("in the header"));
    let encoding = int(0);
    if encoding != 1 {
        return Err(format!(
            "a .vol grid of encoding {encoding}: float32 (encoding 1) is read"
        ));
    }
    let res = [int(1), int(2), int(3)];
    if res.iter().any(|&r| r < 1) {
        return Err(format!("voxel counts {res:?}: each must be at least 1"));
    }
    let channels = int(4);
    if channels != 1 && channels != 3 {
        return Err(format!(
            "a grid of {channels} channels: one or three (RGB) are read"
        ));
    }
    let channels = channels as u32;
    let res = res.map(|r| r as u32);
    let count = res
        .iter()
        .try_fold(u64::from(channels), |n, &r| n.checked_mul(u64::from(r)))
        .filter(|&n| n <= MAX_VOXELS)
        .ok_or_else(|| {
            format!("{res:?} voxels of {channels} channels: at most {MAX_VOXELS} values are read")
        })?;
    let min = [float(24), float(28), float(32)];
    let max = [float(36), float(40), float(44)];
    if !min.iter().chain(&max).all(|v| v.is_finite()) {
        return Err(format!("its box {min:?} to {max:?} is not finite"));
    }
    let data = &bytes[HEADER..];
    if data.len() as u64 != count * 4 {
        return Err(format!(
            "holds {} bytes of values where {res:?} voxels of {channels} float32 take {}",
            data.len(),
            count * 4
        ));
    }
    let values: Vec<f32> = data
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().expect("four bytes")))
        .collect();
    if let Some(i) = values.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
        return Err(format!(
            "value {i} is {}: values must be finite and >= 0",
            values[i]
        ));
    }
    Ok(DensityGrid {
        res,
        channels,
        values,
        bbox: (min, max),
    })
}

/// A `.vol` file of float32 values, `values.len()` / voxels channels of them per voxel
/// (x fastest), in the box `bbox`.
pub fn write_vol(res: [u32; 3], values: &[f32], bbox: ([f32; 3], [f32; 3])) -> Vec<u8> {
    let mut out = b"VOL\x03".to_vec();
    let channels = values.len() / res.iter().map(|&r| r as usize).product::<usize>();
    for i in [
        1,
        res[0] as i32,
        res[1] as i32,
        res[2] as i32,
        channels as i32,
    ] {
        out.extend(i.to_le_bytes());
    }
    for f in bbox.0.iter().chain(&bbox.1).chain(values) {
        out.extend(f.to_le_bytes());
    }
    out
}

impl DensityGrid {
    /// Majorant cells along x, y and z (`MAJORANT_CELL` voxels a side, the last ones
    /// partial).
    pub fn cells(&self) -> [u32; 3] {
        self.res.map(|r| r.div_ceil(MAJORANT_CELL))
    }

    /// The highest density of each majorant cell (x fastest): the largest value (of any
    /// channel) among the voxels a trilinear look-up in it reads (one more on each side).
    pub fn majorants(&self) -> Vec<f32> {
        let cells = self.cells();
        let [rx, ry, _] = self.res.map(|r| r as usize);
        let k = self.channels as usize;
        let range = |c: u32, r: u32| {
            let lo = (c * MAJORANT_CELL).saturating_sub(1);
            let hi = ((c + 1) * MAJORANT_CELL).min(r - 1);
            lo as usize..=hi as usize
        };
        let mut out = Vec::with_capacity(cells.iter().product::<u32>() as usize);
        for cz in 0..cells[2] {
            for cy in 0..cells[1] {
                for cx in 0..cells[0] {
                    let mut m = 0.0f32;
                    for z in range(cz, self.res[2]) {
                        for y in range(cy, self.res[1]) {
                            for x in range(cx, self.res[0]) {
                                let v = (x + rx * (y + ry * z)) * k;
                                m = self.values[v..v + k].iter().fold(m, |m, &d| m.max(d));
                            }
                        }
                    }
                    out.push(m);
                }
            }
        }
        out
    }
}
