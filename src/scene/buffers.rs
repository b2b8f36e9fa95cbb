//! Resolving a glTF file's buffers: the GLB BIN chunk, data URIs and external files.

use std::path::{Path, PathBuf};

use base64::Engine;

/// Loads every buffer of `doc`, checking each against its declared `byteLength`.
///
/// `base_dir` is where relative URIs are resolved; `None` (an embedded scene)
/// makes any external URI an error.
pub(crate) fn load_buffers(
    doc: &gltf::Document,
    bin: Option<&[u8]>,
    base_dir: Option<&Path>,
) -> Result<Vec<Vec<u8>>, String> {
    doc.buffers()
        .map(|buffer| {
            let what = format!("buffer {}", buffer.index());
            let data = match buffer.source() {
                gltf::buffer::Source::Bin => bin
                    .ok_or_else(|| format!("{what} refers to the GLB BIN chunk, but there is none"))?
                    .to_vec(),
                gltf::buffer::Source::Uri(uri) => {
                    load_uri(uri, base_dir, buffer.length() as u64).map_err(|e| format!("{what}: {e}"))?
                }
            };
            if data.len() < buffer.length() {
                return Err(format!(
                    "{what} is truncated: byteLength is {}, but only {} bytes are there",
                    buffer.length(),
                    data.len()
                ));
            }
            Ok(data)
        })
        .collect()
}

/// Reads the bytes a URI names: a base64 `data:` URI or a path relative to
/// `base_dir`, of which at most `max_bytes` are read (a buffer needs no more
/// than its `byteLength`).
pub(crate) fn load_uri(uri: &str, base_dir: Option<&Path>, max_bytes: u64) -> Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, payload) = rest
            .split_once(";base64,")
            .ok_or("data URI is not base64-encoded (only ';base64,' data URIs are supported)")?;
        return base64::engine::general_purpose::STANDARD
            .decode(payload)
            .map_err(|e| format!("data URI has invalid base64: {e}"));
    }
    let path = resolve_uri_path(uri, base_dir)?;
    read_file_prefix(&path, max_bytes).map_err(|e| format!("cannot read '{}': {e}", path.display()))
}

/// The first `max_bytes` bytes of the regular file at `path` (all of it when shorter).
///
/// A hostile scene can name any path: devices and pipes (`/dev/zero`,
/// `/dev/stdin`) are refused rather than read forever, and the limit keeps a
/// huge file from being read in full.
pub(crate) fn read_file_prefix(path: &Path, max_bytes: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let file = std::fs::File::open(path)?;
    if !file.metadata()?.is_file() {
        return Err(std::io::Error::other("not a regular file"));
    }
    let mut bytes = Vec::new();
    file.take(max_bytes).read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// The file path a relative URI names.
pub(crate) fn resolve_uri_path(uri: &str, base_dir: Option<&Path>) -> Result<PathBuf, String> {
    if uri.contains("://") {
        return Err(format!(
            "URI '{uri}' is not a local file (only relative paths and data URIs)"
        ));
    }
    let base = base_dir.ok_or_else(|| format!("URI '{uri}' is external, but this scene has no directory"))?;
    Ok(base.join(percent_decode(uri)))
}

/// Decodes `%XX` escapes (URIs in glTF are percent-encoded, e.g. spaces as `%20`).
fn percent_decode(s: &str) -> String {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            if let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.bin"), "a b.bin");
        assert_eq!(percent_decode("100%"), "100%");
        assert_eq!(percent_decode("%4"), "%4");
        assert_eq!(percent_decode("x%41"), "xA");
    }

    #[test]
    fn data_uri() {
        assert_eq!(
            load_uri("data:application/octet-stream;base64,AAEC", None, 0).unwrap(),
            vec![0, 1, 2]
        );
        assert!(load_uri("data:text/plain,hello", None, 0).is_err());
        assert!(load_uri("x.bin", None, 0).is_err());
    }

    #[cfg(unix)]
    #[test]
    fn devices_are_refused_and_files_read_up_to_the_limit() {
        let err = read_file_prefix(Path::new("/dev/zero"), 16).unwrap_err();
        assert_eq!(err.to_string(), "not a regular file");
        let err = read_file_prefix(Path::new("/"), 16).unwrap_err();
        assert_eq!(err.to_string(), "not a regular file");
        let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml");
        let all = std::fs::read(&file).unwrap();
        assert_eq!(read_file_prefix(&file, 10).unwrap(), all[..10]);
        assert_eq!(read_file_prefix(&file, u64::MAX).unwrap(), all);
    }
}
