//! Accessors and buffer views checked before the crate reads them: a count in range, the
//! type expected, and every byte read (sparse parts too) within its view, so that a file
//! that lies about its sizes is refused with the JSON path of what lies.

use gltf::accessor::{DataType, Dimensions};

use super::error::{GltfError, Result};
use super::loader::Loader;
use crate::scene::mesh::MAX_TRIANGLES;

impl Loader<'_> {
    /// `check_accessor` for an attribute that must have one entry per vertex.
    pub(super) fn check_count(
        &self,
        a: &gltf::Accessor,
        n: usize,
        key: &str,
        dims: &[Dimensions],
        types: &[DataType],
    ) -> Result<()> {
        let count = self.check_accessor(a, key, dims, types)?;
        if count != n {
            return Err(GltfError::new(
                key,
                format!("has {count} entries, but POSITION has {n}"),
            ));
        }
        Ok(())
    }

    /// Checks an accessor of `dims` and one of `types` before it is read: its count, and
    /// that every byte it (and its sparse part) reads lies in its buffer view. Returns its
    /// count.
    pub(super) fn check_accessor(
        &self,
        a: &gltf::Accessor,
        key: &str,
        dims: &[Dimensions],
        types: &[DataType],
    ) -> Result<usize> {
        let at = |what: &str| format!("{key} (accessors[{}]{what})", a.index());
        let count = a.count();
        let max = 3 * MAX_TRIANGLES;
        if count == 0 || count > max {
            return Err(GltfError::new(
                at(".count"),
                format!("is {count}; wgtrace reads 1 to {max}"),
            ));
        }
        if !dims.contains(&a.dimensions()) || !types.contains(&a.data_type()) {
            return Err(GltfError::new(
                at(""),
                format!(
                    "is {:?} of {:?}; expected {} of {types:?}",
                    a.dimensions(),
                    a.data_type(),
                    dims.iter()
                        .map(|d| format!("{d:?}"))
                        .collect::<Vec<_>>()
                        .join(" or ")
                ),
            ));
        }
        let size = a.size();
        match a.view() {
            Some(view) => {
                self.check_view(&view, a.offset(), count, size, view.stride(), &at(""))?
            }
            None if a.sparse().is_none() => {
                return Err(GltfError::new(
                    at(""),
                    "has neither a bufferView nor sparse data",
                ));
            }
            None => {}
        }
        if let Some(s) = a.sparse() {
            if s.count() == 0 || s.count() > count {
                return Err(GltfError::new(
                    at(".sparse.count"),
                    format!("is {}; it must be 1 to the accessor's {count}", s.count()),
                ));
            }
            let index_size = match s.indices().index_type() {
                gltf::accessor::sparse::IndexType::U8 => 1,
                gltf::accessor::sparse::IndexType::U16 => 2,
                gltf::accessor::sparse::IndexType::U32 => 4,
            };
            let i = s.indices();
            self.check_view(
                &i.view(),
                i.offset(),
                s.count(),
                index_size,
                None,
                &at(".sparse.indices"),
            )?;
            let v = s.values();
            self.check_view(
                &v.view(),
                v.offset(),
                s.count(),
                size,
                None,
                &at(".sparse.values"),
            )?;
        }
        Ok(count)
    }

    /// That `count` elements of `size` bytes, `stride` apart (tightly packed without one),
    /// from `offset` lie within `view`.
    fn check_view(
        &self,
        view: &gltf::buffer::View,
        offset: usize,
        count: usize,
        size: usize,
        stride: Option<usize>,
        key: &str,
    ) -> Result<()> {
        let stride = stride.unwrap_or(size) as u128;
        if stride < size as u128 {
            return Err(GltfError::new(
                format!("bufferViews[{}].byteStride", view.index()),
                format!("is {stride}, less than the {size}-byte elements read through it"),
            ));
        }
        // count >= 1 (checked by the callers); u128 never wraps here
        let end = offset as u128 + stride * (count as u128 - 1) + size as u128;
        if end > view.length() as u128 {
            return Err(GltfError::new(
                key,
                format!(
                    "reads up to byte {end} of bufferViews[{}], which has {} bytes",
                    view.index(),
                    view.length()
                ),
            ));
        }
        Ok(())
    }
}

impl Loader<'_> {
    /// The elements of accessor `a` (checked by [`Loader::check_accessor`]) as floats:
    /// floats as they are; integers dequantized as glTF and KHR_mesh_quantization say, a
    /// normalized one over its type's largest value (signed ones at least -1), any other
    /// as its value. Sparse accessors included.
    pub(super) fn read_floats<const N: usize>(
        &self,
        a: &gltf::Accessor,
        key: &str,
    ) -> Result<Vec<[f32; N]>>
    where
        [f32; N]: gltf::accessor::Item,
        [i8; N]: gltf::accessor::Item,
        [u8; N]: gltf::accessor::Item,
        [i16; N]: gltf::accessor::Item,
        [u16; N]: gltf::accessor::Item,
        [u32; N]: gltf::accessor::Item,
    {
        use gltf::accessor::util::Iter;
        use gltf::accessor::DataType;
        let buffers = |b: gltf::Buffer| self.buffers.get(b.index()).map(Vec::as_slice);
        let unreadable = || {
            GltfError::new(
                key,
                "cannot be read (its sparse data points outside its buffer view?)",
            )
        };
        let norm = a.normalized();
        fn read<'s, T: gltf::accessor::Item + Copy, const N: usize>(
            a: &gltf::Accessor<'s>,
            buffers: impl Clone + Fn(gltf::Buffer<'s>) -> Option<&'s [u8]>,
            f: impl Fn(T) -> f32,
        ) -> Option<Vec<[f32; N]>>
        where
            [T; N]: gltf::accessor::Item,
        {
            Some(
                Iter::<[T; N]>::new(a.clone(), buffers)?
                    .map(|v| v.map(&f))
                    .collect(),
            )
        }
        let out = match a.data_type() {
            DataType::F32 => read::<f32, N>(a, buffers, |x| x),
            // normalized integers over their largest value, signed ones at least -1
            DataType::I8 => read::<i8, N>(a, buffers, |x| dequantize(x as f32, 127.0, norm)),
            DataType::U8 => read::<u8, N>(a, buffers, |x| dequantize(x as f32, 255.0, norm)),
            DataType::I16 => read::<i16, N>(a, buffers, |x| dequantize(x as f32, 32767.0, norm)),
            DataType::U16 => read::<u16, N>(a, buffers, |x| dequantize(x as f32, 65535.0, norm)),
            DataType::U32 => read::<u32, N>(a, buffers, |x| x as f32),
        };
        let out = out.ok_or_else(unreadable)?;
        if !out.iter().flatten().all(|x| x.is_finite()) {
            return Err(GltfError::new(key, "has a non-finite value"));
        }
        Ok(out)
    }
}

/// A component as KHR_mesh_quantization reads it: a normalized integer over its largest
/// value `max` (a signed one at least -1), else as it is.
fn dequantize(x: f32, max: f32, normalized: bool) -> f32 {
    if normalized {
        (x / max).max(-1.0)
    } else {
        x
    }
}
