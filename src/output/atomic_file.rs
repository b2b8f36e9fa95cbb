//! Files written whole or not at all: a temporary file beside the target, synced and
//! renamed onto it (see the [module docs](super)); used for images and reports.

use std::ffi::OsString;
use std::fs::{self, File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::codecs::output_error;
use crate::{Error, Result};

/// Writes `bytes` to `path` whole or not at all (a temporary file beside it, renamed into place; see the [module docs](super)): for reports
/// and other small files.
pub fn write_bytes_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    replace_file(path, |f| f.write_all(bytes))
}

/// Replaces `path` with what `write` puts into a fresh file: written to a
/// temporary file in the same directory (so the rename stays on one file
/// system and is atomic), synced, then renamed onto `path`.
///
/// On any failure the temporary file is removed and `path` is untouched.
pub(super) fn replace_file(path: &Path, write: impl FnOnce(&mut File) -> io::Result<()>) -> Result<()> {
    let io_error = |source| Error::Io {
        path: path.to_owned(),
        source,
    };
    let (tmp_path, mut file) = create_temp_beside(path)?;
    let written = write(&mut file).and_then(|()| file.sync_all()).and_then(|()| {
        // Closed before the rename: Windows cannot rename an open file.
        drop(file);
        fs::rename(&tmp_path, path)
    });
    if let Err(source) = written {
        // Best effort: the write error is the one worth reporting.
        let _ = fs::remove_file(&tmp_path);
        return Err(io_error(source));
    }
    sync_directory(&tmp_path);
    Ok(())
}

/// Creates `.NAME.tmp-PID-N` beside `path`, a name no other writer (thread or process) uses.
fn create_temp_beside(path: &Path) -> Result<(PathBuf, File)> {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    // A temporary file left by a crashed process with the same id may exist: take the next number.
    let mut attempts = 0;
    loop {
        let tmp_path = temp_path(path, NEXT.fetch_add(1, Ordering::Relaxed))
            .ok_or_else(|| output_error(path, "the path does not name a file"))?;
        match OpenOptions::new().write(true).create_new(true).open(&tmp_path) {
            Ok(file) => return Ok((tmp_path, file)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists && attempts < 100 => attempts += 1,
            Err(source) => {
                return Err(Error::Io {
                    path: path.to_owned(),
                    source,
                });
            }
        }
    }
}

/// `.NAME.tmp-PID-N` in `path`'s folder (`.` for a bare file name); `None`
/// when `path` names no file (`/`, `..`).
pub(super) fn temp_path(path: &Path, n: u64) -> Option<PathBuf> {
    let name = path.file_name()?;
    let dir = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };
    let mut tmp_name = OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".tmp-{}-{n}", std::process::id()));
    Some(dir.join(tmp_name))
}

/// Makes the rename itself durable by syncing the directory that holds `file`
/// (Unix only; best effort, since the file is already complete either way).
fn sync_directory(file: &Path) {
    #[cfg(unix)]
    if let Some(dir) = file.parent().filter(|d| !d.as_os_str().is_empty()) {
        if let Ok(dir) = File::open(dir) {
            let _ = dir.sync_all();
        }
    }
    #[cfg(not(unix))]
    let _ = file;
}
