//! EXT_meshopt_compression: buffer views whose bytes are meshoptimizer's encoding of
//! vertex attributes or indices, decoded (with the `meshopt` crate) into the view's own
//! buffer at the view's offset, so that every reader after this sees plain data. The
//! view's buffer is usually a fallback one that holds no bytes (`fallback: true`): it is
//! made of zeros of its `byteLength` here, and the decoded views fill it.

use gltf::json::Value;

use super::error::{GltfError, Result};

const EXT: &str = "EXT_meshopt_compression";

/// Most bytes a fallback buffer is made of (the decoded data of a file): 2 GiB.
pub const MAX_FALLBACK_BYTES: u64 = 1 << 31;

/// Whether buffer `b` is a fallback buffer of EXT_meshopt_compression: no data of its own.
pub(super) fn is_fallback(b: &gltf::Buffer) -> bool {
    b.extension_value(EXT)
        .and_then(|e| e.get("fallback"))
        .and_then(Value::as_bool)
        .unwrap_or(false)
}

/// The zeros a fallback buffer starts as; refused past [`MAX_FALLBACK_BYTES`].
pub(super) fn fallback_bytes(b: &gltf::Buffer) -> Result<Vec<u8>> {
    let len = b.length() as u64;
    if len > MAX_FALLBACK_BYTES {
        return Err(GltfError::new(
            format!("buffers[{}].byteLength", b.index()),
            format!("is {len}; wgtrace decodes at most {MAX_FALLBACK_BYTES} bytes a buffer"),
        ));
    }
    Ok(vec![0; len as usize])
}

/// Decodes every compressed view of `doc` into `buffers` (each at least as long as its
/// `byteLength`, the view ranges not yet checked).
pub(super) fn decode_views(doc: &gltf::Document, buffers: &mut [Vec<u8>]) -> Result<()> {
    for view in doc.views() {
        let Some(ext) = view.extension_value(EXT) else {
            continue;
        };
        let key = format!("bufferViews[{}].extensions.{EXT}", view.index());
        let field = |name: &str| ext.get(name).and_then(Value::as_u64);
        let need = |name: &str| {
            field(name).ok_or_else(|| {
                GltfError::new(format!("{key}.{name}"), "is missing or not an integer")
            })
        };
        let source = need("buffer")? as usize;
        let offset = field("byteOffset").unwrap_or(0);
        let length = need("byteLength")?;
        let stride = need("byteStride")? as usize;
        let count = need("count")? as usize;
        let mode = ext.get("mode").and_then(Value::as_str).unwrap_or("");
        let filter = ext.get("filter").and_then(Value::as_str).unwrap_or("NONE");
        let src = buffers.get(source).ok_or_else(|| {
            GltfError::new(
                format!("{key}.buffer"),
                format!(
                    "names buffers[{source}], but the file has {}",
                    buffers.len()
                ),
            )
        })?;
        let end = offset as u128 + length as u128;
        if end > src.len() as u128 {
            return Err(GltfError::new(
                key,
                format!(
                    "reads up to byte {end} of buffers[{source}], which has {} bytes",
                    src.len()
                ),
            ));
        }
        let encoded = src[offset as usize..end as usize].to_vec();
        let bad = |why: String| GltfError::new(key.clone(), why);
        let size = count as u128 * stride as u128;
        if size != view.length() as u128 {
            return Err(bad(format!(
                "decodes to {count} x {stride} bytes, but the view has {}",
                view.length()
            )));
        }
        let mut out = vec![0u8; size as usize];
        let code = match mode {
            "ATTRIBUTES" => {
                if stride == 0 || stride > 256 || !stride.is_multiple_of(4) {
                    return Err(bad(format!(
                        "has byteStride {stride}; ATTRIBUTES needs a multiple of 4 up to 256"
                    )));
                }
                // SAFETY: `out` holds count x stride bytes, the sizes passed; the decoder
                // reads at most `encoded.len()` bytes and is safe on untrusted input
                unsafe {
                    meshopt::ffi::meshopt_decodeVertexBuffer(
                        out.as_mut_ptr().cast(),
                        count,
                        stride,
                        encoded.as_ptr(),
                        encoded.len(),
                    )
                }
            }
            "TRIANGLES" | "INDICES" => {
                if stride != 2 && stride != 4 {
                    return Err(bad(format!("has byteStride {stride}; {mode} needs 2 or 4")));
                }
                if mode == "TRIANGLES" && !count.is_multiple_of(3) {
                    return Err(bad(format!(
                        "has count {count}; TRIANGLES needs a multiple of 3"
                    )));
                }
                // SAFETY: as above, `out` holds count indices of `stride` bytes
                unsafe {
                    if mode == "TRIANGLES" {
                        meshopt::ffi::meshopt_decodeIndexBuffer(
                            out.as_mut_ptr().cast(),
                            count,
                            stride,
                            encoded.as_ptr(),
                            encoded.len(),
                        )
                    } else {
                        meshopt::ffi::meshopt_decodeIndexSequence(
                            out.as_mut_ptr().cast(),
                            count,
                            stride,
                            encoded.as_ptr(),
                            encoded.len(),
                        )
                    }
                }
            }
            other => {
                return Err(GltfError::new(
                    format!("{key}.mode"),
                    format!("is \"{other}\"; it must be ATTRIBUTES, TRIANGLES or INDICES"),
                ))
            }
        };
        if code != 0 {
            return Err(bad(format!(
                "does not decode (meshoptimizer's error {code})"
            )));
        }
        let filter_ok = match filter {
            "NONE" => true,
            "OCTAHEDRAL" => mode == "ATTRIBUTES" && (stride == 4 || stride == 8),
            "QUATERNION" => mode == "ATTRIBUTES" && stride == 8,
            "EXPONENTIAL" => mode == "ATTRIBUTES",
            _ => false,
        };
        if !filter_ok {
            return Err(GltfError::new(
                format!("{key}.filter"),
                format!("is \"{filter}\", which a {mode} view of byteStride {stride} cannot have"),
            ));
        }
        // SAFETY: `out` holds count elements of `stride` bytes, as each filter is told
        unsafe {
            match filter {
                "OCTAHEDRAL" => {
                    meshopt::ffi::meshopt_decodeFilterOct(out.as_mut_ptr().cast(), count, stride)
                }
                "QUATERNION" => {
                    meshopt::ffi::meshopt_decodeFilterQuat(out.as_mut_ptr().cast(), count, stride)
                }
                "EXPONENTIAL" => {
                    meshopt::ffi::meshopt_decodeFilterExp(out.as_mut_ptr().cast(), count, stride)
                }
                _ => {}
            }
        }
        let target = &mut buffers[view.buffer().index()];
        let at = view.offset() as u128;
        if at + size > target.len() as u128 {
            return Err(GltfError::new(
                format!("bufferViews[{}]", view.index()),
                format!(
                    "ends at byte {}, past the end of buffers[{}] ({} bytes)",
                    at + size,
                    view.buffer().index(),
                    target.len()
                ),
            ));
        }
        target[at as usize..(at + size) as usize].copy_from_slice(&out);
    }
    Ok(())
}
