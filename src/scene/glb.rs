//! The GLB container: a 12-byte header, a JSON chunk and an optional BIN chunk.
//!
//! Parsed here rather than by the gltf crate so that lying lengths in a
//! hostile file become errors before anything is allocated or sliced.

/// The two chunks of a GLB file, borrowed from its bytes.
pub(crate) struct GlbChunks<'a> {
    /// The JSON chunk's bytes.
    pub json: &'a [u8],
    /// The BIN chunk's bytes, if the file has one.
    pub bin: Option<&'a [u8]>,
}

const MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// True when `bytes` starts like a GLB file.
pub(crate) fn is_glb(bytes: &[u8]) -> bool {
    bytes.starts_with(MAGIC)
}

fn read_u32(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// Splits a GLB file into its chunks, checking every length against the data.
pub(crate) fn split(bytes: &[u8]) -> Result<GlbChunks<'_>, String> {
    if bytes.len() < 12 {
        return Err(format!(
            "GLB file is truncated: {} bytes, shorter than its 12-byte header",
            bytes.len()
        ));
    }
    if !is_glb(bytes) {
        return Err("not a GLB file (wrong magic)".into());
    }
    let version = read_u32(bytes, 4).unwrap_or(0);
    if version != 2 {
        return Err(format!("GLB version {version} is not supported (only 2)"));
    }
    let declared = read_u32(bytes, 8).unwrap_or(0) as usize;
    if declared > bytes.len() {
        return Err(format!(
            "GLB file is truncated: header says {declared} bytes, file has {}",
            bytes.len()
        ));
    }
    if declared < 12 {
        return Err(format!("GLB header length {declared} is smaller than the header"));
    }
    let data = &bytes[..declared];
    let mut at = 12;
    let mut json = None;
    let mut bin = None;
    while at < data.len() {
        let (Some(len), Some(kind)) = (read_u32(data, at), read_u32(data, at + 4)) else {
            return Err(format!("GLB chunk header at byte {at} is truncated"));
        };
        let start = at + 8;
        let end = start
            .checked_add(len as usize)
            .filter(|&end| end <= data.len())
            .ok_or_else(|| {
                format!(
                    "GLB chunk at byte {at} says {len} bytes, but only {} remain",
                    data.len().saturating_sub(start)
                )
            })?;
        let chunk = &data[start..end];
        match kind {
            CHUNK_JSON if json.is_none() && at == 12 => json = Some(chunk),
            CHUNK_JSON => return Err("GLB has a JSON chunk that is not the first chunk".into()),
            CHUNK_BIN if bin.is_none() && json.is_some() => bin = Some(chunk),
            CHUNK_BIN => return Err("GLB has a misplaced or second BIN chunk".into()),
            _ => {} // Unknown chunk types must be ignored (glTF 2.0 §4.4.3.1).
        }
        // Chunks are 4-byte aligned; a missing final pad is tolerated.
        at = end.div_ceil(4) * 4;
    }
    let json = json.ok_or("GLB has no JSON chunk")?;
    Ok(GlbChunks { json, bin })
}
