//! Bounds-checked reading of glTF accessors.
//!
//! Every offset, stride and count is checked against the buffer view and the
//! buffer before any element is read, with overflow-checked arithmetic, so a
//! file that lies about sizes gives an error, never a panic or a huge allocation.

use gltf::accessor::{DataType, Dimensions};

/// The byte slices of an accessor's elements, one per element.
fn element_slices<'b>(acc: &gltf::Accessor, buffers: &'b [Vec<u8>]) -> Result<Vec<&'b [u8]>, String> {
    let what = format!("accessor {}", acc.index());
    if acc.sparse().is_some() {
        return Err(format!("{what} is sparse; sparse accessors are not supported"));
    }
    let elem = acc.size();
    let count = acc.count();
    let Some(view) = acc.view() else {
        return Err(format!("{what} has no bufferView"));
    };
    let buffer = buffers
        .get(view.buffer().index())
        .ok_or_else(|| format!("{what}: buffer {} is missing", view.buffer().index()))?;
    let stride = view.stride().unwrap_or(elem);
    if stride < elem {
        return Err(format!(
            "{what}: bufferView {} byteStride {stride} is smaller than the element size {elem}",
            view.index()
        ));
    }
    let view_end = view
        .offset()
        .checked_add(view.length())
        .filter(|&end| end <= buffer.len())
        .ok_or_else(|| {
            format!(
                "bufferView {} (offset {}, length {}) runs past the end of buffer {} ({} bytes)",
                view.index(),
                view.offset(),
                view.length(),
                view.buffer().index(),
                buffer.len()
            )
        })?;
    if count == 0 {
        return Ok(Vec::new());
    }
    let needed = (count - 1)
        .checked_mul(stride)
        .and_then(|n| n.checked_add(elem))
        .and_then(|n| n.checked_add(acc.offset()));
    match needed {
        Some(n) if n <= view.length() => {}
        _ => {
            return Err(format!(
                "{what} ({count} elements of {elem} bytes, stride {stride}, offset {}) does not fit in bufferView {} ({} bytes)",
                acc.offset(),
                view.index(),
                view.length()
            ));
        }
    }
    let base = view.offset() + acc.offset();
    debug_assert!(base + (count - 1) * stride + elem <= view_end);
    Ok((0..count)
        .map(|i| &buffer[base + i * stride..base + i * stride + elem])
        .collect())
}

fn f32_at(b: &[u8], i: usize) -> f32 {
    f32::from_le_bytes([b[4 * i], b[4 * i + 1], b[4 * i + 2], b[4 * i + 3]])
}

/// Reads a VEC3 float accessor (positions, normals) as stored: non-finite
/// values are the caller's to handle (the importer drops triangles with a
/// non-finite corner and replaces non-finite normals by the face normal).
pub(crate) fn read_vec3(acc: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<[f32; 3]>, String> {
    let what = format!("accessor {}", acc.index());
    if acc.dimensions() != Dimensions::Vec3 || acc.data_type() != DataType::F32 {
        return Err(format!(
            "{what} is {:?} of {:?}; expected VEC3 of FLOAT (quantized attributes are not supported)",
            acc.dimensions(),
            acc.data_type()
        ));
    }
    let slices = element_slices(acc, buffers)?;
    Ok(slices
        .iter()
        .map(|b| [f32_at(b, 0), f32_at(b, 1), f32_at(b, 2)])
        .collect())
}

/// Reads a VEC2 texture-coordinate accessor (float, or normalized u8/u16).
pub(crate) fn read_texcoords(acc: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<[f32; 2]>, String> {
    let what = format!("accessor {}", acc.index());
    if acc.dimensions() != Dimensions::Vec2 {
        return Err(format!(
            "{what} is {:?}; texture coordinates must be VEC2",
            acc.dimensions()
        ));
    }
    let slices = element_slices(acc, buffers)?;
    let decode = |b: &[u8], i: usize| -> Result<f32, String> {
        match (acc.data_type(), acc.normalized()) {
            (DataType::F32, _) => Ok(f32_at(b, i)),
            (DataType::U8, true) => Ok(f32::from(b[i]) / 255.0),
            (DataType::U16, true) => Ok(f32::from(u16::from_le_bytes([b[2 * i], b[2 * i + 1]])) / 65535.0),
            (t, n) => Err(format!(
                "{what}: texture coordinates of {t:?} (normalized: {n}) are not supported"
            )),
        }
    };
    slices
        .iter()
        .map(|b| {
            let uv = [decode(b, 0)?, decode(b, 1)?];
            // A non-finite UV only spoils a texture lookup; clamp it to 0 rather than reject the file.
            Ok(uv.map(|c| if c.is_finite() { c } else { 0.0 }))
        })
        .collect()
}

/// Reads a SCALAR index accessor of u8, u16 or u32.
pub(crate) fn read_indices(acc: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<u32>, String> {
    let what = format!("accessor {}", acc.index());
    if acc.dimensions() != Dimensions::Scalar {
        return Err(format!(
            "{what} is {:?}; indices must be SCALAR",
            acc.dimensions()
        ));
    }
    let slices = element_slices(acc, buffers)?;
    match acc.data_type() {
        DataType::U8 => Ok(slices.iter().map(|b| u32::from(b[0])).collect()),
        DataType::U16 => Ok(slices
            .iter()
            .map(|b| u32::from(u16::from_le_bytes([b[0], b[1]])))
            .collect()),
        DataType::U32 => Ok(slices
            .iter()
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect()),
        t => Err(format!(
            "{what}: indices of {t:?} are not allowed (u8, u16 or u32)"
        )),
    }
}
